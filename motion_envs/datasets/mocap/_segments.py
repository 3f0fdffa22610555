"""Cutting a continuous recording into movements: by a speed threshold or by a table.

Speed rule (reaches)
--------------------
The speed of sample ``k`` is the central difference ``|y_{k+1} - y_{k-1}| /
(t_{k+1} - t_{k-1})`` (one-sided at the ends): m/s for positions, and for orientations
the angle between ``q_{k-1}`` and ``q_{k+1}`` over the same time (rad/s). A sample moves
when its speed is above ``threshold``. Runs of moving samples separated by fewer than
``min_pause`` seconds of rest are merged; a movement starts at the last resting sample
before its run and ends at the first resting sample after it (so it goes from rest to
rest, both ends at or below the threshold, clipped to the piece); movements shorter
than ``min_duration`` seconds are dropped (counted in the report).

Table rule
----------
A CSV with columns ``start,end`` (seconds from the start of the file, as the imported
``t``) and optionally ``subject``, ``task``, ``trajectory``: each row is a movement, the
samples with ``start <= t <= end``.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from motion_envs._io import check_regular_file
from motion_envs._typing import FloatArray
from motion_envs.datasets.mocap._options import MAX_SEGMENT_ROWS, MAX_SEGMENTS_BYTES
from motion_envs.datasets.sample_table import missing_columns_message, read_csv_exact
from motion_envs.geometry import quaternion as quat

__all__ = ["SegmentRow", "read_segments", "speed", "speed_segments"]


def speed(t: FloatArray, values: FloatArray, rotation: bool) -> FloatArray:
    """``(n,)`` central-difference speed (m/s, or rad/s for unit quaternions)."""
    if t.size < 2:
        return np.zeros(t.size)
    lo = np.concatenate([[0], np.arange(t.size - 2), [t.size - 2]])
    hi = np.concatenate([[1], np.arange(2, t.size), [t.size - 1]])
    if rotation:
        dist = quat.angle(values[lo], values[hi])
    else:
        dist = np.linalg.norm(values[hi] - values[lo], axis=1)
    out: FloatArray = dist / (t[hi] - t[lo])
    return out


def speed_segments(
    t: FloatArray, s: FloatArray, threshold: float, min_duration: float, min_pause: float
) -> tuple[list[tuple[int, int]], int]:
    """Movements ``[(first, last), ...]`` (inclusive sample indices) by the speed rule.

    Returns the movements and how many were dropped as shorter than ``min_duration``.
    """
    moving = np.concatenate([[0], (s > threshold).astype(np.int8), [0]])
    edges = np.diff(moving)
    starts, stops = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1) - 1
    merged: list[list[int]] = []
    for a, b in zip(starts.tolist(), stops.tolist(), strict=True):
        if merged and t[a] - t[merged[-1][1]] < min_pause:
            merged[-1][1] = b
        else:
            merged.append([a, b])
    out, short = [], 0
    for a, b in merged:
        first, last = max(a - 1, 0), min(b + 1, t.size - 1)
        if t[last] - t[first] < min_duration:
            short += 1
            continue
        out.append((first, last))
    return out, short


@dataclass(frozen=True)
class SegmentRow:
    """One row of a segments table: a movement from ``start`` to ``end`` seconds."""

    start: float
    end: float
    subject: str | None
    task: str | None
    trajectory: str | None
    line: int


def _seconds(value: object) -> float:
    """A table cell as seconds (NaN when it is not a number; inf when too large)."""
    try:
        return float(str(value))
    except ValueError:
        return math.nan


def read_segments(path: str | os.PathLike[str]) -> list[SegmentRow]:
    """Read a segments CSV (module docstring); ``ValueError`` naming the file and line.

    A regular file of at most ``MAX_SEGMENTS_BYTES`` bytes and ``MAX_SEGMENT_ROWS`` rows."""
    p = Path(path)
    if not os.path.lexists(p):
        raise FileNotFoundError(f"segments table {p} does not exist")
    check_regular_file(p, max_bytes=MAX_SEGMENTS_BYTES)  # no FIFO, device or folder
    try:
        frame = read_csv_exact(p, dtype={"subject": str, "task": str, "trajectory": str})
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as exc:
        raise ValueError(f"{p}: not a segments CSV ({' '.join(str(exc).split())})") from None
    if len(frame) > MAX_SEGMENT_ROWS:
        raise ValueError(
            f"{p}: {len(frame)} segments, more than the {MAX_SEGMENT_ROWS} movements a "
            "recording is cut into"
        )
    missing = [c for c in ("start", "end") if c not in frame.columns]
    if missing:
        expected = "start,end[,subject,task]"
        raise ValueError(missing_columns_message(str(p), frame.columns, missing, expected))
    times = np.array(
        [[_seconds(v) for v in frame[col]] for col in ("start", "end")], dtype=np.float64
    ).T.reshape(-1, 2)  # cell by cell: an integer too large for a float is inf, not an error
    rows = []
    for i, (start, end) in enumerate(times):
        if not (np.isfinite(start) and np.isfinite(end) and end > start):
            raise ValueError(f"{p}: line {i + 2}: start and end must be numbers with end > start")

        def label(col: str, i: int = i) -> str | None:
            if col not in frame.columns or pd.isna(frame[col].iloc[i]):
                return None
            return str(frame[col].iloc[i])

        rows.append(
            SegmentRow(
                float(start),
                float(end),
                label("subject"),
                label("task"),
                label("trajectory"),
                i + 2,
            )
        )
    if not rows:
        raise ValueError(f"{p}: no segments")
    return rows
