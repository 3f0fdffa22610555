"""Missing samples: short gaps filled (linear for positions, slerp for orientations),
long gaps split the recording into gap-free pieces."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from motion_envs._typing import FloatArray
from motion_envs.datasets.ragged import MIN_SAMPLES
from motion_envs.geometry import quaternion as quat

__all__ = ["GapCounts", "Piece", "fill_gaps"]


@dataclass(frozen=True)
class Piece:
    """A gap-free run of frames ``start .. stop - 1``: times ``(n,)`` and values ``(n, D)``."""

    start: int
    stop: int
    t: FloatArray
    values: FloatArray


@dataclass(frozen=True)
class GapCounts:
    """How the missing samples of one track were handled.

    ``missing`` samples were missing in the file; ``filled`` of them were interpolated
    (gaps of at most ``max_gap`` frames between two present samples); ``dropped`` frames
    are in no piece: the missing ones not filled (at the ends or in longer gaps) and the
    present ones of pieces shorter than the 5 samples a trajectory needs.
    """

    missing: int
    filled: int
    dropped: int
    pieces: int


def _runs(mask: NDArray[np.bool_]) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Start and one-past-end indices of the runs of True in ``mask``."""
    padded = np.concatenate([[False], mask, [False]]).astype(np.int8)
    edges = np.diff(padded)
    return np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)


def fill_gaps(
    t: FloatArray, values: FloatArray, present: NDArray[np.bool_], max_gap: int, rotation: bool
) -> tuple[list[Piece], GapCounts]:
    """Fill gaps of at most ``max_gap`` frames and split at longer ones.

    ``values`` ``(F, D)``: positions (``rotation`` False; filled by linear interpolation
    in time) or unit quaternions ``(w, x, y, z)`` (``rotation`` True; made
    sign-continuous over the present samples first, then filled by slerp between the
    two present neighbours). Missing samples before the first or after the last present
    one are dropped. Pieces with fewer than 5 samples are dropped too.
    """
    present = np.asarray(present, dtype=bool)
    out = np.array(values, dtype=np.float64, copy=True)
    if rotation and present.any():
        out[present] = quat.make_continuous(out[present])
    starts, stops = _runs(~present)
    interior = (starts > 0) & (stops < present.size)
    fill = interior & (stops - starts <= max_gap)
    fillable = np.zeros(present.size, dtype=bool)
    for s, e in zip(starts[fill], stops[fill], strict=True):
        fillable[s:e] = True
    idx = np.flatnonzero(fillable)
    if idx.size:
        known = np.flatnonzero(present)
        right = known[np.searchsorted(known, idx)]
        left = known[np.searchsorted(known, idx) - 1]
        frac = (t[idx] - t[left]) / (t[right] - t[left])
        if rotation:
            out[idx] = quat.slerp(out[left], out[right], frac, validate=False)
        else:
            out[idx] = out[left] + frac[:, None] * (out[right] - out[left])
    usable = present | fillable
    piece_starts, piece_stops = _runs(usable)
    pieces = []
    short = 0
    for s, e in zip(piece_starts, piece_stops, strict=True):
        if e - s < MIN_SAMPLES:
            short += int(e - s)
            continue
        pieces.append(Piece(int(s), int(e), t[s:e].copy(), out[s:e].copy()))
    counts = GapCounts(
        missing=int((~present).sum()),
        filled=int(fillable.sum()),
        dropped=int((~usable).sum()) + short,
        pieces=len(pieces),
    )
    return pieces, counts
