"""Reading and writing the users' one-row-per-sample CSV files, with line-numbered errors.

Both the orientation and the position CSV formats share this layout::

    trajectory, subject, task, t, <value columns ...>[, extra columns ...]

The rows of one trajectory are contiguous; ``t`` strictly increases within a
trajectory; ``subject`` and ``task`` are constant within it. :func:`read_sample_table`
checks all of that and raises ``ValueError`` naming the file and the offending line
numbers (the header is line 1); the format-specific loaders add their own checks with
:meth:`SampleTable.fail` and :meth:`SampleTable.per_trajectory`.
"""

from __future__ import annotations

import gzip
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NoReturn

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from motion_envs._io import atomic_write_bytes, atomic_write_text

__all__ = [
    "LABEL_COLUMNS",
    "SampleTable",
    "read_csv_exact",
    "read_sample_table",
    "replicate_numbers",
    "write_csv",
]

#: Label columns every sample CSV starts with.
LABEL_COLUMNS: tuple[str, ...] = ("trajectory", "subject", "task")


def replicate_numbers(subjects: NDArray[np.str_], tasks: NDArray[np.str_]) -> NDArray[np.int64]:
    """Number trajectories 0, 1, ... in order within each (subject, task) pair."""
    keys = pd.Series(list(zip(subjects, tasks, strict=True)))
    return keys.groupby(keys).cumcount().to_numpy(dtype=np.int64)


_PANDAS_MAJOR = int(pd.__version__.split(".", 1)[0])


def read_csv_exact(path: str | os.PathLike[str], **kwargs: Any) -> pd.DataFrame:
    """``pandas.read_csv`` that parses every float exactly (round trip).

    pandas 3 parses floats exactly by default; pandas 2 needs
    ``float_precision="round_trip"`` (which pandas 3 deprecates), else a float written with
    17 significant digits can read back 1 ulp off.
    """
    if _PANDAS_MAJOR < 3:
        kwargs.setdefault("float_precision", "round_trip")
    return pd.read_csv(path, **kwargs)


def _fail(path: Path, mask: NDArray[np.bool_], what: str) -> NoReturn:
    bad = np.flatnonzero(mask) + 2  # the header is line 1
    shown = ", ".join(str(b) for b in bad[:10]) + (" ..." if bad.size > 10 else "")
    raise ValueError(f"{path}: {what} on line(s) {shown} ({bad.size} row(s))")


def _per_trajectory(
    path: Path, frame: pd.DataFrame, column: str, starts: NDArray[Any], ends: NDArray[Any]
) -> NDArray[Any]:
    arr = frame[column].to_numpy()
    first = arr[starts]
    varies = arr != np.repeat(first, ends - starts)
    if np.any(varies):
        _fail(path, varies, f"{column!r} changes within a trajectory")
    return first


@dataclass(frozen=True)
class SampleTable:
    """A validated sample CSV split into trajectories.

    Attributes
    ----------
    path:
        The file read.
    frame:
        The raw table (``pandas.DataFrame``), one row per sample.
    t:
        ``(n_rows,)`` times.
    values:
        ``(n_rows, k)`` the numeric value columns asked for, all finite.
    value_columns:
        Names of the columns of ``values``.
    starts, ends:
        ``(L,)`` first row and one-past-last row of each trajectory.
    ids, subjects, tasks:
        ``(L,)`` labels of each trajectory.
    """

    path: Path
    frame: pd.DataFrame
    t: NDArray[np.float64]
    values: NDArray[np.float64]
    value_columns: tuple[str, ...]
    starts: NDArray[np.int64]
    ends: NDArray[np.int64]
    ids: NDArray[np.str_]
    subjects: NDArray[np.str_]
    tasks: NDArray[np.str_]

    def fail(self, mask: NDArray[np.bool_], what: str) -> NoReturn:
        """Raise ``ValueError`` listing the line numbers of the rows where ``mask`` is set."""
        _fail(self.path, mask, what)

    def segments(self) -> list[tuple[int, int]]:
        """``[(start, end), ...]`` row range of each trajectory."""
        return list(zip(self.starts.tolist(), self.ends.tolist(), strict=True))

    def per_trajectory(self, column: str) -> NDArray[Any]:
        """The value of ``column`` for each trajectory; it must not change within one."""
        return _per_trajectory(self.path, self.frame, column, self.starts, self.ends)


