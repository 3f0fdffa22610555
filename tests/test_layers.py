"""The layer order of docs/architecture.md holds for every module of the project.

``motion_envs._io < geometry < datasets < models < envs (and the motion_envs package
itself) < baselines``: a module may import only from its own layer or those below, at
module level, inside functions or under ``TYPE_CHECKING`` alike. No module imports a
private name (``_x``) of another module, or reaches into another package's private
module; the exceptions are ``motion_envs._io``, the project's atomic writer, and
``motion_envs._lazy``, the packages' lazy re-exports, which every layer may use.
``geometry``, ``datasets`` and ``models`` import no Gymnasium, MuJoCo or torch. The
checker works on the source (``ast``), so it sees imports that a run would not reach.
"""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("motion_envs", "baselines")

#: Layer of each module prefix; the longest matching prefix wins.
LAYERS: dict[str, int] = {
    "motion_envs._io": 0,
    "motion_envs._lazy": 0,
    "motion_envs.geometry": 1,
    "motion_envs.datasets": 2,
    "motion_envs.models": 3,
    "motion_envs.envs": 4,
    "motion_envs": 4,  # the package __init__ registers the environments
    "baselines": 5,
}
LAYER_NAMES = {0: "_io", 1: "geometry", 2: "datasets", 3: "models", 4: "envs", 5: "baselines"}
#: Private modules every layer may import.
SHARED_PRIVATE = ("motion_envs._io", "motion_envs._lazy")
#: Third-party packages the lower layers must not import (heavy, or another layer's job).
FORBIDDEN_BELOW_ENVS = ("gymnasium", "mujoco", "torch", "stable_baselines3")


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


def layer_of(module: str) -> int | None:
    best = None
    for prefix, layer in LAYERS.items():
        if (module == prefix or module.startswith(prefix + ".")) and (
            best is None or len(prefix) > len(best[0])
        ):
            best = (prefix, layer)
    return None if best is None else best[1]


def _is_private(part: str) -> bool:
    return part.startswith("_") and not (part.startswith("__") and part.endswith("__"))


def _package_of(module: str, is_package: bool) -> str:
    return module if is_package else module.rpartition(".")[0]


def _private_module_allowed(target: str, importer_pkg: str) -> bool:
    """A private module ``a.b._c`` may be imported from inside ``a.b`` (or is shared)."""
    if any(target == s or target.startswith(s + ".") for s in SHARED_PRIVATE):
        return True
    parts = target.split(".")
    for i, part in enumerate(parts):
        if _is_private(part):
            owner = ".".join(parts[:i])
            if not (importer_pkg == owner or importer_pkg.startswith(owner + ".")):
                return False
    return True


def violations(module: str, source: str, is_package: bool = False) -> list[str]:
    """Every broken rule of one module's source, as readable one-line messages."""
    tree = ast.parse(source)
    own = layer_of(module)
    pkg = _package_of(module, is_package)
    found: list[str] = []
    module_aliases: dict[str, str] = {}

    def check_target(target: str, line: int) -> None:
        top = target.split(".")[0]
        if own is not None and own <= 3 and top in FORBIDDEN_BELOW_ENVS:
            found.append(f"{module}:{line}: {LAYER_NAMES[own]} imports {top}")
        layer = layer_of(target)
        if layer is None or own is None:
            return
        if layer > own:
            found.append(
                f"{module}:{line}: upward import of {target} "
                f"({LAYER_NAMES[own]} -> {LAYER_NAMES[layer]})"
            )
        if not _private_module_allowed(target, pkg):
            found.append(f"{module}:{line}: imports private module {target}")

    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                check_target(alias.name, node.lineno)
                if alias.asname:
                    module_aliases[alias.asname] = alias.name
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = pkg.split(".")
                anchor = anchor[: len(anchor) - (node.level - 1)]
                base = ".".join([*anchor, base] if base else anchor)
            check_target(base, node.lineno)
            for alias in node.names:
                full = f"{base}.{alias.name}"
                if full in MODULES or layer_of(base) is None:
                    if full in MODULES:
                        check_target(full, node.lineno)
                        module_aliases[alias.asname or alias.name] = full
                    continue
                if _is_private(alias.name):
                    found.append(f"{module}:{node.lineno}: imports private name {full}")
        elif (
            isinstance(node, ast.Attribute)
            and isinstance(node.value, ast.Name)
            and node.value.id in module_aliases
            and _is_private(node.attr)
        ):
            target = module_aliases[node.value.id]
            if f"{target}.{node.attr}" not in MODULES or not _private_module_allowed(
                f"{target}.{node.attr}", pkg
            ):
                found.append(f"{module}:{node.lineno}: uses private name {target}.{node.attr}")
    return found


@pytest.mark.parametrize("module", sorted(MODULES))
def test_module_respects_the_layers(module):
    path = MODULES[module]
    problems = violations(module, path.read_text(encoding="utf-8"), path.name == "__init__.py")
    assert not problems, "\n".join(problems)


def test_every_project_module_has_a_layer():
    assert all(layer_of(m) is not None for m in MODULES)
    assert {layer_of(m) for m in MODULES} == set(LAYER_NAMES)


@pytest.mark.parametrize(
    ("module", "source", "fragment"),
    [
        ("motion_envs.datasets.cohort", "from motion_envs.models import criteria\n", "upward"),
        ("motion_envs.datasets.cohort", "import motion_envs.models.criteria\n", "upward"),
        ("motion_envs.geometry.bezier", "from motion_envs.datasets import ragged\n", "upward"),
        ("motion_envs.models.criteria", "import gymnasium\n", "imports gymnasium"),
        ("motion_envs.models.criteria", "def f():\n    import torch\n", "imports torch"),
        ("motion_envs.models.criteria", "from motion_envs.envs import vector\n", "upward"),
        ("motion_envs.envs.vector", "from baselines import cli\n", "upward"),
        (
            "motion_envs.models.criteria",
            "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n"
            "    from motion_envs.envs.vector import OrientationReachVectorEnv\n",
            "upward",
        ),
        (
            "baselines.cli",
            "from motion_envs.datasets.cohort_config import _SCHEMA\n",
            "private name",
        ),
        (
            "baselines.cli",
            "from motion_envs.datasets import cohort_config as cc\nx = cc._SCHEMA\n",
            "private name",
        ),
        ("baselines.cli", "from motion_envs.envs import _kernels\n", "private module"),
        ("motion_envs.models.criteria", "from ..envs import vector\n", "upward"),
    ],
)
def test_checker_catches_violations(module, source, fragment):
    """Mutation check: the rules fire on an injected upward or private import."""
    problems = violations(module, source)
    assert any(fragment in p for p in problems), problems


@pytest.mark.parametrize(
    ("module", "source"),
    [
        ("motion_envs.models.criteria", "from motion_envs.datasets.ragged import MIN_SAMPLES\n"),
        ("motion_envs.envs.vector", "from motion_envs.envs import _kernels as K\nK.reward\n"),
        ("baselines.cli", "from motion_envs._io import atomic_write_text\n"),
        ("motion_envs.datasets.cohort", "from motion_envs.geometry import quaternion\n"),
    ],
)
def test_checker_allows_downward_and_package_private(module, source):
    assert violations(module, source) == []


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
