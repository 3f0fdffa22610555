"""Every ratio motion-bench position and agent print carries an interval in results.json,
a win count and a verdict; the agent says when its kept checkpoint is the initial policy."""

from __future__ import annotations

import json

import numpy as np
import pytest

from baselines.cli import main
from baselines.stats import compare_errors
from baselines.verdicts import (
    format_agent_verdicts,
    format_floor,
    kept_initial_policy,
    noise_floor,
    position_verdicts,
)


def test_position_prints_and_stores_every_interval(tmp_path, capsys):
    args = ["position", "--shapes", "Angle", "CShape", "GShape", "--learned", "off"]
    assert main([*args, "--no-peers", "--no-progress", "--out", str(tmp_path)]) == 0
    text = capsys.readouterr().out
    doc = json.loads((tmp_path / "results.json").read_text())
    # line, null, lippi: each against lippi and against null
    assert set(doc["intervals"]) == {"line / lippi", "null / lippi", "line / null", "lippi / null"}
    for v in doc["verdicts"]:
        lo, hi = doc["intervals"][f"{v['a']} / {v['b']}"]
        assert [lo, hi] == v["ci95"] and lo <= v["ratio"] <= hi
        assert f"{v['a']} / {v['b']}" in text and v["lower_is_better"] and v["unit"] == "mm"
        shapes = list(doc["per_shape"])
        a = [doc["per_shape"][s]["criteria"][v["a"]]["max_error"] for s in shapes]
        b = [doc["per_shape"][s]["criteria"][v["b"]]["max_error"] for s in shapes]
        assert v["ratio"] == np.median(a) / np.median(b)
        assert v["wins"] == sum(x < y for x, y in zip(a, b, strict=True))
    assert "lower is better" in text and "over 3 shapes" in text
    # 3 shapes: 10 distinct bootstrap replicates, too few for a verdict (MIN_GROUPS = 6)
    assert "line / lippi" in text and "cannot decide with 3 shapes" in text
    assert "BETTER" not in text and "WORSE" not in text
    assert {v["verdict"] for v in doc["verdicts"]} == {"cannot decide"}


def test_two_shape_recording_cannot_decide(tmp_path, capsys):
    """The modeller's call on a two-shape recording: intervals printed, no verdict."""
    args = ["position", "--shapes", "Angle", "CShape", "--learned", "off", "--no-progress"]
    assert main([*args, "--out", str(tmp_path)]) == 0
    text = capsys.readouterr().out
    doc = json.loads((tmp_path / "results.json").read_text())
    assert "promp / lippi" in doc["intervals"]
    assert "BETTER" not in text and "WORSE" not in text and "no difference" not in text
    assert text.count("cannot decide with 2 shapes (a verdict at 95 % needs at least 6") == len(
        doc["verdicts"]
    )


METHODS = ["null", "lippi", "ridge"]


def test_position_keeps_the_learned_readings_interval():
    doc = {
        "unit": "mm",
        "methods": METHODS,
        "per_shape": {
            s: {"criteria": {m: {"max_error": v} for m, v in zip(METHODS, r, strict=True)}}
            for s, r in {"a": (2.0, 3.0, 1.0), "b": (2.5, 2.0, 1.5), "c": (3.0, 4.0, 2.0)}.items()
        },
        "learned": {
            "comparisons": [
                {"learned": "ridge", "best_analytic": "null", "ratio": 0.5,
                 "ratio_ci95": [0.4, 0.6], "subjects_better": 3, "n_subjects": 3}
            ]
        },
    }  # fmt: skip
    names = [c.name for c in position_verdicts(doc)]
    assert names.count("ridge / null") == 1 and names[0] == "ridge / null"
    assert position_verdicts(doc)[0].ci95 == (0.4, 0.6)


