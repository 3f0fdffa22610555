"""Ball flights assembled from a Qualisys TSV's unlabelled trajectory fragments.

Rules, in order (every decision is counted in the report):

1. Each unlabelled column is cut into fragments: runs of present samples.
2. Fragments shorter than :data:`MIN_FRAGMENT` frames are spurious (reflections,
   ghost markers) and dropped.
3. The remaining fragments are taken in order of their first frame. A fragment
   joins the ball track whose last sample is before its first one and whose ballistic
   prediction at the fragment's first time is nearest to it, within
   :data:`JOIN_TOLERANCE` m and :data:`MAX_PREDICTION` s: the prediction fits the track's
   last (up to 5) samples with constant horizontal velocity and a vertical motion
   under gravity ``g`` (``z = a + b t - g t^2 / 2``). A fragment that overlaps every
   track in time or is predicted by none starts a new track (another ball, or the
   same ball after a long occlusion).
4. The ball is the track with the most samples; the other tracks are ignored.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from motion_envs._typing import FloatArray

__all__ = ["JOIN_TOLERANCE", "MAX_PREDICTION", "MIN_FRAGMENT", "assemble_balls"]

#: Fragments with fewer frames are spurious.
MIN_FRAGMENT = 5
#: Largest distance (m) between a track's ballistic prediction and a fragment it joins.
JOIN_TOLERANCE = 0.05
#: Longest time (s) a track is extrapolated to join a fragment.
MAX_PREDICTION = 0.5
#: Gravity used by the prediction (m/s^2).
GRAVITY = 9.81


@dataclass
class _Track:
    frames: list[NDArray[np.int64]] = field(default_factory=list)
    points: list[FloatArray] = field(default_factory=list)

    @property
    def last(self) -> int:
        return int(self.frames[-1][-1])

    def size(self) -> int:
        return sum(f.size for f in self.frames)

    def predict(self, t: FloatArray, at: float) -> FloatArray:
        k = self.frames[-1][-5:]
        y = self.points[-1][-5:]
        tk = t[k] - t[k[-1]]
        dt = at - t[k[-1]]
        if k.size < 2:
            return y[-1] + np.array([0.0, 0.0, -0.5 * GRAVITY * dt * dt])
        z = y[:, 2] + 0.5 * GRAVITY * tk**2  # remove the known gravity, then a line
        design = np.stack([np.ones_like(tk), tk], axis=1)
        coef, *_ = np.linalg.lstsq(design, np.column_stack([y[:, :2], z]), rcond=None)
        pred = coef[0] + coef[1] * dt
        pred[2] -= 0.5 * GRAVITY * dt * dt
        out: FloatArray = pred
        return out


def assemble_balls(
    t: FloatArray, points: FloatArray, source: str
) -> tuple[FloatArray, NDArray[np.bool_], dict[str, int]]:
    """The ball ``(F, 3)`` (NaN where missing), its present mask and the decision counts.

    ``points`` ``(F, U, 3)`` are the unlabelled columns (NaN where absent, metres, Z-up);
    ``source`` names the file in the error raised when no fragment is long enough.
    """
    fragments: list[tuple[NDArray[np.int64], FloatArray]] = []
    spurious = 0
    for u in range(points.shape[1]):
        ok = np.isfinite(points[:, u]).all(axis=1)
        edges = np.diff(np.concatenate([[0], ok.astype(np.int8), [0]]))
        for s, e in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1), strict=True):
            if e - s < MIN_FRAGMENT:
                spurious += 1
                continue
            fragments.append((np.arange(s, e), points[s:e, u]))
    fragments.sort(key=lambda f: int(f[0][0]))
    tracks: list[_Track] = []
    joined = 0
    for frames, pts in fragments:
        best, best_err = None, JOIN_TOLERANCE
        for track in tracks:
            if track.last >= frames[0] or t[frames[0]] - t[track.last] > MAX_PREDICTION:
                continue
            err = float(np.linalg.norm(track.predict(t, float(t[frames[0]])) - pts[0]))
            if err <= best_err:
                best, best_err = track, err
        if best is None:
            tracks.append(_Track([frames], [pts]))
        else:
            best.frames.append(frames)
            best.points.append(pts)
            joined += 1
    if not tracks:
        raise ValueError(f"{source}: no unlabelled fragment of at least {MIN_FRAGMENT} frames")
    ball_track = max(tracks, key=lambda tr: tr.size())
    ball = np.full((t.size, 3), np.nan)
    for frames, pts in zip(ball_track.frames, ball_track.points, strict=True):
        ball[frames] = pts
    counts = {
        "fragments": len(fragments) + spurious,
        "spurious dropped": spurious,
        "joined by ballistic prediction": joined,
        "tracks": len(tracks),
        "other tracks ignored": len(tracks) - 1,
        "fragments in the ball": len(ball_track.frames),
    }
    return ball, np.isfinite(ball).all(axis=1), counts
