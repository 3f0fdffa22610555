"""THE physical bounds of a motion capture recording, checked on every one that is read.

Every reader (C3D, BVH, Qualisys TSV) builds a :class:`MocapRecording`, whose
construction calls :func:`check_recording` after the unit scaling, so ``motion-bench
import``, ``--data 'FILE?...'`` and the environments' ``data=`` are all held to the same
bounds (the CSV loaders have theirs in :mod:`motion_envs.datasets.sample_table`):

* a frame rate in ``[MIN_RATE_HZ, MAX_RATE_HZ]`` (1 Hz to 100 kHz: from a slow tracker
  to a high-speed camera), so every time ``k / rate`` is finite and the recording lasts
  at most :data:`MAX_DURATION_S`;
* marker or joint names unique (an unlabelled Qualisys fragment, ``""``, may repeat):
  a repeated name would silently stand for the first of its columns;
* positions in metres (once the unit is known) within :data:`MAX_ABS_POSITION_M` of
  the origin: a capture volume, not a city. Beyond it the declared unit does not fit a
  human body (a C3D declaring ``m`` for millimetre data puts a hand a kilometre away)
  and the recording is refused, naming a unit that would fit; positions all within
  :data:`MIN_EXTENT_M` of the origin get a warning (millimetres declared for metre data).
"""

from __future__ import annotations

import math
import warnings
from collections import Counter
from collections.abc import Sequence
from pathlib import Path
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from motion_envs.datasets.mocap._options import UNITS


class _Recording(Protocol):
    """What :func:`check_recording` reads of a ``MocapRecording``."""

    @property
    def path(self) -> Path: ...
    @property
    def fmt(self) -> str: ...
    @property
    def rate(self) -> float: ...
    @property
    def labels(self) -> tuple[str, ...]: ...
    @property
    def points(self) -> NDArray[np.float64]: ...
    @property
    def scale(self) -> float | None: ...
    @property
    def n_frames(self) -> int: ...


__all__ = [
    "MAX_ABS_POSITION_M",
    "MAX_DURATION_S",
    "MAX_RATE_HZ",
    "MIN_EXTENT_M",
    "MIN_RATE_HZ",
    "check_rate",
    "check_recording",
    "check_unique_names",
]

#: Slowest and fastest plausible frame rates (Hz).
MIN_RATE_HZ = 1.0
MAX_RATE_HZ = 100_000.0
#: Longest plausible recording (s): a day.
MAX_DURATION_S = 86_400.0
#: Farthest plausible position from the origin (m): a large capture volume.
MAX_ABS_POSITION_M = 100.0
#: Positions all this close to the origin (m) suggest a unit a thousand times too small.
MIN_EXTENT_M = 0.01


def check_rate(path: Path | str, rate: float, where: str) -> float:
    """``rate`` (Hz) when it is plausible, else a one-line ``ValueError`` naming the file
    and where the rate came from."""
    if not math.isfinite(rate) or rate <= 0:
        raise ValueError(f"{path}: frame rate {rate:g} Hz ({where}); expected > 0")
    if not MIN_RATE_HZ <= rate <= MAX_RATE_HZ:
        raise ValueError(
            f"{path}: frame rate {rate:g} Hz ({where}) is not a motion capture rate; "
            f"expected {MIN_RATE_HZ:g} to {MAX_RATE_HZ:g} Hz"
        )
    return float(rate)


def check_unique_names(path: Path | str, labels: Sequence[str], what: str) -> None:
    """A one-line ``ValueError`` naming the file and the names that repeat (``""``, an
    unlabelled fragment, may repeat)."""
    repeated = sorted(n for n, k in Counter(labels).items() if n and k > 1)
    if repeated:
        shown = ", ".join(repr(n) for n in repeated[:10]) + (" ..." if len(repeated) > 10 else "")
        raise ValueError(
            f"{path}: {what} name(s) {shown} appear more than once; each {what} needs its own "
            "name (rename them in the capture software)"
        )


def _fitting_unit(largest: float, scale: float) -> str | None:
    """A unit of :data:`UNITS` that puts ``largest`` (m at ``scale``) in a capture volume."""
    raw = largest / scale
    for name, metres in sorted(UNITS.items(), key=lambda kv: kv[1]):
        if MIN_EXTENT_M <= raw * metres <= MAX_ABS_POSITION_M / 10:
            return name
    return None


def check_recording(rec: _Recording) -> None:
    """Refuse (one-line ``ValueError`` naming the file) a recording outside the physical
    bounds of the module; warn when its positions are implausibly small."""
    check_rate(rec.path, rec.rate, rec.fmt.upper() + " header")
    end = (getattr(rec, "first_frame", 0) + rec.n_frames) / rec.rate  # the last time, s
    if end > MAX_DURATION_S:
        raise ValueError(
            f"{rec.path}: frames up to {end:.3g} s at {rec.rate:g} Hz, more than the "
            f"{MAX_DURATION_S:g} s of a recording"
        )
    check_unique_names(rec.path, rec.labels, "joint" if rec.fmt == "bvh" else "marker")
    if rec.scale is None or rec.points.size == 0:
        return  # a BVH read without a unit: lengths in an unknown unit
    finite = np.abs(rec.points[np.isfinite(rec.points)])
    if finite.size == 0:
        return
    largest = float(finite.max())
    unit = next((k for k, v in UNITS.items() if v == rec.scale), f"{rec.scale:g} m")
    if largest > MAX_ABS_POSITION_M:
        fits = _fitting_unit(largest, rec.scale)
        hint = f" (the data look like {fits}: give unit {fits})" if fits else ""
        raise ValueError(
            f"{rec.path}: positions up to {largest:.4g} m in unit {unit}, beyond the "
            f"{MAX_ABS_POSITION_M:g} m of a capture volume: the unit does not fit a human "
            f"body{hint}"
        )
    if largest < MIN_EXTENT_M:
        fits = _fitting_unit(largest, rec.scale)
        hint = f"; the data look like {fits}: give unit {fits}" if fits else ""
        warnings.warn(
            f"{rec.path}: every position is within {largest * 1000:.3g} mm of the origin in "
            f"unit {unit}: too small for a human body{hint}",
            UserWarning,
            stacklevel=3,
        )
