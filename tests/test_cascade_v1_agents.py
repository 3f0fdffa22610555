"""``experiments/cascade_v1_agents.py`` end to end on a tiny run (and the shared
:mod:`baselines.agents.against_rows`).

A run folder of a few hundred PPO steps of the shipped Cascade-v1 block (frame stack of
8, trained with at most 1 catch) is made by the shared ``train_or_reuse`` and scored by
the script's ``main`` on 2 test episodes against the rows of ``run_cascade_v1`` (2
validation episodes, at most 3 catches). Checked against independent computations: the
rows' and the agent's episodes are the test seeds' (the agent replayed one episode at a
time through Gymnasium's own frame stack, the rows by the env's ``play``), the agent is
scored with the rows' ``max_catches`` and not its training one, and every difference is
the paired one over those episodes; the same pipeline with the agent's seeds shifted by
one fails.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from _helpers import load_experiment

import motion_envs  # noqa: F401
from motion_envs.datasets.juggling import episode_seeds

pytest.importorskip("stable_baselines3")

ENV = "MotionEnvs/Cascade-v1"
ARGS = ["--levels", "medium", "--seeds", "0", "--test-episodes", "2", "--val-episodes", "2",
        "--pick-episodes", "2", "--max-catches", "3", "--reuse-only"]  # fmt: skip


def _script() -> Any:
    return load_experiment("cascade_v1_agents")


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """``ROOT/medium-seed0``: the shipped block, 400 steps, at most 1 catch in training."""
    from baselines.agents.against_rows import train_or_reuse

    root = tmp_path_factory.mktemp("runs")
    out = train_or_reuse(
        ENV, "medium", 0, root, timesteps=400, env_kwargs={"max_catches": 1}, progress=False,
        overrides={"n_envs": 2, "eval_freq": 200, "eval_episodes": 2, "n_steps": 100,
                   "batch_size": 100, "n_epochs": 1},
    )  # fmt: skip
    assert out == root / "medium-seed0" and (out / "run.json").exists()
    # a complete folder is reused, not retrained (reuse_only would refuse a missing one)
    assert train_or_reuse(ENV, "medium", 0, root, reuse_only=True) == out
    with pytest.raises(FileNotFoundError, match="medium-seed1"):
        train_or_reuse(ENV, "medium", 1, root, reuse_only=True)
    return root


def _agent_episode(loaded: Any, kwargs: dict[str, Any], seed: int) -> tuple[int, int, list[float]]:
    """One episode of the kept policy through Gymnasium's FrameStackObservation (what
    training saw), alone: (catches, tosses, the hands' segment deviations from the
    held-out three-ball demonstrations)."""
    from baselines.agents.cascade_score import (
        cascade_demonstration_paths,
        hand_segment_deviations,
    )

    env = gym.wrappers.FlattenObservation(
        gym.wrappers.FrameStackObservation(gym.make(ENV, **kwargs), loaded.frame_stack)
    )
    obs, info = env.reset(seed=seed)
    infos = [info]
    while True:
        obs, _, terminated, truncated, info = env.step(loaded.predict(obs[None])[0])
        infos.append(info)
        if terminated or truncated:
            env.close()
            devs = hand_segment_deviations(
                np.array([i["time"] for i in infos]), np.array([i["hands"] for i in infos]),
                [i["phases"] for i in infos], cascade_demonstration_paths(3, "test"),
            )  # fmt: skip
            return int(info["catches"]), int(info["tosses"]), [d for *_, d in devs]


#: The zero-action rows' controllers (the bench's module docstring), written out here.
CONTROLLERS = {
    "juggler": "juggler",
    "oracle_catch": "juggler_oracle_catch",
    "juggler_mean_delay": "juggler_mean_delay",
    "late_meeting": "juggler_mean_delay",
    "mean_delay_catch": "juggler_mean_delay_catch",
    "delay_estimator": "juggler_delay_estimator",
    "delay_estimator_catch": "juggler_delay_estimator_catch",
    "fixed_point": "fixed_point",
}


def _row_catches(name: str, offset: float, seeds: list[int]) -> list[int]:
    """A zero-action row's catches before the first drop on ``seeds``, played here."""
    from motion_envs.envs.juggling import CascadeV1Env

    kwargs: dict[str, Any] = {"level": "medium", "pattern": "3", "max_catches": 3,
                              "residual_scale": 0.1, "controller": CONTROLLERS[name]}  # fmt: skip
    if name == "late_meeting" and offset:
        kwargs["delay_offset"] = offset
    env = CascadeV1Env(**kwargs)
    return [int(env.play(seed)[0]) for seed in seeds]