def read_sample_table(
    path: str | os.PathLike[str],
    value_columns: Sequence[str],
    min_samples: int,
    kind: str,
    optional_value_columns: Sequence[str] = (),
) -> SampleTable:
    """Read a sample CSV and check the layout shared by every format.

    Parameters
    ----------
    path:
        The CSV file.
    value_columns:
        Required numeric columns after ``t`` (e.g. ``qw, qx, qy, qz`` or ``x, y``).
    min_samples:
        Fewest samples accepted per trajectory.
    kind:
        Word used in messages (``"orientation"``, ``"position"``).
    optional_value_columns:
        Numeric columns appended to ``values`` when the file has them (e.g. ``z``).

    Raises ``FileNotFoundError`` for a missing file and ``ValueError`` naming the file
    and line numbers for: missing columns, empty labels, NaN/inf/non-numeric values,
    non-contiguous trajectories, too few samples, times that do not strictly increase,
    subject or task labels changing within a trajectory.
    """
    p = Path(path)
    if not p.exists():
        raise FileNotFoundError(f"{kind} CSV {p} does not exist")
    required = (*LABEL_COLUMNS, "t", *value_columns)
    frame = read_csv_exact(p, dtype={c: str for c in LABEL_COLUMNS})
    missing = [c for c in required if c not in frame.columns]
    if missing:
        raise ValueError(f"{p}: missing column(s) {missing}; expected header {','.join(required)}")
    if len(frame) == 0:
        raise ValueError(f"{p}: no data rows")
    for col in LABEL_COLUMNS:
        empty = frame[col].isna().to_numpy()
        if empty.any():
            _fail(p, empty, f"empty {col!r}")
    numeric = ["t", *value_columns, *(c for c in optional_value_columns if c in frame.columns)]
    data = frame[numeric].apply(pd.to_numeric, errors="coerce").to_numpy(dtype=np.float64)
    nonfinite = ~np.isfinite(data).all(axis=1)
    if nonfinite.any():
        _fail(p, nonfinite, f"NaN, infinite or non-numeric value in {'/'.join(numeric)}")

    traj = frame["trajectory"].to_numpy(dtype=str)
    starts = np.flatnonzero(np.concatenate([[True], traj[1:] != traj[:-1]]))
    ids = traj[starts]
    if len(set(ids)) != ids.size:
        dup = pd.Series(ids)[pd.Series(ids).duplicated()].iloc[0]
        repeated = starts[ids == dup][1:]
        _fail(p, np.isin(np.arange(len(frame)), repeated), f"trajectory {dup!r} is not contiguous")
    ends = np.concatenate([starts[1:], [len(frame)]])
    lengths = ends - starts
    short = np.isin(np.arange(len(frame)), starts[lengths < min_samples])
    if short.any():
        _fail(p, short, f"trajectory with fewer than {min_samples} samples starts")
    seg = np.repeat(np.arange(ids.size), lengths)
    t = data[:, 0]
    unsorted = np.concatenate([[False], (np.diff(t) <= 0) & (seg[1:] == seg[:-1])])
    if unsorted.any():
        _fail(p, unsorted, "time not strictly increasing within its trajectory")
    labels = {c: _per_trajectory(p, frame, c, starts, ends).astype(str) for c in LABEL_COLUMNS[1:]}
    return SampleTable(
        path=p,
        frame=frame,
        t=t,
        values=data[:, 1:],
        value_columns=tuple(numeric[1:]),
        starts=starts.astype(np.int64),
        ends=ends.astype(np.int64),
        ids=ids.astype(str),
        subjects=labels["subject"],
        tasks=labels["task"],
    )


def write_csv(frames: Sequence[pd.DataFrame], path: str | os.PathLike[str]) -> Path:
    """Concatenate per-trajectory frames and write them to ``path`` atomically.

    Floats are written with 17 significant digits, so a float64 read back is identical.
    A path ending in ``.gz`` is gzip-compressed.
    """
    text = pd.concat(frames, ignore_index=True).to_csv(index=False, float_format="%.17g")
    if str(path).lower().endswith(".gz"):
        return atomic_write_bytes(path, gzip.compress(text.encode("utf-8"), mtime=0))
    return atomic_write_text(path, text)
