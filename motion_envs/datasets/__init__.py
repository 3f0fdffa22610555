"""Datasets: real human recordings shipped with the package and the users' CSV formats."""

from __future__ import annotations

import os
from collections.abc import Sequence

import numpy as np

from motion_envs.datasets.mocap import (
    import_orientation,
    import_position,
    is_mocap_source,
    parse_source,
)
from motion_envs.datasets.orientation import OrientationDataset, read_orientation_csv
from motion_envs.datasets.position_csv import PositionDataset, read_position_csv
from motion_envs.datasets.registry import DATASETS, data_file, dataset_names, load_builtin
from motion_envs.datasets.vr_kitchen import DEFAULT_MIN_DEG, load_vr_kitchen

__all__ = [
    "DATASETS",
    "OrientationDataset",
    "PositionDataset",
    "dataset_names",
    "load_orientation_dataset",
    "load_position_dataset",
    "load_vr_kitchen",
    "read_orientation_csv",
    "read_position_csv",
]


def load_orientation_dataset(
    data: str | os.PathLike[str],
    min_deg: float = DEFAULT_MIN_DEG,
    up: tuple[float, float, float] | None = None,
) -> OrientationDataset:
    """Load a built-in orientation dataset by name (:mod:`motion_envs.datasets.registry`),
    the users' CSV at a path, or a recording.

    A motion capture file (``.c3d``, ``.bvh``, ``.tsv``) is imported with the options
    after its name: ``"rec.c3d?markers=O,X,P&up=y"`` (:mod:`motion_envs.datasets.mocap`,
    ``docs/recordings.md``).

    ``"cohort"`` is the simulated cohort ``faraway2008``; ``"cohort:CONFIG"`` another
    cohort, CONFIG being a name under ``configs/cohorts/`` or a path to a YAML file
    (:mod:`motion_envs.datasets.cohort`). Trajectories rotating less than ``min_deg``
    degrees from start to end are dropped and counted in ``n_dropped``. ``up`` (the
    data's vertical axis) overrides the dataset's own (``+z`` for a CSV and the cohort,
    ``+y`` for vr-kitchen).
    """
    if up is not None:
        from dataclasses import replace

        from motion_envs.datasets.orientation import check_up

        x, y, z = (float(v) for v in check_up(up))
        return replace(load_orientation_dataset(data, min_deg), up=(x, y, z))
    builtin: OrientationDataset | None = load_builtin(data, "orientation", min_deg=min_deg)
    if builtin is not None:
        return builtin
    if is_mocap_source(data):
        path, options = parse_source(data)
        return import_orientation(path, options)[0].drop_small_rotations(min_deg)
    path = data_file(data, "orientation", "a path to an orientation CSV")
    return read_orientation_csv(path).drop_small_rotations(min_deg)


def load_position_dataset(
    data: str | os.PathLike[str], shapes: Sequence[str] | None = None
) -> PositionDataset:
    """Load a built-in position dataset by name (``"lasa"``,
    :mod:`motion_envs.datasets.registry`), the users' position CSV at a path, or a recording.

    A motion capture file is imported with the options after its name:
    ``"rec.c3d?marker=RFIN&speed-threshold=0.05"`` (:mod:`motion_envs.datasets.mocap`).

    ``shapes`` keeps only those tasks (LASA shape names, or the CSV's task labels);
    an unknown name raises ``ValueError`` naming it.
    """
    builtin: PositionDataset | None = load_builtin(data, "position", shapes=shapes)
    if builtin is not None:
        return builtin
    if is_mocap_source(data):
        path, options = parse_source(data)
        ds = import_position(path, options)[0]
    else:
        path = data_file(data, "position", "a path to a position CSV")
        ds = read_position_csv(path)
    if shapes:
        unknown = sorted(set(shapes) - set(ds.tasks.tolist()))
        if unknown:
            raise ValueError(f"shapes: task(s) {unknown} are not in {path}")
        ds = ds.subset(np.isin(ds.tasks, list(shapes)))
    return ds
