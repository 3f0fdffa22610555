"""The agent and sweep configs ship inside the wheel, identical to the repository's.

The canonical files are the repository's top-level ``configs/agents`` and
``configs/sweeps``; ``baselines/configs/`` holds byte-identical copies that
``pyproject.toml`` ships as package data, so that ``motion-bench train`` without
``--config`` works from a wheel (not only from a checkout), as
``tests/test_cohort_calibration.py`` does for ``configs/cohorts``. Edit the canonical
file, then copy it over the package's.
"""

from __future__ import annotations

import os
from glob import glob
from pathlib import Path

import pytest

from baselines.agents.config import DEFAULT_CONFIG_DIR, SWEEP_CONFIG_DIR, default_config_path
from baselines.agents.sweep.cli import sweep_file

try:
    import tomllib
except ImportError:  # Python 3.10
    tomllib = pytest.importorskip("tomli")

ROOT = Path(__file__).resolve().parents[1]
SHIPPED = {"agents": DEFAULT_CONFIG_DIR, "sweeps": SWEEP_CONFIG_DIR}


def package_data_files(package: str) -> set[Path]:
    """The files ``pyproject.toml``'s ``package-data`` of ``package`` puts in the wheel,
    expanded as setuptools' ``build_py.find_data_files`` does (``glob(...,
    recursive=True)`` relative to the package folder, files only)."""
    doc = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    patterns = doc["tool"]["setuptools"]["package-data"].get(package, [])
    src = ROOT / package
    return {
        Path(f).resolve()
        for pattern in patterns
        for f in glob(os.path.join(src, pattern), recursive=True)
        if os.path.isfile(f)
    }


@pytest.mark.parametrize("kind", sorted(SHIPPED))
def test_package_copy_is_byte_identical_to_the_canonical_configs(kind):
    canonical = {p.name: p for p in (ROOT / "configs" / kind).iterdir() if p.is_file()}
    packaged = {p.name: p for p in SHIPPED[kind].iterdir() if p.is_file()}
    assert canonical, f"configs/{kind}/ is empty"
    assert sorted(packaged) == sorted(canonical), f"copy configs/{kind}/ to {SHIPPED[kind]}"
    for name, path in canonical.items():
        assert packaged[name].read_bytes() == path.read_bytes(), f"{kind}/{name} differs"


@pytest.mark.parametrize("kind", sorted(SHIPPED))
def test_every_shipped_config_is_matched_by_the_package_data_globs(kind):
    shipped = package_data_files("baselines")
    files = {p.resolve() for p in SHIPPED[kind].iterdir() if p.is_file()}
    assert files and files <= shipped, sorted(str(p) for p in files - shipped)


def test_package_data_glob_expansion_is_not_vacuous():
    """The expansion above finds what it should, and nothing outside the globs."""
    shipped = package_data_files("baselines")
    assert all(p.suffix == ".yaml" and p.parent.parent.name == "configs" for p in shipped)
    assert package_data_files("motion_envs") >= {
        (ROOT / "motion_envs" / "datasets" / "cohorts" / "faraway2008.yaml").resolve()
    }


def test_defaults_resolve_inside_the_package():
    baselines_dir = (ROOT / "baselines").resolve()
    for algo in ("ppo", "sac", "td3"):
        path = default_config_path(algo).resolve()
        assert path.is_file() and path.is_relative_to(baselines_dir)


def test_sweep_config_takes_a_shipped_name_or_a_path(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # outside the checkout: no configs/ beside
    assert sweep_file("tiny") == SWEEP_CONFIG_DIR / "tiny.yaml"
    own = tmp_path / "tiny.yaml"
    own.write_text("seeds: [0]\n")
    assert sweep_file(str(own)) == own
    assert sweep_file("tiny.yaml") == Path("tiny.yaml")  # an existing file wins
