"""A sub-command whose optional dependency is missing says, in one line, which extra to
install (exit 2), instead of a ModuleNotFoundError traceback."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

from baselines.cli import EXTRA_OF_MODULE

try:
    import tomllib
except ImportError:  # Python 3.10
    tomllib = pytest.importorskip("tomli")

ROOT = Path(__file__).resolve().parents[1]


def test_every_optional_module_is_in_the_extra_it_names():
    extras = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"][
        "optional-dependencies"
    ]

    def names(extra):
        return {re.split(r"[<>=\[; ]", r, maxsplit=1)[0].lower() for r in extras[extra]}

    for module, (extra, dist) in EXTRA_OF_MODULE.items():
        assert dist in names(extra), f"{module}: {dist} is not in the {extra!r} extra"


@pytest.mark.parametrize(
    ("module", "argv", "extra"),
    [
        (
            "stable_baselines3",
            ["train", "--algo", "ppo", "--env", "MotionEnvs/PositionReach-v1"],
            "rl",
        ),
        ("ray", ["sweep", "--config", str(ROOT / "configs/sweeps/tiny.yaml")], "sweep"),
    ],
)
def test_a_missing_extra_is_one_line_naming_it(module, argv, extra, tmp_path):
    """The module is made unimportable (``sys.modules[name] = None``, as Python does for
    a module that is not installed) in a fresh interpreter running the CLI."""
    code = (
        f"import sys; sys.modules[{module!r}] = None; "
        f"from baselines.cli import main; sys.exit(main({[*argv, '--out', str(tmp_path)]!r}))"
    )
    proc = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=300, cwd=tmp_path
    )
    lines = proc.stderr.strip().splitlines()
    assert proc.returncode == 2, proc.stderr
    assert len(lines) == 1, proc.stderr
    assert f'pip install -e ".[{extra}]"' in lines[0] and "Traceback" not in proc.stderr
