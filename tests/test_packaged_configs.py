"""The shipped configs have one file each, and an installed package finds them.

The agent configs, the sweeps and the cohort configs are package data
(``baselines/configs/agents``, ``baselines/configs/sweeps``,
``motion_envs/datasets/cohorts``), so that ``motion-bench train`` without ``--config``,
``motion-bench sweep --config NAME`` and ``data="cohort"`` work from a wheel; the
repository's top-level ``configs/agents``, ``configs/sweeps`` and ``configs/cohorts`` are
symbolic links to those folders (one file on disk, nothing to keep in step).
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
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
COHORTS = ROOT / "motion_envs" / "datasets" / "cohorts"
#: Top-level folder -> the package folder it links to.
LINKS = {"agents": DEFAULT_CONFIG_DIR, "sweeps": SWEEP_CONFIG_DIR, "cohorts": COHORTS}


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


@pytest.mark.parametrize("kind", sorted(LINKS))
def test_top_level_configs_link_to_the_package_data(kind):
    """One file on disk: ``configs/KIND`` is a link to the package's folder, whose
    files are real (a wheel copies them, not links)."""
    top = ROOT / "configs" / kind
    assert top.is_symlink(), f"configs/{kind} must be a link to {LINKS[kind]}"
    assert top.resolve() == LINKS[kind].resolve()
    assert not os.path.isabs(os.readlink(top)), "a relative link survives a moved checkout"
    files = sorted(LINKS[kind].glob("*.y*ml"))
    assert files and not any(p.is_symlink() for p in files)


@pytest.mark.parametrize("kind", ["agents", "sweeps"])
def test_every_shipped_config_is_matched_by_the_package_data_globs(kind):
    shipped = package_data_files("baselines")
    files = {p.resolve() for p in LINKS[kind].iterdir() if p.is_file()}
    assert files and files <= shipped, sorted(str(p) for p in files - shipped)


def test_package_data_glob_expansion_is_not_vacuous():
    """The expansion above finds what it should, and nothing outside the globs."""
    shipped = package_data_files("baselines")
    assert all(p.suffix == ".yaml" and p.parent.parent.name == "configs" for p in shipped)
    assert package_data_files("motion_envs") >= {(COHORTS / "faraway2008.yaml").resolve()}


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


#: Run in a fresh interpreter from the installed copy, outside the checkout.
PROBE = """
import json, sys
import baselines, motion_envs
from baselines.agents.config import default_config_path, resolve_hyperparams
from baselines.agents.sweep.space import load_sweep
from baselines.cli import build_parser
from motion_envs.datasets import load_orientation_dataset
from motion_envs.datasets.cohort_config import resolve_cohort_config

sweep = build_parser().parse_args(["sweep", "--config", "tiny"]).config
print(json.dumps({
    "packages": [baselines.__file__, motion_envs.__file__],
    "agents": [str(default_config_path(a)) for a in ("ppo", "sac", "td3")],
    "ppo_juggling": resolve_hyperparams("ppo", "MotionEnvs/Juggling-v1")["env_kwargs"],
    "sweep": str(sweep),
    "sweep_seeds": list(load_sweep(sweep, out="unused").seeds),
    "cohort": str(resolve_cohort_config("faraway2008")),
    "cohort_simulated": load_orientation_dataset("cohort").simulated,
}))
"""


@pytest.mark.slow
def test_installed_wheel_finds_the_configs(tmp_path):
    """``pip install`` (not editable) of a copy of the sources into a fresh folder: the
    installed package finds the default agent configs, ``sweep --config tiny`` and the
    cohort config in itself, run from a folder with no ``configs/``."""
    src = tmp_path / "src"
    ignore = shutil.ignore_patterns("__pycache__", "*.pyc")
    for name in ("baselines", "motion_envs"):
        shutil.copytree(ROOT / name, src / name, ignore=ignore)
    for name in ("pyproject.toml", "README.md", "LICENSE"):
        shutil.copy2(ROOT / name, src / name)
    site = tmp_path / "site"
    pip = [sys.executable, "-m", "pip", "install", "--quiet", "--no-deps"]
    pip += ["--no-build-isolation", "--no-compile", "--target", str(site), str(src)]
    built = subprocess.run(pip, capture_output=True, text=True, timeout=600)
    assert built.returncode == 0, built.stderr
    run = tmp_path / "elsewhere"
    run.mkdir()
    env = {**os.environ, "PYTHONPATH": str(site)}
    out = subprocess.run(
        [sys.executable, "-c", PROBE],
        cwd=run,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert out.returncode == 0, out.stderr
    doc = json.loads(out.stdout.strip().splitlines()[-1])
    assert all(Path(p).is_relative_to(site) for p in doc["packages"]), doc["packages"]
    for path in [*doc["agents"], doc["sweep"], doc["cohort"]]:
        assert Path(path).is_relative_to(site) and Path(path).is_file(), path
        assert not Path(path).is_symlink()
    assert doc["ppo_juggling"]["level"] == "medium"
    assert doc["sweep_seeds"] and doc["cohort_simulated"] is True
