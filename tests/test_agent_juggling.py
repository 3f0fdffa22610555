"""Agents on Juggling-v0: the seed-range splits, the catch rate and the hand's deviation
from the demonstrations (baselines.agents.juggling_score), train and agent end to end."""

from __future__ import annotations

import json

import numpy as np
import pytest

pytest.importorskip("stable_baselines3")

from baselines.agents.juggling_score import (
    DEFAULT_EPISODES,
    demonstration_paths,
    departure_from_line,
    juggling_episodes,
    segment_deviations,
)
from motion_envs.datasets.juggling import SPLIT_SEEDS

ENV = "MotionEnvs/Juggling-v0"
KWARGS = {"noise": 0.05, "max_cycles": 2, "frame_skip": 5}


# -- the deviation, against hand-worked cases ---------------------------------------------
def test_departure_from_line_is_zero_at_the_ends_and_ignores_lines():
    rng = np.random.default_rng(0)
    paths = rng.normal(size=(7, 50, 2))
    r = departure_from_line(paths)
    np.testing.assert_allclose(r[:, 0], 0, atol=1e-15)
    np.testing.assert_allclose(r[:, -1], 0, atol=1e-15)
    tau = np.linspace(0, 1, 50)[:, None]
    line = rng.normal(size=(7, 1, 2)) + tau * rng.normal(size=(7, 1, 2))
    np.testing.assert_allclose(departure_from_line(paths + line), r, atol=1e-12)
    # a straight line departs from itself nowhere
    np.testing.assert_allclose(departure_from_line(line), 0, atol=1e-12)


def test_segment_deviation_hand_worked():
    """A segment shaped like demonstration 1 (shifted, stretched in time) is 0 from it; a
    bump of height h on a straight segment is h from a straight demonstration."""
    n = 50
    tau = np.linspace(0, 1, n)
    arc = np.column_stack([tau, 0.1 * np.sin(np.pi * tau)])
    straight = np.column_stack([tau, 0 * tau])
    demos = {"toss": departure_from_line(np.stack([straight, arc]))}
    # samples of the arc at 80 steps, moved by (3, 2); labels: toss then go_down
    t = np.linspace(0, 2.0, 81)
    path = np.column_stack([t / 2 + 3.0, 0.1 * np.sin(np.pi * t / 2) + 2.0])
    phases = ["toss"] * 80 + ["go_down"]
    got = segment_deviations(t, path, phases, demos)
    assert [p for p, _ in got] == ["toss"]  # the go_down run is incomplete
    assert got[0][1] == pytest.approx(0.0, abs=1e-3)
    bump = np.column_stack([t / 2, 0.03 * np.sin(np.pi * t / 2)])
    demos_straight = {"toss": departure_from_line(straight[None])}
    ((_, dev),) = segment_deviations(t, bump, phases, demos_straight)
    assert dev == pytest.approx(0.03, rel=1e-3)


def test_segments_cut_like_the_demonstrations():
    """Runs of one label plus the first sample of the next; runs of < 3 samples skipped."""
    t = np.arange(12.0)
    hand = np.column_stack([t, t**2])
    phases = ["toss"] * 4 + ["go_down"] + ["catch"] * 4 + ["return"] * 3
    demos = {p: np.zeros((1, 50, 2)) for p in ("toss", "go_down", "catch", "return")}
    got = segment_deviations(t, hand, phases, demos)
    assert [p for p, _ in got] == ["toss", "catch"]
    # the toss segment spans samples 0..4 (x = t, z = t^2), resampled linearly at k / 49:
    # its departure from the line peaks at the grid point next to t = 2, tau = 24 / 49,
    # where z = 1 + 3 (4 tau - 1) and the line is at 16 tau (x departs nowhere)
    tau = 24 / 49
    assert got[0][1] == pytest.approx(16 * tau - (1 + 3 * (4 * tau - 1)), rel=1e-12)


