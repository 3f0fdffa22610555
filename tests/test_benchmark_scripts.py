"""Every benchmark script still imports and parses its arguments (they are not run here:
timing belongs in benchmarks/, not in the test suite)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

BENCHMARKS = Path(__file__).resolve().parents[1] / "benchmarks"
SCRIPTS = sorted(
    p
    for p in BENCHMARKS.glob("*.py")
    if not p.name.startswith("_") and p.name != "plain_numpy_quaternion.py"
)


def test_scripts_found():
    names = {p.name for p in SCRIPTS}
    assert {"quaternion_ops.py", "bezier_fit.py", "table1_vr_kitchen.py"} <= names
    assert {"env_throughput.py", "position_timing.py", "cohort_scaling.py"} <= names
    assert "juggling_throughput.py" in names


@pytest.mark.parametrize("script", SCRIPTS, ids=lambda p: p.name)
def test_script_help(script):
    out = subprocess.run(
        [sys.executable, str(script), "--help"], capture_output=True, text=True, timeout=120
    )
    assert out.returncode == 0, out.stderr
    assert "usage:" in out.stdout


def test_residual_sensitivity_fixed_offsets_on_training_seeds():
    """The one diagnosis cheap enough to run here: a fixed offset is played on the seeds
    asked for, and a malformed offset is a one-line usage error."""
    import json

    script = str(BENCHMARKS / "cascade_residual_sensitivity.py")
    argv = [sys.executable, script, "--episodes", "2", "--scales", "0.05", "--split", "train"]
    out = subprocess.run(
        [*argv, "--fixed=-0.05,0,0.05,0"], capture_output=True, text=True, timeout=300
    )
    assert out.returncode == 0, out.stderr
    doc = json.loads(out.stdout.strip().splitlines()[-1])
    assert doc["split"] == "train"
    assert [r["residual"] for r in doc["rows"]][-1] == "fixed -0.05,0,0.05,0"
    assert "2 training seeds" in out.stdout
    bad = subprocess.run([*argv, "--fixed=1,2,x"], capture_output=True, text=True, timeout=120)
    assert bad.returncode == 2 and "--fixed: '1,2,x' is not four" in bad.stderr
