"""The analytic cascade juggler's fit, state and sensor: an odd cascade of ``balls``
balls (3 or 5) with two hands.

**Fit** (:func:`cascade_fit`): the SIMULATED two-hand demonstrations of the pattern
(:func:`~motion_envs.datasets.juggling.generate_cascade_demonstrations` with ``balls``;
each hand in its own frame, the left hand mirrored ``x -> -x``) are split by
demonstration and the per-phase sine-series models
(:class:`~motion_envs.models.juggling.AnalyticJuggler`, the one-ball juggler's fit with
``V1_N_SINES`` sines per phase) are fitted on the training cycles of both hands pooled.
The pattern's timing (:class:`CascadePattern`): the dwell ratio ``r`` is the training
cycles' median (return plus toss to the release, over the hand's cycle); the flight ``F``
is that of the juggler's own nominal toss to the mean catch height; Shannon's theorem
``(F + D) H = (V + D) N`` (``H = 2``, ``N = balls``) gives the period
``C = F / (N / H - r)``; a juggler with another dwell ratio keeps the flight.

The control (each hand the one-ball juggler, scheduled by the pattern) is
:mod:`~motion_envs.models.juggling._cascade_control`'s; one hand's controller is
:mod:`~motion_envs.models.juggling._cascade_hand`'s.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from motion_envs.datasets.juggling import (
    CASCADE_BALLS,
    CASCADE_HANDS,
    JugglingDemos,
    JugglingTask,
    cascade_timing,
    generate_cascade_demonstrations,
    split_cycles,
)
from motion_envs.geometry import sine_series as ss
from motion_envs.models.juggling._fit import FIT_SEED, FIT_TEST_FRACTION, V1_N_SINES
from motion_envs.models.juggling._juggler import AnalyticJuggler
from motion_envs.models.juggling._levels import HumanLikeness
from motion_envs.models.juggling._sensor import BallSensor, predict_forward

__all__ = [
    "CascadeFit",
    "CascadePattern",
    "CascadeSensor",
    "CascadeState",
    "cascade_fit",
    "cascade_likeness",
    "nominal_release",
]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class CascadeState:
    """The cascade world after one step (or at reset); ``(x, z)`` rows, ``B`` balls.

    ``holder[i]``: the hand holding ball ``i`` (0 right, 1 left) or -1 in flight;
    ``released[h]`` / ``caught[h]``: the ball hand ``h`` released / caught during the last
    step, or -1; ``dropped[i]``: ball ``i`` touched the floor (sticky).
    """

    time: float
    hand_pos: FloatArray  # (2, 2)
    hand_vel: FloatArray  # (2, 2)
    ball_pos: FloatArray  # (B, 2)
    ball_vel: FloatArray  # (B, 2)
    holder: tuple[int, ...]
    released: tuple[int, ...]  # per hand
    caught: tuple[int, ...]  # per hand
    dropped: tuple[bool, ...]

    @property
    def any_dropped(self) -> bool:
        """Whether a ball has touched the floor."""
        return any(self.dropped)


@dataclass(frozen=True)
class CascadePattern:
    """The pattern's timing (module docstring).

    ``dwell_ratio`` and ``demo_period`` are the medians over the training cycles of both
    hands (``demo_flight`` what Shannon's theorem gives for them); ``lead`` (toss start to
    release), ``release_position`` / ``release_velocity`` (own frame) are the juggler's
    nominal toss's (the fitted toss plan from home to the mean toss end over the mean toss
    duration, released where its commanded vertical acceleration first falls below
    ``-toss_threshold`` after ``release_after``); ``flight`` is that toss's flight to the
    mean catch height (descending); ``catch_duration`` the training catches' median;
    ``balls`` the cascade's (Shannon's ``N``).
    """

    dwell_ratio: float
    demo_period: float
    demo_flight: float
    flight: float
    lead: float
    release_position: FloatArray
    release_velocity: FloatArray
    catch_duration: float
    balls: int = CASCADE_BALLS

    def timing(self, dwell_ratio: float | None = None) -> tuple[float, float]:
        """``(period, beat)`` of the juggler's flight at ``dwell_ratio`` (None: the
        demonstrations')."""
        r = self.dwell_ratio if dwell_ratio is None else float(dwell_ratio)
        t = cascade_timing(self.flight, r, CASCADE_HANDS, self.balls)
        return t.period, t.beat


