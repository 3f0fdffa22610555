"""The static type checker passes: mypy with the configuration in pyproject.toml
(strict on motion_envs/_io, geometry, datasets and models; baselines checked too)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.slow
def test_mypy_passes():
    out = subprocess.run(
        # no cache: a stale .mypy_cache in a work tree must not hide what a fresh clone sees
        [sys.executable, "-m", "mypy", "--no-error-summary", "--cache-dir=/dev/null"],
        capture_output=True,
        text=True,
        cwd=ROOT,
    )
    assert out.returncode == 0, out.stdout + out.stderr


def test_mypy_is_strict_on_the_lower_layers():
    text = (ROOT / "pyproject.toml").read_text()
    config = text.split("[tool.mypy]", 1)[1]
    for module in ("motion_envs.geometry.*", "motion_envs.models.*", "motion_envs.datasets.*"):
        assert f'"{module}"' in config
    assert "strict = true" in config
