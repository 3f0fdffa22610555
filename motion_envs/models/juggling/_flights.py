"""Ball flights in recorded juggling: free-flight detection, gravity, releases and catches.

Input: ball marker positions ``(F, U, D)`` at times ``(F,)``, NaN where a marker is
missing, ``D`` = 2 (lateral, vertical) or 3 (two horizontal axes, vertical last; lengths
in metres). The ``U`` columns may be labelled balls or unlabelled trajectory fragments
(a column can hold several balls one after the other, gaps, marker swaps, spurious
markers).

Assumptions: a ball is in free fall (no drag) or in an open hand that pushes it; its
marker sits at the ball's centre (a reflective ball; a patch on a spinning ball moves
off the parabola by the ball's radius); two balls' markers are at least a ball's
diameter apart, so a label handed from one ball to another is a jump.

Steps (:func:`detect_flights`; every rejection is counted in :attr:`FlightAnalysis.counts`):

1. **Noise.** The measurement noise ``sigma`` is given or estimated from the data: the
   third difference of a polynomial of degree 2 is zero, so over every run of
   consecutive samples ``sigma = 1.4826 MAD(diff3) / sqrt(20)``, floored at
   :attr:`FlightOptions.min_noise`. The tolerance is ``tol = tolerance * sigma``.
2. **Fragments.** Each column is cut into runs of present samples (bridging gaps of up
   to 3 dropped frames), and a run again where one sample jumps from the last faster
   than :attr:`FlightOptions.max_speed` (plus ``tol``), and where a sample is off the
   line through the two samples before it and the sample before it off the line
   through the two after it, both by more than ``max_acceleration dt^2 + 5 sqrt(6)
   sigma`` (a bridged gap stays cut when either is): a marker swap, which a speed alone
   misses when the balls are a few centimetres apart. A fragment whose vertical
   acceleration (a quadratic over a window) is below ``-(gravity + pull_margin)`` by 4
   standard errors anywhere a window or more from its ends is not a ball (a hand's skin
   marker decelerates faster than gravity after each throw; a ball in an open hand
   cannot; near its ends a ball's marker may move as the palm covers it): dropped.
3. **Seeds.** On every fragment a window of :attr:`FlightOptions.window` seconds slides
   sample by sample; the vertical coordinate is fitted by a quadratic in time, each
   horizontal one by a line (free flight, no drag). A window is a seed when its residual
   rms is at most ``2 sigma`` and its vertical acceleration points down.
4. **Growth.** From the best seed (lowest rms) still free, a piece grows: the samples of
   the fragment on the current fit (residual at most ``tol`` in every coordinate, or an
   isolated outlier between two such samples), in the contiguous run that holds the
   seed; refit; repeat until the run no longer changes. Its ends are then placed by a
   change point: within half a window of each end, the split between the parabola and
   a free quadratic (the ball in the hand) with the least total squared residual. The
   piece's samples are taken, and the next best free seed grows. A piece is kept when
   its fitted downward acceleration is within :attr:`FlightOptions.gravity_range`
   widened by 4 standard errors of the fit.
5. **Joining.** Pieces in time order join a flight when one parabola fits both (every
   sample within ``max(tol, join_tolerance)`` of it, rms at most the larger of
   ``2 sigma`` and half that: a marker's position steps by a millimetre or two when the
   cameras that see it change; up to a window of samples at the two outer ends may be
   left out of that fit, each piece keeping at least half its samples), with at most
   :attr:`FlightOptions.max_join_gap` s between them: a flight split by a tracking gap,
   a swap or a camera switch, continued in another column, or seen twice (a duplicated
   marker). Flights that the order of joining left in two are joined after.
6. **Flights, releases and catches.** A joined flight is kept when it lasts at least
   :attr:`FlightOptions.min_duration` s and its downward acceleration, fitted on all its
   samples, is within :attr:`FlightOptions.gravity_range` (no widening). Its first
   sample is a **release** (``start_seen``) only when the same marker is seen just
   before it in a hand: within :attr:`FlightOptions.carry_window` s before it (same
   fragment, at least 4 samples) the marker rises :attr:`FlightOptions.carry_rise`
   above the flight's parabola and is above it on average (a hand holds the ball
   against gravity, so in the hand it is accelerated upward relative to free fall);
   the last sample is a **catch** (``end_seen``) on the same test after it. An end at a
   tracking loss, a swap, a camera switch the join did not bridge, or a fragment's end
   is neither.

Per flight: gravity ``g = -2 c2`` of ``z = c0 + c1 tau + c2 tau^2``, apex
``c0 - c1^2 / (4 c2)`` at ``tau = -c1 / (2 c2)``, first and last sample, whether they
are a release and a catch, residual rms. The pattern of the flights is
:func:`~motion_envs.models.juggling.pattern_summary`'s.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view
from numpy.typing import NDArray

from motion_envs._typing import FloatArray

__all__ = [
    "Flight",
    "FlightAnalysis",
    "FlightOptions",
    "detect_flights",
    "estimate_noise",
]

IntArray = NDArray[np.int64]

#: MAD to standard deviation for normal noise.
_MAD_TO_STD = 1.4826
#: Standard deviation of the third difference of unit white noise: sqrt(1 + 9 + 9 + 1).
_DIFF3_STD = math.sqrt(20.0)


@dataclass(frozen=True)
class FlightOptions:
    """How :func:`detect_flights` decides (module docstring, steps 1-6).

    Attributes
    ----------
    noise:
        Measurement noise std (m) of one coordinate; None: estimated from the data.
    min_noise:
        Floor of the noise (m), so that exact (synthetic) data keep a tolerance.
    tolerance:
        A sample is on a parabola when its residual is at most ``tolerance * noise`` in
        every coordinate.
    window:
        Seed window (s); at least 6 samples.
    min_duration:
        Shortest flight (s), first to last sample.
    gravity_range:
        ``(low, high)`` downward acceleration (m/s^2) of a flight: 9.81 +- 20 % (a
        hand's own arc seldom keeps one acceleration that close; lengths not in metres
        or a wrong up axis give no flight).
    max_speed:
        A jump between consecutive samples faster than this (m/s) cuts a fragment.
    max_acceleration:
        A sample that leaves the line through the two before it (and the two after it)
        by more than ``max_acceleration dt^2`` plus 5 noise std of a second difference
        cuts a fragment: a marker swap between two balls (their centres are a ball's
        diameter apart) or to a spurious marker, which a speed alone does not show.
    max_join_gap:
        Longest time (s) between two pieces of one flight.
    join_tolerance:
        Pieces of one flight may sit off one parabola by up to this (m), or the
        tolerance if larger: a marker's position steps when the cameras that see it
        change, and a re-identified marker can be offset by a millimetre or two.
    gravity:
        The gravity (m/s^2) a ball falls with, for the tests on the ball's vertical
        acceleration (``pull_margin``, ``carry_rise``); lengths must be in metres.
    pull_margin:
        A fragment whose vertical acceleration is below ``-(gravity + pull_margin)``
        (and 4 standard errors) is not a ball (:func:`_pulled_down`).
    carry_window:
        Time (s) after a catch (before a release) in which the ball, in the hand, must
        leave the flight's parabola upward by ``carry_rise``.
    carry_rise:
        How far (m) above the flight's parabola the hand takes the ball within
        ``carry_window``: the hand holds the ball against gravity, so a ball in the
        hand is accelerated upward relative to free fall.
    """

    noise: float | None = None
    min_noise: float = 1e-4
    tolerance: float = 4.5
    window: float = 0.06
    min_duration: float = 0.1
    gravity_range: tuple[float, float] = (7.8, 11.8)
    max_speed: float = 20.0
    max_acceleration: float = 500.0
    max_join_gap: float = 0.25
    join_tolerance: float = 0.005
    gravity: float = 9.81
    pull_margin: float = 5.0
    carry_window: float = 0.1
    carry_rise: float = 0.01

    def __post_init__(self) -> None:
        positive = {
            "min_noise": self.min_noise,
            "tolerance": self.tolerance,
            "window": self.window,
            "max_speed": self.max_speed,
            "max_acceleration": self.max_acceleration,
            "carry_window": self.carry_window,
            "carry_rise": self.carry_rise,
            "gravity": self.gravity,
            "pull_margin": self.pull_margin,
        }
        if self.noise is not None:
            positive["noise"] = self.noise
        for name, value in positive.items():
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"{name}: expected a finite number > 0; got {value!r}")
        for name, value in {
            "min_duration": self.min_duration,
            "max_join_gap": self.max_join_gap,
            "join_tolerance": self.join_tolerance,
        }.items():
            if not (math.isfinite(value) and value >= 0):
                raise ValueError(f"{name}: expected a finite number >= 0; got {value!r}")
        low, high = self.gravity_range
        if not (math.isfinite(low) and math.isfinite(high) and 0 < low < high):
            raise ValueError(
                f"gravity_range: expected finite 0 < low < high; got {self.gravity_range!r}"
            )


@dataclass(frozen=True)
class Flight:
    """One ball flight: samples, fit and events (times in the input's seconds).

    ``coef`` is ``(3, D)``: per coordinate ``c0 + c1 tau + c2 tau^2`` with
    ``tau = t - t_ref`` (horizontal ``c2`` = 0). ``start_seen``/``end_seen``: the ball
    was seen just before the first (after the last) sample, off the parabola: the
    release (catch) is then the first (last) sample, to one frame.
    """

    start: float
    end: float
    t_ref: float
    coef: FloatArray
    gravity: float
    gravity_se: float
    apex_height: float
    apex_time: float
    residual_rms: float
    n_samples: int
    pieces: int
    start_seen: bool
    end_seen: bool
    recording: str = ""

    @property
    def duration(self) -> float:
        return self.end - self.start

    def position(self, t: FloatArray | float) -> FloatArray:
        """``(..., D)`` the fitted position at times ``t``."""
        tau = np.asarray(t, dtype=np.float64)[..., None] - self.t_ref
        out: FloatArray = self.coef[0] + self.coef[1] * tau + self.coef[2] * tau**2
        return out

    def row(self, lateral: int = 0) -> dict[str, float | int | bool | str]:
        """The flight as a table row (release and catch on the ``lateral`` axis)."""
        ends = self.position(np.array([self.start, self.end]))
        return {
            "recording": self.recording,
            "start": self.start,
            "end": self.end,
            "duration": self.duration,
            "gravity": self.gravity,
            "gravity_se": self.gravity_se,
            "apex_height": self.apex_height,
            "apex_time": self.apex_time,
            "release_height": float(ends[0, -1]),
            "release_lateral": float(ends[0, lateral]),
            "catch_height": float(ends[1, -1]),
            "catch_lateral": float(ends[1, lateral]),
            "residual_rms": self.residual_rms,
            "n_samples": self.n_samples,
            "pieces": self.pieces,
            "start_seen": self.start_seen,
            "end_seen": self.end_seen,
        }


@dataclass(frozen=True)
class FlightAnalysis:
    """:func:`detect_flights`' result: the flights, the noise used, the decision counts."""

    flights: tuple[Flight, ...]
    noise: float
    counts: dict[str, int] = field(default_factory=dict)

    @property
    def gravity_median(self) -> float:
        """Median fitted gravity (m/s^2); NaN without flights."""
        if not self.flights:
            return math.nan
        return float(np.median([f.gravity for f in self.flights]))


# ----------------------------------------------------------------------------- fits


def _design(tau: FloatArray, degree: int) -> FloatArray:
    return np.stack([tau**k for k in range(degree + 1)], axis=-1)


def _fit(t: FloatArray, pts: FloatArray, t_ref: float) -> tuple[FloatArray, FloatArray]:
    """``(3, D)`` coefficients (vertical quadratic, horizontal lines) and residuals."""
    tau = t - t_ref
    coef = np.zeros((3, pts.shape[1]))
    quad = _design(tau, 2)
    coef[:, -1] = np.linalg.lstsq(quad, pts[:, -1], rcond=None)[0]
    if pts.shape[1] > 1:
        coef[:2, :-1] = np.linalg.lstsq(quad[:, :2], pts[:, :-1], rcond=None)[0]
    resid: FloatArray = pts - (coef[0] + coef[1] * tau[:, None] + coef[2] * tau[:, None] ** 2)
    return coef, resid


def _predict(coef: FloatArray, t: FloatArray, t_ref: float) -> FloatArray:
    tau = (t - t_ref)[:, None]
    out: FloatArray = coef[0] + coef[1] * tau + coef[2] * tau**2
    return out


def _gravity_se(t: FloatArray, t_ref: float, sigma: float) -> float:
    """Standard error of ``-2 c2`` for white noise ``sigma``."""
    quad = _design(t - t_ref, 2)
    try:
        cov = np.linalg.inv(quad.T @ quad)
    except np.linalg.LinAlgError:
        return math.inf
    return float(2.0 * sigma * math.sqrt(max(cov[2, 2], 0.0)))


def estimate_noise(points: FloatArray) -> float:
    """Noise std of one coordinate from the third differences of ``(F, U, D)`` points
    (NaN where missing), ``1.4826 MAD / sqrt(20)``; NaN when no four consecutive samples
    exist."""
    pts = np.asarray(points, dtype=np.float64)
    d3 = np.diff(pts, n=3, axis=0)
    vals = d3[np.isfinite(d3)]
    if vals.size == 0:
        return math.nan
    return float(_MAD_TO_STD * np.median(np.abs(vals - np.median(vals))) / _DIFF3_STD)


# ------------------------------------------------------------------------ fragments


def _fragments(
    t: FloatArray, points: FloatArray, max_speed: float, tol: float, jump: float, bridge: int = 3
) -> list[tuple[int, IntArray]]:
    """``(column, frame indices)`` of each fragment (step 2): runs of present samples
    (across gaps of at most ``bridge`` frames: dropped samples), cut where a step is
    faster than ``max_speed`` (plus ``tol``) and where a sample leaves the line through
    the two samples before it AND the line through the two after it by more than
    ``jump`` (m at one frame's spacing, growing with the square of a gap): a marker
    swap."""
    out: list[tuple[int, IntArray]] = []
    dt = float(np.median(np.diff(t))) if t.size > 1 else 1.0
    for u in range(points.shape[1]):
        ok = np.isfinite(points[:, u]).all(axis=1)
        present = np.flatnonzero(ok)
        if present.size == 0:
            continue
        breaks = np.flatnonzero(np.diff(present) > bridge + 1) + 1
        for idx in np.split(present.astype(np.int64), breaks):
            if idx.size < 2:
                out.append((u, idx))
                continue
            p = points[idx, u]
            tt = t[idx]
            h = np.diff(tt)
            step = np.linalg.norm(np.diff(p, axis=0), axis=1)
            cut = set((np.flatnonzero(step > max_speed * h + tol) + 1).tolist())
            cut.update((np.flatnonzero(np.diff(idx) > 1) + 1).tolist())  # re-tested below
            if idx.size >= 3:
                # e[j]: sample j + 2 off the line through samples j, j + 1; a jump
                # between samples i - 1 and i puts e[i - 2] and, backwards, the
                # residual of sample i - 1 from i, i + 1 over the limit
                fwd = p[2:] - p[1:-1] - (p[1:-1] - p[:-2]) * (h[1:] / h[:-1])[:, None]
                bwd = p[:-2] - p[1:-1] - (p[1:-1] - p[2:]) * (h[:-1] / h[1:])[:, None]
                scale = np.maximum(h[1:], h[:-1]) / dt
                limit = jump * scale**2
                big_f = np.linalg.norm(fwd, axis=1) > limit  # about sample j + 2
                big_b = np.linalg.norm(bwd, axis=1) > limit  # about sample j
                # cut before sample i when i is off the line of the two before it and
                # i - 1 off the line of the two after it
                i = np.arange(2, idx.size - 1)
                both = big_f[i - 2] & big_b[i - 1]
                cut.update(i[both].tolist())
                gaps = [c for c in cut if idx[c] - idx[c - 1] > 1]
                for c in gaps:  # a bridged gap stays cut unless both sides agree
                    if 2 <= c <= idx.size - 2 and not (big_f[c - 2] or big_b[c - 1]):
                        cut.discard(c)
            out.extend((u, part) for part in np.split(idx, sorted(cut)) if part.size)
    return out


@dataclass
class _Piece:
    """Samples of a ballistic piece (or of joined pieces) and, for each of its two
    ends, where the ball may be seen beyond it: ``(column, first frame, last frame)``
    of the samples of the same fragment before the first sample (after the last)."""

    t: FloatArray
    pts: FloatArray
    before: tuple[int, int, int]
    after: tuple[int, int, int]
    column: int
    count: int = 1


def _window_seeds(tt: FloatArray, pts: FloatArray, n_w: int, sigma: float) -> FloatArray:
    """rms of each window's fit; inf where the window is not a seed (step 3)."""
    tw = sliding_window_view(tt, n_w)  # (W, n)
    pw = sliding_window_view(pts, n_w, axis=0)  # (W, D, n)
    tau = tw - tw[:, n_w // 2 : n_w // 2 + 1]
    quad = _design(tau, 2)  # (W, n, 3)
    proj = np.linalg.pinv(quad)  # (W, 3, n)
    cz = np.einsum("wkn,wn->wk", proj, pw[:, -1, :])
    rz = pw[:, -1, :] - np.einsum("wnk,wk->wn", quad, cz)
    sq = np.sum(rz**2, axis=1)
    if pts.shape[1] > 1:
        lin = quad[:, :, :2]
        proj1 = np.linalg.pinv(lin)
        ch = np.einsum("wkn,wdn->wdk", proj1, pw[:, :-1, :])
        rh = pw[:, :-1, :] - np.einsum("wnk,wdk->wdn", lin, ch)
        sq = sq + np.sum(rh**2, axis=(1, 2))
    rms = np.sqrt(sq / (n_w * pts.shape[1]))
    seed = (rms <= 2.0 * sigma) & (cz[:, 2] < 0)
    out: FloatArray = np.where(seed, rms, np.inf)
    return out


def _within(resid: FloatArray, tol: float) -> NDArray[np.bool_]:
    """``(n,)`` True where a sample is on the curve: within ``tol`` in every coordinate,
    or an isolated outlier between two samples that are (noise has tails; the hand
    moves the ball off a parabola for several samples in a row)."""
    ok: NDArray[np.bool_] = np.asarray((np.abs(resid) <= tol).all(axis=1))
    if ok.size >= 3:
        lone = ~ok[1:-1] & ok[:-2] & ok[2:]
        ok[1:-1] |= lone
    return ok


def _grow(
    tt: FloatArray, pts: FloatArray, free: NDArray[np.bool_], lo: int, hi: int, tol: float
) -> tuple[int, int]:
    """Grow ``[lo, hi)`` over the free samples whose residual is within ``tol`` (step 4)."""
    n = tt.size
    for _ in range(50):
        t_ref = float(tt[(lo + hi) // 2])
        coef, _ = _fit(tt[lo:hi], pts[lo:hi], t_ref)
        good = _within(pts - _predict(coef, tt, t_ref), tol) & free
        mid = (lo + hi) // 2
        if not good[mid]:
            inside = np.flatnonzero(good[lo:hi])
            if inside.size == 0:
                return lo, hi
            mid = lo + int(inside[np.argmin(np.abs(inside + lo - mid))])
        bad = np.flatnonzero(~good)
        left = bad[bad < mid]
        right = bad[bad > mid]
        new_lo = int(left[-1]) + 1 if left.size else 0
        new_hi = int(right[0]) if right.size else n
        if (new_lo, new_hi) == (lo, hi):
            break
        lo, hi = new_lo, new_hi
    return lo, hi


def _sse(t: FloatArray, pts: FloatArray, flight: bool) -> float:
    """Residual sum of squares of a flight (vertical quadratic, horizontal lines) or of a
    free quadratic in every coordinate (the ball in the hand)."""
    t_ref = float(t[t.size // 2])
    if flight:
        _, resid = _fit(t, pts, t_ref)
    else:
        quad = _design(t - t_ref, 2)
        coef = np.linalg.lstsq(quad, pts, rcond=None)[0]
        resid = pts - quad @ coef
    return float(np.sum(resid**2))


def _longest(costs: dict[int, float], eps: float, first: bool) -> int:
    """The split of least cost; of splits within ``eps`` of it, the longest flight."""
    best = min(costs.values())
    near = [s for s, c in costs.items() if c <= best + eps]
    return min(near) if first else max(near)


def _refine(
    tt: FloatArray,
    pts: FloatArray,
    free: NDArray[np.bool_],
    lo: int,
    hi: int,
    k: int,
    eps: float,
) -> tuple[int, int]:
    """Release and catch of a grown piece ``[lo, hi)`` by a change point (step 4).

    Within ``k`` samples of each end the split between the flight (a parabola) and the
    ball in the hand (a free quadratic, on the up to ``k`` free samples beyond the end)
    with the least total squared residual (ties within ``eps``: the longest flight; a
    sample on both curves is in the flight); both sides keep at least 4 samples."""
    a = lo
    while a > 0 and free[a - 1] and lo - a < k:
        a -= 1
    if lo - a >= 2:
        costs = {
            s: _sse(tt[s:hi], pts[s:hi], True) + _sse(tt[a:s], pts[a:s], False)
            for s in range(max(lo, a + 4), min(lo + k, hi - 4) + 1)
        }
        if costs:
            lo = _longest(costs, eps, first=True)
    b = hi
    while b < tt.size and free[b] and b - hi < k:
        b += 1
    if b - hi >= 2:
        costs = {
            s: _sse(tt[lo:s], pts[lo:s], True) + _sse(tt[s:b], pts[s:b], False)
            for s in range(max(hi - k, lo + 4), min(hi, b - 4) + 1)
        }
        if costs:
            hi = _longest(costs, eps, first=False)
    return lo, hi


def _pulled_down(
    t: FloatArray,
    points: FloatArray,
    frag: tuple[int, IntArray],
    n_w: int,
    sigma: float,
    opts: FlightOptions,
) -> bool:
    """True when somewhere in the fragment, a window or more from its ends, the
    marker's vertical acceleration (a quadratic fitted over a window of ``n_w``
    samples) is below ``-(g + pull_margin)`` by more than 4 of its standard errors: a
    ball is in free fall or pushed up by a hand, never pulled down faster than gravity;
    a skin marker is, after each throw. (Near a fragment's ends a ball's marker may
    move as the palm covers it before it is lost: not counted.)"""
    column, idx = frag
    tt = t[idx]
    z = points[idx, column, -1]
    if idx.size < n_w:
        return False
    tw = sliding_window_view(tt, n_w)
    zw = sliding_window_view(z, n_w)
    tau = tw - tw[:, n_w // 2 : n_w // 2 + 1]
    quad = _design(tau, 2)
    proj = np.linalg.pinv(quad)  # (W, 3, n)
    accel = 2.0 * np.einsum("wn,wn->w", proj[:, 2, :], zw)
    se = 2.0 * sigma * np.linalg.norm(proj[:, 2, :], axis=1)
    limit = -(opts.gravity + opts.pull_margin) - 4.0 * se
    inner = accel[n_w : accel.size - n_w] < limit[n_w : accel.size - n_w]
    return bool(inner.any())


def _pieces(
    t: FloatArray,
    points: FloatArray,
    frag: tuple[int, IntArray],
    n_w: int,
    sigma: float,
    tol: float,
    options: FlightOptions,
    counts: dict[str, int],
) -> list[_Piece]:
    column, idx = frag
    tt = t[idx]
    pts = points[idx, column]
    rms = _window_seeds(tt, pts, n_w, sigma)
    free = np.ones(idx.size, dtype=bool)
    out: list[_Piece] = []
    low, high = options.gravity_range
    while True:
        csum = np.concatenate([[0], np.cumsum(free)])
        all_free = (csum[n_w:] - csum[:-n_w]) == n_w
        cand = np.where(all_free, rms, np.inf)
        w = int(np.argmin(cand))
        if not math.isfinite(cand[w]):
            break
        lo, hi = _grow(tt, pts, free, w, w + n_w, tol)
        lo, hi = _refine(tt, pts, free, lo, hi, max(n_w // 2, 6), (1e-3 * sigma) ** 2)
        free[lo:hi] = False
        rms[max(lo - n_w + 1, 0) : hi] = np.inf
        if hi - lo < n_w:
            counts["pieces too short"] += 1
            continue
        t_ref = float(tt[(lo + hi) // 2])
        coef, _ = _fit(tt[lo:hi], pts[lo:hi], t_ref)
        g = -2.0 * float(coef[2, -1])
        se = _gravity_se(tt[lo:hi], t_ref, sigma)
        if not (low - 4 * se <= g <= high + 4 * se):
            counts["pieces not ballistic"] += 1
            continue
        before = (column, int(idx[0]), int(idx[lo]))
        after = (column, int(idx[hi - 1]) + 1, int(idx[-1]) + 1)
        out.append(_Piece(tt[lo:hi], pts[lo:hi], before, after, column))
    return out


def _merge(a: _Piece, b: _Piece, tol: float, rms_max: float, k: int) -> _Piece | None:
    """``a`` and ``b`` as one flight, or None (step 5).

    One parabola must fit every sample within ``tol`` with rms at most ``rms_max``; up to
    ``k`` samples at each of the two outer ends may be left out of the fit (a short piece
    that ended in the hand, without samples enough beyond it for the change point); the
    outer samples within ``tol`` of that fit are then taken back. Each piece must keep at
    least half its samples."""
    t = np.concatenate([a.t, b.t])
    pts = np.concatenate([a.pts, b.pts])
    order = np.argsort(t, kind="stable")
    t, pts = t[order], pts[order]
    from_a = (order < a.t.size).astype(np.int64)
    n = t.size
    first = a if a.t[0] <= b.t[0] else b
    last = a if a.t[-1] >= b.t[-1] else b
    t_ref = float(0.5 * (t[0] + t[-1]))
    cuts = sorted(
        {(h, e) for h in (0, k // 2, k) for e in (0, k // 2, k) if n - h - e >= 2 * k},
        key=sum,
    )
    for head, tail in cuts:
        coef, resid = _fit(t[head : n - tail], pts[head : n - tail], t_ref)
        if not _within(resid, tol).all() or float(np.sqrt(np.mean(resid**2))) > rms_max:
            continue
        good = _within(pts - _predict(coef, t, t_ref), tol)
        lo, hi = head, n - tail
        while lo > 0 and good[lo - 1]:
            lo -= 1
        while hi < n and good[hi]:
            hi += 1
        kept_a = int(from_a[lo:hi].sum())
        if 2 * kept_a < a.t.size or 2 * (hi - lo - kept_a) < b.t.size:
            continue  # most of a piece left out: not one flight
        return _Piece(
            t[lo:hi],
            pts[lo:hi],
            first.before,
            last.after,
            first.column,
            a.count + b.count,
        )
    return None


def _join(
    pieces: list[_Piece],
    sigma: float,
    tol: float,
    max_gap: float,
    k: int,
    counts: dict[str, int],
    join_tolerance: float = 0.0,
) -> list[_Piece]:
    """Join the pieces of each flight (step 5): one parabola within
    ``max(tol, join_tolerance)`` of every sample, rms at most the larger of ``2 sigma``
    and half that."""
    tol = max(tol, join_tolerance)
    rms_max = max(2.0 * sigma, 0.5 * tol)
    groups: list[_Piece] = []
    for piece in sorted(pieces, key=lambda p: float(p.t[0])):
        best: tuple[int, _Piece] | None = None
        best_rms = math.inf
        for i, group in enumerate(groups):
            if piece.t[0] - group.t[-1] > max_gap or group.t[0] - piece.t[-1] > max_gap:
                continue
            merged = _merge(group, piece, tol, rms_max, k)
            if merged is None:
                continue
            _, resid = _fit(merged.t, merged.pts, float(merged.t[merged.t.size // 2]))
            rms = float(np.sqrt(np.mean(resid**2)))
            if rms < best_rms:
                best, best_rms = (i, merged), rms
        if best is None:
            groups.append(piece)
        else:
            groups[best[0]] = best[1]
            counts["pieces joined"] += 1
    merged_any = True
    while merged_any:  # groups that grew into one flight (the greedy order split them)
        merged_any = False
        groups.sort(key=lambda g: float(g.t[0]))
        for i, j in itertools.combinations(range(len(groups)), 2):
            a, b = groups[i], groups[j]
            if b.t[0] - a.t[-1] > max_gap or a.t[0] - b.t[-1] > max_gap:
                continue
            merged = _merge(a, b, tol, rms_max, k)
            if merged is not None:
                groups[i] = merged
                del groups[j]
                counts["pieces joined"] += 1
                merged_any = True
                break
    return groups


def _beyond(
    t: FloatArray,
    points: FloatArray,
    coef: FloatArray,
    t_ref: float,
    beyond: tuple[int, int, int],
    n_c: int,
    opts: FlightOptions,
    first: bool,
) -> int:
    """What the marker does just before the flight's first sample (``first``) or just
    after its last, within ``n_c`` samples of the same fragment (step 6): +1 the hand
    carries it (it rises ``carry_rise`` above the flight's parabola and is above it on
    average), -1 it falls ``carry_rise`` below it (below on average: no hand's carry;
    the marker moved as it was being lost, or is not a ball), 0 neither or fewer than
    4 samples. Only +1 makes the end a release or a catch."""
    column, a, b = beyond
    if first:
        a = max(a, b - n_c)
    else:
        b = min(b, a + n_c)
    if b - a < 4:
        return 0
    up = points[a:b, column, -1] - _predict(coef, t[a:b], t_ref)[:, -1]
    if up.max() >= opts.carry_rise and up.mean() > 0.0:
        return 1
    if up.min() <= -opts.carry_rise and up.mean() < 0.0:
        return -1
    return 0


def detect_flights(
    t: FloatArray,
    points: FloatArray,
    options: FlightOptions | None = None,
    recording: str = "",
) -> FlightAnalysis:
    """The free flights in ``points`` ``(F, U, D)`` at times ``t`` ``(F,)`` (module
    docstring). Raises ``ValueError`` for shapes that do not match, times that are not
    finite and strictly increasing, or infinite positions."""
    opts = options or FlightOptions()
    t = np.asarray(t, dtype=np.float64)
    points = np.asarray(points, dtype=np.float64)
    if points.ndim == 2:
        points = points[:, None, :]
    if t.ndim != 1 or points.ndim != 3 or points.shape[0] != t.size:
        raise ValueError(
            f"points: expected shape (F, U, D) with F = {t.size} times; got {points.shape}"
        )
    if points.shape[2] not in (2, 3):
        raise ValueError(f"points: expected D = 2 or 3 coordinates; got {points.shape[2]}")
    if not np.isfinite(t).all() or (t.size > 1 and (np.diff(t) <= 0).any()):
        raise ValueError("t: expected finite, strictly increasing times")
    if np.isinf(points).any():
        raise ValueError("points: infinite value (use NaN for a missing sample)")
    counts = {
        "fragments": 0,
        "fragments shorter than a window": 0,
        "fragments pulled down": 0,
        "pieces too short": 0,
        "pieces not ballistic": 0,
        "pieces": 0,
        "pieces joined": 0,
        "flights too short": 0,
        "flights not ballistic": 0,
        "flights": 0,
    }
    if opts.noise is not None:
        sigma = max(opts.noise, opts.min_noise)
    else:
        est = estimate_noise(points)
        sigma = opts.min_noise if not math.isfinite(est) else max(est, opts.min_noise)
    tol = opts.tolerance * sigma
    dt = float(np.median(np.diff(t))) if t.size > 1 else math.inf
    n_w = max(6, round(opts.window / dt) + 1) if math.isfinite(dt) else 6
    pieces: list[_Piece] = []
    jump = opts.max_acceleration * dt * dt + 5.0 * math.sqrt(6.0) * sigma
    for frag in _fragments(t, points, opts.max_speed, tol, jump):
        counts["fragments"] += 1
        if frag[1].size < n_w:
            counts["fragments shorter than a window"] += 1
            continue
        if _pulled_down(t, points, frag, n_w, sigma, opts):
            counts["fragments pulled down"] += 1
            continue
        pieces.extend(_pieces(t, points, frag, n_w, sigma, tol, opts, counts))
    counts["pieces"] = len(pieces)
    flights = []
    low, high = opts.gravity_range
    n_c = max(4, round(opts.carry_window / dt)) if math.isfinite(dt) else 4
    groups = _join(pieces, sigma, tol, opts.max_join_gap, n_w, counts, opts.join_tolerance)
    for group in groups:
        ft = group.t
        t_ref = float(0.5 * (ft[0] + ft[-1]))
        coef, resid = _fit(ft, group.pts, t_ref)
        if ft[-1] - ft[0] < opts.min_duration:
            counts["flights too short"] += 1
            continue
        g = -2.0 * float(coef[2, -1])
        if not low <= g <= high:
            counts["flights not ballistic"] += 1
            continue
        before = _beyond(t, points, coef, t_ref, group.before, n_c, opts, first=True)
        after = _beyond(t, points, coef, t_ref, group.after, n_c, opts, first=False)
        c0, c1, c2 = (float(c) for c in coef[:, -1])
        flights.append(
            Flight(
                start=float(ft[0]),
                end=float(ft[-1]),
                t_ref=t_ref,
                coef=coef,
                gravity=g,
                gravity_se=_gravity_se(ft, t_ref, sigma),
                apex_height=c0 - c1 * c1 / (4.0 * c2),
                apex_time=t_ref - c1 / (2.0 * c2),
                residual_rms=float(np.sqrt(np.mean(resid**2))),
                n_samples=int(ft.size),
                pieces=group.count,
                start_seen=before == 1,
                end_seen=after == 1,
                recording=recording,
            )
        )
    flights.sort(key=lambda f: f.start)
    counts["flights"] = len(flights)
    return FlightAnalysis(tuple(flights), sigma, counts)
