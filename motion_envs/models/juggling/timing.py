r"""A juggling pattern's timing measured from its trajectories: the balls' releases and
catches, each throw's value, the beat, the dwell and the dwell ratio, the flight and
height of each throw value, the hands' span.

Input: :class:`PatternTrajectories`, the two hands' and the balls' positions in the
vertical plane of the pattern (``x`` lateral, ``z`` up, metres; NaN where a marker is
missing), from a simulation or from a recording (:func:`read_pattern_markers`: a C3D or
Qualisys TSV file through :func:`motion_envs.datasets.mocap.read_recording`, or a CSV of
``t`` and ``<marker>_x, <marker>_z`` columns). Nothing here knows the pattern played:
every quantity is measured from the positions alone.
(:func:`motion_envs.models.juggling.detect_flights` finds flights from ball markers
alone, unlabelled fragments included; this module needs labelled balls and both hands,
and from the hands it gets the thrower, the catcher and each dwell.)

**Flights** (:func:`detect_throws`). For each ball, the frames where it is farther than
``contact_radius`` from both hands are runs (the *core* of a flight, at least
``min_core_frames`` frames). A run is a flight when a parabola fits it: ``x`` linear in
time and ``z`` quadratic with the quadratic's acceleration within ``accel_tolerance`` of
``-g`` (``|2c + g| <= accel_tolerance * g``); a carried ball held away from the hand
fails this. Its **release** is the change point, in the frames before the core back to
the previous flight (at most ``search_window`` s), where the ball stops following its
hand (``ball - hand - offset``, ``offset`` the ball's median offset from that hand while
within ``contact_radius`` of it: a marker on the back of the hand is not the ball's
centre) and starts following the core's parabola (fitted with ``g`` fixed): the ``k``
minimising ``sum_{i<k} |ball_i - hand_i - offset|^2 + sum_{i>=k} |ball_i -
parabola_i|^2``, the release put halfway between frames ``k - 1`` and ``k``. The
**catch** is the same change point after the core (parabola, then hand). The thrower
(catcher) is the hand nearest the ball at the release (catch). A run at the start or
end of the data, or next to a missing frame, has no release (catch) and is not a flight.

**Timing** (:func:`measure_timing`). The beat ``b``: the releases of both hands, in
order, are on beats ``k_i`` (``k_0 = 0``, each gap rounded to whole beats of the median
of the gaps shorter than 1.5 times their first quartile: a held ``2`` leaves a gap of
two beats), and ``b`` is the least-squares slope of ``t_i = t_0 + k_i b``. For a flight,
``G`` is the time from its release to the same ball's next release and ``d`` its dwell,
from its catch to that release, measured only when the ball is seen within
``contact_radius`` of a hand all that time (a flight missed in a gap of the data leaves
it unknown). Since a hand holds a caught ball less than its own period ``2b`` unless it
holds it over beats (a ``2``), ``n = floor(d / 2b)`` is the number of beats held and the
throw's value is ``h = round(G / b) - 2n`` (siteswap: the ball thrown on beat ``k`` with
value ``h`` is thrown again on beat ``k + h``). The dwell ``D``: the median of ``d -
2nb`` (the catch to the beat the ball landed on) after the throws of 3 or more (all
throws if there are none); the dwell ratio ``r = D / 2b``. Per throw value: the
flights', dwells' and heights' (apex above the release: ``v_z^2 / 2g`` of the fitted
parabola) medians. The tempo: the share of beats with a throw (the throws of known value
over those plus the beats held after them) over ``b``; per hand, its throws of known
value over those plus the beats it held, over its period ``2b`` (each ball's last throw
has no value, so at the ends a throw or a hold may be missing from the count: about 1/40
at 40 throws). The span: each hand's horizontal range (5th to 95th percentile), and the
mean distance of the release and catch points from the pattern's midline (the mean of
the two hands' ``x``).
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from motion_envs._typing import FloatArray

__all__ = [
    "MIN_RATE_HZ",
    "PatternTiming",
    "PatternTrajectories",
    "Throw",
    "TimingOptions",
    "detect_throws",
    "measure_timing",
    "read_pattern_markers",
]

#: The slowest sampling a timing is measured at (a 20 ms frame already blurs a release).
MIN_RATE_HZ = 50.0
#: Hands a pattern is juggled with.
HANDS = 2


@dataclass(frozen=True)
class PatternTrajectories:
    """Positions in the pattern's vertical plane, metres: ``t`` ``(F,)`` s strictly
    increasing; ``hands`` ``(F, 2, 2)`` (right, left; ``x, z``); ``balls`` ``(F, N, 2)``;
    NaN where missing. ``source`` names where they come from; ``simulated`` labels
    SIMULATED trajectories."""

    t: FloatArray
    hands: FloatArray
    balls: FloatArray
    source: str
    simulated: bool = False

    def __post_init__(self) -> None:
        t, hands, balls = (
            np.asarray(a, dtype=np.float64) for a in (self.t, self.hands, self.balls)
        )
        src = self.source
        if t.ndim != 1 or t.size < 10:
            raise ValueError(f"{src}: t must be 1-D with at least 10 samples; got {t.shape}")
        if not np.isfinite(t).all() or not (np.diff(t) > 0).all():
            raise ValueError(f"{src}: t must be finite and strictly increasing")
        if hands.shape != (t.size, HANDS, 2):
            raise ValueError(f"{src}: hands must be ({t.size}, 2, 2); got {hands.shape}")
        if balls.ndim != 3 or balls.shape[0] != t.size or balls.shape[2] != 2:
            raise ValueError(f"{src}: balls must be ({t.size}, N, 2); got {balls.shape}")
        if balls.shape[1] < 1:
            raise ValueError(f"{src}: no ball")
        rate = 1.0 / float(np.median(np.diff(t)))
        if rate < MIN_RATE_HZ:
            raise ValueError(
                f"{src}: sampled at {rate:.3g} Hz; measuring a timing needs at least "
                f"{MIN_RATE_HZ:g} Hz"
            )
        for name, a in (("hands", hands), ("balls", balls)):
            if np.isinf(a).any():
                raise ValueError(f"{src}: {name} has infinite positions")
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "hands", hands)
        object.__setattr__(self, "balls", balls)


@dataclass(frozen=True)
class TimingOptions:
    """The detector's settings (module docstring); ``skip_start``: s from the start whose
    releases are not counted (a simulation's start from rest); ``skip_end``: s before the
    end whose catches are not counted (the throws before a drop)."""

    gravity: float = 9.81
    contact_radius: float = 0.08
    min_core_frames: int = 4
    accel_tolerance: float = 0.25
    search_window: float = 0.2
    skip_start: float = 0.0
    skip_end: float = 0.0

    def __post_init__(self) -> None:
        checks = {
            "gravity": (0.1, 100.0),
            "contact_radius": (1e-3, 1.0),
            "accel_tolerance": (0.01, 1.0),
            "search_window": (0.01, 2.0),
            "skip_start": (0.0, 1e4),
            "skip_end": (0.0, 1e4),
        }
        for name, (lo, hi) in checks.items():
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and lo <= v <= hi):
                raise ValueError(f"TimingOptions.{name} must be in [{lo:g}, {hi:g}]; got {v!r}")
        if not (isinstance(self.min_core_frames, int) and self.min_core_frames >= 3):
            raise ValueError(
                f"TimingOptions.min_core_frames must be an int >= 3; got {self.min_core_frames!r}"
            )


@dataclass(frozen=True)
class Throw:
    """One throw: ``ball`` index, ``release`` and ``catch`` times (s), ``thrower`` and
    ``catcher`` (0 right, 1 left), the apex ``height`` above the release (m), the release
    and catch points ``(x, z)`` (m)."""

    ball: int
    release: float
    catch: float
    thrower: int
    catcher: int
    height: float
    release_point: tuple[float, float]
    catch_point: tuple[float, float]

    @property
    def duration(self) -> float:
        """s in the air."""
        return self.catch - self.release


@dataclass(frozen=True)
class PatternTiming:
    """What :func:`measure_timing` measured (module docstring; times in s, lengths in m).

    ``values``: each counted flight's throw value (0: unknown, the ball's last flight);
    ``holds``: each counted flight's beats held after its catch; ``dwells``: each
    counted flight's dwell (NaN for the last); ``*_by_value``: medians per throw value.
    """

    source: str
    simulated: bool
    flights: tuple[Throw, ...]
    values: tuple[int, ...]
    holds: tuple[int, ...]
    dwells: tuple[float, ...]
    beat: float
    beat_residual: float
    dwell: float
    dwell_ratio: float
    throws_per_second: float
    throws_per_second_per_hand: tuple[float, float]
    flight_by_value: dict[int, float] = field(default_factory=dict)
    dwell_by_value: dict[int, float] = field(default_factory=dict)
    height_by_value: dict[int, float] = field(default_factory=dict)
    count_by_value: dict[int, int] = field(default_factory=dict)
    hand_span: tuple[float, float] = (math.nan, math.nan)
    release_offset: float = math.nan
    catch_offset: float = math.nan

    def summary(self) -> dict[str, Any]:
        """The scalars and the per-value tables (JSON-ready; value keys as text)."""

        def table(d: dict[int, float] | dict[int, int]) -> dict[str, float]:
            return {str(k): float(v) for k, v in sorted(d.items())}

        return {
            "source": self.source,
            "simulated": self.simulated,
            "throws": len(self.flights),
            "beat": self.beat,
            "beat_residual": self.beat_residual,
            "dwell": self.dwell,
            "dwell_ratio": self.dwell_ratio,
            "throws_per_second": self.throws_per_second,
            "throws_per_second_per_hand": list(self.throws_per_second_per_hand),
            "flight_by_value": table(self.flight_by_value),
            "dwell_by_value": table(self.dwell_by_value),
            "height_by_value": table(self.height_by_value),
            "count_by_value": table(self.count_by_value),
            "hand_span": list(self.hand_span),
            "release_offset": self.release_offset,
            "catch_offset": self.catch_offset,
        }


def _runs(mask: NDArray[np.bool_]) -> list[tuple[int, int]]:
    """``[start, end)`` of each run of True."""
    edges = np.diff(np.concatenate([[0], mask.astype(np.int8), [0]]))
    return list(
        zip(np.flatnonzero(edges == 1).tolist(), np.flatnonzero(edges == -1).tolist(), strict=True)
    )


def _contact(
    traj: PatternTrajectories, j: int, radius: float
) -> tuple[NDArray[np.bool_], NDArray[np.int64], NDArray[np.bool_]]:
    """Ball ``j``'s frames with the ball and both hands seen, its nearest hand, and the
    seen frames where it is within ``radius`` of that hand."""
    ball = traj.balls[:, j]
    ok = np.asarray(
        np.isfinite(ball).all(axis=1) & np.isfinite(traj.hands).all(axis=(1, 2)), dtype=bool
    )
    dist = np.linalg.norm(ball[:, None, :] - traj.hands, axis=2)
    dist[~ok] = np.inf
    near = np.argmin(dist, axis=1).astype(np.int64)
    within = np.asarray(ok & (dist.min(axis=1) <= radius), dtype=bool)
    return ok, near, within


def _offsets(
    ball: FloatArray, hands: FloatArray, near: NDArray[np.int64], within: NDArray[np.bool_]
) -> FloatArray:
    """``(2, 2)``: the ball's median offset from each hand over the frames it is within
    the contact radius of that hand (0 where it never is)."""
    out = np.zeros((HANDS, 2))
    for h in range(HANDS):
        k = within & (near == h)
        if k.any():
            out[h] = np.median(ball[k] - hands[k, h], axis=0)
    return out


def _change_point(before: FloatArray, after: FloatArray) -> int:
    """``k`` in ``[0, n]`` minimising ``sum(before[:k]) + sum(after[k:])`` (squared
    errors per frame)."""
    cost = np.concatenate([[0.0], np.cumsum(before)]) + np.concatenate(
        [np.cumsum(after[::-1])[::-1], [0.0]]
    )
    return int(np.argmin(cost))


def detect_throws(traj: PatternTrajectories, options: TimingOptions | None = None) -> list[Throw]:
    """Every flight of every ball, by release time (module docstring)."""
    opts = options or TimingOptions()
    g = opts.gravity
    t = traj.t
    window = opts.search_window
    flights: list[Throw] = []
    for j in range(traj.balls.shape[1]):
        ball = traj.balls[:, j]
        ok, near, within = _contact(traj, j, opts.contact_radius)
        dmin = np.linalg.norm(ball - traj.hands[np.arange(t.size), near], axis=1)
        off = _offsets(ball, traj.hands, near, within)
        core = ok & (dmin > opts.contact_radius)
        runs = [(s, e) for s, e in _runs(core) if e - s >= opts.min_core_frames]
        prev_end = 0
        for idx, (s, e) in enumerate(runs):
            if s == 0 or e >= t.size or not (within[s - 1] and within[e]):
                prev_end = e
                continue
            tau = t[s:e] - t[s]
            design = np.stack([np.ones_like(tau), tau, tau**2], axis=1)
            free, *_ = np.linalg.lstsq(design, ball[s:e, 1], rcond=None)
            if abs(2.0 * free[2] + g) > opts.accel_tolerance * g:
                prev_end = e
                continue
            lin = design[:, :2]
            cx, *_ = np.linalg.lstsq(lin, ball[s:e, 0], rcond=None)
            cz, *_ = np.linalg.lstsq(lin, ball[s:e, 1] + 0.5 * g * tau**2, rcond=None)

            def parabola(
                i: NDArray[np.int64],
                cx: FloatArray = cx,
                cz: FloatArray = cz,
                t0: float = float(t[s]),
            ) -> FloatArray:
                u = t[i] - t0
                return np.stack([cx[0] + cx[1] * u, cz[0] + cz[1] * u - 0.5 * g * u**2], axis=1)

            # the release: frames [lo, s) hold the change from hand to parabola
            lo = s - 1
            while lo > prev_end and ok[lo - 1] and t[s] - t[lo - 1] <= window:
                lo -= 1
            thrower = int(near[s - 1])
            i = np.arange(lo, s)
            on_hand = np.sum((ball[i] - traj.hands[i, thrower] - off[thrower]) ** 2, axis=1)
            on_par = np.sum((ball[i] - parabola(i)) ** 2, axis=1)
            k = lo + _change_point(on_hand, on_par)
            release = float(t[k]) if k == lo else 0.5 * float(t[k - 1] + t[k])
            # the catch: frames [e, hi) hold the change from parabola to hand
            nxt = runs[idx + 1][0] if idx + 1 < len(runs) else t.size
            hi = e + 1
            while hi < nxt and ok[hi] and t[hi] - t[e - 1] <= window:
                hi += 1
            catcher = int(near[e])
            i = np.arange(e, hi)
            on_par = np.sum((ball[i] - parabola(i)) ** 2, axis=1)
            on_hand = np.sum((ball[i] - traj.hands[i, catcher] - off[catcher]) ** 2, axis=1)
            k = e + _change_point(on_par, on_hand)
            catch = float(t[k]) if k == e else 0.5 * float(t[k - 1] + t[k])
            vz = cz[1] - g * (release - t[s])
            u = release - t[s]
            rel = (float(cx[0] + cx[1] * u), float(cz[0] + cz[1] * u - 0.5 * g * u * u))
            u = catch - t[s]
            cat = (float(cx[0] + cx[1] * u), float(cz[0] + cz[1] * u - 0.5 * g * u * u))
            flights.append(
                Throw(
                    j,
                    release,
                    catch,
                    thrower,
                    catcher,
                    float(max(vz, 0.0) ** 2 / (2 * g)),
                    rel,
                    cat,
                )
            )
            prev_end = e
    flights.sort(key=lambda f: f.release)
    return flights


def _median_by(values: Sequence[int], data: Sequence[float]) -> dict[int, float]:
    out: dict[int, float] = {}
    for v in sorted(set(values) - {0}):
        x = [d for w, d in zip(values, data, strict=True) if w == v and math.isfinite(d)]
        if x:
            out[v] = float(np.median(x))
    return out


def measure_timing(
    traj: PatternTrajectories, options: TimingOptions | None = None
) -> PatternTiming:
    """The pattern's timing (module docstring); ``ValueError`` naming the source when
    fewer than 4 releases are counted (no beat can be measured)."""
    opts = options or TimingOptions()
    every = detect_throws(traj, opts)
    start, end = traj.t[0] + opts.skip_start, traj.t[-1] - opts.skip_end
    counted = [f for f in every if f.release >= start and f.catch <= end]
    if len(counted) < 4:
        raise ValueError(
            f"{traj.source}: {len(counted)} throws detected (release and catch both seen); "
            "at least 4 are needed to measure a beat (check the hand and ball markers and "
            "contact_radius)"
        )
    rel = np.array([f.release for f in counted])
    gaps = np.diff(rel)
    # the beat's first guess: the shorter gaps' median (a hold, a 2, leaves a gap of 2b)
    short = gaps[gaps < 1.5 * np.percentile(gaps, 25)]
    b0 = float(np.median(short))
    k = np.concatenate([[0], np.cumsum(np.maximum(np.rint(gaps / b0), 1))])
    slope, intercept = np.polyfit(k, rel, 1)
    beat = float(slope)
    residual = float(np.sqrt(np.mean((rel - (intercept + slope * k)) ** 2)))
    # each flight's next release of the same ball (among every flight detected)
    values: list[int] = []
    holds: list[int] = []
    dwells: list[float] = []
    in_hand = [_contact(traj, j, opts.contact_radius)[2] for j in range(traj.balls.shape[1])]
    for f in counted:
        nxt = [x for x in every if x.ball == f.ball and x.release > f.catch]
        inside = (traj.t > f.catch) & (traj.t < nxt[0].release) if nxt else None
        if inside is None or not in_hand[f.ball][inside][1:-1].all():
            values.append(0)
            holds.append(0)
            dwells.append(math.nan)
            continue
        n2 = nxt[0]
        d = n2.release - f.catch
        n = math.floor(d / (2.0 * beat))
        h = round((n2.release - f.release) / beat) - 2 * n
        values.append(max(h, 0))
        holds.append(n)
        dwells.append(d)
    plain = [d - 2.0 * n * beat for d, n in zip(dwells, holds, strict=True)]
    high = [d for d, v in zip(plain, values, strict=True) if v >= 3 and math.isfinite(d)]
    pool = high or [d for d in plain if math.isfinite(d)]
    dwell = float(np.median(pool)) if pool else math.nan
    # the tempo: the beats with a throw (not a hold) per second; per hand, its throws
    # against the beats it held, per hand period 2b
    known = sum(v > 0 for v in values)
    tempo = known / (known + sum(holds)) / beat if known else math.nan
    per_hand = []
    for h in range(HANDS):
        thrown = sum(f.thrower == h and v > 0 for f, v in zip(counted, values, strict=True))
        held = sum(n for f, n in zip(counted, holds, strict=True) if f.catcher == h)
        per_hand.append(thrown / (thrown + held) / (2.0 * beat) if thrown else math.nan)
    # the span: the hands' horizontal ranges over the counted time
    keep = (traj.t >= start) & (traj.t <= end)
    x = traj.hands[keep, :, 0]
    hand_span = tuple(
        float(np.nanpercentile(x[:, h], 95) - np.nanpercentile(x[:, h], 5)) for h in range(HANDS)
    )
    mid = float(np.nanmean(x))
    return PatternTiming(
        source=traj.source,
        simulated=traj.simulated,
        flights=tuple(counted),
        values=tuple(values),
        holds=tuple(holds),
        dwells=tuple(dwells),
        beat=beat,
        beat_residual=residual,
        dwell=dwell,
        dwell_ratio=dwell / (2.0 * beat),
        throws_per_second=tempo,
        throws_per_second_per_hand=(per_hand[0], per_hand[1]),
        flight_by_value=_median_by(values, [f.duration for f in counted]),
        dwell_by_value=_median_by(values, plain),
        height_by_value=_median_by(values, [f.height for f in counted]),
        count_by_value={v: values.count(v) for v in sorted(set(values) - {0})},
        hand_span=(hand_span[0], hand_span[1]),
        release_offset=float(np.mean([abs(f.release_point[0] - mid) for f in counted])),
        catch_offset=float(np.mean([abs(f.catch_point[0] - mid) for f in counted])),
    )


#: Axis names :func:`read_pattern_markers` takes.
_AXES = {"x": 0, "y": 1}


def _csv_markers(path: Path, names: Sequence[str]) -> tuple[FloatArray, FloatArray]:
    """``t`` and ``(F, M, 2)`` ``(x, z)`` of each marker from a CSV of ``t`` and
    ``<marker>_x, <marker>_z`` columns (empty cells: missing)."""
    from motion_envs.datasets.sample_table import (
        fail_rows,
        missing_columns_message,
        read_csv_text,
    )

    frame = read_csv_text(path, "pattern markers", label_columns=())
    columns = ["t", *(f"{m}_{a}" for m in names for a in ("x", "z"))]
    missing = [c for c in columns if c not in frame.columns]
    if missing:
        raise ValueError(
            missing_columns_message(str(path), list(frame.columns), missing, ",".join(columns))
        )
    if len(frame) < 10:
        raise ValueError(f"{path}: {len(frame)} data rows; at least 10 are needed")
    raw = frame[columns]
    data = raw.apply(pd.to_numeric, errors="coerce").to_numpy(dtype=np.float64)
    bad = (np.isnan(data) & raw.notna().to_numpy()) | np.isinf(data)
    if bad.any():
        fail_rows(path, bad.any(axis=1), "a cell that is not a finite number")
    t = data[:, 0]
    if np.isnan(t).any():
        fail_rows(path, np.isnan(t), "no time t")
    back = np.concatenate([[False], np.diff(t) <= 0])
    if back.any():
        fail_rows(path, back, "t not strictly increasing")
    return t, data[:, 1:].reshape(len(t), len(names), 2)


def read_pattern_markers(
    path: str | os.PathLike[str],
    hands: Sequence[str],
    balls: Sequence[str],
    *,
    unit: str | None = None,
    up: str = "z",
    lateral: str = "x",
) -> PatternTrajectories:
    """A recording's two hands (``hands``: the right hand's marker, then the left's) and
    its balls (``balls``: one labelled marker per ball) in the pattern's plane.

    ``.c3d`` and ``.tsv`` (Qualisys) files are read by
    :func:`motion_envs.datasets.mocap.read_recording` (``unit``: its unit option; ``up``:
    the file's vertical axis, ``"z"`` or ``"y"``; ``lateral``: the horizontal axis of the
    pattern's plane after the ``z``-up turn, ``"x"`` or ``"y"``). A ``.csv`` (or
    ``.csv.gz``) has a header with ``t`` (s) and ``<marker>_x``, ``<marker>_z`` (m, ``x``
    lateral, ``z`` up) for each marker named, an empty cell where a marker is missing.
    Errors are one line naming the file (and the CSV lines)."""
    p = Path(path)
    names = [*hands, *balls]
    if len(hands) != HANDS:
        raise ValueError(f"{p}: give two hand markers (right, left); got {list(hands)}")
    if not balls:
        raise ValueError(f"{p}: give at least one ball marker")
    if len(set(names)) != len(names):
        raise ValueError(f"{p}: a marker is named twice in {names}")
    if up not in ("z", "y") or lateral not in _AXES:
        raise ValueError(
            f"{p}: up must be 'z' or 'y' and lateral 'x' or 'y'; got {up!r}, {lateral!r}"
        )
    suffixes = [s.lower() for s in p.suffixes[-2:]]
    if suffixes and (suffixes[-1] == ".csv" or suffixes == [".csv", ".gz"]):
        if unit is not None:
            raise ValueError(f"{p}: a CSV is in metres; unit applies to C3D and TSV files")
        if not p.exists():
            raise FileNotFoundError(f"pattern markers CSV {p} does not exist")
        t, xz = _csv_markers(p, names)
    else:
        from motion_envs.datasets.mocap import YUP_TO_ZUP, read_recording

        rec = read_recording(p, unit, names)
        if rec.fmt == "bvh":
            raise ValueError(f"{p}: a BVH file has joints, not ball markers; use C3D, TSV or CSV")
        cols = [rec.index(m) for m in names]
        pts = np.where(rec.missing()[:, cols, None], np.nan, rec.points[:, cols])
        if up == "y":
            pts = pts @ YUP_TO_ZUP.T
        t = rec.t
        xz = pts[:, :, [_AXES[lateral], 2]]
    for m, col in zip(names, range(len(names)), strict=True):
        if not np.isfinite(xz[:, col]).all(axis=1).any():
            raise ValueError(f"{p}: marker {m!r} has no sample (all missing)")
    return PatternTrajectories(
        t=t, hands=xz[:, :HANDS], balls=xz[:, HANDS:], source=str(p), simulated=False
    )
