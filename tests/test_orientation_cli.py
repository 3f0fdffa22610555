"""``motion-bench orientation`` end to end."""

from __future__ import annotations

import csv
import json
import subprocess
import sys

import numpy as np
import pytest

from baselines import orientation_bench, run_all
from baselines.cli import main
from baselines.learned.rows import LEARNED_ROWS
from baselines.options import ConfigError
from motion_envs.datasets import load_vr_kitchen
from motion_envs.models.criteria import criterion_names, table1
from motion_envs.models.paper_values import FARAWAY_CHOE_TABLE1


@pytest.mark.slow
def test_cli_prints_table_and_writes_results(tmp_path, capsys):
    assert main(["orientation", "--out", str(tmp_path), "--learned", "quick"]) == 0
    out = capsys.readouterr().out
    for name in criterion_names():
        assert name in out
    assert "0.242 in the text, 0.265 in the table" in out
    doc = json.loads((tmp_path / "results.json").read_text())
    assert doc["dataset"] == "vr-kitchen"
    assert doc["n_trajectories"] == 648 and doc["n_dropped"] == 152  # laser and stick
    assert doc["simulated"] is False
    assert list(doc["criteria"]) == criterion_names() + list(LEARNED_ROWS)
    for name in LEARNED_ROWS:
        assert name in out and doc["criteria"][name] > 0
    assert "95% CI over subjects" in out
    assert (tmp_path / "learned_ratio.png").read_bytes()[:4] == b"\x89PNG"
    ds = load_vr_kitchen()
    ref = table1(ds.ragged, ds.subjects, ds.tasks, up=ds.up).criteria
    for k, v in ref.items():
        assert doc["criteria"][k] == pytest.approx(v, rel=0, abs=0)
        if k in FARAWAY_CHOE_TABLE1:
            assert f"{v:7.3f} {FARAWAY_CHOE_TABLE1[k]:7.3f}" in out
    png = (tmp_path / "residuals.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 10_000


def test_cli_min_deg_and_csv(tmp_path, capsys):
    ds = load_vr_kitchen(min_deg=0).subset(np.arange(60))
    path = ds.to_csv(tmp_path / "mine.csv")
    assert (
        main(["orientation", "--data", str(path), "--min-deg", "20", "--out", str(tmp_path / "o")])
        == 0
    )
    doc = json.loads((tmp_path / "o" / "results.json").read_text())
    kept = int((np.degrees(ds.rotation_angles()) >= 20).sum())
    assert doc["n_trajectories"] == kept and doc["n_dropped"] == 60 - kept
    assert doc["dataset"] == "mine.csv"


def test_cli_errors_are_clear(tmp_path, capsys):
    assert main(["orientation", "--data", str(tmp_path / "missing.csv")]) == 2
    assert "does not exist" in capsys.readouterr().err
    assert main(["orientation", "--min-deg", "179"]) == 2
    assert "lower --min-deg" in capsys.readouterr().err


def test_console_script_help():
    out = subprocess.run(
        [sys.executable, "-m", "baselines.cli", "orientation", "--help"],
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    for flag in ("--data", "--min-deg", "--out", "--plot-task"):
        assert flag in out


def test_cli_writes_results_csv(tmp_path, capsys):
    assert main(["orientation", "--out", str(tmp_path), "--learned", "off"]) == 0
    rows = list(csv.DictReader((tmp_path / "results.csv").open()))
    assert [r["name"] for r in rows] == criterion_names()
    doc = json.loads((tmp_path / "results.json").read_text())
    for row in rows:
        assert float(row["ours"]) == doc["criteria"][row["name"]]
        paper = FARAWAY_CHOE_TABLE1.get(row["name"])
        assert row["paper"] == ("" if paper is None else str(paper))


@pytest.mark.slow
def test_all_runs_the_selected_jobs(tmp_path, capsys):
    out = tmp_path / "res"
    argv = ["all", "--out", str(out), "--only", "orientation-vr-kitchen", "--learned", "off"]
    assert main(argv) == 0
    index = json.loads((out / "index.json").read_text())
    assert [j["folder"] for j in index["jobs"]] == ["orientation-vr-kitchen"]
    assert index["jobs"][0]["exit_code"] == 0
    assert (out / "orientation-vr-kitchen" / "results.json").exists()
    assert not (out / "position-lasa").exists()
    assert "real data" in capsys.readouterr().out


def test_up_and_learned_reach_run():
    config = orientation_bench.OrientationConfig(learned="off", up=(0.0, 0.0, 2.0))
    results = orientation_bench.run(config)
    assert results.dataset.up == (0.0, 0.0, 1.0)  # normalised; vr-kitchen's own is +y
    assert results.learned is None and results.learned_note is None
    assert "learned" not in orientation_bench.document(results)
    for bad in ({"learned": "fast"}, {"up": (0.0, 0.0, 0.0)}):
        with pytest.raises(ConfigError) as info:
            orientation_bench.run(orientation_bench.OrientationConfig(**bad))
        assert info.value.field == next(iter(bad))


def test_all_lowers_the_learned_budget_of_every_job(tmp_path):
    jobs = {job.folder: job.with_learned("quick") for job in run_all.JOBS}
    assert jobs["orientation-vr-kitchen"].config.learned == "quick"
    assert jobs["position-lasa"].config.learned == "quick"
    assert jobs["orientation-cohort"].config.learned == "off"  # never trained in `all`
    assert "--learned quick" in jobs["position-lasa"].command(tmp_path)
    assert "--learned off" in jobs["orientation-cohort"].command(tmp_path)
    assert "--learned" not in run_all.JOBS[0].command(tmp_path)
    assert all(job.with_learned("full") is job for job in run_all.JOBS)


def test_min_deg_that_leaves_no_replicates_says_what_it_dropped_and_what_to_change(
    tmp_path, capsys
):
    """A recording whose repeats of a task rotate less than the default --min-deg 10: the
    error says how many were dropped and why, and the --min-deg it suggests works."""
    ds = load_vr_kitchen(min_deg=0)
    angles = np.degrees(ds.rotation_angles())
    chosen = []  # per (subject, task): one reach over 10 degrees and one under
    for key in sorted(set(zip(ds.subjects.tolist(), ds.tasks.tolist(), strict=True)))[:40]:
        idx = np.flatnonzero((ds.subjects == key[0]) & (ds.tasks == key[1]))
        big, small = idx[angles[idx] >= 10], idx[angles[idx] < 10]
        if big.size and small.size:
            chosen += [int(big[0]), int(small[0])]
    assert len(chosen) >= 4
    path = ds.subset(np.array(chosen)).to_csv(tmp_path / "mine.csv")
    assert main(["orientation", "--data", str(path), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    n = len(chosen)
    assert len(err) == 1 and err[0].startswith("motion-bench orientation: error: argument --min")
    assert f"{n // 2} of {n} trajectories rotate less than 10 degrees" in err[0]
    assert "no (subject, task) pair left has 2 replicates" in err[0]
    suggested = err[0].split("lower --min-deg to ")[1].split(" ")[0]
    args = ["orientation", "--data", str(path), "--min-deg", suggested, "--learned", "off"]
    assert main([*args, "--out", str(tmp_path / "o")]) == 0
    out = capsys.readouterr().out
    assert f"dropped for rotating less than {suggested} degrees (--min-deg)" in out
