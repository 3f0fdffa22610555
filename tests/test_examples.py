"""Every script of ``examples/`` (the gallery and the tutorials) runs as shown.

The documentation test builds the site without running the gallery; this test runs each
script in a fresh interpreter with a temporary folder as its argument and working
directory, and checks a line of what it printed. The scripts' budgets are tiny (2,000
training steps, six juggling seeds), so the whole set takes about a minute of CPU.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = sorted((ROOT / "examples").glob("*.py"))

#: What each script must print (a result, not only a header), and the extra it needs.
EXPECTED: dict[str, tuple[str, str | None]] = {
    "modeller_quickstart.py": ("eq. 9 end velocity", None),
    "reach_nominal.py": ("max error (mm): nominal", None),
    "table1_row.py": ("null (d=2): by hand", None),
    "juggling_levels.py": ("hard   juggler", None),
    "tutorial_own_recordings.py": ("10 movements of", None),
    "tutorial_train_and_compare.py": ("agent / nominal = ", "stable_baselines3"),
    "tutorial_sweep.py": ("(best on val)", "ray"),
}


def test_every_example_has_an_expectation():
    assert sorted(EXPECTED) == sorted(p.name for p in EXAMPLES)


#: Examples that train agents (measured with --durations: the longest of the set).
SLOW_EXAMPLES = {
    "tutorial_sweep": [pytest.mark.ray, pytest.mark.slow],
    "tutorial_train_and_compare": [pytest.mark.slow],
}


@pytest.mark.parametrize(
    "script",
    [
        pytest.param(
            p,
            id=p.stem,
            marks=SLOW_EXAMPLES.get(p.stem, []),
        )
        for p in EXAMPLES
    ],
)
def test_example_runs(script, tmp_path):
    expected, extra = EXPECTED[script.name]
    if extra is not None:
        pytest.importorskip(extra)
    env = {**os.environ, "MPLBACKEND": "Agg", "PYTHONPATH": str(ROOT)}
    out = subprocess.run(
        [sys.executable, str(script), str(tmp_path)],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=900,
    )
    assert out.returncode == 0, out.stderr[-4000:]
    assert expected in out.stdout, out.stdout[-2000:]
