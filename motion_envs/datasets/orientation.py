"""Orientation-trajectory datasets and the users' CSV format.

CSV format (one row per sample, header required, extra columns allowed)::

    trajectory, subject, task, t, qw, qx, qy, qz[, predictor columns ...]

* ``trajectory``: an identifier; the rows of one trajectory are contiguous.
* ``subject``, ``task``: labels (any text); constant within a trajectory.
* ``t``: time in seconds, strictly increasing within a trajectory.
* ``qw, qx, qy, qz``: the orientation as a unit quaternion, scalar first (norms within
  ``1e-3`` of 1 are accepted and renormalised).
* ``replicate`` (optional): integer replicate number within the (subject, task) pair;
  without it replicates are numbered 0, 1, ... in file order within each pair.
* any other **numeric** column is a per-trajectory predictor (e.g. age, height); it must
  be constant within a trajectory and at most ``MAX_ABS_VALUE`` (10^12) in absolute value.

Each trajectory needs at least 5 samples; ``|t|`` is at most 10^10 s. Errors name the
file and the line number (the header is line 1; blank lines and multi-line quoted fields
are counted); an empty, binary or non-UTF-8 file names the file. Labels such as ``NA``,
``None`` or ``null`` are labels, not missing values.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from functools import cached_property
from pathlib import Path

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike, NDArray

from motion_envs.datasets.ragged import MIN_SAMPLES, RaggedTrajectories
from motion_envs.datasets.sample_table import (
    MAX_ABS_VALUE,
    read_sample_table,
    replicate_numbers,
    write_csv,
)
from motion_envs.geometry import quaternion as quat

__all__ = [
    "CSV_COLUMNS",
    "DATA_UNIT_TOLERANCE",
    "DEFAULT_UP",
    "OrientationDataset",
    "check_up",
    "read_orientation_csv",
]

#: Required columns of the users' orientation CSV, in order.
CSV_COLUMNS: tuple[str, ...] = ("trajectory", "subject", "task", "t", "qw", "qx", "qy", "qz")
#: Accepted deviation of a data quaternion's norm from 1 (then renormalised).
DATA_UNIT_TOLERANCE = 1e-3
#: Vertical axis of a dataset when none is given: world ``+z`` (right-handed, z up).
DEFAULT_UP: tuple[float, float, float] = (0.0, 0.0, 1.0)


def check_up(up: ArrayLike, name: str = "up") -> NDArray[np.float64]:
    """``up`` as a unit float vector ``(3,)``; ``ValueError`` if not 3 finite non-zero values."""
    arr = np.asarray(up, dtype=np.float64)
    if arr.shape != (3,) or not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be 3 finite numbers (x, y, z); got {up!r}")
    norm = float(np.linalg.norm(arr))
    if norm < 1e-12:
        raise ValueError(f"{name} must not be the zero vector")
    return arr / norm


@dataclass(frozen=True)
class OrientationDataset:
    """A set of orientation trajectories with their design labels.

    Attributes
    ----------
    name:
        Dataset name (``"vr-kitchen"``, a file name, ...).
    quaternions, times:
        Per trajectory: ``(n_l, 4)`` unit quaternions ``(w, x, y, z)`` and ``(n_l,)``
        times in seconds.
    trajectory_ids, subjects, tasks:
        ``(L,)`` string labels.
    replicates:
        ``(L,)`` replicate number of the trajectory within its (subject, task) pair.
    predictors:
        Numeric per-trajectory predictors, name -> ``(L,)`` float array.
    n_dropped:
        How many trajectories the loader dropped (e.g. rotation below ``min_deg``).
    simulated:
        True for generated (virtual) data, False for real recordings.
    up:
        The data's vertical axis in the world frame of the quaternions (used by the
        path frame, :mod:`motion_envs.models.path_frame`); default :data:`DEFAULT_UP`
        (``+z``); ``vr-kitchen`` is y-up; a CSV's is given by ``read_orientation_csv(up=)``
        or ``motion-bench orientation --up``.
    """

    name: str
    quaternions: tuple[NDArray[np.float64], ...]
    times: tuple[NDArray[np.float64], ...]
    trajectory_ids: NDArray[np.str_]
    subjects: NDArray[np.str_]
    tasks: NDArray[np.str_]
    replicates: NDArray[np.int64]
    predictors: dict[str, NDArray[np.float64]] = field(default_factory=dict)
    n_dropped: int = 0
    simulated: bool = False
    up: tuple[float, float, float] = DEFAULT_UP

    def __post_init__(self) -> None:
        L = len(self.quaternions)
        for attr in ("times", "trajectory_ids", "subjects", "tasks", "replicates"):
            if len(getattr(self, attr)) != L:
                raise ValueError(
                    f"{attr} has {len(getattr(self, attr))} entries but there are {L} trajectories"
                )
        for key, value in self.predictors.items():
            if len(value) != L:
                raise ValueError(f"predictor {key!r} has {len(value)} values, expected {L}")

    def __len__(self) -> int:
        return len(self.quaternions)

    @cached_property
    def ragged(self) -> RaggedTrajectories:
        """The trajectories packed flat for the vectorised pipeline (validated once)."""
        return RaggedTrajectories.from_sequences(self.quaternions, self.times)

    def rotation_angles(self) -> NDArray[np.float64]:
        """``(L,)`` angle in radians between each trajectory's first and last orientation."""
        starts = np.stack([q[0] for q in self.quaternions])
        ends = np.stack([q[-1] for q in self.quaternions])
        return quat.angle(starts, ends)

    def subset(self, mask: NDArray[np.bool_] | Sequence[int]) -> OrientationDataset:
        """A dataset holding the selected trajectories (boolean mask or indices)."""
        idx = np.arange(len(self))[np.asarray(mask)]
        return replace(
            self,
            quaternions=tuple(self.quaternions[i] for i in idx),
            times=tuple(self.times[i] for i in idx),
            trajectory_ids=self.trajectory_ids[idx],
            subjects=self.subjects[idx],
            tasks=self.tasks[idx],
            replicates=self.replicates[idx],
            predictors={k: v[idx] for k, v in self.predictors.items()},
        )

    def drop_small_rotations(self, min_deg: float) -> OrientationDataset:
        """Drop trajectories whose start-to-end rotation is below ``min_deg`` degrees.

        The slerp and the speed profile are ill-posed for tiny rotations. The result's
        ``n_dropped`` adds the number dropped here.
        """
        if not np.isfinite(min_deg) or min_deg < 0:
            raise ValueError(f"min_deg must be a finite angle >= 0 in degrees; got {min_deg!r}")
        keep = np.degrees(self.rotation_angles()) >= min_deg
        out = self.subset(keep)
        return replace(out, n_dropped=self.n_dropped + int(np.count_nonzero(~keep)))

    def to_csv(self, path: str | os.PathLike[str]) -> Path:
        """Write the dataset in the users' CSV format (see the module docstring)."""
        frames = []
        for l in range(len(self)):
            q = self.quaternions[l]
            frame = {
                "trajectory": self.trajectory_ids[l],
                "subject": self.subjects[l],
                "task": self.tasks[l],
                "replicate": self.replicates[l],
                "t": self.times[l],
                "qw": q[:, 0],
                "qx": q[:, 1],
                "qy": q[:, 2],
                "qz": q[:, 3],
            }
            for key, value in self.predictors.items():
                frame[key] = value[l]
            frames.append(pd.DataFrame(frame))
        return write_csv(frames, path)


