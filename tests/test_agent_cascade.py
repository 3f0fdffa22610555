"""Cascade-v0's agent scorer: the zero action's episodes and numbers are ``motion-bench
juggling --pattern 3``'s juggler on the same seeds, the differences are agent - nominal,
and ``motion-bench train``/``agent`` run with the shipped config."""

from __future__ import annotations

import json
from types import SimpleNamespace

import gymnasium as gym
import numpy as np
import pytest

import motion_envs  # noqa: F401  (registers the ids)
from baselines.agents.cascade_score import (
    CascadeAgentEpisodes,
    cascade_agent_episodes,
    cascade_agent_results,
    catches_median_comparison,
    catches_median_difference,
)
from baselines.agents.config import resolve_hyperparams
from baselines.juggling_bench.cascade import CascadeConfig, cascade_episodes, run_cascade
from motion_envs.datasets.juggling import SPLIT_SEEDS

ENV_ID = "MotionEnvs/Cascade-v0"
KWARGS = {
    "level": "medium",
    "max_catches": 10,
    "residual_scale": 0.4,
    "residual_phases": ["catch"],
}
N = 6


def zero_policy(obs):
    return np.zeros((obs.shape[0], 4), dtype=np.float32)


def lifting_policy(obs):
    """Both hands 0.15 m higher while they hold no ball, 0.15 m lower while they do (an
    arbitrary deterministic policy that changes the episodes; it acts in the catch phase
    only)."""
    held = obs[:, [4, 19]]  # the hands' "holds a ball" entries
    out = np.zeros((obs.shape[0], 4), dtype=np.float32)
    out[:, [1, 3]] = np.where(held > 0.5, -0.375, 0.375)  # of residual_scale 0.4 m
    return out


def loaded(policy):
    return SimpleNamespace(
        env_id=ENV_ID, env_kwargs=dict(KWARGS), predict=policy, policy=lambda: policy, manifest={}
    )


def independent_episode(policy, seed: int) -> tuple[int, int, bool, float]:
    """One episode played on its own env, one observation at a time."""
    env = gym.make(ENV_ID, **KWARGS)
    obs, _ = env.reset(seed=seed)
    while True:
        action = policy(obs[None])[0]
        obs, _, terminated, truncated, info = env.step(action)
        if terminated or truncated:
            env.close()
            return info["catches"], info["tosses"], terminated, info["time"]


def test_zero_action_episodes_are_the_cascade_benchmarks_juggler():
    got = cascade_agent_episodes(None, ENV_ID, KWARGS, "val", N)
    ref = cascade_episodes("medium", "juggler", CascadeConfig(episodes=N, split="val"))
    np.testing.assert_array_equal(got.seeds, SPLIT_SEEDS["val"] + np.arange(N))
    np.testing.assert_array_equal(got.seeds, ref.seeds)
    np.testing.assert_array_equal(got.catches, ref.catches)
    np.testing.assert_array_equal(got.tosses, ref.tosses)
    np.testing.assert_array_equal(got.dropped, ref.dropped)
    np.testing.assert_allclose(got.time, ref.time)
    assert got.max_catches == 10
    # drops per catch, pooled: the validation criterion
    assert got.criterion == pytest.approx(ref.dropped.sum() / ref.catches.sum())


def test_zero_action_results_equal_the_pattern_3_benchmark():
    """The zero action as the 'agent': both columns are the juggler of ``motion-bench
    juggling --pattern 3`` on the same test seeds (median, interval, catch rate), and every
    difference is 0."""
    res = cascade_agent_results(loaded(zero_policy), "test", N)
    doc = run_cascade(
        CascadeConfig(levels=("medium",), methods=("juggler",), episodes=N, split="test")
    )
    juggler = doc["levels"][0]["methods"]["juggler"]
    for prefix in ("", "nominal_"):
        assert res[f"{prefix}catches_median"] == juggler["catches_median"]
        assert res[f"{prefix}catches_median_ci"] == juggler["catches_median_ci"]
        assert res[f"{prefix}catch_rate"] == juggler["catch_rate"]
        assert res[f"{prefix}catch_rate_ci"] == juggler["catch_rate_ci"]
        assert res[f"{prefix}catches_mean"] == juggler["catches_mean"]
    assert res["censored"] == juggler["censored"]
    assert res["tosses"] == juggler["tosses"] == res["nominal_tosses"]
    assert res["catches_median_difference"] == 0.0
    assert res["catches_median_difference_ci"] == [0.0, 0.0]
    assert res["catch_rate_difference"] == 0.0 and not res["beats_nominal_median"]
    assert res["episodes"]["seed"] == (SPLIT_SEEDS["test"] + np.arange(N)).tolist()


