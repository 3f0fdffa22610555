"""What every reader returns: a :class:`MocapRecording` (points in metres, file axes)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from motion_envs._typing import FloatArray

__all__ = ["MocapRecording"]


@dataclass(frozen=True)
class MocapRecording:
    """One motion capture file as read, before any conversion but the unit.

    Attributes
    ----------
    path:
        The file read.
    fmt:
        ``"c3d"``, ``"bvh"`` or ``"tsv"``.
    rate:
        Frame rate in Hz (from the file; within the physical bounds of
        :mod:`motion_envs.datasets.mocap._bounds`, checked on construction with the
        names and the positions' magnitude).
    labels:
        ``(M,)`` marker (C3D, TSV) or joint (BVH) names; ``""`` for an unlabelled
        Qualisys trajectory fragment.
    points:
        ``(F, M, 3)`` positions in metres in the file's axes; NaN where missing. For a
        BVH without a unit (``scale`` None) in the file's length unit.
    residuals:
        ``(F, M)`` C3D residuals (negative: missing), else None.
    quaternions:
        ``(F, M, 4)`` global orientation ``(w, x, y, z)`` of each BVH joint (forward
        kinematics, file axes), else None.
    scale:
        Metres per file unit used (None: unknown, a BVH read without ``unit``).
    first_frame:
        Number of the first frame, counted from 0: a C3D file's header value (ezc3d's
        ``header.points.first_frame``, e.g. 99 for a trial cropped to start at frame
        100), so that the file's own event times line up with :attr:`t`; 0 for BVH and
        TSV.
    """

    path: Path
    fmt: str
    rate: float
    labels: tuple[str, ...]
    points: FloatArray
    residuals: FloatArray | None = None
    quaternions: FloatArray | None = None
    scale: float | None = 1.0
    first_frame: int = 0

    def __post_init__(self) -> None:
        from motion_envs.datasets.mocap._bounds import check_recording

        check_recording(self)  # THE physical bounds, whichever reader built the recording

    @property
    def n_frames(self) -> int:
        return int(self.points.shape[0])

    @property
    def t(self) -> FloatArray:
        """``(F,)`` time of each frame in seconds: ``(first frame + k) / rate`` (C3D), else
        from the start of the file."""
        return (self.first_frame + np.arange(self.n_frames, dtype=np.float64)) / self.rate

    def index(self, name: str, what: str = "marker") -> int:
        """Column of the marker or joint ``name``; ``ValueError`` naming the file if absent."""
        try:
            return self.labels.index(name)
        except ValueError:
            known = sorted({x for x in self.labels if x})
            shown = ", ".join(known[:20]) + (" ..." if len(known) > 20 else "")
            raise ValueError(f"{self.path}: no {what} {name!r}; the file has: {shown}") from None

    def missing(self) -> NDArray[np.bool_]:
        """``(F, M)`` True where a sample is missing (NaN, or a negative residual)."""
        miss: NDArray[np.bool_] = np.logical_not(np.isfinite(self.points).all(axis=2))
        if self.residuals is not None:
            miss = miss | (self.residuals < 0)
        return miss