def nominal_release(juggler: AnalyticJuggler) -> tuple[float, FloatArray, FloatArray]:
    """``(lead, position, velocity)`` of the juggler's nominal toss (own frame; see
    :class:`CascadePattern`)."""
    fit = juggler.phases_["toss"]
    start, end = juggler.home_, fit.end_mean
    duration = float(np.mean(fit.duration_range))
    p = fit.model.plan(
        np.concatenate([start, end]), duration, start, end, final_velocity=np.zeros(2),
        axes=[1], mode="hyperplane", fix_end=False, max_end_shift=None,
    )  # fmt: skip
    dt = juggler.task.dt
    k = np.arange(math.ceil(duration / dt - 1e-9) + 1)
    y = ss.evaluate(p, np.minimum(k * dt / duration, 1.0))
    az = np.full(len(k), np.inf)
    az[2:] = (y[2:, 1] - 2 * y[1:-1, 1] + y[:-2, 1]) / dt**2
    fired = np.flatnonzero((k * dt >= juggler.release_after) & (az < -juggler.task.toss_threshold))
    if fired.size == 0:
        raise ValueError("the fitted toss never reaches the toss threshold")
    j = int(fired[0])
    return j * dt, y[j].copy(), (y[j] - y[j - 1]) / dt


def _measure_pattern(
    demos: JugglingDemos,
    cycles: frozenset[tuple[int, int]],
    juggler: AnalyticJuggler,
    balls: int,
) -> CascadePattern:
    dwell, period, catch = [], [], []
    by_cycle: dict[tuple[int, int], dict[str, float]] = {}
    for s in demos.segments():
        if (s.recording, s.cycle) not in cycles:
            continue
        by_cycle.setdefault((s.recording, s.cycle), {})[s.phase] = s.duration
        if s.phase == "catch":
            catch.append(s.duration)
    for d in by_cycle.values():
        c = d["toss"] + d["go_down"] + d["catch"] + d["return"]
        dwell.append((d["toss"] + d["return"]) / c)
        period.append(c)
    r, c = float(np.median(dwell)), float(np.median(period))
    lead, p, v = nominal_release(juggler)
    g = juggler.task.gravity
    z_catch = float(juggler.phases_["catch"].end_mean[1])
    flight = float((v[1] + math.sqrt(max(v[1] ** 2 + 2 * g * (p[1] - z_catch), 0.0))) / g)
    return CascadePattern(
        dwell_ratio=r,
        demo_period=c,
        demo_flight=c * (balls / CASCADE_HANDS - r),
        flight=flight,
        lead=lead,
        release_position=p,
        release_velocity=v,
        catch_duration=float(np.median(catch)),
        balls=balls,
    )


@dataclass(frozen=True)
class CascadeFit:
    """The cascade's default fit: demonstrations, split, fitted hand model, pattern."""

    demos: JugglingDemos
    train: frozenset[tuple[int, int]]
    test: frozenset[tuple[int, int]]
    juggler: AnalyticJuggler
    pattern: CascadePattern


