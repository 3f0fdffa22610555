r"""How Juggling-v2 sees the ball: a camera with a hidden human delay, and estimators of
the flight from its frames.

**The camera** (:class:`CameraSensor`) reports ball POSITIONS only, at a camera rate
(``frame_rate``, frames captured every ``round(1 / (frame_rate dt))`` control periods),
as a motion-capture system does: each captured frame is lost with probability
``drop_prob`` (a frame drop), is missing while the ball is held or its centre is within
``occlusion_radius`` of the hand's origin (the hand occludes it; near the palm markers
vanish), and carries white Gaussian noise of ``position_std`` m. A frame reaches the
controller after the episode's visuomotor delay plus a per-frame jitter (normal,
``jitter_std`` s), at the first control step at or after ``capture + delay + jitter``,
in capture order (a frame never overtakes an earlier one: first in, first out). The
delay is drawn per episode by the environment from the level's human range and never
shown: a frame says where the ball was, not when.

**Gaze** (Juggling-v2's level ``gaze``): a juggler fixates near the apex of the toss
(Huys & Beek 2002, *The coupling between point-of-gaze and ball movements in three-ball
cascade juggling: the effects of expertise, pattern and tempo*, J. Sports Sciences 20:
171-186), so the ball near the hand is seen in the periphery, and visual reaction times
rise with retinal eccentricity (Payne 1967, *Visual reaction times on a circle about the
fovea*, Science 155: 481-482). With a ``slope`` (s per degree; :meth:`CameraSensor.reset`)
each captured frame's latency is ``delay + slope * ecc + jitter``, ``ecc`` the angle in
degrees (:func:`eccentricity`), seen from the eye (:func:`gaze_eye`), between the ball's
true position at capture and the fixation point: the apex of the current flight predicted
ballistically from the release state (:func:`ballistic_apex`; the person anticipates the
apex; drag ignored), told the camera at each release (:meth:`CameraSensor.fixate`). Before
the first release nothing is fixated (and no frame is captured: the ball is held). With
``slope`` 0 (every other level, Cascade-v1) every frame is exactly as without gaze.

Four random numbers are drawn per captured frame (drop, jitter, two noises), whether or
not the frame is lost, so a frame's fate does not shift the next frames' draws.

**The estimators** (:class:`FlightEstimator`) turn the frames received since the last
release into the ball's position and velocity NOW, for the analytic juggler's eq. 10
correction. Each fits the flight ``p(t) = a + b (t - t_0) + c (t - t_0)^2 / 2`` (``c``
gravity, plus, for an estimator that knows it, the drag deceleration ``-k |b| b`` held
constant over the window, one fixed-point refit) by least squares to the newest
``window`` frames, each frame placed at a time that the estimator believes it was
captured at:

* ``"arrival"`` (the analytic juggler): at its arrival (the delay ignored, as the
  juggler of Lippi et al. takes what it sees as the present);
* ``"mean_delay"``: at its arrival minus a fixed delay (the level's mean);
* ``"release"`` (the hand-written delay estimator): at its arrival minus the delay
  estimated from the release. The hand knows when and where it let the ball go (touch,
  no delay); the ball's flight from that point, ``r + v s - g s^2 / 2``, must pass
  through the frames at ``s = arrival - t_r - d``: for each delay ``d`` on a 5 ms grid
  over ``DELAY_GRID`` the least-squares ``v`` and the residual, the best ``d`` per
  flight from its first ``ANCHOR_FRAMES`` frames (the drag has not yet bent the flight
  much), averaged over the episode's flights (the delay is one per episode); with an
  ``offset`` the frames are placed by that average plus the offset, at least 0 (a
  correction of the estimate chosen elsewhere, on validation seeds, plus an agent's
  timing entry where the envs have one, set per flight at its release; 0 by default);
* ``"gaze_release"`` (the hand-written gaze-aware estimator, for the level ``gaze``; it
  is written knowing the gaze model's FORM, the eye :data:`GAZE_EYE` and the fixation on
  the apex, not its numbers): the release-anchored estimator with a latency ``d + k ecc``
  of two numbers per episode, both found from the releases. A flight's apex is
  anticipated ballistically from the HAND's release position and velocity (what the
  juggler knows of its own toss; the ball's true release differs by the toss's scatter),
  each frame's eccentricity taken from its MEASURED position; at each flight's anchoring
  ``(d, k)`` is the grid point (``DELAY_GRID`` x :data:`SLOPE_GRID`) with the least
  ballistic residual of the anchor frames at ``s = arrival - t_r - d - k ecc``, each
  flight with its own least-squares velocity, summed over the episode's anchored flights
  (pooled: both numbers are one per episode). Every frame of the current flight is then
  placed at ``arrival - d - k ecc``. (The apex from the flight's own fit instead was
  tried first: on a noise-free flight the true apex is an UNSTABLE fixed point of "fit,
  predict the apex, recompute the eccentricities, refit" at the true ``(d, k)``, an apex
  10 cm too high or low running off by 0.37-1.4 m, so the fit cannot find it.)
* ``"oracle"``: at its arrival minus the episode's TRUE delay and the frame's TRUE gaze
  latency (``slope * ecc``, :attr:`CameraFrame.gaze`; 0 but on level ``gaze``), with the
  ball's true drag (an upper reference, given what the world hides; labelled so wherever
  it is reported).
  Like every other estimator it does not know a frame's jitter: no observation could
  tell it (a frame carries no capture time).

The fitted state is carried to the present along the estimator's model of the flight
(ballistic, or with the known drag by :func:`drag_flight`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "ANCHOR_FRAMES",
    "DELAY_GRID",
    "ESTIMATORS",
    "GAZE_EYE",
    "SLOPE_GRID",
    "AnchoredFlight",
    "CameraFrame",
    "CameraSensor",
    "DelayRule",
    "FlightEstimator",
    "ballistic_apex",
    "drag_flight",
    "eccentricities",
    "eccentricity",
    "gaze_eye",
    "mean_flight_delay",
    "release_residuals",
]

FloatArray = NDArray[np.float64]
#: The estimators that anchor on the release.
_ANCHORED = ("release", "gaze_release")

#: The estimators' names (module docstring).
ESTIMATORS = ("arrival", "mean_delay", "release", "oracle", "gaze_release")
#: s; the delays the release-anchored estimator tries (5 ms apart).
DELAY_GRID = np.round(np.arange(0.0, 0.4001, 0.005), 6)
#: Frames after a release from which the release-anchored estimator finds the delay.
ANCHOR_FRAMES = 8
#: s per degree; the gaze slopes the gaze-aware estimator tries (0.1 ms/deg apart, 0 to
#: twice the level's largest), declared before any run.
SLOPE_GRID = np.round(np.arange(0.0, 0.00301, 0.0001), 7)
#: m; the eye relative to the hand's home ``(dx, dz, y)``: at the home's ``x``, 0.45 m above
#: it and 0.40 m out of the juggling plane (toward the juggler), for the ``gaze`` level's
#: eccentricity. A reasoned choice, not a measurement: a juggler's hands work at about
#: elbow height, some 0.4-0.5 m below the eyes, and 0.3-0.5 m in front of the body.
GAZE_EYE = (0.0, 0.45, 0.40)


#: One anchored flight as the release-anchored estimators keep it: per anchor frame its
#: arrival minus the release time (s, shape ``(n,)``) and its position minus the release
#: point (m, shape ``(n, 2)``).
AnchoredFlight = tuple[FloatArray, FloatArray]


class DelayRule(Protocol):
    """How a release-anchored estimator turns the episode's anchored flights into one
    delay (s), or None when they tell none (:class:`FlightEstimator`'s ``rule``)."""

    def __call__(self, flights: Sequence[AnchoredFlight], gravity: float) -> float | None: ...


def release_residuals(
    s0: FloatArray, q: FloatArray, gravity: float, grid: FloatArray = DELAY_GRID
) -> FloatArray:
    r"""Per delay ``d`` of ``grid``, the least-squares residual of the ballistic flight
    from the release point through one flight's anchor frames (``inf`` where a frame
    would precede the release, ``s <= 0``).

    With ``s_i = s0_i - d`` and ``y_i = q_i + (0, g s_i^2 / 2)``, the flight
    ``r + v s - g s^2 / 2`` passes through the frames when ``y_i = v s_i``; the best
    ``v = \sum s_i y_i / \sum s_i^2`` and the residual ``\sum_i |y_i - v s_i|^2``.
    """
    s = np.asarray(s0, dtype=np.float64)[None, :] - np.asarray(grid)[:, None]  # (delays, n)
    ok = (s > 0).all(axis=1)
    y = np.broadcast_to(np.asarray(q, dtype=np.float64), (s.shape[0], *np.shape(q))).copy()
    y[..., 1] += 0.5 * gravity * s * s
    ss = np.where(ok, (s * s).sum(axis=1), 1.0)
    v = (s[..., None] * y).sum(axis=1) / ss[:, None]
    sse = ((y - s[..., None] * v[:, None, :]) ** 2).sum(axis=(1, 2))
    return np.where(ok, sse, np.inf)


def mean_flight_delay(flights: Sequence[AnchoredFlight], gravity: float) -> float | None:
    """The release-anchored estimators' default :class:`DelayRule`: each flight's
    least-residual delay on :data:`DELAY_GRID` (:func:`release_residuals`), averaged over
    the flights that tell one; None when none does."""
    delays = []
    for s0, q in flights:
        r = release_residuals(s0, q, gravity)
        if np.isfinite(r).any():
            delays.append(float(DELAY_GRID[int(np.argmin(r))]))
    return float(np.mean(delays)) if delays else None


def gaze_eye(home: tuple[float, float]) -> tuple[float, float, float]:
    """The eye ``(x, z, y)`` (m) for the hand's ``home`` ``(x, z)`` (:data:`GAZE_EYE`; the
    juggling plane is ``y = 0``)."""
    dx, dz, y = GAZE_EYE
    return float(home[0]) + dx, float(home[1]) + dz, y


def ballistic_apex(
    p: tuple[float, float], v: tuple[float, float], gravity: float
) -> tuple[float, float]:
    """The apex ``(x, z)`` of the ballistic flight from ``p`` at ``v`` (drag ignored); the
    release point itself when the ball does not rise (``v_z <= 0``)."""
    vz = float(v[1])
    if vz <= 0:
        return float(p[0]), float(p[1])
    s = vz / gravity
    return float(p[0]) + float(v[0]) * s, float(p[1]) + 0.5 * vz * s


def eccentricities(
    positions: FloatArray, fixations: FloatArray, eye: tuple[float, float, float]
) -> FloatArray:
    """Degrees ``(..., n)``; :func:`eccentricity` of ``n`` positions ``(n, 2)`` from each
    fixation ``(..., 2)`` (vectorised; 0 where either is at the eye)."""
    e = np.asarray(eye, dtype=np.float64)
    a = np.concatenate([positions - e[:2], np.full((len(positions), 1), -e[2])], axis=1)
    f = np.asarray(fixations, dtype=np.float64)
    b = np.concatenate([f - e[:2], np.full((*f.shape[:-1], 1), -e[2])], axis=-1)
    b = b[..., None, :]  # (..., 1, 3) against a (n, 3)
    cross = np.linalg.norm(np.cross(a, b), axis=-1)
    dot = (a * b).sum(axis=-1)
    out: FloatArray = np.degrees(np.arctan2(cross, dot))
    return out


def eccentricity(
    ball: tuple[float, float], fixation: tuple[float, float], eye: tuple[float, float, float]
) -> float:
    """Degrees; the angle at ``eye`` ``(x, z, y)`` between the ball and the fixation point,
    both ``(x, z)`` in the plane ``y = 0`` (0 when either coincides with the eye)."""
    ex, ez, ey = eye
    a = (ball[0] - ex, ball[1] - ez, -ey)
    b = (fixation[0] - ex, fixation[1] - ez, -ey)
    na, nb = math.hypot(*a), math.hypot(*b)
    if na == 0.0 or nb == 0.0:
        return 0.0
    cross = math.hypot(a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                       a[0] * b[1] - a[1] * b[0])  # fmt: skip
    dot = a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
    return math.degrees(math.atan2(cross, dot))


@dataclass(frozen=True)
class CameraFrame:
    """One received frame: the ball's measured ``x, z`` (m), when it was captured
    (``capture``, s; hidden from all but the oracle), when it arrived (``arrival``) and
    its gaze latency ``slope * ecc`` (``gaze``, s; the part of its latency the
    eccentricity adds, jitter excluded; 0 without gaze; hidden from all but the
    oracle)."""

    capture: float
    arrival: float
    x: float
    z: float
    gaze: float = 0.0


class CameraSensor:
    """A position-only, delayed camera (module docstring).

    Parameters
    ----------
    dt:
        s, the control period.
    frame_rate:
        Hz; frames are captured every ``round(1 / (frame_rate dt))`` control periods.
    jitter_std:
        s, the std of each frame's extra latency.
    drop_prob:
        Probability that a captured frame is lost.
    occlusion_radius:
        m; a ball whose centre is this close to the hand's origin is not seen.
    position_std:
        m, the std of the white noise on each coordinate.
    """

    def __init__(
        self,
        dt: float,
        frame_rate: float,
        jitter_std: float,
        drop_prob: float,
        occlusion_radius: float,
        position_std: float,
    ) -> None:
        for name, value, low, high in (
            ("dt", dt, 1e-6, 1.0),
            ("frame_rate", frame_rate, 1.0, 1e4),
            ("jitter_std", jitter_std, 0.0, 1.0),
            ("drop_prob", drop_prob, 0.0, 1.0),
            ("occlusion_radius", occlusion_radius, 0.0, 10.0),
            ("position_std", position_std, 0.0, 1.0),
        ):
            if not (math.isfinite(value) and low <= value <= high):
                raise ValueError(f"{name} must be in [{low}, {high}]; got {value!r}")
        self.dt = float(dt)
        self.frame_steps = max(1, round(1.0 / (frame_rate * dt)))
        self.jitter_std = float(jitter_std)
        self.drop_prob = float(drop_prob)
        self.occlusion_radius = float(occlusion_radius)
        self.position_std = float(position_std)
        self.delay = 0.0
        #: s per degree of eccentricity (level ``gaze``; 0: no gaze latency)
        self.slope = 0.0
        self.eye = (0.0, 0.0, 1.0)
        #: the fixation point ``(x, z)`` of the current flight (None before a release)
        self.fixation: tuple[float, float] | None = None
        self._pending: list[tuple[int, CameraFrame]] = []
        self._last_arrival = -1
        self._rng: np.random.Generator = np.random.default_rng(0)

    def reset(
        self,
        delay: float,
        rng: np.random.Generator,
        slope: float = 0.0,
        eye: tuple[float, float, float] = (0.0, 0.0, 1.0),
    ) -> None:
        """A new episode with the visuomotor ``delay`` (s), the gaze ``slope`` (s per
        degree, module docstring; 0: none) seen from ``eye`` ``(x, z, y)`` (m, off the
        plane ``y = 0``); no frame in flight, nothing fixated."""
        if not (math.isfinite(delay) and delay >= 0):
            raise ValueError(f"delay must be finite and >= 0; got {delay!r}")
        if not (math.isfinite(slope) and 0 <= slope <= 0.01):
            raise ValueError(f"slope must be in [0, 0.01] s per degree; got {slope!r}")
        if len(eye) != 3 or not all(math.isfinite(e) for e in eye) or eye[2] == 0:
            raise ValueError(f"eye must be 3 finite numbers (x, z, y), y != 0; got {eye!r}")
        self.delay = float(delay)
        self.slope = float(slope)
        self.eye = (float(eye[0]), float(eye[1]), float(eye[2]))
        self.fixation = None
        self._rng = rng
        self._pending = []
        self._last_arrival = -1

    def fixate(self, apex: tuple[float, float]) -> None:
        """The new flight's fixation point ``(x, z)`` (its predicted apex); the envs call
        it at each release, before that step's frame."""
        self.fixation = (float(apex[0]), float(apex[1]))

    def record(
        self, k: int, ball: tuple[float, float], hand: tuple[float, float], held: bool
    ) -> list[CameraFrame]:
        """The world at control step ``k`` (time ``k dt``): capture a frame when one is
        due; return the frames that arrive at step ``k`` (capture order)."""
        if k % self.frame_steps == 0:
            u = float(self._rng.random())
            jitter, ex, ez = (float(e) for e in self._rng.standard_normal(3))
            bx, bz = ball
            near = math.hypot(bx - hand[0], bz - hand[1]) < self.occlusion_radius
            if not (held or near or u < self.drop_prob):
                t = k * self.dt
                gaze = 0.0
                if self.slope and self.fixation is not None:
                    gaze = self.slope * eccentricity(ball, self.fixation, self.eye)
                base = self.delay + gaze if gaze else self.delay
                latency = max(base + self.jitter_std * jitter, 0.0)
                arrive = max(k + math.ceil(latency / self.dt - 1e-9), self._last_arrival)
                self._last_arrival = arrive
                frame = CameraFrame(
                    t,
                    arrive * self.dt,
                    bx + self.position_std * ex,
                    bz + self.position_std * ez,
                    gaze,
                )
                self._pending.append((arrive, frame))
        out = [f for a, f in self._pending if a <= k]
        if out:
            self._pending = [(a, f) for a, f in self._pending if a > k]
        return out


def drag_flight(
    p: tuple[float, float], v: tuple[float, float], seconds: float, gravity: float, drag: float
) -> tuple[float, float, float, float]:
    """``(x, z, vx, vz)`` ``seconds`` later (may be negative) of a ball at ``p`` moving at
    ``v`` under gravity and the quadratic drag ``dv/dt = -k |v| v`` (``k = drag``, 1/m):
    classical Runge-Kutta (Nystrom form for the position) with steps of at most 10 ms
    (ballistic, exactly, when ``drag == 0``; the test compares it with scipy's
    ``solve_ivp``)."""
    x, z = p
    vx, vz = v
    if drag == 0.0:
        s = seconds
        return x + vx * s, z + vz * s - 0.5 * gravity * s * s, vx, vz - gravity * s
    n = max(1, math.ceil(abs(seconds) / 0.01))
    h = seconds / n
    hyp, k, g = math.hypot, drag, gravity
    for _ in range(n):
        s1 = k * hyp(vx, vz)
        a1x, a1z = -s1 * vx, -g - s1 * vz
        ux, uz = vx + 0.5 * h * a1x, vz + 0.5 * h * a1z
        s2 = k * hyp(ux, uz)
        a2x, a2z = -s2 * ux, -g - s2 * uz
        ux, uz = vx + 0.5 * h * a2x, vz + 0.5 * h * a2z
        s3 = k * hyp(ux, uz)
        a3x, a3z = -s3 * ux, -g - s3 * uz
        ux, uz = vx + h * a3x, vz + h * a3z
        s4 = k * hyp(ux, uz)
        a4x, a4z = -s4 * ux, -g - s4 * uz
        x += h * (vx + h / 6 * (a1x + a2x + a3x))
        z += h * (vz + h / 6 * (a1z + a2z + a3z))
        vx += h / 6 * (a1x + 2 * a2x + 2 * a3x + a4x)
        vz += h / 6 * (a1z + 2 * a2z + 2 * a3z + a4z)
    return x, z, vx, vz


class FlightEstimator:
    """The ball's position and velocity now, from the frames since the last release
    (module docstring).

    Parameters
    ----------
    mode:
        One of :data:`ESTIMATORS`.
    gravity:
        m/s^2.
    window:
        The newest frames the flight is fitted to (>= 3).
    delay:
        s; ``"mean_delay"``'s fixed delay.
    offset:
        s; added to ``"release"``'s estimated delay where it places the frames (may be
        negative; the sum at least 0; the estimate itself, :attr:`delay_estimate`, is
        unchanged); only ``"release"`` takes a nonzero one. An attribute the envs may set
        again between flights (an agent's timing entry, latched at each release).
    drag:
        1/m; the oracle's drag (set per episode by :meth:`reset`).
    rule:
        ``"release"`` only: how the episode's anchored flights make one delay
        (:class:`DelayRule`); None: :func:`mean_flight_delay`, each flight's least-residual
        delay averaged over the flights.
    anchor_frames:
        ``"release"`` only: the frames after a release the delay is found from (>= 3;
        :data:`ANCHOR_FRAMES` by default).
    """

    def __init__(
        self, mode: str, gravity: float, window: int = 10, delay: float = 0.0,
        offset: float = 0.0, rule: DelayRule | None = None,
        anchor_frames: int = ANCHOR_FRAMES,
    ) -> None:  # fmt: skip
        if mode not in ESTIMATORS:
            raise ValueError(f"mode must be one of {list(ESTIMATORS)}; got {mode!r}")
        if window < 3:
            raise ValueError(f"window must be >= 3; got {window!r}")
        if not math.isfinite(offset) or (offset and mode != "release"):
            raise ValueError(
                f"offset must be finite and nonzero only for mode 'release'; got {offset!r}"
            )
        if (rule is not None or anchor_frames != ANCHOR_FRAMES) and mode != "release":
            raise ValueError(f"rule and anchor_frames are for mode 'release'; got {mode!r}")
        if int(anchor_frames) != anchor_frames or anchor_frames < 3:
            raise ValueError(f"anchor_frames must be an integer >= 3; got {anchor_frames!r}")
        self.mode = mode
        self.rule = rule
        self.anchor_frames = int(anchor_frames)
        self.gravity = float(gravity)
        self.window = int(window)
        self.fixed_delay = float(delay)
        #: s added to the release-anchored estimate where the frames are placed
        self.offset = float(offset)
        self.drag = 0.0
        #: the eye ``(x, z, y)`` the ``gaze_release`` estimator measures eccentricities
        #: from (:func:`gaze_eye` of the hand's home; the envs set it)
        self.eye = (0.0, 0.0, 1.0)
        self.reset()

    def reset(self, drag: float = 0.0, delay: float = 0.0) -> None:
        """A new episode (the oracle is told the ball's ``drag`` and the episode's
        ``delay``)."""
        self.drag = float(drag) if self.mode == "oracle" else 0.0
        self.true_delay = float(delay) if self.mode == "oracle" else 0.0
        self.frames: list[CameraFrame] = []
        self.release: tuple[float, float, float] | None = None
        self._delays: list[float] = []
        #: the anchored flights a :attr:`rule` reads (kept only with one)
        self._anchors: list[AnchoredFlight] = []
        self._ruled: tuple[int, float | None] = (0, None)
        #: ``gaze_release``: the anchored flights ``(s0, q, ecc)`` (per anchor frame its
        #: arrival minus the release time, position minus the release point and
        #: eccentricity from the anticipated apex) and the pooled ``(d, k)``
        self._gaze_flights: list[tuple[FloatArray, FloatArray, FloatArray]] = []
        self.gaze_estimate: tuple[float, float] | None = None
        #: ``gaze_release``: the current flight's apex anticipated from the hand's release
        self._apex: tuple[float, float] | None = None
        self._anchored = False
        self._fit: tuple[float, FloatArray, FloatArray] | None = None
        self._fitted = False
        self._cached: tuple[tuple[int, float], tuple[float, float]] | None = None
        self._version = 0

    def retell(self, drag: float, delay: float) -> None:
        """The world's drag and delay changed between flights (Juggling-v2's ``drift``
        level): the oracle is told the new values; every other estimator ignores this
        (it keeps its frames and its delay estimates)."""
        if self.mode == "oracle":
            self.drag, self.true_delay = float(drag), float(delay)
            self._fitted = False

    def tell(self, *, delay: float | None = None, offset: float | None = None) -> None:
        """A new told ``delay`` (the fixed delay: ``"mean_delay"``'s, a pooled estimator's
        prior) and/or ``offset`` (on the release-anchored estimate), used from the next
        fit on (a tracker's or an agent's timing entry, latched at a release)."""
        if delay is not None:
            self.fixed_delay = float(delay)
        if offset is not None:
            self.offset = float(offset)
        self._fitted = False

    def released(
        self, time: float, x: float, z: float, velocity: tuple[float, float] = (0.0, 0.0)
    ) -> None:
        """The hand let the ball go at ``time`` from ``(x, z)`` moving at ``velocity``
        (the hand's, m/s; read by ``gaze_release`` only): a new flight."""
        if self.mode in _ANCHORED and self.release is not None and not self._anchored:
            self._anchor()  # a short flight still tells the delay
        self.release = (float(time), float(x), float(z))
        if self.mode == "gaze_release":  # the apex the juggler anticipates from its toss
            self._apex = ballistic_apex((x, z), velocity, self.gravity)
        self.frames = []
        self._anchored = False
        self._fitted = False

    def add(self, frames: list[CameraFrame]) -> None:
        """Frames that arrived this step."""
        if self.release is None:
            return
        if frames:
            self.frames.extend(frames)
            self._fitted = False
        if self.mode in _ANCHORED and not self._anchored and len(self.frames) >= self.anchor_frames:
            self._anchor()

    def _anchor(self) -> None:
        """The release-anchored delay of the current flight (module docstring)."""
        self._anchored = True
        if self.release is None or len(self.frames) < 3:
            return
        if self.mode == "gaze_release":
            self._anchor_gaze()
            return
        s0, q = self._anchor_frames()
        residuals = release_residuals(s0, q, self.gravity)
        if np.isfinite(residuals).any():
            self._delays.append(float(DELAY_GRID[int(np.argmin(residuals))]))
            if self.rule is not None:
                self._anchors.append((s0, q))
            self._fitted = False

    def _anchor_frames(self) -> AnchoredFlight:
        """The current flight's first :attr:`anchor_frames` frames: arrival minus release
        time and position minus release point."""
        assert self.release is not None
        t_r, rx, rz = self.release
        first = self.frames[: self.anchor_frames]
        s0 = np.array([f.arrival - t_r for f in first])
        q = np.array([[f.x - rx, f.z - rz] for f in first])
        return s0, q

    def _anchor_gaze(self) -> None:
        """``gaze_release``'s pooled ``(d, k)`` with this flight (module docstring)."""
        assert self.release is not None and self._apex is not None
        s0, q = self._anchor_frames()
        _, rx, rz = self.release
        ecc = eccentricities(q + np.array([rx, rz]), np.array(self._apex), self.eye)
        flights = [*self._gaze_flights, (s0, q, ecc)]
        total = np.zeros((len(DELAY_GRID), len(SLOPE_GRID)))
        for s0, q, ecc in flights:
            s = s0 - DELAY_GRID[:, None, None] - SLOPE_GRID[None, :, None] * ecc  # (D, K, n)
            ok = (s > 0).all(axis=-1)
            y = np.broadcast_to(q, (*s.shape, 2)).copy()
            y[..., 1] += 0.5 * self.gravity * s * s
            ss = np.where(ok, (s * s).sum(axis=-1), 1.0)
            v = (s[..., None] * y).sum(axis=-2) / ss[..., None]
            sse = ((y - s[..., None] * v[..., None, :]) ** 2).sum(axis=(-2, -1))
            total += np.where(ok, sse, np.inf)
        if not np.isfinite(total).any():
            return
        i, j = np.unravel_index(int(np.argmin(total)), total.shape)
        self._gaze_flights = flights
        self.gaze_estimate = (float(DELAY_GRID[i]), float(SLOPE_GRID[j]))
        self._fitted = False

    @property
    def delay_estimate(self) -> float | None:
        """s; the release-anchored estimator's delay from the episode's flights so far
        (by its :attr:`rule`; without one the mean of the flights' delays), or None
        before the first."""
        if self.rule is None:
            return float(np.mean(self._delays)) if self._delays else None
        if self._ruled[0] != len(self._anchors):  # the rule asked once per new flight
            got = self.rule(self._anchors, self.gravity) if self._anchors else None
            self._ruled = (len(self._anchors), got)
        return self._ruled[1]

    def _times(self, frames: list[CameraFrame]) -> FloatArray | None:
        arrivals = np.array([f.arrival for f in frames])
        if self.mode == "arrival":
            return arrivals
        if self.mode == "mean_delay":
            return arrivals - self.fixed_delay
        if self.mode == "release":
            d = self.delay_estimate
            return None if d is None else arrivals - max(d + self.offset, 0.0)
        if self.mode == "gaze_release":
            if self.gaze_estimate is None:
                return None
            d, k = self.gaze_estimate
            assert self._apex is not None
            pos = np.array([[f.x, f.z] for f in frames])
            return arrivals - (d + k * eccentricities(pos, np.array(self._apex), self.eye))
        gaze = np.array([f.gaze for f in frames])
        if gaze.any():  # level gaze: each frame's own gaze latency
            return arrivals - (self.true_delay + gaze)
        return arrivals - self.true_delay

    def fit(self) -> tuple[float, FloatArray, FloatArray] | None:
        """The fitted flight ``(t0, position, velocity)`` at the newest frame's believed
        time ``t0`` (refitted only when frames arrived), or None (fewer than 3 frames of
        this flight, or no delay estimate yet)."""
        if not self._fitted:
            self._fit = self._refit()
            self._fitted = True
            self._version += 1
        return self._fit

    def _refit(self) -> tuple[float, FloatArray, FloatArray] | None:
        frames = self.frames[-self.window :]
        if len(frames) < 3:
            return None
        times = self._times(frames)
        if times is None:
            return None
        t0 = float(times[-1])
        tau = times - t0
        p = np.array([[f.x, f.z] for f in frames])
        design = np.stack([np.ones_like(tau), tau], axis=1)
        acc = np.array([0.0, -self.gravity])
        for _ in range(2 if self.drag > 0 else 1):
            y = p - 0.5 * (tau * tau)[:, None] * acc[None, :]
            (a, b), *_ = np.linalg.lstsq(design, y, rcond=None)
            sp = math.hypot(float(b[0]), float(b[1]))
            acc = np.array([-self.drag * sp * b[0], -self.gravity - self.drag * sp * b[1]])
        return t0, a, b

    def estimate(self, now: float) -> tuple[FloatArray, FloatArray] | None:
        """The ball's ``(position, velocity)`` at ``now`` along the fitted flight
        (:meth:`fit`) under this estimator's model, or None without a fit."""
        fit = self.fit()
        if fit is None:
            return None
        t0, a, b = fit
        x, z, vx, vz = drag_flight(
            (float(a[0]), float(a[1])), (float(b[0]), float(b[1])), now - t0, self.gravity,
            self.drag,
        )  # fmt: skip
        return np.array([x, z]), np.array([vx, vz])

    def position_at(self, time: float) -> tuple[float, float] | None:
        """The fitted flight's position at ``time`` (cached per fit and time)."""
        fit = self.fit()
        if fit is None:
            return None
        key = (self._version, time)
        if self._cached is None or self._cached[0] != key:
            t0, a, b = fit
            x, z, _, _ = drag_flight(
                (float(a[0]), float(a[1])), (float(b[0]), float(b[1])), time - t0,
                self.gravity, self.drag,
            )  # fmt: skip
            self._cached = (key, (x, z))
        return self._cached[1]
