"""The layer order of docs/architecture.md, as import-linter contracts (pyproject.toml's
``[tool.importlinter]``), kept by ``lint-imports``.

``motion_envs._io``, ``_lazy``, ``_typing`` < ``geometry`` < ``datasets`` < ``models`` <
``envs`` (and the ``motion_envs`` package itself) < ``baselines``: a module imports only
from its own layer or those below; ``geometry``, ``datasets`` and ``models`` import no
Gymnasium, MuJoCo, torch or SB3; a private module (``_x``) is imported from inside its own
package only (``_io``, ``_lazy`` and ``_typing`` from everywhere); no import cycle among
the sub-packages and modules of a package, nor among all the modules. grimp reads every
import statement (module level, inside functions, under ``TYPE_CHECKING``). A private
*name* of another module (``from m import _x``, ``m._x``) is not a contract import-linter
has: tests/test_layers.py checks it with ``ast``. Each contract is shown to break on an
injected import, in a small tree of the same packages.
"""

from __future__ import annotations

import graphlib
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
LINT = shutil.which("lint-imports") or str(Path(sys.executable).with_name("lint-imports"))

pytest.importorskip("importlinter")


def lint(root: Path) -> subprocess.CompletedProcess[str]:
    """``lint-imports`` on the packages under ``root`` with the project's contracts."""
    env = {**os.environ, "PYTHONPATH": str(root)}
    return subprocess.run(
        [LINT, "--config", str(ROOT / "pyproject.toml"), "--no-cache"],
        capture_output=True,
        text=True,
        cwd=root,
        env=env,
        timeout=300,
    )


def test_the_project_keeps_every_contract():
    proc = lint(ROOT)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "5 kept, 0 broken" in proc.stdout


def test_no_import_cycle_among_all_the_modules():
    """Beyond siblings (the contract): no module reaches itself through any chain, a
    package's ``__init__`` and its own modules included."""
    import grimp

    graph = grimp.build_graph("motion_envs", "baselines")
    mine = {m for m in graph.modules if m.split(".")[0] in ("motion_envs", "baselines")}
    edges = {m: graph.find_modules_directly_imported_by(m) & mine for m in mine}
    graphlib.TopologicalSorter(edges).prepare()  # CycleError names the cycle


#: A module of the small tree per layer (and the shared private modules).
_TREE = (
    "motion_envs/__init__.py",
    "motion_envs/_io.py",
    "motion_envs/_lazy.py",
    "motion_envs/_typing.py",
    "motion_envs/geometry/__init__.py",
    "motion_envs/geometry/bezier.py",
    "motion_envs/datasets/__init__.py",
    "motion_envs/datasets/ragged.py",
    "motion_envs/models/__init__.py",
    "motion_envs/models/criteria.py",
    "motion_envs/models/nominal.py",
    "motion_envs/envs/__init__.py",
    "motion_envs/envs/_kernels.py",
    "motion_envs/envs/vector.py",
    "baselines/__init__.py",
    "baselines/cli.py",
)


@pytest.mark.parametrize(
    ("module", "source", "broken"),
    [
        ("geometry/bezier", "from motion_envs.datasets import ragged\n", "Layers"),
        ("models/criteria", "from ..envs import vector\n", "Layers"),
        ("envs/vector", "def f():\n    from baselines import cli\n", "Layers"),
        (
            "models/criteria",
            "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n"
            "    from motion_envs.envs.vector import X\n",
            "Layers",
        ),
        ("datasets/ragged", "from motion_envs import ENV_IDS\n", "package itself"),
        ("models/criteria", "def f():\n    import torch\n", "No Gymnasium"),
        ("geometry/bezier", "import gymnasium\n", "No Gymnasium"),
        ("baselines/cli", "from motion_envs.envs import _kernels\n", "Private modules"),
        ("models/criteria", "from motion_envs.models import nominal\n", "No import cycle"),
    ],
)
def test_each_contract_breaks_on_an_injected_import(tmp_path, module, source, broken):
    for name in _TREE:
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / name).write_text("")
    # allowed: downward, the shared private modules, a package's own private module
    (tmp_path / "baselines/cli.py").write_text("from motion_envs._io import x\n")
    (tmp_path / "motion_envs/envs/vector.py").write_text("from motion_envs.envs import _kernels\n")
    (tmp_path / "motion_envs/models/nominal.py").write_text(
        "from motion_envs.models import criteria\nfrom motion_envs.datasets import ragged\n"
    )
    assert lint(tmp_path).returncode == 0, "the small tree breaks a contract by itself"
    path = tmp_path / "motion_envs" / f"{module}.py"
    if module.startswith("baselines/"):
        path = tmp_path / f"{module}.py"
    path.write_text(path.read_text() + source)
    proc = lint(tmp_path)
    assert proc.returncode == 1, proc.stdout
    lines = [line for line in proc.stdout.splitlines() if " BROKEN" in line]
    assert len(lines) == 1 and broken in lines[0], proc.stdout
