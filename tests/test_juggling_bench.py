"""``motion-bench juggling`` end to end on a small run."""

from __future__ import annotations

import csv
import json

import pytest

from baselines import juggling_bench as jb
from baselines import options
from baselines.cli import main
from motion_envs.datasets.juggling import generate_demonstrations, write_juggling_csv


@pytest.mark.slow
def test_small_run_writes_the_documented_results(tmp_path, capsys):
    out = tmp_path / "res"
    argv = ["juggling", "--cycles", "30", "--seed", "2", "--mujoco-cycles", "8"]
    rc = main([*argv, "--out", str(out), "--no-progress"])
    assert rc == 0
    text = capsys.readouterr().out
    assert "SIMULATED" in text and "catch rate, unperturbed" in text
    assert "median over demos of max_t |error|" in text
    doc = json.loads((out / "results.json").read_text())
    assert doc["simulated"] is True and "SIMULATED" in doc["data"]
    assert 0.0 <= doc["catch_rate"] <= 1.0
    keys = {(r["noise"], r["correction"]) for r in doc["catch_rates"]}
    assert keys == {(0.05, False), (0.05, True), (0.1, False), (0.1, True)}
    for r in doc["catch_rates"]:
        assert set(r) >= {"noise", "correction", "catch_rate"}
    for phase in ("toss", "go_down", "catch", "return"):
        v = doc["per_phase"][phase]
        assert {"lippi", "minimum_jerk"} <= set(v["methods"])
        for m in v["methods"].values():
            assert m["max_error"] >= m["rmse"] > 0
        assert doc["validation"][phase]
    assert doc["split"]["n_train_cycles"] + doc["split"]["n_test_cycles"] == 50
    rows = list(csv.DictReader((out / "results.csv").open()))
    assert sum(r["kind"] == "catch_rate" for r in rows) == 5
    assert (out / "juggling_fig6.png").stat().st_size > 10_000
    assert (out / "juggling.gif").read_bytes()[:3] == b"GIF"
    # the MuJoCo scene ran the first cycles of every run, with the pure model's outcomes
    for r in [doc["catch_rate_detail"], *doc["catch_rates"]]:
        assert r["mujoco"]["agrees_with_pure_model"] is True
    assert doc["catch_rate_detail"]["mujoco"]["cycles"] == 8


def test_deterministic_under_a_seed():
    cfg = jb.JugglingConfig(
        cycles=40, seed=3, progress=False, use_dmp=False, figure_cycles=1, world="model"
    )
    a, b = jb.run(cfg), jb.run(cfg)
    assert a["catch_rates"] == [
        {**r, "seconds": a["catch_rates"][i]["seconds"]} for i, r in enumerate(b["catch_rates"])
    ]
    assert a["per_phase"]["catch"]["methods"] == b["per_phase"]["catch"]["methods"]


def test_test_split_is_not_used_for_fitting(monkeypatch):
    """The juggler is fitted on the training cycles only (N by CV inside them)."""
    seen = {}
    from motion_envs.models.juggling import AnalyticJuggler

    original = AnalyticJuggler.fit

    def spy(self, demos, cycles=None):
        seen["cycles"] = cycles
        return original(self, demos, cycles)

    monkeypatch.setattr(AnalyticJuggler, "fit", spy)
    cfg = jb.JugglingConfig(
        cycles=5, seed=1, progress=False, use_dmp=False, figure_cycles=1, world="model"
    )
    doc = jb.run(cfg)
    demos = doc["_demos"]
    assert seen["cycles"] is not None and not (seen["cycles"] & doc["_test"])
    assert len(seen["cycles"]) + len(doc["_test"]) == len(demos.cycles())


def test_users_csv(tmp_path, capsys, monkeypatch):
    path = write_juggling_csv(generate_demonstrations(n_cycles=16, seed=4), tmp_path / "mine.csv")
    argv = ["juggling", "--data", str(path), "--cycles", "10", "--world", "model", "--no-dmp"]
    monkeypatch.chdir(tmp_path)  # without --out: results/juggling, as motion-bench all
    rc = main([*argv, "--no-progress", "--no-video"])
    assert rc == 0
    assert "mine.csv" in capsys.readouterr().out
    assert (tmp_path / "results" / "juggling" / "results.json").is_file()


@pytest.mark.parametrize(
    ("argv", "match"),
    [
        (["--cycles", "0"], "argument --cycles: expected an integer >= 1"),
        (["--data", "missing.csv"], "argument --data: missing.csv does not exist"),
        (["--noise", "0.05,2"], "argument --noise: expected a comma list of numbers in [0, 1)"),
        (["--demo-cycles", "3"], "argument --demo-cycles: 3 cycle(s) x 1 person(s)"),
    ],
)
def test_bad_arguments(argv, match, capsys):
    assert main(["juggling", *argv, "--no-progress"]) == 2
    assert match in capsys.readouterr().err


@pytest.mark.parametrize(
    ("field", "value"),
    [("cycles", 0), ("noise", (0.05, 1.0)), ("tracking", float("nan")), ("world", "moon")],
)
def test_run_rejects_a_bad_config_before_computing(field, value, monkeypatch):
    def started(*args, **kwargs):
        raise AssertionError("the computation started before the config was checked")

    monkeypatch.setattr(jb.runner, "load_demos", started)
    cfg = jb.JugglingConfig(progress=False, **{field: value})
    with pytest.raises(options.ConfigError) as info:
        jb.run(cfg)
    assert info.value.field == field


def test_config_is_frozen():
    from dataclasses import FrozenInstanceError

    with pytest.raises(FrozenInstanceError):
        jb.JugglingConfig().cycles = 3  # type: ignore[misc]


def test_motion_bench_all_includes_juggling():
    from baselines.run_all import JOBS

    assert "juggling" in [job.folder for job in JOBS]