# -- splits ------------------------------------------------------------------------------
def test_val_and_test_compare_with_disjoint_demonstrations():
    from motion_envs.datasets.juggling import JugglingTask
    from motion_envs.models.juggling import juggler_demonstrations

    demos, train, test = juggler_demonstrations(None, JugglingTask())
    assert train and test and not train & test
    val_paths, test_paths = demonstration_paths({}, "val"), demonstration_paths({}, "test")
    for phase in ("toss", "go_down", "catch", "return"):
        n_test = sum((s.recording, s.cycle) in test for s in demos.segments(phase))
        assert test_paths[phase].shape == (n_test, 50, 2)
        n_train = sum((s.recording, s.cycle) in train for s in demos.segments(phase))
        assert val_paths[phase].shape == (n_train, 50, 2)
    seeds = sorted(SPLIT_SEEDS.values())
    assert seeds[2] - seeds[1] >= 10**9 and seeds[1] - seeds[0] >= 10**9
    with pytest.raises(ValueError, match="split must be one of"):
        demonstration_paths({}, "validation")


def test_zero_action_episodes_equal_a_plain_env_loop():
    """The vectorised scorer plays exactly the single env's episodes on the split's seeds."""
    import gymnasium as gym

    import motion_envs  # noqa: F401

    got = juggling_episodes(None, ENV, KWARGS, "val", 3)
    env = gym.make(ENV, **KWARGS)
    for i in range(3):
        env.reset(seed=SPLIT_SEEDS["val"] + i)
        while True:
            _, _, term, trunc, info = env.step(np.zeros(2, np.float32))
            if term or trunc:
                break
        assert got.tosses[i] == info["cycles"] and got.catches[i] == info["catches"]
        assert got.dropped[i] == term
    assert got.seeds.tolist() == [SPLIT_SEEDS["val"] + i for i in range(3)]
    assert got.catch_rate == got.catches.sum() / got.tosses.sum()
    assert got.criterion == 1 - got.catch_rate
    # every episode contributes its complete phases (2 cycles: >= 4 segments)
    assert np.bincount(got.segment_episode, minlength=3).min() >= 4
    assert 0 < got.deviation < 0.2  # metres


def test_an_offset_hand_deviates_more_and_wrong_input_is_refused():
    nominal = juggling_episodes(None, ENV, KWARGS, "test", 2)

    def wobble(obs):  # a hand that shakes: +-1 alternating with the phase time
        s = np.sign(np.sin(400.0 * obs[:, 13]))
        return np.column_stack([s, s]).astype(np.float32)

    shaky = juggling_episodes(wobble, ENV, KWARGS, "test", 2)
    assert shaky.deviation > nominal.deviation
    with pytest.raises(ValueError, match="not a juggling environment"):
        juggling_episodes(None, "MotionEnvs/OrientationReach-v0", {}, "val", 1)
    with pytest.raises(ValueError, match="split must be one of"):
        juggling_episodes(None, ENV, KWARGS, "holdout", 1)
    assert DEFAULT_EPISODES["test"] >= DEFAULT_EPISODES["val"]


# -- train and agent, end to end -----------------------------------------------------------
@pytest.fixture(scope="module")
def juggling_run(tmp_path_factory):
    from baselines.agents.train import TrainConfig
    from baselines.agents.train import run as train_run

    out = tmp_path_factory.mktemp("jruns") / "ppo"
    config = TrainConfig(
        algo="ppo",
        env_id=ENV,
        out=str(out),
        timesteps=1024,
        n_envs=2,
        env_kwargs={"max_cycles": 1},
        overrides={"n_steps": 256, "batch_size": 128, "n_epochs": 1, "eval_freq": 512,
                   "eval_episodes": 3},
        progress=False,
        tensorboard=False,
    )  # fmt: skip
    return out, train_run(config)


