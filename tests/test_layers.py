"""No module uses a private name (``_x``) of another module: the one layer rule that
import-linter's contracts (tests/test_import_contracts.py) cannot express, read from the
source with ``ast`` (module level, inside functions and under ``TYPE_CHECKING`` alike).

``from m import _x`` and ``m._x`` (``m`` imported as a module) are refused unless ``_x``
is itself a module the importer may use (a private module of its own package, or the
shared ``motion_envs._io`` and ``motion_envs._lazy``: the contracts check those). Also:
``import motion_envs`` loads no torch, no models and no datasets (a run-time check).
"""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("motion_envs", "baselines")


def project_modules() -> dict[str, Path]:
    """Dotted module name -> file, for every module of the project's packages."""
    out = {}
    for pkg in PACKAGES:
        for path in sorted((ROOT / pkg).rglob("*.py")):
            parts = list(path.relative_to(ROOT).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts = parts[:-1]
            out[".".join(parts)] = path
    return out


MODULES = project_modules()


def _is_private(part: str) -> bool:
    return part.startswith("_") and not (part.startswith("__") and part.endswith("__"))


def private_names(module: str, source: str, is_package: bool = False) -> list[str]:
    """Every private name of another project module that ``source`` uses, as one-line
    messages."""
    tree = ast.parse(source)
    pkg = module if is_package else module.rpartition(".")[0]
    found: list[str] = []
    aliases: dict[str, str] = {}
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                if alias.asname and alias.name.split(".")[0] in PACKAGES:
                    aliases[alias.asname] = alias.name
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = pkg.split(".")
                anchor = anchor[: len(anchor) - (node.level - 1)]
                base = ".".join([*anchor, base] if base else anchor)
            if base.split(".")[0] not in PACKAGES:
                continue
            for alias in node.names:
                full = f"{base}.{alias.name}"
                if full in MODULES:
                    aliases[alias.asname or alias.name] = full
                elif _is_private(alias.name):
                    found.append(f"{module}:{node.lineno}: imports private name {full}")
        elif (
            isinstance(node, ast.Attribute)
            and isinstance(node.value, ast.Name)
            and node.value.id in aliases
            and _is_private(node.attr)
            and f"{aliases[node.value.id]}.{node.attr}" not in MODULES
        ):
            target = aliases[node.value.id]
            found.append(f"{module}:{node.lineno}: uses private name {target}.{node.attr}")
    return found


def test_no_module_uses_a_private_name_of_another():
    problems = [
        p
        for module, path in MODULES.items()
        for p in private_names(module, path.read_text(encoding="utf-8"), path.name == "__init__.py")
    ]
    assert not problems, "\n".join(problems)


@pytest.mark.parametrize(
    ("source", "fragment"),
    [
        ("from motion_envs.datasets.cohort_config import _SCHEMA\n", "private name"),
        ("from motion_envs.datasets import cohort_config as cc\nx = cc._SCHEMA\n", "private name"),
        ("import motion_envs.datasets.cohort_config as cc\nx = cc._SCHEMA\n", "private name"),
        ("def f():\n    from ..datasets.cohort_config import _SCHEMA\n", "private name"),
    ],
)
def test_checker_catches_a_private_name(source, fragment):
    """Mutation check: the rule fires on an injected use of a private name."""
    problems = private_names("motion_envs.models.criteria", source)
    assert any(fragment in p for p in problems), problems


@pytest.mark.parametrize(
    "source",
    [
        "from motion_envs.datasets.ragged import MIN_SAMPLES\n",
        "from motion_envs.envs import _kernels as K\nK.reward\n",
        "from motion_envs._io import atomic_write_text\n",
        "from motion_envs.envs import vector\nvector.__name__\n",
    ],
)
def test_checker_allows_public_names_and_private_modules(source):
    assert private_names("motion_envs.envs.vector", source) == []


def test_import_motion_envs_loads_no_torch_and_no_models():
    code = (
        "import sys, motion_envs, motion_envs.geometry;"
        "bad = [m for m in ('torch', 'stable_baselines3', 'motion_envs.models', "
        "'motion_envs.datasets', 'pandas') if m in sys.modules];"
        "print(','.join(bad))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=ROOT
    )
    assert out.stdout.strip() == ""