def test_differences_are_agent_minus_nominal_on_the_same_seeds():
    res = cascade_agent_results(loaded(lifting_policy), "test", N)
    ep = res["episodes"]
    a, b = np.array(ep["agent_catches"]), np.array(ep["nominal_catches"])
    assert not np.array_equal(a, b)  # the policy changes the episodes
    first = independent_episode(lifting_policy, SPLIT_SEEDS["test"])
    assert first[:3] == (a[0], ep["agent_tosses"][0], ep["agent_dropped"][0])
    assert first[3] == pytest.approx(ep["agent_time"][0])
    assert res["catches_median"] == np.median(a)
    assert res["nominal_catches_median"] == np.median(b)
    assert res["catches_median_difference"] == np.median(a) - np.median(b)
    lo, hi = res["catches_median_difference_ci"]
    assert lo <= res["catches_median_difference"] <= hi
    assert res["beats_nominal_median"] == (lo > 0)
    rate = a.sum() / np.sum(ep["agent_tosses"])
    nominal_rate = b.sum() / np.sum(ep["nominal_tosses"])
    assert res["catch_rate"] == pytest.approx(rate)
    assert res["catch_rate_difference"] == pytest.approx(rate - nominal_rate)
    hazard = np.sum(ep["agent_dropped"]) / a.sum()
    nominal_hazard = np.sum(ep["nominal_dropped"]) / b.sum()
    assert res["criterion"] == pytest.approx(hazard)
    assert res["ratio"] == pytest.approx(hazard / nominal_hazard)
    (verdict,) = res["verdicts"]
    assert verdict["ratio"] == pytest.approx(hazard / nominal_hazard)
    assert verdict["n_groups"] == N and verdict["group"] == "episodes"
    # every paired difference carries its power line, and the printed summary shows it
    median, rate = res["differences"]
    assert (median["difference"], median["ci95"]) == (
        res["catches_median_difference"], res["catches_median_difference_ci"]
    )  # fmt: skip
    assert (rate["difference"], rate["ci95"]) == (
        res["catch_rate_difference"], res["catch_rate_difference_ci"]
    )  # fmt: skip
    for d in (median, rate):
        assert d["n_groups"] == N and d["group"] == "episodes" and d["power"] == 0.8
        below, above = d["detectable_differences"]
        assert below <= 0 <= above
        assert d["power_line"].startswith(f"80% power at {N} episodes for differences <=")
        if d["decidable"] is False and d["verdict"] == "no difference":
            assert d["sentence"].endswith("cannot decide at this size")
    from baselines.agents.evaluate import _cascade_lines

    text = _cascade_lines(res | {"env_id": ENV_ID, "algo": "ppo", "split": "test"})
    assert text.count(f"80% power at {N} episodes for differences") == 2
    assert median["sentence"] in text and rate["power_line"] in text


def test_median_difference_interval_is_paired():
    """Resampling episodes together: a policy that always catches one more than the other
    has the difference 1 with the interval [1, 1]; unpaired resampling would spread it."""
    rng = np.random.default_rng(3)
    base = rng.integers(0, 10, 40)

    def eps(catches):
        n = catches.size
        return CascadeAgentEpisodes(
            np.arange(n), catches, catches + 2, np.ones(n, bool), np.ones(n), 30
        )

    assert catches_median_difference(eps(base + 1), eps(base)) == (1.0, 1.0, 1.0)
    # the power line: a constant one-catch gain has a point interval, detected at any size
    sure = catches_median_comparison(eps(base + 1), eps(base))
    assert sure.detectable == (0.0, 0.0) and sure.decidable
    assert sure.sentence() == "agent is BETTER than nominal at 95 %"
    other = CascadeAgentEpisodes(
        np.arange(1, 41), base, base + 2, np.ones(40, bool), np.ones(40), 30
    )
    with pytest.raises(ValueError, match="different seeds"):
        catches_median_difference(eps(base), other)


