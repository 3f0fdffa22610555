"""Position-trajectory datasets and the users' position CSV format.

CSV format (one row per sample, header required, extra columns ignored)::

    trajectory, subject, task, t, x, y[, z]

* ``trajectory``: an identifier; the rows of one trajectory are contiguous.
* ``subject``, ``task``: labels (any text); constant within a trajectory. For the
  position benchmark a *task* is one shape/phase, its trajectories the replicates.
* ``t``: time in seconds, strictly increasing within a trajectory.
* ``x, y`` and optionally ``z``: positions (any unit, the same for every row).

Each trajectory needs at least 5 samples. Errors name the file and the line numbers
(the header is line 1): missing columns, NaN or non-numeric values, unsorted times,
too few samples, non-contiguous trajectories, labels changing within a trajectory.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from motion_envs.datasets.orientation import _replicate_numbers
from motion_envs.models.sine_regression import MIN_SAMPLES

__all__ = ["CSV_COLUMNS", "PositionDataset", "read_position_csv"]

#: Required columns of the users' position CSV (``z`` is optional).
CSV_COLUMNS: tuple[str, ...] = ("trajectory", "subject", "task", "t", "x", "y")


@dataclass(frozen=True)
class PositionDataset:
    """Position trajectories with their labels.

    Attributes
    ----------
    name:
        Dataset name (``"lasa"``, a file name, ...).
    positions, times:
        Per trajectory: ``(n_l, D)`` positions and ``(n_l,)`` times in seconds.
    trajectory_ids, subjects, tasks:
        ``(L,)`` string labels.
    replicates:
        ``(L,)`` replicate number of the trajectory within its (subject, task) pair.
    unit:
        Unit of the positions (``"mm"`` for LASA).
    """

    name: str
    positions: tuple[NDArray[np.float64], ...]
    times: tuple[NDArray[np.float64], ...]
    trajectory_ids: NDArray[np.str_]
    subjects: NDArray[np.str_]
    tasks: NDArray[np.str_]
    replicates: NDArray[np.int64]
    unit: str = ""

    def __post_init__(self) -> None:
        n = len(self.positions)
        for attr in ("times", "trajectory_ids", "subjects", "tasks", "replicates"):
            if len(getattr(self, attr)) != n:
                raise ValueError(
                    f"{attr} has {len(getattr(self, attr))} entries but there are {n} trajectories"
                )

    def __len__(self) -> int:
        return len(self.positions)

    @property
    def n_dims(self) -> int:
        """Number of coordinates ``D``."""
        return int(self.positions[0].shape[1])

    def task_names(self) -> list[str]:
        """Task labels in order of first appearance."""
        return list(dict.fromkeys(self.tasks.tolist()))

    def subset(self, mask: NDArray[np.bool_] | Sequence[int]) -> PositionDataset:
        """A dataset holding the selected trajectories (boolean mask or indices)."""
        idx = np.arange(len(self))[np.asarray(mask)]
        return replace(
            self,
            positions=tuple(self.positions[i] for i in idx),
            times=tuple(self.times[i] for i in idx),
            trajectory_ids=self.trajectory_ids[idx],
            subjects=self.subjects[idx],
            tasks=self.tasks[idx],
            replicates=self.replicates[idx],
        )

    def to_csv(self, path: str | os.PathLike[str]) -> Path:
        """Write the dataset in the users' CSV format (atomic rename)."""
        axes = ("x", "y", "z")[: self.n_dims]
        frames = []
        for i in range(len(self)):
            frame = {
                "trajectory": self.trajectory_ids[i],
                "subject": self.subjects[i],
                "task": self.tasks[i],
                "t": self.times[i],
            }
            frame.update({a: self.positions[i][:, k] for k, a in enumerate(axes)})
            frames.append(pd.DataFrame(frame))
        target = Path(path)
        target.parent.mkdir(parents=True, exist_ok=True)
        tmp = target.with_name(f".{target.name}.tmp")
        pd.concat(frames, ignore_index=True).to_csv(tmp, index=False, float_format="%.17g")
        os.replace(tmp, target)
        return target


def read_position_csv(
    path: str | os.PathLike[str], min_samples: int = MIN_SAMPLES
) -> PositionDataset:
    """Read and validate a position CSV (format in the module docstring).

    Raises ``ValueError`` naming the file and line numbers of the bad rows.
    """
    p = Path(path)
    if not p.exists():
        raise FileNotFoundError(f"position CSV {p} does not exist")
    df = pd.read_csv(p, dtype={"trajectory": str, "subject": str, "task": str})
    missing = [c for c in CSV_COLUMNS if c not in df.columns]
    if missing:
        raise ValueError(
            f"{p}: missing column(s) {missing}; expected header {','.join(CSV_COLUMNS)}[,z]"
        )
    if len(df) == 0:
        raise ValueError(f"{p}: no data rows")
    line = np.arange(len(df)) + 2  # header is line 1

    def fail(mask: NDArray[np.bool_], what: str) -> None:
        bad = line[mask]
        shown = ", ".join(str(b) for b in bad[:10]) + (" ..." if bad.size > 10 else "")
        raise ValueError(f"{p}: {what} on line(s) {shown} ({bad.size} row(s))")

    for col in ("trajectory", "subject", "task"):
        empty = df[col].isna().to_numpy()
        if empty.any():
            fail(empty, f"empty {col!r}")
    axes = ["x", "y"] + (["z"] if "z" in df.columns else [])
    numeric = ["t", *axes]
    values = df[numeric].apply(pd.to_numeric, errors="coerce").to_numpy(dtype=np.float64)
    nonfinite = ~np.isfinite(values).all(axis=1)
    if nonfinite.any():
        fail(nonfinite, f"NaN, infinite or non-numeric value in {'/'.join(numeric)}")
    t, y = values[:, 0], values[:, 1:]

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
    unsorted = np.concatenate([[False], (np.diff(t) <= 0) & (seg[1:] == seg[:-1])])
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
    bounds = list(zip(starts, ends, strict=True))
    return PositionDataset(
        name=p.name,
        positions=tuple(y[s:e].copy() for s, e in bounds),
        times=tuple(t[s:e].copy() for s, e in bounds),
        trajectory_ids=ids.astype(str),
        subjects=subjects,
        tasks=tasks,
        replicates=_replicate_numbers(subjects, tasks),
    )
