"""SIMULATED juggling recordings for the flight analysis' tests: a cascade of N balls
with two hands, ball marker noise and the defects of optical tracking (occlusions,
dropouts, unlabelled fragments, marker swaps, spurious markers)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

G = 9.81


@dataclass(frozen=True)
class TrueFlight:
    ball: int
    hand: int
    start: float
    end: float
    p0: np.ndarray  # release position (3,)
    v0: np.ndarray  # release velocity (3,)

    def position(self, t: np.ndarray, g: float = G) -> np.ndarray:
        tau = (t - self.start)[:, None]
        out = self.p0 + self.v0 * tau
        out[:, 2] -= 0.5 * g * tau[:, 0] ** 2
        return out


@dataclass(frozen=True)
class Cascade:
    """The ball positions ``(F, N, 3)`` (all present) and the true flights (those cut by
    the recording's start or end too: :meth:`complete` are the others)."""

    t: np.ndarray
    balls: np.ndarray
    flights: list[TrueFlight]
    beat: float
    dwell: float
    flight: float

    def complete(self) -> list[TrueFlight]:
        return [f for f in self.flights if f.start >= self.t[0] and f.end <= self.t[-1]]


def quintic(t0, t1, p0, v0, a0, p1, v1, a1, t):
    """Quintic Hermite through position, velocity, acceleration at both ends."""
    h = t1 - t0
    s = ((np.asarray(t) - t0) / h)[:, None]
    h00 = 1 - 10 * s**3 + 15 * s**4 - 6 * s**5
    h10 = s - 6 * s**3 + 8 * s**4 - 3 * s**5
    h20 = 0.5 * s**2 - 1.5 * s**3 + 1.5 * s**4 - 0.5 * s**5
    h01 = 10 * s**3 - 15 * s**4 + 6 * s**5
    h11 = -4 * s**3 + 7 * s**4 - 3 * s**5
    h21 = 0.5 * s**3 - s**4 + 0.5 * s**5
    return h00 * p0 + h10 * h * v0 + h20 * h * h * a0 + h01 * p1 + h11 * h * v1 + h21 * h * h * a1


def cascade(
    n_balls: int = 3,
    beat: float = 0.25,
    dwell_ratio: float = 0.65,
    rate: float = 300.0,
    duration: float = 20.0,
    g: float = G,
    seed: int = 0,
    jitter: float = 0.005,
) -> Cascade:
    """A SIMULATED N-ball cascade (odd N): throws every ``beat`` s, alternating hands
    (right at x > 0), thrown from x = +-0.1 m at 1.0 m, caught at x = -+0.3 m at 1.05 m;
    in the hand a quintic path from the catch (ball's velocity, 20 m/s^2 up) to the
    release (the flight's velocity, no acceleration: at release the ball's acceleration
    jumps to -g)."""
    rng = np.random.default_rng(seed)
    dwell = 2 * dwell_ratio * beat
    flight = n_balls * beat - dwell
    n_throws = int((duration + 4 * n_balls * beat) / beat) + n_balls
    t_throw = np.arange(n_throws) * beat + rng.normal(0, jitter, n_throws)
    t_flight = flight * (1 + rng.normal(0, 0.02, n_throws))
    flights = []
    for k in range(n_throws):
        side = 1.0 if k % 2 == 0 else -1.0
        p0 = np.array([0.1 * side, rng.normal(0, 0.02), 1.0 + rng.normal(0, 0.01)])
        p1 = np.array([-0.3 * side, rng.normal(0, 0.02), 1.05 + rng.normal(0, 0.01)])
        ft = t_flight[k]
        v0 = (p1 - p0) / ft
        v0[2] = (p1[2] - p0[2] + 0.5 * g * ft * ft) / ft
        flights.append(TrueFlight(k % n_balls, k % 2, t_throw[k], t_throw[k] + ft, p0, v0))
    t0 = 2 * n_balls * beat
    t = t0 + np.arange(int(duration * rate)) / rate
    balls = np.full((t.size, n_balls, 3), np.nan)
    for k, f in enumerate(flights):
        inside = (t >= f.start) & (t <= f.end)
        balls[inside, f.ball] = f.position(t[inside], g)
        if k + n_balls < n_throws:
            nxt = flights[k + n_balls]
            held = (t > f.end) & (t < nxt.start)
            v_in = f.v0 - np.array([0, 0, g * (f.end - f.start)])
            p_in = f.position(np.array([f.end]), g)[0]
            balls[held, f.ball] = quintic(
                f.end,
                nxt.start,
                p_in,
                v_in,
                np.array([0, 0, 20.0]),
                nxt.p0,
                nxt.v0,
                np.zeros(3),
                t[held],
            )
    keep = [f for f in flights if f.end > t[0] and f.start < t[-1]]
    assert np.isfinite(balls).all()
    return Cascade(t, balls, keep, beat, dwell, flight)


def unlabelled_columns(vis: np.ndarray, pts: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Unlabelled marker columns ``(n_f, n_columns, 3)`` as a tracker writes them: each
    visible stretch of ball ``b`` (``vis (n_f, n_b)``, positions ``pts (n_f, n_b, 3)``)
    goes into a column free over it and the frame before (drawn with ``rng``), NaN
    elsewhere."""
    n_f, n_b = vis.shape
    cols: list[np.ndarray] = []
    busy: list[np.ndarray] = []
    for b in range(n_b):
        edges = np.diff(np.concatenate([[0], vis[:, b].astype(np.int8), [0]]))
        for s, e in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1), strict=True):
            free = [c for c in range(len(cols)) if not busy[c][max(s - 1, 0) : e + 1].any()]
            if free:
                c = free[int(rng.integers(len(free)))]
            else:
                cols.append(np.full((n_f, 3), np.nan))
                busy.append(np.zeros(n_f, dtype=bool))
                c = len(cols) - 1
            cols[c][s:e] = pts[s:e, b]
            busy[c][s:e] = True
    return np.stack(cols, axis=1)


def with_defects(
    rec: Cascade,
    seed: int = 0,
    noise: float = 0.001,
    occlusion: float = 0.4,
    flight_gap: float = 0.2,
    dropout: float = 0.01,
    swaps: int = 10,
    static: int = 2,
    jittering: int = 2,
    ghosts: int = 200,
) -> np.ndarray:
    """Unlabelled columns ``(F, U, 3)`` (NaN missing) with noise and defects:

    * ``occlusion``: probability that a ball is hidden for part of a dwell (in the hand);
    * ``flight_gap``: probability that a flight has a 10-40 frame tracking gap;
    * ``dropout``: single missing samples;
    * every visible run of a ball becomes a fragment in a free column (unlabelled), then
      ``swaps`` times two columns exchange their contents from a random frame on;
    * ``static`` fixed markers (0.2 mm noise), ``jittering`` markers at hand height with
      5 mm noise, each present for random stretches; ``ghosts`` fragments of 1-4 frames
      at random places in the capture volume.
    """
    rng = np.random.default_rng(seed)
    n_f, n_b, _ = rec.balls.shape
    t = rec.t
    vis = np.ones((n_f, n_b), dtype=bool)
    dt = 1.0 / float(np.median(np.diff(t)))
    for f in rec.flights:
        if rng.random() < flight_gap:
            i0 = int(np.searchsorted(t, f.start + rng.uniform(0.05, 0.8) * (f.end - f.start)))
            vis[i0 : i0 + int(rng.integers(10, 41)), f.ball] = False
        if rng.random() < occlusion:  # hidden in the hand after the catch
            i0 = int(np.searchsorted(t, f.end)) + int(rng.integers(0, 10))
            vis[i0 : i0 + int(rng.uniform(0.3, 0.9) * rec.dwell * dt), f.ball] = False
    vis &= rng.random(vis.shape) >= dropout
    pts = rec.balls + rng.normal(0, noise, rec.balls.shape)
    out = unlabelled_columns(vis, pts, rng)
    for _ in range(swaps):
        a, b = rng.choice(out.shape[1], 2, replace=False)
        i = int(rng.integers(n_f))
        out[i:, [a, b]] = out[i:, [b, a]]
    extra = []
    for k in range(static + jittering):
        col = np.full((n_f, 3), np.nan)
        centre = np.array([rng.uniform(-0.5, 0.5), rng.uniform(-0.3, 0.3), rng.uniform(0.8, 1.6)])
        std = 0.0002 if k < static else 0.005
        on = rng.random(n_f) < 0.9  # present most of the time, with gaps
        col[on] = centre + rng.normal(0, std, (int(on.sum()), 3))
        extra.append(col)
    ghost = np.full((n_f, 4, 3), np.nan)
    for _ in range(ghosts):
        i = int(rng.integers(n_f - 4))
        c = int(rng.integers(4))
        n = int(rng.integers(1, 5))
        ghost[i : i + n, c] = rng.uniform([-0.5, -0.3, 0.5], [0.5, 0.3, 2.0]) + rng.normal(
            0, 0.01, (n, 3)
        )
    return np.concatenate([out, np.stack(extra, axis=1), ghost], axis=1)


def match(found, truth: list[TrueFlight], g: float = G, within: float = 0.01, slack: float = 0.004):
    """Each found flight's true flight (None: spurious) and duplicates.

    A found flight matches the true flight it overlaps most in time when its fitted
    parabola stays within ``within`` m of the true one over its samples' span and its
    span lies inside the true flight's, give or take ``slack`` s."""
    out = []
    ts_of = {id(f): np.linspace(f.start, f.end, 50) for f in found}
    for f in found:
        ts = ts_of[id(f)]
        best, best_dev = None, within
        for k, tf in enumerate(truth):
            if min(f.end, tf.end) - max(f.start, tf.start) <= 0:
                continue
            if not (f.start >= tf.start - slack and f.end <= tf.end + slack):
                continue
            axes = [0, 1, 2] if f.coef.shape[1] == 3 else [0, 2]  # (x, z) of a CSV
            dev = np.abs(f.position(ts) - tf.position(ts, g)[:, axes]).max()
            if dev <= best_dev:
                best, best_dev = k, dev
        out.append(best)
    return out