def test_pipeline_pairs_the_agent_with_the_rows_on_the_test_seeds(
    runs: Path, tmp_path: Path
) -> None:
    from baselines.agents.rundir import load_run

    mod = _script()
    out = tmp_path / "results.json"
    assert mod.main([*ARGS, "--runs", str(runs), "--out", str(out)]) == 0
    doc = json.loads(out.read_text())
    assert (tmp_path / "cascade_v1_agents.png").stat().st_size > 0
    lv = doc["levels"][0]
    best = lv["best_non_oracle"]
    assert best not in ("oracle", "oracle_catch")
    (run,) = lv["runs"]
    test_seeds = episode_seeds("test", 2).tolist()
    assert run["episodes"]["seed"] == test_seeds
    assert set(lv["row_episodes"]) == {best, "oracle_catch"}
    # the rows' episodes: the bench's test seeds, as the env plays them
    for name, eps in lv["row_episodes"].items():
        assert eps["seed"] == test_seeds
        if name in CONTROLLERS:  # oracle_catch always; the best row where it is one
            assert _row_catches(name, lv["bench"]["late_offset_s"], test_seeds) == eps["catches"]
        assert np.mean(eps["catches"]) == pytest.approx(lv["bench"]["rows"][name]["catches_mean"])
    # the agent: its own env keywords, the ROWS' max_catches, replayed alone
    assert run["trained_max_catches"] == 1
    assert run["scored_env_kwargs"]["max_catches"] == 3
    loaded = load_run(runs / "medium-seed0")
    kwargs = {**loaded.env_kwargs, "max_catches": 3}
    alone = [_agent_episode(loaded, kwargs, s) for s in test_seeds]
    assert [c for c, _, _ in alone] == run["episodes"]["catches"]
    assert [t for _, t, _ in alone] == run["episodes"]["tosses"]
    # its hand deviation: the median of these episodes' segments of both hands
    segments = [d for *_, devs in alone for d in devs]
    assert run["deviation_mm"] == pytest.approx(1000 * float(np.median(segments)))
    lo, hi = run["deviation_ci_mm"]
    assert lo <= run["deviation_mm"] <= hi
    # every difference is the paired one over these episodes
    a = np.array(run["episodes"]["catches"]), np.array(run["episodes"]["tosses"])
    b = np.array(lv["row_episodes"][best]["catches"]), np.array(lv["row_episodes"][best]["tosses"])
    o = (np.array(lv["row_episodes"]["oracle_catch"]["catches"]),
         np.array(lv["row_episodes"]["oracle_catch"]["tosses"]))  # fmt: skip

    def rate(x: tuple[np.ndarray, np.ndarray]) -> float:
        return float(x[0].sum() / max(int(x[1].sum()), 1))

    assert run["minus_best_mean_catches"] == pytest.approx(float(np.mean(a[0] - b[0])))
    assert run["oracle_minus_mean_catches"] == pytest.approx(float(np.mean(o[0] - a[0])))
    assert run["minus_best_catch_rate"] == pytest.approx(rate(a) - rate(b))
    assert run["oracle_minus_catch_rate"] == pytest.approx(rate(o) - rate(a))
    assert run["agent"]["catches_mean"] == pytest.approx(float(a[0].mean()))
    for key in ("minus_best_mean_catches", "minus_best_catch_rate"):
        lo, hi = run[f"{key}_ci"]
        assert lo <= run[key] <= hi
    # the bench's own paired room (oracle_catch - best) from the same episodes
    assert lv["bench"]["room"]["value"] == pytest.approx(float(np.mean(o[0] - b[0])))
    # the targets follow from the numbers; the likeness one against the juggler row's
    # deviation on the same test episodes
    t = run["targets"]
    assert t["catch_rate"] == (run["minus_best_catch_rate"] >= 0.05
                               and run["minus_best_catch_rate_ci"][0] > 0)  # fmt: skip
    assert t["mean_catches"] == (run["minus_best_mean_catches_ci"][0] > 0)
    juggler_mm = 1000 * lv["bench"]["rows"]["juggler"]["deviation_m"]
    assert run["juggler_deviation_mm"] == pytest.approx(juggler_mm)
    assert t["likeness"] == (run["deviation_mm"] <= juggler_mm + 5.0)
    assert lv["deviation"]["median_met"] == t["likeness"]  # one seed: its own
    assert "held-out SIMULATED 3-ball" in doc["deviation"]
    assert (tmp_path / "cascade_v1_agents_deviation.png").stat().st_size > 0
    assert lv["median"]["mean_catches"]["seed"] == lv["validation_pick"]["seed"] == 0


def test_shifted_seeds_fail(runs: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The agent played on the test seeds shifted by one: the script refuses to pair."""
    import baselines.agents.cascade_score as cs

    real = cs.episode_seeds
    monkeypatch.setattr(cs, "episode_seeds", lambda split, n: real(split, n) + 1)
    mod = _script()
    with pytest.raises(RuntimeError, match="different seeds"):
        mod.main([*ARGS, "--runs", str(runs), "--out", str(tmp_path / "r.json")])
    assert not (tmp_path / "r.json").exists()


def test_a_reused_folder_must_be_the_run_asked_for(runs: Path) -> None:
    """A folder of another level, algorithm or pattern is one line naming it."""
    from baselines.agents.against_rows import check_run
    from baselines.agents.rundir import load_run
    from baselines.juggling_bench.cascade_v1 import CascadeV1Config

    loaded = load_run(runs / "medium-seed0")
    check_run(loaded, ENV, "ppo", "medium", 0)
    for args, match in [
        ((ENV, "ppo", "hard", 0), "level is 'medium', expected 'hard'"),
        ((ENV, "sac", "medium", 0), "algo"),
        (("MotionEnvs/Juggling-v2", "ppo", "medium", 0), "env_id"),
        ((ENV, "ppo", "medium", 2), "seed"),
    ]:
        with pytest.raises(ValueError, match=match) as err:
            check_run(loaded, *args)
        assert "\n" not in str(err.value) and "medium-seed0" in str(err.value)
    with pytest.raises(ValueError, match="pattern '3', the rows' is '5'"):
        _script().scoring_kwargs(loaded, CascadeV1Config(pattern="5"))


def test_median_and_pick_helpers() -> None:
    from baselines.agents.against_rows import margin_met, median_run, validation_pick

    runs = [
        {"seed": s, "d": d, "v": v} for s, d, v in [(0, 0.3, 0.2), (1, -0.1, 0.1), (2, 0.1, 0.1)]
    ]
    assert median_run(runs, "d")["seed"] == 2
    assert median_run(runs[:2], "d")["seed"] == 0  # the upper one of two
    assert validation_pick(runs, "v")["seed"] == 1  # the first of ties
    assert margin_met(0.05, [0.001, 0.1]) and not margin_met(0.049, [0.01, 0.1])
    assert not margin_met(0.2, [0.0, 0.4])
