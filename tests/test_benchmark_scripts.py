"""Every script of benchmarks/ (timings), experiments/ (outcomes) and tools/ still imports
and parses its arguments (they are not run here: timing belongs in benchmarks/, not in
the test suite); each experiment names the BENCHMARKS.md section it feeds."""

from __future__ import annotations

import math
import re
import subprocess
import sys
from pathlib import Path

import pytest
from _helpers import load_experiment

ROOT = Path(__file__).resolve().parents[1]
BENCHMARKS = ROOT / "benchmarks"
EXPERIMENTS = ROOT / "experiments"
SCRIPTS = sorted(
    p
    for folder in (BENCHMARKS, EXPERIMENTS, ROOT / "tools")
    for p in folder.glob("*.py")
    if not p.name.startswith("_") and p.name != "plain_numpy_quaternion.py"
)


def test_scripts_found():
    names = {p.name for p in SCRIPTS}
    assert {"quaternion_ops.py", "bezier_fit.py", "table1_vr_kitchen.py"} <= names
    assert {"env_throughput.py", "position_timing.py", "cohort_scaling.py"} <= names
    assert {"juggling_throughput.py", "cascade_drops.py", "output_identity.py"} <= names


def test_benchmarks_are_timings_and_experiments_name_their_section():
    """benchmarks/ holds timings only (no script there says it is not one); every
    experiment is in experiments/README.md with the BENCHMARKS.md (or docs) section it
    feeds, and that section exists."""
    for path in BENCHMARKS.glob("*.py"):
        assert "Not a timing" not in path.read_text(encoding="utf-8"), path.name
    readme = (EXPERIMENTS / "README.md").read_text(encoding="utf-8")
    rows = dict(re.findall(r"^\| `(\w+\.py)` \|[^\n]*?\| ([^|\n]+) \|$", readme, re.M))
    assert set(rows) == {p.name for p in EXPERIMENTS.glob("*.py")}
    headings = {
        (doc, line.lstrip("#").strip())
        for doc in ("BENCHMARKS.md", *(f"docs/{p.name}" for p in (ROOT / "docs").glob("*.md")))
        for line in (ROOT / doc).read_text(encoding="utf-8").splitlines()
        if line.startswith("#")
    }
    benchmarks_md = (ROOT / "BENCHMARKS.md").read_text(encoding="utf-8")
    for script, where in rows.items():
        sections = re.findall(r"\[([^\]]+)\]\(\.\./([^)#]+)#[^)]*\)", where)
        assert sections, (script, where)
        for title, doc in sections:
            assert (doc, title) in headings, (script, doc, title)
            if doc == "BENCHMARKS.md":  # which points back to the script where it now is
                assert f"experiments/{script}" in benchmarks_md, script


@pytest.mark.parametrize("script", SCRIPTS, ids=lambda p: p.name)
def test_script_help(script):
    out = subprocess.run(
        [sys.executable, str(script), "--help"], capture_output=True, text=True, timeout=120
    )
    assert out.returncode == 0, out.stderr
    assert "usage:" in out.stdout


@pytest.mark.slow
def test_residual_sensitivity_fixed_offsets_on_training_seeds():
    """The one diagnosis cheap enough to run here: a fixed offset is played on the seeds
    asked for, and a malformed offset is a one-line usage error."""
    import json

    script = str(EXPERIMENTS / "cascade_residual_sensitivity.py")
    argv = [sys.executable, script, "--episodes", "2", "--scales", "0.05", "--split", "train"]
    out = subprocess.run(
        [*argv, "--fixed=-0.05,0,0.05,0"], capture_output=True, text=True, timeout=300
    )
    assert out.returncode == 0, out.stderr
    doc = json.loads(out.stdout.strip().splitlines()[-1])
    assert doc["split"] == "train"
    assert [r["residual"] for r in doc["rows"]][-1] == "fixed -0.05,0,0.05,0"
    assert "2 training seeds" in out.stdout
    assert all(r["diff_power"].startswith("80% power at 2 episodes") for r in doc["rows"])
    bad = subprocess.run([*argv, "--fixed=1,2,x"], capture_output=True, text=True, timeout=120)
    assert bad.returncode == 2 and "--fixed: '1,2,x' is not four" in bad.stderr


@pytest.mark.slow
def test_cascade_oracle_residual_is_the_latency_aware_juggler():
    """The oracle residual, unclipped, plays the latency-aware juggler's episodes (its
    targets are the juggler's plus their difference, the same random plan ends): the
    hands move as the latency-aware juggler's, period by period; clipped to almost nothing
    it plays the juggler's; outside its phases it does nothing; episodes repeat exactly.
    Training seeds only."""

    import gymnasium as gym
    import numpy as np

    mod = load_experiment("cascade_oracle_residual")  # puts benchmarks/ on sys.path itself
    phases = mod.PHASES

    def hands(controller: str, oracle: bool, seed: int) -> list:
        env = gym.make("MotionEnvs/Cascade-v0", controller=controller, max_catches=6)
        base = env.unwrapped
        if oracle:
            aware = mod.make_cascade_controller(
                "juggler_latency_aware", mod.cascade_fit(9.81), base.latency, None
            )
            base.controller = mod.OracleResidual(base.controller, aware, math.inf, phases)
        env.reset(seed=seed)
        out = []
        while True:
            _, _, term, trunc, info = env.step(np.zeros(4, np.float32))
            out.append(info["hands"])
            if term or trunc:
                return out

    for seed in range(2):
        got, want = hands("juggler", True, seed), hands("juggler_latency_aware", False, seed)
        assert len(got) == len(want)
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-9)
    alone, _, _ = mod.episodes("medium", 3, 6, "train", None, phases)
    tiny, _, _ = mod.episodes("medium", 3, 6, "train", 1e-12, phases)
    none, _, _ = mod.episodes("medium", 3, 6, "train", math.inf, ("nothing",))
    full, _, records = mod.episodes("medium", 3, 6, "train", math.inf, phases)
    again, _, _ = mod.episodes("medium", 3, 6, "train", 0.15, phases)
    assert again.tolist() == mod.episodes("medium", 3, 6, "train", 0.15, phases)[0].tolist()
    assert tiny.tolist() == alone.tolist() == none.tolist()
    assert full.sum() > alone.sum()
    assert {p for p, _ in records} == set(phases)
