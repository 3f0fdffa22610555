"""SIMULATED motion capture of juggling for the pattern analysis' tests: any vanilla
(asynchronous) siteswap or single throws, two hands moving on their paths, balls in
flight under gravity, markers at 300 Hz with the defects of optical capture.

Kinematics (:func:`juggle`, :func:`single_throws`): the hands throw in turn, one beat
``b`` apart (jittered); the ball thrown on beat ``i`` with value ``h`` is caught by the
hand of beat ``i + h`` a dwell ``D`` before that beat and thrown again on it (vanilla
siteswap); in flight it is a parabola under ``g``; in the hand it follows a quintic
path from the catch (the ball's velocity, an upward acceleration: the impact) to the
release (the next flight's velocity, an acceleration drawn between -0.6 g and +0.3 g: the
hand lets the ball go while decelerating). An empty hand moves on a quintic from its
release to its next catch. Released from the inside (+-0.1 m from the body's middle),
caught outside (+-0.3 m), along the across-body axis ``u``; skin markers ride on the
hands.

Capture (:func:`capture`): white noise; steps of a marker's position when the cameras
that see it change (camera switching); the ball hidden in the palm for part of some
dwells (at the catch or up to the release), its centroid moving as fingers cover it;
gaps in flight; dropped samples; every visible run in a random free unlabelled
column; marker swaps when two balls pass close and at random frames; skin markers on
the hands, static markers, ghost fragments; the whole capture rotated by any angle
about the vertical, Z-up or Y-up.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np
from _juggling_recordings import quintic, unlabelled_columns

from motion_envs.datasets.mocap import YUP_TO_ZUP

G = 9.81
#: Release and catch positions along the across-body axis (m from the middle).
X_IN, X_OUT = 0.1, 0.3


@dataclass(frozen=True)
class Throw:
    """One true throw: ball, hands, beat, value, release and catch (s), release
    position and velocity (in the unrotated frame: hands apart along x)."""

    ball: int
    hand: int
    catch_hand: int
    beat: int
    value: int
    start: float
    end: float
    p0: np.ndarray
    v0: np.ndarray

    def position(self, t: np.ndarray, g: float = G) -> np.ndarray:
        tau = (np.asarray(t, dtype=float) - self.start)[..., None]
        out = self.p0 + self.v0 * tau
        out[..., 2] -= 0.5 * g * tau[..., 0] ** 2
        return out

    @property
    def duration(self) -> float:
        return self.end - self.start


@dataclass(frozen=True)
class Juggle:
    """Ball centres ``(F, N, 3)`` (NaN before a ball's first throw), hands ``(F, 2, 3)``
    and the true throws, unrotated (Z-up, hands apart along x)."""

    t: np.ndarray
    balls: np.ndarray
    hands: np.ndarray
    throws: list[Throw]
    pattern: str
    beat: float
    dwell: float

    def inside(self) -> list[Throw]:
        """The throws whose release and catch are both inside the recording."""
        return [f for f in self.throws if f.start >= self.t[0] and f.end <= self.t[-1]]


def _side(hand: int) -> float:
    return 1.0 if hand == 0 else -1.0


@dataclass
class _Event:
    time: float
    kind: str  # "catch" or "throw"
    pos: np.ndarray
    vel: np.ndarray
    acc: np.ndarray
    ball: int


def _carry(ev0: _Event, ev1: _Event, t: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """The ball's path in the hand from a catch ``ev0`` to the throw ``ev1``; a long
    hold comes to rest in between (single throws)."""
    span = ev1.time - ev0.time
    if span <= 0.9:
        return quintic(ev0.time, ev1.time, ev0.pos, ev0.vel, ev0.acc, ev1.pos, ev1.vel, ev1.acc, t)
    t_a, t_b = ev0.time + 0.3, ev1.time - 0.3
    rest_a = ev0.pos + 0.5 * 0.3 * ev0.vel  # constant deceleration to rest
    rest_b = ev1.pos - 0.5 * 0.3 * ev1.vel  # constant acceleration from rest
    zero = np.zeros(3)
    out = np.empty((t.size, 3))
    a = t < t_a
    b = t > t_b
    m = ~a & ~b
    out[a] = quintic(ev0.time, t_a, ev0.pos, ev0.vel, ev0.acc, rest_a, zero, zero, t[a])
    out[b] = quintic(t_b, ev1.time, rest_b, zero, zero, ev1.pos, ev1.vel, ev1.acc, t[b])
    out[m] = quintic(t_a, t_b, rest_a, zero, zero, rest_b, zero, zero, t[m])
    return out


def _build(
    throws: list[Throw], t: np.ndarray, n_balls: int, g: float, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray]:
    """Ball and hand positions from the throws (module docstring)."""
    balls = np.full((t.size, n_balls, 3), np.nan)
    hands = np.full((t.size, 2, 3), np.nan)
    events: list[list[_Event]] = [[], []]
    by_ball: dict[int, list[Throw]] = {}
    for f in throws:
        by_ball.setdefault(f.ball, []).append(f)
        a_rel = np.array([0.0, 0.0, rng.uniform(-0.6, 0.3) * g])
        events[f.hand].append(_Event(f.start, "throw", f.p0, f.v0, a_rel, f.ball))
        p1 = f.position(np.array(f.end), g)
        v1 = f.v0 - np.array([0.0, 0.0, g * f.duration])
        a_c = np.array([0.0, 0.0, rng.uniform(15.0, 30.0)])
        events[f.catch_hand].append(_Event(f.end, "catch", p1, v1, a_c, f.ball))
    for fs in by_ball.values():
        for f in fs:
            inside = (t >= f.start) & (t <= f.end)
            balls[inside, f.ball] = f.position(t[inside], g)
    offset = np.array([0.0, 0.0, -0.035])  # the hand marker under the ball
    for h in (0, 1):
        evs = sorted(events[h], key=lambda e: e.time)
        for e0, e1 in itertools.pairwise(evs):
            sel = (t > e0.time) & (t < e1.time)
            if not sel.any():
                continue
            if e0.kind == "catch" and e1.kind == "throw" and e0.ball == e1.ball:
                path = _carry(e0, e1, t[sel], rng)
                balls[sel, e0.ball] = path
                hands[sel, h] = path + offset
            else:  # an empty hand (or an event the recording cut): to the next event
                hands[sel, h] = quintic(
                    e0.time,
                    e1.time,
                    e0.pos + offset,
                    0.3 * e0.vel,
                    np.zeros(3),
                    e1.pos + offset,
                    0.3 * e1.vel,
                    np.zeros(3),
                    t[sel],
                )
        for e in evs:
            near = np.abs(t - e.time) < 1e-9
            hands[near, h] = e.pos + offset
    return balls, hands


def _throw(
    rng: np.random.Generator,
    ball: int,
    hand: int,
    catch_hand: int,
    beat: int,
    value: int,
    start: float,
    end: float,
    g: float,
    z_catch: float = 1.05,
) -> Throw:
    x_catch = X_OUT if value != 1 else 1.5 * X_IN
    p0 = np.array([X_IN * _side(hand), rng.normal(0, 0.02), 1.0 + rng.normal(0, 0.01)])
    p1 = np.array([x_catch * _side(catch_hand), rng.normal(0, 0.02), z_catch])
    ft = end - start
    v0 = (p1 - p0) / ft
    v0[2] = (p1[2] - p0[2] + 0.5 * g * ft * ft) / ft
    return Throw(ball, hand, catch_hand, beat, value, start, end, p0, v0)


def _catch_heights(
    starts: np.ndarray, ends: np.ndarray, nxt: np.ndarray, g: float, z0: float = 1.0
) -> np.ndarray:
    """Catch heights for which each carry, at constant acceleration, takes the ball
    from the catch to its next release (``nxt``: index of the rethrow, -1: none):
    ``z_c = (z_r + D/2 (z0/F + g F/2 - v_r)) / (1 + D/(2F))``, by fixed-point
    sweeps, within 0.7-1.3 m (a hand can only push: no dip faster than g)."""
    z = np.full(starts.size, 1.05)
    f = ends - starts
    for _ in range(30):
        for i in range(starts.size):
            j = nxt[i]
            if j < 0:
                continue
            d = starts[j] - ends[i]
            v_r = (z[j] - z0 + 0.5 * g * f[j] ** 2) / f[j]
            z[i] = (z0 + 0.5 * d * (z0 / f[i] + 0.5 * g * f[i] - v_r)) / (1 + 0.5 * d / f[i])
        z = np.clip(z, 0.7, 1.3)
    return z


def juggle(
    pattern: str = "3",
    beat: float = 0.25,
    dwell_ratio: float = 0.65,
    duration: float = 12.0,
    rate: float = 300.0,
    g: float = G,
    seed: int = 0,
    jitter: float = 0.005,
) -> Juggle:
    """A SIMULATED vanilla siteswap (module docstring): throws every ``beat`` s
    (jittered by ``jitter`` s), the dwell ``dwell_ratio * 2 beat`` (2 % jitter); the
    catch heights make every carry possible at constant acceleration."""
    rng = np.random.default_rng(seed)
    values = [int(c, 36) for c in pattern]
    p = len(values)
    dwell = dwell_ratio * 2 * beat
    top = max(values)
    n_beats = int(duration / beat) + 4 * top + 8
    t_beat = np.arange(n_beats) * beat + rng.normal(0, jitter, n_beats)
    d_beat = dwell * (1 + rng.normal(0, 0.02, n_beats))
    landing: dict[int, int] = {}
    rows: list[tuple[int, int, int, float, float]] = []  # ball, beat, value, start, end
    next_ball = 0
    for i in range(n_beats - top - 1):
        h = values[i % p]
        if h == 0:
            continue
        ball = landing.pop(i, None)
        if ball is None:
            ball, next_ball = next_ball, next_ball + 1
        landing[i + h] = ball
        end = t_beat[i + h] - d_beat[i + h]
        if end - t_beat[i] < 0.08:
            raise ValueError(f"{pattern}: the throw of {h} has no flight at this tempo")
        rows.append((ball, i, h, t_beat[i], end))
    at_beat = {r[1]: k for k, r in enumerate(rows)}
    nxt = np.array([at_beat.get(r[1] + r[2], -1) for r in rows])
    z_c = _catch_heights(np.array([r[3] for r in rows]), np.array([r[4] for r in rows]), nxt, g)
    throws = [
        _throw(rng, b, i % 2, (i + h) % 2, i, h, s, e, g, float(z))
        for (b, i, h, s, e), z in zip(rows, z_c, strict=True)
    ]
    t0 = (2 * top + 2) * beat
    t = t0 + np.arange(int(duration * rate)) / rate
    balls, hands = _build(throws, t, next_ball, g, rng)
    keep = [f for f in throws if f.end > t[0] and f.start < t[-1]]
    return Juggle(t, balls, hands, keep, pattern, beat, dwell)


def single_throws(
    n: int = 12, rate: float = 300.0, g: float = G, seed: int = 0, same_hand: float = 0.3
) -> Juggle:
    """One ball thrown at irregular times: flights of 0.45-1.1 s, caught by the other
    hand (or, with probability ``same_hand``, the thrower), held 0.4-2 s."""
    rng = np.random.default_rng(seed)
    throws: list[Throw] = []
    time, hand = 1.0, 0
    for k in range(n):
        flight = rng.uniform(0.45, 1.1)
        catch_hand = hand if rng.random() < same_hand else 1 - hand
        throws.append(_throw(rng, 0, hand, catch_hand, k, 0, time, time + flight, g))
        time += flight + rng.uniform(0.4, 2.0)
        hand = catch_hand
    t = np.arange(int((time + 0.5) * rate)) / rate
    balls, hands = _build(throws, t, 1, g, rng)
    held = np.isnan(balls[:, 0, 0]) & (t < throws[0].start)
    balls[held, 0] = throws[0].p0  # held still before the first throw
    return Juggle(t, balls, hands, throws, "", float("nan"), float("nan"))


@dataclass(frozen=True)
class Capture:
    """Unlabelled columns ``(F, U, 3)`` (NaN missing) in the lab frame and that frame:
    the rotation ``angle`` (rad) about the vertical and ``up`` (``z`` or ``y``)."""

    columns: np.ndarray
    angle: float
    up: str


def rotation(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def capture(
    rec: Juggle,
    seed: int = 0,
    angle: float = 0.0,
    up: str = "z",
    noise: float = 0.0005,
    camera_steps: float = 0.0008,
    palm: float = 0.4,
    palm_shift: float = 0.02,
    flight_gap: float = 0.15,
    dropout: float = 0.01,
    close_swap: float = 0.5,
    swaps: int = 10,
    skin: int = 2,
    static: int = 2,
    ghosts: int = 200,
) -> Capture:
    """The capture of ``rec`` (module docstring). ``noise``: white noise std (m);
    ``camera_steps``: std (m) of the step a marker's position takes each time its camera
    set changes (about 3 times a second); ``palm``: probability the ball is hidden in
    the hand for part of a dwell, its centroid moving by about ``palm_shift`` (m, any
    direction) over the 6 frames before it is lost and after it is found again (the
    fingers cover part of it); ``flight_gap``: probability of a 10-40 frame gap in a
    flight; ``close_swap``: probability that two balls passing within 12 cm swap
    labels; ``swaps`` random swaps; ``skin`` markers on each hand."""
    rng = np.random.default_rng(seed)
    t = rec.t
    n_f, n_b, _ = rec.balls.shape
    rate = 1.0 / float(np.median(np.diff(t)))
    vis = np.isfinite(rec.balls).all(axis=2)
    hidden: list[tuple[int, int, int]] = []
    for f in rec.throws:
        if rng.random() < flight_gap:
            i0 = int(np.searchsorted(t, f.start + rng.uniform(0.05, 0.8) * f.duration))
            vis[i0 : i0 + int(rng.integers(10, 41)), f.ball] = False
        if rng.random() < palm:  # hidden in the palm: after the catch or up to the release
            if rng.random() < 0.5:
                i0 = int(np.searchsorted(t, f.end)) + int(rng.integers(0, 10))
                i1 = i0 + int(rng.uniform(0.02, 0.15) * rate)
            else:
                i1 = max(int(np.searchsorted(t, f.start)) - int(rng.integers(0, 6)), 0)
                i0 = max(i1 - int(rng.uniform(0.02, 0.15) * rate), 0)
            vis[i0:i1, f.ball] = False
            hidden.append((f.ball, min(i0, n_f), min(i1, n_f)))
    vis &= rng.random(vis.shape) >= dropout

    def observed(path: np.ndarray) -> np.ndarray:
        steps = np.cumsum(rng.random(n_f) < 3.0 / rate)
        jumps = rng.normal(0, camera_steps, (int(steps[-1]) + 1, 3))
        return path + jumps[steps] + rng.normal(0, noise, path.shape)

    pts = np.stack([observed(rec.balls[:, b]) for b in range(n_b)], axis=1)
    for b, i0, i1 in hidden:  # fingers cover part of the ball: its centroid moves
        for k in (np.arange(max(i0 - 6, 0), i0), np.arange(i1, min(i1 + 6, n_f))):
            if k.size:
                near = (k - k[0] + 1) if k[-1] < i0 else (k[-1] - k + 1)
                shift = rng.normal(0, palm_shift / math.sqrt(3), 3)
                pts[k, b] += (near / k.size)[:, None] * shift
    out = unlabelled_columns(vis, pts, rng)
    if close_swap > 0:  # the tracker hands a label to the other ball where two pass close
        i = 0
        while i < n_f:
            present = np.flatnonzero(np.isfinite(out[i]).all(axis=1))
            done = False
            for a_k, a in enumerate(present):
                for b in present[a_k + 1 :]:
                    if np.linalg.norm(out[i, a] - out[i, b]) < 0.12 and rng.random() < close_swap:
                        out[i:, [a, b]] = out[i:, [b, a]]
                        done = True
                        break
                if done:
                    break
            i += int(0.1 * rate) if done else 1
    for _ in range(swaps):
        a, b = rng.choice(out.shape[1], 2, replace=False)
        i = int(rng.integers(n_f))
        out[i:, [a, b]] = out[i:, [b, a]]
    extra = []
    for h in (0, 1):
        for _ in range(skin):
            off = rng.normal(0, 0.03, 3) + np.array([0.0, 0.0, -0.03])
            col = observed(rec.hands[:, h] + off)
            col[rng.random(n_f) < 0.05] = np.nan
            extra.append(col)
    for _ in range(static):
        col = np.full((n_f, 3), np.nan)
        centre = np.array([rng.uniform(-0.5, 0.5), rng.uniform(-0.3, 0.3), rng.uniform(0.8, 1.6)])
        on = rng.random(n_f) < 0.9
        col[on] = centre + rng.normal(0, 0.0002, (int(on.sum()), 3))
        extra.append(col)
    ghost = np.full((n_f, 4, 3), np.nan)
    for _ in range(ghosts):
        i = int(rng.integers(n_f - 4))
        c = int(rng.integers(4))
        n = int(rng.integers(1, 5))
        ghost[i : i + n, c] = rng.uniform([-0.5, -0.3, 0.5], [0.5, 0.3, 2.0]) + rng.normal(
            0, 0.01, (n, 3)
        )
    cols_all = np.concatenate([out, np.stack(extra, axis=1), ghost], axis=1) if extra else out
    lab = cols_all @ rotation(angle).T
    if up == "y":
        lab = lab @ YUP_TO_ZUP  # the file's (x, y, z) with y up
    return Capture(lab, angle, up)