def test_agent_verdict_lines_and_initial_policy():
    rng = np.random.default_rng(0)
    groups = np.repeat(["p1", "p2", "p3", "p4", "p5", "p6"], 10)
    nominal = rng.gamma(3, 0.05, 60)
    agent = nominal * 0.8
    from baselines.verdicts import agent_comparisons

    entries = agent_comparisons(agent, nominal, groups, "people", "rad")
    c = compare_errors(agent, nominal, groups, "agent", "nominal")
    assert entries["ratio_ci"] == list(c.ci95) and entries["intervals"] == {
        "agent / nominal": list(c.ci95)
    }
    assert entries["verdict"] == "agent is BETTER than nominal at 95 %"
    assert entries["criterion_ci"][0] < np.median(agent) < entries["criterion_ci"][1]
    assert kept_initial_policy({"best_timesteps": 0}, "best")
    assert not kept_initial_policy({"best_timesteps": 0}, "final")
    assert not kept_initial_policy({"best_timesteps": 2000}, "best")
    text = format_agent_verdicts({**entries, "kept_initial_policy": True})
    assert "agent / nominal = 0.800" in text and "lower on 6/6 people" in text
    assert "INITIAL policy" in text
    four = agent_comparisons(agent[:40], nominal[:40], groups[:40], "people", "rad")
    assert four["verdict"].startswith("cannot decide with 4 people")


def test_noise_floor_rows_against_the_floor_of_their_frame():
    criteria = {
        "within_subject": 0.1,
        "predictive_floor": 0.15,
        "predictive_floor_path": 0.12,
        "within_subject_loo": 0.2,
        "null_d2_loso": 0.2,
        "null_d2_path_loso": 0.13,
        "person_k5_loso": 0.18,
        "ridge_loso": 0.14,
        "person_k5_path_loso": 0.126,
        "slerp_loso_predicted_timing": 0.3,
        "b": 0.0,
    }
    floor = noise_floor(criteria)
    assert floor is not None and floor["in_sample"] == {"row": "within_subject", "value": 0.1}
    assert floor["floors"]["body"]["leave_one_out"] == 0.2
    assert floor["floors"]["path"]["leave_one_out"] is None
    rows = floor["rows"]
    assert set(rows) == {"null_d2_loso", "null_d2_path_loso", "person_k5_loso", "ridge_loso",
                         "person_k5_path_loso", "slerp_loso_predicted_timing"}  # fmt: skip
    assert rows["person_k5_loso"]["floor"] == 0.15 and rows["person_k5_loso"]["frame"] == "body"
    assert rows["ridge_loso"]["distance"] == pytest.approx(0.02)
    assert rows["person_k5_path_loso"]["ratio"] == pytest.approx(1.05)
    assert rows["slerp_loso_predicted_timing"]["floor_row"] == "predictive_floor_path"
    assert "predictive_floor_path = 0.120" in format_floor(floor)
    assert noise_floor({"within_subject": 0.1}) is None


def test_motion_bench_agent_prints_and_stores_the_verdict(tmp_path, capsys):
    pytest.importorskip("stable_baselines3")
    from baselines.agents.train import TrainConfig
    from baselines.agents.train import run as train_run

    out = tmp_path / "run"
    config = TrainConfig(
        algo="ppo", env_id="MotionEnvs/OrientationReach-v1", out=str(out), seed=0,
        timesteps=400, n_envs=2, progress=False,
        overrides={"eval_freq": 200, "n_steps": 100, "batch_size": 100, "n_epochs": 1},
    )  # fmt: skip
    result = train_run(config)
    assert main(["agent", str(out), "--split", "val", "--out", str(tmp_path / "eval")]) == 0
    text = capsys.readouterr().out
    doc = json.loads((tmp_path / "eval" / "results.json").read_text())
    c = compare_errors(
        doc["episodes"]["agent_max_error"], doc["episodes"]["nominal_max_error"],
        _people(doc), "agent", "nominal",
    )  # fmt: skip
    assert doc["ratio_ci"] == list(c.ci95) == doc["intervals"]["agent / nominal"]
    assert doc["verdict"] == c.sentence() and doc["verdict"] in text
    assert set(doc["intervals"]) == {"agent / nominal", "agent / learned"}
    assert doc["kept_initial_policy"] == (result.best_timesteps == 0)
    assert ("INITIAL policy" in text) == doc["kept_initial_policy"]
    assert "lower is better" in text and "people" in text


def _people(doc):
    import gymnasium as gym

    import motion_envs  # noqa: F401

    kwargs = {k: v for k, v in doc["env_kwargs"].items() if k != "split"}
    task = gym.make(doc["env_id"], split=doc["split"], **kwargs).unwrapped.task
    return np.asarray(task.subjects)[: doc["n_episodes"]]
