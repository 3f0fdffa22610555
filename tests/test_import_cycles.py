"""No import cycle among the project's modules, nor among its sub-packages.

Read from the source with ``ast`` (module level, inside functions and under
``TYPE_CHECKING`` alike, as ``tests/test_layers.py`` does), every import of a project
module is an edge; ``from pkg import name`` is an edge to ``pkg.name`` when that is a
module, else to ``pkg``. Two graphs must be acyclic (``graphlib`` finds a cycle):

* modules: ``a`` imports ``b`` (a package ``__init__`` re-exporting its sub-modules is
  an edge down, never back up);
* units: every module of a sub-package (``baselines.learned.*``, ``motion_envs.envs.*``)
  counts as that sub-package, every other module as itself, so a sub-package and a
  module beside it cannot lean on each other (a former ``baselines.learned_rows``
  imported ``baselines.learned`` while ``baselines.learned.position_reading`` imported it
  back).
"""

from __future__ import annotations

import ast
import graphlib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("motion_envs", "baselines")


def project_modules(root: Path = ROOT) -> dict[str, tuple[Path, bool]]:
    """Dotted module name -> (file, is a package ``__init__``)."""
    out = {}
    for pkg in PACKAGES:
        for path in sorted((root / pkg).rglob("*.py")):
            parts = list(path.relative_to(root).with_suffix("").parts)
            is_package = parts[-1] == "__init__"
            if is_package:
                parts = parts[:-1]
            out[".".join(parts)] = (path, is_package)
    return out


def imported_modules(
    module: str, source: str, is_package: bool, modules: dict[str, tuple[Path, bool]]
) -> set[str]:
    """The project modules that ``module``'s source imports (itself left out)."""

    def resolve(name: str) -> str | None:
        while name and name not in modules:
            name = name.rpartition(".")[0]
        return name or None

    pkg = module if is_package else module.rpartition(".")[0]
    found: set[str | None] = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            found.update(resolve(alias.name) for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = pkg.split(".")[: len(pkg.split(".")) - (node.level - 1)]
                base = ".".join([*anchor, base] if base else anchor)
            found.update(resolve(f"{base}.{alias.name}") for alias in node.names)
    return {m for m in found if m is not None and m != module}


def unit_of(module: str, modules: dict[str, tuple[Path, bool]]) -> str:
    """The sub-package (``top.sub``) a module belongs to, else the module itself."""
    parts = module.split(".")
    if len(parts) >= 3 or (len(parts) == 2 and modules[module][1]):
        return ".".join(parts[:2])
    return module


def module_graph(
    root: Path = ROOT, overrides: dict[str, str] | None = None
) -> tuple[dict[str, set[str]], dict[str, set[str]]]:
    """The module graph and the unit graph; ``overrides`` replaces modules' sources."""
    modules = project_modules(root)
    graph = {}
    for module, (path, is_package) in modules.items():
        source = (overrides or {}).get(module) or path.read_text(encoding="utf-8")
        graph[module] = imported_modules(module, source, is_package, modules)
    units: dict[str, set[str]] = {}
    for module, targets in graph.items():
        own = unit_of(module, modules)
        units.setdefault(own, set()).update(
            unit_of(t, modules) for t in targets if unit_of(t, modules) != own
        )
    return graph, units


def cycle(graph: dict[str, set[str]]) -> list[str] | None:
    """One cycle of ``graph`` (``graphlib``'s), or None when it is acyclic."""
    try:
        tuple(graphlib.TopologicalSorter(graph).static_order())
    except graphlib.CycleError as exc:
        found: list[str] = exc.args[1]
        return found
    return None


def test_no_import_cycle_among_modules():
    graph, _ = module_graph()
    assert len(graph) > 50
    assert cycle(graph) is None, " -> ".join(cycle(graph) or [])


def test_no_import_cycle_among_subpackages():
    _, units = module_graph()
    assert {"baselines.learned", "baselines.agents", "motion_envs.envs"} <= set(units)
    assert cycle(units) is None, " -> ".join(cycle(units) or [])


@pytest.mark.parametrize(
    ("overrides", "graph_index", "members"),
    [
        # a module cycle: the options checkers importing the CLI that imports them
        ({"baselines.options": "from baselines.cli import main\n"}, 0, {"baselines.options"}),
        # a unit cycle without a module cycle: a learned module importing a benchmark
        # package that imports baselines.learned (no module of the loop imports it back)
        (
            {"baselines.learned.model_file": "import baselines.orientation_bench\n"},
            1,
            {"baselines.learned", "baselines.orientation_bench"},
        ),
    ],
)
def test_checker_finds_an_injected_cycle(overrides, graph_index, members):
    """Mutation check: an injected import that closes a loop is found."""
    found = cycle(module_graph(overrides=overrides)[graph_index])
    assert found is not None and members <= set(found)