def test_motion_bench_agent_on_juggling(juggling_run, tmp_path, capsys):
    from baselines.cli import main

    out, result = juggling_run
    assert result.val_nominal_criterion == result.evaluations[0]["val_criterion"]
    assert main(["agent", str(out), "--episodes", "3", "--out", str(tmp_path)]) == 0
    printed = capsys.readouterr().out
    doc = json.loads((tmp_path / "results.json").read_text())
    assert doc["env_id"] == ENV and doc["split"] == "test" and doc["n_episodes"] == 3
    assert doc["deviation_reference"] == "held-out demonstrations"
    nominal = juggling_episodes(None, ENV, doc["env_kwargs"], "test", 3)
    assert doc["nominal_catch_rate"] == nominal.catch_rate
    assert doc["nominal_deviation"] == nominal.deviation
    assert doc["criterion"] == 1 - doc["catch_rate"]
    assert doc["deviation_ratio"] == doc["deviation"] / doc["nominal_deviation"]
    lo, hi = doc["catch_rate_difference_ci"]
    diff = doc["catch_rate_difference"]
    assert diff == pytest.approx(doc["catch_rate"] - doc["nominal_catch_rate"])
    assert f"catch rate agent - nominal = {diff:+.3f} (95% CI {lo:+.3f} to {hi:+.3f}" in printed
    if result.best_timesteps == 0:  # the kept checkpoint is the initial policy: the nominal
        assert doc["catch_rate"] == doc["nominal_catch_rate"]
        assert doc["deviation_ratio"] == 1.0
    assert doc["learned_criterion"] is None and "no learned regressor" in doc["learned_skipped"]
    header = (tmp_path / "results.csv").read_text().splitlines()[0].split(",")
    assert header[:3] == ["seed", "agent_tosses", "agent_catches"]
    assert (tmp_path / "agent_vs_nominal.png").stat().st_size > 10_000


def test_training_seeds_stay_below_the_validation_seeds(tmp_path):
    from baselines.agents.train import TrainConfig
    from baselines.agents.train import run as train_run

    config = TrainConfig(
        algo="ppo", env_id=ENV, out=str(tmp_path / "r"), seed=SPLIT_SEEDS["val"] - 1,
        timesteps=100, n_envs=2, progress=False, tensorboard=False,
    )  # fmt: skip
    with pytest.raises(ValueError, match=r"seed: .* would reset on the validation seeds"):
        train_run(config)
    assert not (tmp_path / "r").exists()


def test_subproc_vec_env_trains_exactly_as_dummy(tmp_path):
    """``vec_env: subproc`` (one process per copy) plays the same episodes as the default
    ``DummyVecEnv``: the same validation curve and the same final policy. (Reward
    normalisation off: SB3's DummyVecEnv holds rewards in float32, SubprocVecEnv in
    float64, so VecNormalize's running reward statistics round differently.)"""
    from baselines.agents.rundir import load_run
    from baselines.agents.train import TrainConfig
    from baselines.agents.train import run as train_run

    curves, actions = [], []
    obs = np.random.default_rng(1).normal(size=(16, 16)).astype(np.float32)
    for kind in ("dummy", "subproc"):
        out = tmp_path / kind
        config = TrainConfig(
            algo="ppo", env_id=ENV, out=str(out), timesteps=512, n_envs=2,
            env_kwargs={"max_cycles": 1},
            overrides={"n_steps": 128, "batch_size": 128, "n_epochs": 1, "eval_freq": 256,
                       "eval_episodes": 2, "vec_env": kind,
                       "normalize": {"obs": True, "reward": False}},
            progress=False, tensorboard=False,
        )  # fmt: skip
        train_run(config)
        curves.append((out / "evaluations.csv").read_text())
        actions.append(load_run(out, "final").model.predict(obs, deterministic=True)[0])
    assert curves[0] == curves[1]
    np.testing.assert_array_equal(actions[0], actions[1])