def read_orientation_csv(
    path: str | os.PathLike[str],
    min_samples: int = MIN_SAMPLES,
    up: tuple[float, float, float] = DEFAULT_UP,
) -> OrientationDataset:
    """Read and validate an orientation CSV (format in the module docstring).

    Raises ``ValueError`` naming the file and line numbers for: missing columns, NaN or
    non-numeric values, quaternions whose norm is not within 1e-3 of 1, times that do
    not strictly increase, trajectories with fewer than ``min_samples`` samples, rows of
    one trajectory that are not contiguous, labels or predictors that change within a
    trajectory. ``up`` is the data's vertical axis (stored as the dataset's ``up``).
    """
    table = read_sample_table(path, CSV_COLUMNS[4:], min_samples, kind="orientation")
    q = table.values
    norms = np.linalg.norm(q, axis=1)
    nonunit = np.abs(norms - 1.0) > DATA_UNIT_TOLERANCE
    if nonunit.any():
        table.fail(nonunit, f"quaternion norm not within {DATA_UNIT_TOLERANCE:g} of 1")
    q = q / norms[:, None]
    df = table.frame
    subjects, tasks = table.subjects, table.tasks
    if "replicate" in df.columns:
        rep = pd.to_numeric(df["replicate"], errors="coerce").to_numpy(dtype=np.float64)
        bad_rep = ~np.isfinite(rep) | (rep != np.round(rep)) | (rep < 0) | (rep > 1e9)
        if bad_rep.any():
            table.fail(bad_rep, "'replicate' must be a non-negative integer (at most 10^9)")
        replicates = table.per_trajectory("replicate").astype(np.int64)
    else:
        replicates = replicate_numbers(subjects, tasks)
    predictors: dict[str, NDArray[np.float64]] = {}
    for col in df.columns:
        if col in (*CSV_COLUMNS, "replicate"):
            continue
        if not pd.api.types.is_numeric_dtype(df[col]):
            continue
        col_values = df[col].to_numpy(dtype=np.float64)
        if not np.all(np.isfinite(col_values)):
            table.fail(~np.isfinite(col_values), f"NaN in predictor column {col!r}")
        if np.any(np.abs(col_values) > MAX_ABS_VALUE):
            table.fail(
                np.abs(col_values) > MAX_ABS_VALUE,
                f"predictor {col!r} beyond the plausible range |value| <= {MAX_ABS_VALUE:g}",
            )
        predictors[col] = table.per_trajectory(col).astype(np.float64)

    quats = tuple(quat.make_continuous(q[s:e]) for s, e in table.segments())
    times = tuple(table.t[s:e].copy() for s, e in table.segments())
    return OrientationDataset(
        name=table.path.name,
        quaternions=quats,
        times=times,
        trajectory_ids=table.ids,
        subjects=subjects,
        tasks=tasks,
        replicates=replicates,
        predictors=predictors,
        up=tuple(float(x) for x in up),  # type: ignore[arg-type]
    )