@functools.lru_cache(maxsize=8)
def cascade_fit(gravity: float, balls: int = CASCADE_BALLS) -> CascadeFit:
    """The cascade juggler's fit at ``gravity`` for the cascade of ``balls`` balls (3 or
    5): the built-in SIMULATED two-hand demonstrations of that cascade (seed
    ``FIT_SEED``, two persons), split by demonstration (held-out share
    ``FIT_TEST_FRACTION``), the hand model (``V1_N_SINES`` sines per phase, the release
    first armed as Juggling-v1's; the controller arms it later,
    :class:`~motion_envs.models.juggling.CascadeTunables`) and the pattern fitted on the
    training cycles. Computed once per process, gravity and ball count; do not change
    it."""
    task = JugglingTask(gravity=float(gravity))
    demos = generate_cascade_demonstrations(n_persons=2, seed=FIT_SEED, task=task, balls=balls)
    train, test = split_cycles(demos, FIT_TEST_FRACTION, FIT_SEED)
    juggler = AnalyticJuggler(
        task=task, n_sines=V1_N_SINES, release_after=0.25 * math.sqrt(1.0 / task.gravity)
    ).fit(demos, train)
    pattern = _measure_pattern(demos, frozenset(train), juggler, balls)
    return CascadeFit(demos, frozenset(train), frozenset(test), juggler, pattern)


@functools.lru_cache(maxsize=8)
def cascade_likeness(gravity: float, split: str, balls: int = CASCADE_BALLS) -> HumanLikeness:
    """Human-likeness (own frame) against the ``balls``-ball cascade demonstrations'
    ``"train"`` or held-out ``"test"`` cycles at ``gravity``."""
    if split not in ("train", "test"):
        raise ValueError(f"split must be 'train' or 'test'; got {split!r}")
    fit = cascade_fit(float(gravity), balls)
    return HumanLikeness(fit.demos, fit.train if split == "train" else fit.test)


class CascadeSensor:
    """The ``balls`` balls seen through Juggling-v1's sensor: one
    :class:`~motion_envs.models.juggling.BallSensor` per ball (the same latency and noise;
    one generator, used ball by ball in order). ``dt``: s per control period."""

    def __init__(
        self,
        delay_steps: int,
        position_std: float,
        velocity_std: float,
        dt: float,
        balls: int = CASCADE_BALLS,
    ) -> None:
        self.sensors = [BallSensor(delay_steps, position_std, velocity_std) for _ in range(balls)]
        self.delay_steps = self.sensors[0].delay_steps
        self.dt = float(dt)

    def reset(
        self, state: CascadeState, rng: np.random.Generator | None, gravity: float
    ) -> CascadeState:
        """Start: a held ball is measured exactly; a flying ball's delayed buffer holds its
        ballistic past (as if it had flown ``delay_steps`` periods already) and its
        measurement now is its state ``delay_steps`` periods ago. Returns the measured
        state."""
        pos, vel = state.ball_pos.copy(), state.ball_vel.copy()
        for i, sensor in enumerate(self.sensors):
            if state.holder[i] >= 0:
                m = sensor.reset(state.ball_pos[i], state.ball_vel[i], rng)
                pos[i], vel[i] = m.position, m.velocity
                continue
            d = sensor.delay_steps
            p0, v0 = state.ball_pos[i], state.ball_vel[i]
            past = [predict_forward(p0, v0, -k * self.dt, gravity) for k in range(d, -1, -1)]
            sensor.reset(past[0][0], past[0][1], rng)
            for p, v in past[1:]:
                sensor.measure(p, v, False)
            pos[i], vel[i] = past[0]
        return _with_balls(state, pos, vel)

    def measure(self, state: CascadeState) -> CascadeState:
        """Record the true state of this step; return the measured state."""
        pos, vel = state.ball_pos.copy(), state.ball_vel.copy()
        for i, sensor in enumerate(self.sensors):
            m = sensor.measure(state.ball_pos[i], state.ball_vel[i], state.holder[i] >= 0)
            pos[i], vel[i] = m.position, m.velocity
        return _with_balls(state, pos, vel)


def _with_balls(state: CascadeState, pos: FloatArray, vel: FloatArray) -> CascadeState:
    return CascadeState(
        time=state.time,
        hand_pos=state.hand_pos,
        hand_vel=state.hand_vel,
        ball_pos=pos,
        ball_vel=vel,
        holder=state.holder,
        released=state.released,
        caught=state.caught,
        dropped=state.dropped,
    )
