"""SIMULATED three-ball cascade demonstrations: a seeded model of a person juggling three
balls with two hands, each hand recorded in its own (mirrored) frame.

The cascade's timing is Shannon's juggling theorem ``(F + D) H = (V + D) N`` with
``H = 2`` hands and ``N = 3`` balls (:func:`cascade_timing`): a hand's period is
``C = V + D`` (dwell ``D`` holding a ball, vacant ``V`` empty), the hands throw in turn
every beat ``b = C / 2``, and a ball flies ``F = 3 b - D`` from one hand's release to the
other hand's catch. The dwell ratio ``r = D / C`` is a parameter of the person.

**Frames.** The world is the vertical plane ``(x, z)`` with the body's midline at ``x = 0``;
the right hand works at ``x > 0``. Each hand is recorded in its *own* frame: the right
hand's is the world's, the left hand's the mirror image ``x -> -x``. In its own frame every
hand does the same thing: it throws from the inside (small ``x``) upwards and inwards,
across the midline, and catches the other hand's ball on the outside (larger ``x``).

**One hand's cycle** (the four phases of the one-ball task, :data:`PHASES`), generated with
quintic (minimum-jerk) polynomials and the ballistic closed form only (never the
sine-series model, so fitting that model to these data is a real test):

1. **toss**: from rest at home a quintic to the top of the toss that stops sharply
   (zero vertical end velocity, vertical end acceleration ``brake``, still moving inwards
   at ``toss_vx``); the ball is released at the first sample where the hand's vertical
   acceleration (second backward difference) falls below ``-toss_threshold``, with the
   hand's velocity. The toss starts ``lead`` (the nominal toss's release time) before the
   hand's beat, so that the release falls on the beat;
2. **go down**: a quintic from the state at the release to a waiting point below and
   outside the catch point, at rest; it ends ``catch_share V`` before the incoming ball
   (thrown by the other hand one beat earlier) reaches the person's catch height;
3. **catch**: a quintic from the waiting point to the ball's crossing of the catch height,
   arriving with it; the first aim carries a perception error (``aim_error``), re-planned
   to the real intercept after a reaction delay (at most 60 % into the reach); the catch
   is the first sample where the hand centre is within ``catch_radius`` of the ball's;
4. **return** (the carry): a quintic from the catch state to home at rest, arriving
   ``lead`` before the hand's next beat (the dwell absorbs the flights' scatter, so the
   pattern keeps its beat).

The person's tempo follows their throw: the nominal toss fixes the release velocity, the
catch height (``catch_drop`` below the release) the flight time ``F``, and the dwell ratio
the period ``C = F / (1.5 - r)``. The pattern starts with a ball in each hand and one in
flight towards the right hand (thrown by the left hand one beat before the first beat).
Two options of the style change the cycle (both off in the three- and five-ball
populations; ``experiments/five_ball_demos.py`` explores them): ``catch_follow`` (the
go-down ends at the waiting point, and the catch at the ball, moving with that share of
the ball's velocity at the catch, so the carry starts with it) and ``toss_to_top`` (the
toss phase goes on past the release to the toss plan's top, the go-down starting there).
Per person (seeded): home, toss, brake, speed, catch height, dwell ratio, waiting point,
reaction delay. Per cycle: small variations of each, physiological tremor and sensor noise
on the recorded hand (as :func:`~motion_envs.datasets.juggling.generate_demonstrations`).
Every generated set has ``simulated = True``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from motion_envs.datasets.juggling import rules
from motion_envs.datasets.juggling._records import JugglingDemos, JugglingRecording
from motion_envs.datasets.juggling._task import JugglingTask, ballistic_position
from motion_envs.geometry.minimum_jerk import quintic, quintic_evaluate

__all__ = [
    "CASCADE_BALLS",
    "CASCADE_HANDS",
    "CASCADE_STYLES",
    "CascadeStyle",
    "CascadeTiming",
    "NominalToss",
    "cascade_timing",
    "draw_cascade_person",
    "generate_cascade_demonstrations",
    "mirror_x",
    "nominal_toss",
    "style_timing",
]

FloatArray = NDArray[np.float64]

#: Hands and balls of the cascade (Shannon's ``H`` and ``N``).
CASCADE_HANDS = 2
CASCADE_BALLS = 3
#: m/s^2, the gravity the styles' times are written for (times scale with ``sqrt(g0 / g)``).
_STYLE_GRAVITY = 9.81


@dataclass(frozen=True)
class CascadeTiming:
    """The pattern's times (s) from Shannon's theorem (:func:`cascade_timing`)."""

    period: float  # C = V + D, one hand's cycle
    beat: float  # C / H, between two throws (of alternate hands)
    dwell: float  # D, a ball in a hand
    vacant: float  # V, a hand empty
    flight: float  # F, release to catch


def cascade_timing(
    flight: float, dwell_ratio: float, hands: int = CASCADE_HANDS, balls: int = CASCADE_BALLS
) -> CascadeTiming:
    """The pattern's times for a flight ``F`` (s) and a dwell ratio ``r = D / (V + D)``:
    Shannon's ``(F + D) H = (V + D) N`` with ``C = V + D`` gives ``C = F / (N / H - r)``.

    Raises ``ValueError`` unless ``F > 0``, ``0 < r < 1`` and ``N > H r`` (a ball must
    fly)."""
    if not (math.isfinite(flight) and flight > 0):
        raise ValueError(f"flight must be finite and > 0; got {flight!r}")
    if not (0.0 < dwell_ratio < 1.0):
        raise ValueError(f"dwell_ratio must be in (0, 1); got {dwell_ratio!r}")
    if hands < 1 or balls <= hands * dwell_ratio:
        raise ValueError(f"need balls > hands * dwell_ratio; got {balls}, {hands}, {dwell_ratio}")
    period = flight / (balls / hands - dwell_ratio)
    dwell = dwell_ratio * period
    return CascadeTiming(period, period / hands, dwell, period - dwell, flight)


def mirror_x(values: FloatArray) -> FloatArray:
    """``(..., 2)`` points or velocities with ``x`` negated (world <-> the left hand's frame)."""
    out = np.array(values, dtype=np.float64)
    out[..., 0] *= -1.0
    return out


@dataclass(frozen=True)
class CascadeStyle:
    """A simulated cascade juggler's style (SI units, a hand's own frame; times for
    9.81 m/s^2; see the module docstring)."""

    home: tuple[float, float]  # throw start, inside
    toss: tuple[float, float]  # toss plan end offset from home (dx < 0: inwards)
    brake: float  # m/s^2, vertical end acceleration of the toss plan (negative)
    toss_vx: float  # m/s, horizontal end velocity of the toss plan (negative: inwards)
    toss_time: float  # s, toss plan duration
    catch_drop: float  # m, catch height below the release height
    dwell_ratio: float  # D / (V + D)
    wait: tuple[float, float]  # waiting point's offset from the nominal catch point
    catch_share: float  # share of the vacant time taken by the catch reach
    reaction: float  # s, reaction delay of the catch correction
    aim_error: float  # m, std of the first aim of the catch
    variation: float  # relative per-cycle variation
    spread: float  # m, per-cycle std of the points
    #: share of the ball's velocity the hand has when it meets the ball (0: the waiting
    #: point and the catch at rest, both populations; > 0: the hand goes down through the
    #: waiting point and meets the falling ball moving with it, the carry keeping that
    #: momentum; explored by ``experiments/five_ball_demos.py``)
    catch_follow: float = 0.0
    #: whether the hand goes on to its toss plan's top (vertically at rest) after the
    #: release before it goes down, the toss phase lasting until then, as the juggler's
    #: toss plan does (False: the go-down starts at the release, both populations)
    toss_to_top: bool = False


def draw_cascade_person(rng: np.random.Generator, balls: int = CASCADE_BALLS) -> CascadeStyle:
    """A juggler's style for the cascade of ``balls`` balls drawn from that cascade's
    population (:data:`CASCADE_STYLES`; seeded by ``rng``)."""
    if balls not in CASCADE_STYLES:
        raise ValueError(f"balls must be one of {sorted(CASCADE_STYLES)}; got {balls!r}")
    return CASCADE_STYLES[balls](rng)


def _three_ball_person(rng: np.random.Generator) -> CascadeStyle:
    """The three-ball cascade's population."""
    u = rng.uniform
    return CascadeStyle(
        home=(0.06 + u(-0.02, 0.02), 1.0 + u(-0.03, 0.03)),
        toss=(u(-0.06, -0.04), u(0.42, 0.48)),
        brake=u(-115.0, -105.0),
        toss_vx=u(-0.8, -0.65),
        toss_time=u(0.25, 0.27),
        catch_drop=u(0.17, 0.23),
        dwell_ratio=u(0.52, 0.58),
        wait=(u(-0.05, -0.03), u(-0.05, -0.02)),
        catch_share=u(0.35, 0.45),
        reaction=u(0.15, 0.25),
        aim_error=u(0.004, 0.008),
        variation=u(0.01, 0.02),
        spread=u(0.004, 0.008),
    )


def _five_ball_person(rng: np.random.Generator) -> CascadeStyle:
    """The five-ball cascade's population: a human dwell ratio (about 2/3: J. Kalvan, "How
    many objects can be juggled", 1997: "My tests show r is usually about 2/3"; his
    "Optimal Juggling", 1996, reports the same for 3, 5, 7 and 9 balls), a shorter,
    faster toss (0.17 s instead of 0.26 s; released at about 3.7 m/s upwards, a flight of
    about 0.74 s and a throw every 0.20 s: real five-ball cascades throw every ~0.2 s
    with flights of ~0.65-0.77 s), caught a little ABOVE the release (the empty hand has
    only ~0.14 s to stop rising and reach the catch) and a narrower pattern."""
    u = rng.uniform
    return CascadeStyle(
        home=(0.06 + u(-0.02, 0.02), 1.1 + u(-0.03, 0.03)),
        toss=(u(-0.05, -0.03), u(0.38, 0.42)),
        brake=u(-115.0, -105.0),
        toss_vx=u(-0.3, -0.2),
        toss_time=u(0.165, 0.175),
        catch_drop=u(-0.08, -0.03),
        dwell_ratio=u(0.64, 0.69),
        wait=(u(-0.06, -0.04), u(-0.05, -0.03)),
        catch_share=u(0.3, 0.4),
        reaction=u(0.06, 0.1),
        aim_error=u(0.003, 0.006),
        variation=u(0.008, 0.015),
        spread=u(0.003, 0.006),
    )


#: Per cascade (ball count), its population of simulated jugglers' styles.
CASCADE_STYLES: dict[int, Callable[[np.random.Generator], CascadeStyle]] = {
    3: _three_ball_person,
    5: _five_ball_person,
}


@dataclass(frozen=True)
class NominalToss:
    """The release of a style's nominal toss (own frame, relative to the toss start)."""

    lead: float  # s from the toss start to the release
    position: FloatArray  # release point
    velocity: FloatArray  # release velocity


def _toss_plan(
    start: FloatArray, top: FloatArray, style: CascadeStyle, scale: float, duration: float
) -> FloatArray:
    z2 = np.zeros(2)
    v_top = np.array([style.toss_vx / scale, 0.0])
    brake = np.array([0.0, style.brake / scale**2])
    return quintic(start, z2, z2, top, v_top, brake, duration)


def _release_index(y: FloatArray, prev: FloatArray, task: JugglingTask) -> int | None:
    """First sample of the toss ``y`` where the release fires (``prev``: the two samples
    before it)."""
    full = np.concatenate([prev, y])
    az = rules.hand_acceleration(full[2:, 1], full[1:-1, 1], full[:-2, 1], task.dt)
    fired = np.flatnonzero(rules.release_fires(np.arange(len(y)) > 0, az, task.toss_threshold))
    return int(fired[0]) if fired.size else None


def nominal_toss(style: CascadeStyle, task: JugglingTask) -> NominalToss:
    """The release of the style's nominal toss (no variation, no tremor), from rest at
    home; raises ``ValueError`` if the toss threshold never fires."""
    scale = math.sqrt(_STYLE_GRAVITY / task.gravity)
    start = np.asarray(style.home, dtype=np.float64)
    duration = style.toss_time * scale
    c = _toss_plan(start, start + np.asarray(style.toss), style, scale, duration)
    k = np.arange(math.floor(duration / task.dt) + 1)
    y = quintic_evaluate(c, k * task.dt)
    j = _release_index(y, np.repeat(y[:1], 2, axis=0), task)
    if j is None or j == 0:
        raise ValueError("the style's toss never reaches the toss threshold")
    return NominalToss(j * task.dt, y[j], rules.hand_velocity(y[j], y[j - 1], task.dt))


def _descend_time(p: FloatArray, v: FloatArray, z: float, g: float) -> float:
    """s until a ball at ``p`` with ``v`` falls through height ``z`` (descending)."""
    disc = v[1] ** 2 + 2.0 * g * (p[1] - z)
    return float((v[1] + math.sqrt(max(disc, 0.0))) / g)


def style_timing(
    style: CascadeStyle, task: JugglingTask, balls: int = CASCADE_BALLS
) -> tuple[NominalToss, CascadeTiming]:
    """The style's nominal toss and the timing it implies for the cascade of ``balls``
    balls (module docstring)."""
    toss = nominal_toss(style, task)
    flight = _descend_time(
        toss.position, toss.velocity, float(toss.position[1]) - style.catch_drop, task.gravity
    )
    return toss, cascade_timing(flight, style.dwell_ratio, CASCADE_HANDS, balls)


class _Hand:
    """One hand's recording on the shared grid, in its own frame."""

    def __init__(self, n: int, home: FloatArray) -> None:
        self.y = np.tile(home, (n, 1))
        self.label = np.full(n, "rest", dtype="<U8")

    def put(self, c: FloatArray, t0: float, k_from: int, k_to: int, phase: str, dt: float) -> None:
        k = np.arange(k_from, k_to)
        self.y[k_from:k_to] = quintic_evaluate(c, k * dt - t0)
        self.label[k_from:k_to] = phase


def generate_cascade_demonstrations(
    n_cycles: int = 50,
    n_persons: int = 1,
    seed: int = 0,
    task: JugglingTask | None = None,
    sensor_noise: float = 5e-5,
    styles: list[CascadeStyle] | None = None,
    balls: int = CASCADE_BALLS,
) -> JugglingDemos:
    """SIMULATED cascade demonstrations of ``balls`` balls (odd: 3 or 5): per person,
    ``n_cycles`` cycles of each hand, two recordings (the right hand, then the left hand
    mirrored into its own frame). Without ``styles`` each person is drawn from the
    population of the ``balls``-ball cascade (:func:`draw_cascade_person`).

    ``task`` holds gravity, the control period, the catch radius and the toss threshold
    (default ``JugglingTask(gravity=9.81)``). Seeded: the same arguments give the same
    arrays. Raises ``RuntimeError`` if the simulated person misses a ball.
    """
    if n_cycles < 2 or n_persons < 1:
        raise ValueError(f"n_cycles must be >= 2 and n_persons >= 1; got {n_cycles}, {n_persons}")
    if sensor_noise < 0:
        raise ValueError(f"sensor_noise must be >= 0; got {sensor_noise}")
    if balls not in CASCADE_STYLES:
        raise ValueError(f"balls must be one of {sorted(CASCADE_STYLES)}; got {balls!r}")
    task = task or JugglingTask(gravity=_STYLE_GRAVITY)
    root = np.random.SeedSequence(seed)
    recordings = []
    tag = "cascade-" if balls == CASCADE_BALLS else f"cascade{balls}-"
    for p, ss in enumerate(root.spawn(n_persons)):
        rng = np.random.default_rng(ss)
        style = styles[p] if styles is not None else draw_cascade_person(rng, balls)
        hands = _simulate(style, task, n_cycles, rng, balls)
        t = np.arange(len(hands[0].y), dtype=np.float64) * task.dt
        for h, name in enumerate(("right", "left")):
            recorded = hands[h].y + sensor_noise * rng.standard_normal(hands[h].y.shape)
            recordings.append(
                JugglingRecording(
                    name=f"simulated-{tag}person-{p}-{name}",
                    t=t,
                    hand=recorded,
                    phase=hands[h].label.astype(str),
                    person=f"simulated-{tag}person-{p}",
                )
            )
    return JugglingDemos(
        name=f"simulated-{tag[:-1]}(seed={seed})",
        recordings=tuple(recordings),
        simulated=True,
        task=task,
    )


def _simulate(
    style: CascadeStyle, task: JugglingTask, n_cycles: int, rng: np.random.Generator, balls: int
) -> tuple[_Hand, _Hand]:
    dt, g = task.dt, task.gravity
    scale = math.sqrt(_STYLE_GRAVITY / g)
    toss0, timing = style_timing(style, task, balls)
    b = timing.beat
    home = np.asarray(style.home, dtype=np.float64)
    catch_z = float(toss0.position[1]) - style.catch_drop
    # the nominal catch point: the other hand's nominal ball, in this hand's frame
    catch_x = -float(toss0.position[0] + toss0.velocity[0] * timing.flight)
    n_slots = 2 * n_cycles + 2
    t_first = toss0.lead + 0.1  # the first beat (a short rest before it)
    n = round((t_first + (n_slots + 2) * b) / dt) + 1
    hands = (_Hand(n, home), _Hand(n, home))
    freqs = rng.uniform(8.0, 12.0, size=(2, 2, 2))
    phs = rng.uniform(0, 2 * np.pi, size=(2, 2, 2))
    amps = rng.uniform(0.5e-4, 1.5e-4, size=(2, 2, 2))
    z2 = np.zeros(2)

    def vary(x: float) -> float:
        return x * (1.0 + style.variation * float(rng.standard_normal()))

    # balls as (release time, position, velocity) in the WORLD frame, by slot: before the
    # first beat, the balls landing on beats 2 .. N - 1 were thrown on beats 2 - N .. -1
    # by the hand of their beat (the left hand on the odd ones)
    releases: dict[int, tuple[float, FloatArray, FloatArray]] = {}
    for slot in range(2 - balls, 0):
        own0 = (lambda a: a) if slot % 2 == 0 else mirror_x
        releases[slot] = (t_first + slot * b, own0(toss0.position), own0(toss0.velocity))
    start_k = [round((t_first + h * b - toss0.lead) / dt) for h in (0, 1)]
    for slot in range(n_slots):
        h = slot % 2
        own = (lambda a: a) if h == 0 else mirror_x
        hand = hands[h]
        # 1. toss from rest at home, starting at start_k[h]
        k0 = start_k[h]
        t0 = k0 * dt
        start = hand.y[k0 - 1].copy() if k0 > 0 else home.copy()
        top = start + np.asarray(style.toss) * (1 + style.variation * rng.standard_normal(2))
        toss_time = vary(style.toss_time) * scale
        c_toss = _toss_plan(start, top, style, scale, toss_time)
        kk = np.arange(k0, k0 + round(style.toss_time * scale * 1.2 / dt))
        y = quintic_evaluate(c_toss, kk * dt - t0)
        j = _release_index(y, hand.y[k0 - 2 : k0] if k0 >= 2 else np.repeat(y[:1], 2, 0), task)
        if j is None or j == 0:
            raise RuntimeError("simulated toss never reached the toss threshold")
        k_rel = k0 + j
        if k_rel >= n - 1:
            break
        # the toss phase ends at the release, or at the toss plan's top (``toss_to_top``)
        k_off = max(k0 + math.floor(toss_time / dt), k_rel) if style.toss_to_top else k_rel
        hand.put(c_toss, t0, k0, k_off, "toss", dt)
        p_rel, v_rel = y[j], rules.hand_velocity(y[j], y[j - 1], dt)
        releases[slot] = (k_rel * dt, own(p_rel), own(v_rel))
        # 2.-3. go down, catch the ball of slot + 2 - N (thrown by the other hand, it is
        # thrown again on this hand's next beat)
        t_r_in, p_in, v_in = releases[slot + 2 - balls]
        p_in, v_in = own(p_in), own(v_in)
        s_c = _descend_time(p_in, v_in, catch_z + style.spread * rng.standard_normal(), g)
        t_c = t_r_in + s_c
        target = ballistic_position(p_in, v_in, s_c, g)
        k_c = math.floor(t_c / dt)
        t_reach = vary(style.catch_share * timing.vacant)
        k_b = min(max(round((t_c - t_reach) / dt), k_off + 8), k_c - 6)
        s_rel = k_off * dt - t0
        q_rel = [quintic_evaluate(c_toss, np.array(s_rel), o) for o in range(3)]
        wait = np.array([catch_x, catch_z]) + np.asarray(style.wait)
        wait = wait + style.spread * rng.standard_normal(2)
        v_meet = z2
        if style.catch_follow > 0:  # the ball's velocity at the catch, followed in part
            v_meet = style.catch_follow * (v_in + np.array([0.0, -g * s_c]))
        c_down = quintic(q_rel[0], q_rel[1], q_rel[2], wait, v_meet, z2, (k_b - k_off) * dt)
        hand.put(c_down, k_off * dt, k_off, k_b, "go_down", dt)
        t_b = k_b * dt
        aim = target + style.aim_error * rng.standard_normal(2)
        c_aim = quintic(wait, v_meet, z2, aim, v_meet, z2, t_c - t_b)
        t_fix = t_b + min(vary(style.reaction), 0.6 * (t_c - t_b))
        q = [quintic_evaluate(c_aim, np.array(t_fix - t_b), o) for o in range(3)]
        c_fix = quintic(q[0], q[1], q[2], target, v_meet, z2, t_c - t_fix)
        k_fix = math.ceil(t_fix / dt)
        hand.put(c_aim, t_b, k_b, k_fix, "catch", dt)
        k_end = min(math.ceil(t_c / dt) + 1, n)
        hand.put(c_fix, t_fix, k_fix, k_end, "catch", dt)
        kc = np.arange(k_b, k_end)
        ball = ballistic_position(p_in, v_in, kc * dt - t_r_in, g)
        dist = np.linalg.norm(hand.y[k_b:k_end] - ball, axis=1)
        touch = np.flatnonzero(dist <= task.catch_radius)
        if touch.size == 0:  # cannot happen: the hand reaches the ball centre at t_c
            raise RuntimeError("simulated catch missed the ball")
        k_touch = k_b + int(touch[0])
        t_touch = k_touch * dt
        # 4. return (carry) home, arriving lead before the next beat of this hand
        c_last, t_last = (c_fix, t_fix) if t_touch >= t_fix else (c_aim, t_b)
        q = [quintic_evaluate(c_last, np.array(t_touch - t_last), o) for o in range(3)]
        k_home = round((t_first + (slot + 2) * b - toss0.lead) / dt)
        k_home = max(k_home, k_touch + round(0.5 * (timing.dwell - toss0.lead) / dt))
        home_next = home + style.spread * rng.standard_normal(2)
        if k_home >= n:
            hand.label[k_touch:] = "return"
            hand.y[k_touch:] = quintic_evaluate(
                quintic(q[0], q[1], q[2], home_next, z2, z2, (k_home - k_touch) * dt),
                np.arange(k_touch, n) * dt - t_touch,
            )
            break
        c_ret = quintic(q[0], q[1], q[2], home_next, z2, z2, (k_home - k_touch) * dt)
        hand.put(c_ret, t_touch, k_touch, k_home, "return", dt)
        hand.y[k_home:] = home_next
        hand.label[k_home:] = "rest"
        start_k[h] = k_home
    for h, hand in enumerate(hands):
        t = np.arange(n) * dt
        f, ph, a = freqs[h], phs[h], amps[h]
        arg = 2 * np.pi * f[None] * t[:, None, None] + ph[None]
        hand.y = hand.y + np.sum(a[None] * np.sin(arg), axis=2)
    return hands