def test_shipped_config_block():
    """The shipped PPO block: the medium level, seed-range validation (no val_fraction),
    the residual in the catch phase only, state-dependent exploration as Juggling-v1's,
    the policy starting at the juggler."""
    hp = resolve_hyperparams("ppo", ENV_ID)
    assert hp["env_kwargs"] == KWARGS
    assert hp["use_sde"] is True and hp["sde_sample_freq"] == 16
    assert hp["policy_kwargs"]["log_std_init"] == -3.5
    assert hp["action_head_scale"] == 0.0


@pytest.mark.slow
def test_motion_bench_train_and_agent_smoke(tmp_path):
    """``motion-bench train --env MotionEnvs/Cascade-v0`` with the shipped PPO config, then
    ``motion-bench agent``: the juggler's numbers on the same test seeds are reported."""
    pytest.importorskip("stable_baselines3")
    from baselines.cli import main

    out = tmp_path / "run"
    argv = ["train", "--algo", "ppo", "--env", ENV_ID, "--timesteps", "1024", "--seed", "0"]
    assert main([*argv, "--out", str(out), "--no-progress"]) == 0
    assert main(["agent", str(out), "--episodes", "4"]) == 0
    doc = json.loads((out / "eval-test" / "results.json").read_text())
    assert doc["env_id"] == ENV_ID and doc["n_episodes"] == 4
    ref = cascade_episodes("medium", "juggler", CascadeConfig(episodes=4, split="test"))
    assert doc["episodes"]["nominal_catches"] == ref.catches.tolist()
    assert 0 <= doc["catch_rate"] <= 1 and 0 <= doc["nominal_catch_rate"] <= 1
    assert (out / "eval-test" / "agent_vs_nominal.png").stat().st_size > 0
    assert (out / "eval-test" / "results.csv").read_text().startswith("seed,agent_catches")


def test_median_difference_power_says_when_it_cannot_decide():
    """A gain of one catch in a few of 40 noisy episodes: the interval contains 0 and the
    claimed difference is below the detectable one, "cannot decide at this size"; the
    same gain on every one of 400 episodes is decided, and its detectable difference
    shrinks about as 1 / sqrt(n)."""
    from baselines.stats import detectable_differences, group_bootstrap_replicates

    rng = np.random.default_rng(8)

    def eps(catches):
        n = catches.size
        return CascadeAgentEpisodes(
            np.arange(n), catches, catches + 2, np.ones(n, bool), np.ones(n), 30
        )

    base = rng.integers(0, 30, 40)
    gain = base + (rng.random(40) < 0.1)
    small = catches_median_comparison(eps(gain), eps(base), names=("policy", "juggler"))
    lo, hi = small.ci95
    assert lo <= 0 <= hi and small.decidable is False
    assert small.sentence().endswith("cannot decide at this size")
    assert "is below the detectable" in small.power_text()
    if small.difference in small.ci95:  # integer medians: an interval end at the point
        assert "discrete replicates" in small.power_text()
    # the same numbers as the interval helper's replicates through the power helper
    ca, cb = gain.astype(float), base.astype(float)
    point, plo, phi, reps = group_bootstrap_replicates(
        lambda rows: float(np.median(ca[rows]) - np.median(cb[rows])), np.arange(40)
    )
    assert small.detectable == detectable_differences(point, plo, phi, reps)
    wide = rng.integers(0, 30, 400)
    large = catches_median_comparison(eps(wide + 3), eps(wide))
    assert large.verdict == "better" and large.decidable
