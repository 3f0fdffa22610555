"""Position-trajectory datasets and the users' position CSV format.

CSV format (one row per sample, header required, extra columns ignored)::

    trajectory, subject, task, t, x, y[, z]

* ``trajectory``: an identifier; the rows of one trajectory are contiguous.
* ``subject``, ``task``: labels (any text); constant within a trajectory. For the
  position benchmark a *task* is one shape/phase, its trajectories the replicates.
* ``t``: time in seconds, strictly increasing within a trajectory.
* ``x, y`` and optionally ``z``: positions (any unit, the same for every row), at most
  :data:`MAX_ABS_POSITION` (10^9) in absolute value: a larger value is a corrupt or
  mis-scaled file (its squares would approach float64's range in the criteria).

Each trajectory needs at least 5 samples. Errors name the file and the line numbers
(the header is line 1; blank lines and multi-line quoted fields counted): missing
columns, NaN or non-numeric values, a time or position beyond its plausible range,
unsorted times, too few samples, non-contiguous trajectories, labels changing within a
trajectory; an empty, binary or non-UTF-8 file names the file. Labels such as ``NA``
or ``null`` are labels, not missing values.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from motion_envs.datasets.ragged import MIN_SAMPLES
from motion_envs.datasets.sample_table import read_sample_table, replicate_numbers, write_csv

__all__ = ["CSV_COLUMNS", "MAX_ABS_POSITION", "PositionDataset", "read_position_csv"]

#: Required columns of the users' position CSV (``z`` is optional).
CSV_COLUMNS: tuple[str, ...] = ("trajectory", "subject", "task", "t", "x", "y")

#: Largest plausible ``|x|``, ``|y|``, ``|z|`` of a position CSV (in the file's unit).
MAX_ABS_POSITION = 1e9


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
        return write_csv(frames, path)


def read_position_csv(
    path: str | os.PathLike[str], min_samples: int = MIN_SAMPLES
) -> PositionDataset:
    """Read and validate a position CSV (format in the module docstring).

    Raises ``ValueError`` naming the file and line numbers of the bad rows.
    """
    table = read_sample_table(
        path,
        CSV_COLUMNS[4:],
        min_samples,
        kind="position",
        optional_value_columns=("z",),
        max_abs_value=MAX_ABS_POSITION,
        value_unit="(in the file's unit)",
    )
    return PositionDataset(
        name=table.path.name,
        positions=tuple(table.values[s:e].copy() for s, e in table.segments()),
        times=tuple(table.t[s:e].copy() for s, e in table.segments()),
        trajectory_ids=table.ids,
        subjects=table.subjects,
        tasks=table.tasks,
        replicates=replicate_numbers(table.subjects, table.tasks),
    )
