"""The built-in dataset names come from one registry (``motion_envs.datasets.registry``):
every registered name loads its own data through the kind's public loader, an unknown
or wrong-kind name is a one-line error listing the known names, and the environments'
``data=`` and ``docs/data.md`` take their names from it (the CLI's ``--data``:
``tests/test_cli_errors.py``)."""

from __future__ import annotations

import re
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import motion_envs  # noqa: F401
from motion_envs.datasets import load_orientation_dataset, load_position_dataset
from motion_envs.datasets.registry import DATASETS, KINDS, dataset_names, lookup
from motion_envs.models.juggling import FIT_SEED, load_demonstrations

ROOT = Path(__file__).resolve().parents[1]


def _direct(name):
    """The data each name stands for, read by its own module (not through the registry)."""
    if name == "vr-kitchen":
        from motion_envs.datasets.vr_kitchen import load_vr_kitchen

        return load_vr_kitchen(min_deg=2.0)
    if name == "cohort":
        from motion_envs.datasets.cohort import load_cohort

        return load_cohort("faraway2008", min_deg=2.0)
    if name == "lasa":
        from motion_envs.datasets.lasa import load_lasa

        return load_lasa()
    if name == "simulated":
        from motion_envs.datasets.juggling import generate_demonstrations

        return generate_demonstrations(n_cycles=10, seed=FIT_SEED)
    raise AssertionError(f"no direct reader for the new built-in dataset {name!r}: add one")


def _through_registry(name):
    kind = DATASETS[name].kind
    if kind == "orientation":
        return load_orientation_dataset(name, min_deg=2.0)
    if kind == "position":
        return load_position_dataset(name)
    return load_demonstrations(name, seed=FIT_SEED, n_cycles=10)


def _arrays(data):
    """The samples of any kind of dataset, as one flat array, and its labels."""
    if hasattr(data, "quaternions"):
        return np.concatenate([q.ravel() for q in data.quaternions]), list(data.trajectory_ids)
    if hasattr(data, "positions"):
        return np.concatenate([p.ravel() for p in data.positions]), list(data.trajectory_ids)
    flat = np.concatenate([np.concatenate([r.t, r.hand.ravel()]) for r in data.recordings])
    return flat, [r.name for r in data.recordings]


@pytest.mark.parametrize("name", sorted(DATASETS))
def test_every_registered_name_loads_its_own_data(name):
    got, want = _through_registry(name), _direct(name)
    assert type(got) is type(want)
    got_values, got_labels = _arrays(got)
    want_values, want_labels = _arrays(want)
    assert got_labels == want_labels
    np.testing.assert_array_equal(got_values, want_values)
    if hasattr(got, "simulated"):
        assert got.simulated is DATASETS[name].simulated


def test_names_of_different_data_differ():
    """No two registered names read the same samples (the bug: every name loading LASA)."""
    seen = {}
    for name in DATASETS:
        values, _ = _arrays(_through_registry(name))
        key = (values.size, float(values[:1000].sum()))
        assert key not in seen, (name, seen.get(key))
        seen[key] = name


@pytest.mark.parametrize(
    ("load", "data", "match"),
    [
        (load_position_dataset, "lasa2", r"'lasa2' is not a built-in position dataset \('lasa'\)"),
        (
            load_orientation_dataset,
            "kitchen",
            r"'kitchen' is not a built-in orientation dataset \('vr-kitchen', 'vr-kitchen:MODE', "
            r"'cohort', 'cohort:CONFIG'\)",
        ),
        (
            load_position_dataset,
            "vr-kitchen",
            "is the built-in orientation dataset; built-in position datasets: 'lasa'",
        ),
        (load_orientation_dataset, "lasa", "built-in orientation datasets: 'vr-kitchen'"),
        (load_demonstrations, "lasa", "built-in juggling datasets: 'simulated'"),
        (load_demonstrations, "juggle", r"not a built-in juggling dataset \('simulated'\)"),
        (load_orientation_dataset, "cohort:", "needs a config name"),
        (load_orientation_dataset, "vr-kitchen:pen", r"must be one of \['laser', 'stick'\]"),
    ],
)
def test_unknown_or_wrong_kind_name_is_one_line_listing_the_names(load, data, match):
    with pytest.raises(ValueError, match=match) as info:
        load(data)
    assert "\n" not in str(info.value)


def test_a_name_without_parameter_takes_no_value():
    assert lookup("lasa:x", "position") is None  # a path, then
    assert lookup("cohort:small", "orientation") == (DATASETS["cohort"], "small")
    assert lookup(Path("lasa"), "position") is None


def test_every_kind_has_a_name_and_entries_are_complete():
    assert {d.kind for d in DATASETS.values()} == set(KINDS)
    for name, d in DATASETS.items():
        assert d.name == name and d.licence and d.source


def test_environments_data_argument_uses_the_registry():
    with pytest.raises(ValueError, match="built-in position datasets: 'lasa'"):
        gym.make("MotionEnvs/PositionReach-v0", data="vr-kitchen")
    with pytest.raises(ValueError, match="not a built-in orientation dataset"):
        gym.make("MotionEnvs/OrientationReach-v0", data="kitchen")


def test_docs_list_exactly_the_registered_datasets():
    """docs/data.md's table: one row per registered name, with its kind, SIMULATED or
    real, and licence as the registry says."""
    text = (ROOT / "docs" / "data.md").read_text(encoding="utf-8")
    rows = re.findall(r"^\| `([^`]+)` \| (\w+) \| (SIMULATED|real) \| ([^|]+) \|", text, re.M)
    assert {r[0] for r in rows} == set(DATASETS)
    for name, kind, label, licence in rows:
        d = DATASETS[name]
        assert (kind, label == "SIMULATED", licence.strip()) == (d.kind, d.simulated, d.licence)
    for kind in KINDS:
        assert dataset_names(kind)
