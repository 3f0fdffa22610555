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
  be constant within a trajectory.

Each trajectory needs at least 5 samples. Errors name the file and the line number (the header is
line 1).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from functools import cached_property
from pathlib import Path

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from motion_envs.geometry import quaternion as quat
from motion_envs.models.slerp_residual import MIN_SAMPLES, RaggedTrajectories

__all__ = [
    "CSV_COLUMNS",
    "DATA_UNIT_TOLERANCE",
    "OrientationDataset",
    "read_orientation_csv",
]

#: Required columns of the users' orientation CSV, in order.
CSV_COLUMNS: tuple[str, ...] = ("trajectory", "subject", "task", "t", "qw", "qx", "qy", "qz")
#: Accepted deviation of a data quaternion's norm from 1 (then renormalised).
DATA_UNIT_TOLERANCE = 1e-3


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
        target = Path(path)
        target.parent.mkdir(parents=True, exist_ok=True)
        tmp = target.with_name(f".{target.name}.tmp")
        pd.concat(frames, ignore_index=True).to_csv(tmp, index=False, float_format="%.17g")
        os.replace(tmp, target)
        return target


def _replicate_numbers(subjects: NDArray[np.str_], tasks: NDArray[np.str_]) -> NDArray[np.int64]:
    """Number trajectories 0, 1, ... in order within each (subject, task) pair."""
    keys = pd.Series(list(zip(subjects, tasks, strict=True)))
    return keys.groupby(keys).cumcount().to_numpy(dtype=np.int64)


def read_orientation_csv(
    path: str | os.PathLike[str], min_samples: int = MIN_SAMPLES
) -> OrientationDataset:
    """Read and validate an orientation CSV (format in the module docstring).

    Raises ``ValueError`` naming the file and line numbers for: missing columns, NaN or
    non-numeric values, quaternions whose norm is not within 1e-3 of 1, times that do
    not strictly increase, trajectories with fewer than ``min_samples`` samples, rows of
    one trajectory that are not contiguous, labels or predictors that change within a
    trajectory.
    """
    p = Path(path)
    if not p.exists():
        raise FileNotFoundError(f"orientation CSV {p} does not exist")
    df = pd.read_csv(p, dtype={"trajectory": str, "subject": str, "task": str})
    missing = [c for c in CSV_COLUMNS if c not in df.columns]
    if missing:
        raise ValueError(
            f"{p}: missing column(s) {missing}; expected header {','.join(CSV_COLUMNS)}"
        )
    if len(df) == 0:
        raise ValueError(f"{p}: no data rows")
    line = np.arange(len(df)) + 2  # header is line 1

    def fail(mask: NDArray[np.bool_], what: str) -> None:
        bad = line[mask]
        shown = ", ".join(str(b) for b in bad[:10]) + (" ..." if bad.size > 10 else "")
        raise ValueError(f"{p}: {what} on line(s) {shown} ({bad.size} row(s))")

    for col in ("trajectory", "subject", "task"):
        fail_mask = df[col].isna().to_numpy()
        if fail_mask.any():
            fail(fail_mask, f"empty {col!r}")
    numeric = ["t", "qw", "qx", "qy", "qz"]
    values = df[numeric].apply(pd.to_numeric, errors="coerce").to_numpy(dtype=np.float64)
    nonfinite = ~np.isfinite(values).all(axis=1)
    if nonfinite.any():
        fail(nonfinite, "NaN, infinite or non-numeric value in t/qw/qx/qy/qz")
    t = values[:, 0]
    q = values[:, 1:]
    norms = np.linalg.norm(q, axis=1)
    nonunit = np.abs(norms - 1.0) > DATA_UNIT_TOLERANCE
    if nonunit.any():
        fail(nonunit, f"quaternion norm not within {DATA_UNIT_TOLERANCE:g} of 1")
    q = q / norms[:, None]

    traj = df["trajectory"].to_numpy(dtype=str)
    change = np.concatenate([[True], traj[1:] != traj[:-1]])
    starts = np.flatnonzero(change)
    ids = traj[starts]
    if len(set(ids)) != ids.size:
        dup = pd.Series(ids)[pd.Series(ids).duplicated()].iloc[0]
        first_rows = starts[ids == dup]
        fail(np.isin(np.arange(len(df)), first_rows[1:]), f"trajectory {dup!r} is not contiguous")
    ends = np.concatenate([starts[1:], [len(df)]])
    lengths = ends - starts
    short = np.isin(np.arange(len(df)), starts[lengths < min_samples])
    if short.any():
        fail(short, f"trajectory with fewer than {min_samples} samples starts")
    seg = np.repeat(np.arange(ids.size), lengths)
    dt = np.diff(t)
    unsorted = np.concatenate([[False], (dt <= 0) & (seg[1:] == seg[:-1])])
    if unsorted.any():
        fail(unsorted, "time not strictly increasing within its trajectory")

    def per_trajectory(col: str) -> NDArray:
        arr = df[col].to_numpy()
        first = arr[starts]
        varies = arr != first[seg]
        if np.any(varies):
            fail(varies, f"{col!r} changes within a trajectory")
        return first

    subjects = per_trajectory("subject").astype(str)
    tasks = per_trajectory("task").astype(str)
    predictors: dict[str, NDArray[np.float64]] = {}
    if "replicate" in df.columns:
        rep = pd.to_numeric(df["replicate"], errors="coerce").to_numpy(dtype=np.float64)
        bad_rep = ~np.isfinite(rep) | (rep != np.round(rep)) | (rep < 0)
        if bad_rep.any():
            fail(bad_rep, "'replicate' must be a non-negative integer")
        replicates = per_trajectory("replicate").astype(np.int64)
    else:
        replicates = _replicate_numbers(subjects, tasks)
    for col in df.columns:
        if col in (*CSV_COLUMNS, "replicate"):
            continue
        if not pd.api.types.is_numeric_dtype(df[col]):
            continue
        col_values = df[col].to_numpy(dtype=np.float64)
        if not np.all(np.isfinite(col_values)):
            fail(~np.isfinite(col_values), f"NaN in predictor column {col!r}")
        predictors[col] = per_trajectory(col).astype(np.float64)

    quats = tuple(quat.make_continuous(q[s:e]) for s, e in zip(starts, ends, strict=True))
    times = tuple(t[s:e].copy() for s, e in zip(starts, ends, strict=True))
    return OrientationDataset(
        name=p.name,
        quaternions=quats,
        times=times,
        trajectory_ids=ids.astype(str),
        subjects=subjects,
        tasks=tasks,
        replicates=replicates,
        predictors=predictors,
    )
