"""The documentation site builds with warnings as errors and documents every public name."""

from __future__ import annotations

import importlib
import inspect
import os
import pkgutil
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("sphinx")
pytest.importorskip("myst_parser")
pytest.importorskip("furo")
pytest.importorskip("sphinx_gallery")

ROOT = Path(__file__).resolve().parents[1]
SPHINX_ARGS = ("-b", "html", "-W", "--keep-going", "-q")


def public_names() -> set[str]:
    """``module.name`` of every class and function in ``__all__`` of every public module of
    both packages (module-level constants are described in their modules' docstrings)."""
    names: set[str] = set()
    for name, module in public_modules():
        for obj in getattr(module, "__all__", ()):
            value = getattr(module, obj)
            if inspect.isclass(value) or inspect.isroutine(value):
                names.add(f"{name}.{obj}")
    return names


def public_modules() -> list[tuple[str, object]]:
    """Every module of both packages whose dotted name has no private part."""
    import warnings

    out = []
    for package in ("motion_envs", "baselines"):
        root = importlib.import_module(package)
        names = [root.__name__]
        for info in pkgutil.walk_packages(root.__path__, prefix=f"{package}."):
            if not any(part.startswith("_") for part in info.name.split(".")):
                names.append(info.name)
        with warnings.catch_warnings():  # the deprecated modules warn on import
            warnings.simplefilter("ignore", DeprecationWarning)
            out += [(name, importlib.import_module(name)) for name in names]
    return out


def canonical(qualified: str) -> str:
    """Where the object named ``module.name`` is defined (``__module__.__qualname__``)."""
    module, _, name = qualified.rpartition(".")
    obj = getattr(importlib.import_module(module), name)
    return f"{getattr(obj, '__module__', module)}.{getattr(obj, '__qualname__', name)}"


@pytest.fixture(scope="module")
def built_site(tmp_path_factory):
    out = tmp_path_factory.mktemp("site")
    env = {**os.environ, "MOTION_ENVS_DOCS_RUN_EXAMPLES": "0"}
    proc = subprocess.run(
        [sys.executable, "-m", "sphinx", *SPHINX_ARGS, "docs", str(out)],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert proc.returncode == 0, proc.stderr[-4000:]
    return out


def test_site_builds_with_warnings_as_errors(built_site):
    assert (built_site / "index.html").exists()
    assert (built_site / "api.html").exists()


def test_every_environment_has_a_page(built_site):
    import motion_envs

    for env_id in motion_envs.ENV_IDS:
        page = built_site / "environments" / f"{env_id.split('/')[-1].lower()}.html"
        assert page.exists(), env_id
        assert "Action Space" in page.read_text(encoding="utf-8"), env_id


def test_every_public_name_is_in_the_api_reference(built_site):
    from sphinx.util.inventory import InventoryFile

    with open(built_site / "objects.inv", "rb") as fh:
        inventory = InventoryFile.load(fh, "", lambda base, uri: uri)
    data = getattr(inventory, "data", inventory)  # a dict before Sphinx 8.2, an Inventory after
    documented = {name for entries in data.values() for name in entries}
    missing = sorted(
        n for n in public_names() if n not in documented and canonical(n) not in documented
    )
    assert not missing, missing
