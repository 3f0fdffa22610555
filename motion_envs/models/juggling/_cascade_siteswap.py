r"""The siteswap juggler's plan: any vanilla siteswap with two hands, each throw value
planned on its own flight (Shannon's theorem, throw by throw), every hand movement a
quintic within the hand's speed and acceleration limits.

**Beats.** Beat ``k`` is at ``t_k = t_0 + k b``; the right hand throws on even beats, the
left on odd ones; the throw on beat ``k`` has value ``h_k`` (the siteswap read
cyclically) and lands on beat ``k + h_k`` in hand ``(k + h_k) mod 2``: an odd throw
crosses, an even one comes back to its thrower. A hand's period is ``2 b``, its dwell
``D = r 2 b`` at the dwell ratio ``r = D / (V + D)``.

**Each throw value's flight** (:meth:`SiteswapTiming.flight`): the ball thrown on beat
``k`` is thrown again on beat ``k + h``, the catching hand holding it ``D_h`` before that,
so it flies ``F_h = h b - D_h`` (:func:`~motion_envs.datasets.juggling.siteswap_flights`;
for the cascade, ``h = N``, this is Shannon's ``(F + D) H = (V + D) N``). ``D_h = D`` for
``h >= 3``; two values are special:

* ``h = 2`` is a **hold**: the hand keeps the ball over the beat (no release, no catch;
  its carry runs on to its next throw). A vanilla ``2`` lands in the thrower two beats
  later, so holding it is the same siteswap; people hold a ``2`` in ``423``.
* ``h = 1`` is a **pass**: a short, nearly horizontal toss from the thrower's release
  point to the other hand's inner catch point (``SiteswapStyle.pass_x``) that flies
  ``pass_flight`` of a beat, so the catching hand holds it ``D_1 = (1 - pass_flight) b``
  (shorter than ``D``: with ``D >= b``, as at any human dwell ratio over 1/2, a ``1``
  with the common dwell could not fly).

``h = 0`` (an empty hand) is refused (:func:`siteswap_reasons`).

**Each throw's velocity** (:meth:`SiteswapPlan.throw_velocity`): from the release point
(own frame) to the landing hand's catch point (the outer catch point, the pass point
for a ``1``) in ``F_h``: ``v_x = \Delta x / F_h``, ``v_z = \Delta z / F_h + g F_h / 2``.

**The hand's movements** are quintics (minimum jerk between two states, position,
velocity and acceleration): the *carry* from the catch (at the ball's position, moving
with ``catch_follow`` of the ball's velocity) to the release (at the release point with
the throw's velocity, decelerating at ``release_brake`` toss thresholds, so that the
world's release rule fires there), and the *vacant* movement from the release to the
next catch. The **tempo** (:func:`choose_beat`): the beat at which the nominal pattern's
largest acceleration is least, searched over :data:`BEATS`; a pattern whose least peak
is above ``SiteswapStyle.limit_share`` of the hand's acceleration limit (or whose peak
speed is above that share of its speed limit) is refused with the numbers.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from motion_envs._typing import FloatArray
from motion_envs.datasets.juggling import (
    JugglingDemos,
    JugglingRecording,
    JugglingTask,
    ballistic_position,
    parse_siteswap,
    siteswap_balls,
)
from motion_envs.geometry.minimum_jerk import quintic, quintic_evaluate

__all__ = [
    "BEATS",
    "DEMO_PERSONS",
    "DEMO_VARIATION",
    "HAND_ACCEL_LIMIT",
    "HAND_SPEED_LIMIT",
    "SiteswapPlan",
    "SiteswapStyle",
    "SiteswapTiming",
    "choose_beat",
    "peak",
    "siteswap_demonstrations",
    "siteswap_reasons",
]


#: The hand's limits (the world's ``WorldSpec`` defaults; the models layer cannot import
#: the env layer, a test checks they are equal).
HAND_SPEED_LIMIT = 6.0
HAND_ACCEL_LIMIT = 120.0
#: The beats (s) the tempo is searched over.
BEATS = tuple(round(0.15 + 0.005 * i, 3) for i in range(61))
#: The tempo: the fastest beat whose nominal peak acceleration is within this share of
#: the least over :data:`BEATS` (the peak falls with the beat to a plateau: the vacant
#: hand reverses from the throw's speed in a time that grows with the beat as that speed
#: does).
TEMPO_SLACK = 0.05
#: Most balls the juggler plays (the world holds 5).
MAX_SITESWAP_BALLS = 5


@dataclass(frozen=True)
class SiteswapStyle:
    """The siteswap juggler's geometry and choices (own frame of the right hand, m and s;
    a variant is ``dataclasses.replace``).

    ``release``: the release point (inside); ``catch``: the catch point (outside) for
    balls thrown higher than 1; ``pass_x``: the own ``x`` where a pass (a ``1``) is
    caught, at the release height; ``pass_flight``: a pass's flight in beats;
    ``release_brake``: the planned vertical deceleration at the release, in toss
    thresholds (> 1: the release rule fires); ``catch_follow``: share of the ball's
    velocity the hand has when it meets the ball; ``catch_below``, ``catch_above``: m,
    the band around the catch height the intercept is chosen in (a hand rising high into a
    falling ball meets it rising, and the ball bounces off); ``clearance``: m, how far a
    falling ball must stay from a carrying palm (across, and above it) for the carry's
    release point to stay where it is; ``toss_share``: the last share of a
    carry that is the toss phase (observed, the release armed there); ``limit_share``:
    share of the hand's limits the nominal plan may use; ``beat``: s, None for
    :func:`choose_beat`'s.
    """

    release: tuple[float, float] = (0.08, 1.05)
    catch: tuple[float, float] = (0.24, 1.15)
    pass_x: float = 0.0
    pass_flight: float = 0.25
    pass_rise: float = -0.05
    release_brake: float = 1.5
    catch_follow: float = 0.25
    catch_below: float = 0.2
    catch_above: float = 0.0
    clearance: float = 0.1
    toss_share: float = 0.5
    limit_share: float = 1.0
    beat: float | None = None

    def __post_init__(self) -> None:
        for name in ("release", "catch"):
            p = getattr(self, name)
            if len(p) != 2 or not all(isinstance(v, float) and math.isfinite(v) for v in p):
                raise ValueError(f"SiteswapStyle.{name} must be two finite floats; got {p!r}")
        bounds = {
            "pass_x": (-0.5, 1.0),
            "pass_flight": (0.05, 0.95),
            "pass_rise": (-0.3, 0.3),
            "release_brake": (1.05, 3.0),
            "catch_follow": (0.0, 0.9),
            "catch_below": (0.0, 1.0),
            "catch_above": (-0.5, 1.0),
            "clearance": (0.0, 0.5),
            "toss_share": (0.1, 1.0),
            "limit_share": (0.1, 1.0),
        }
        for name, (lo, hi) in bounds.items():
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and lo <= v <= hi):
                raise ValueError(f"SiteswapStyle.{name} must be in [{lo}, {hi}]; got {v!r}")
        b = self.beat
        if b is not None and not (isinstance(b, float) and 0.1 <= b <= 1.0):
            raise ValueError(f"SiteswapStyle.beat must be None or a float in [0.1, 1]; got {b!r}")


def siteswap_reasons(siteswap: str) -> tuple[str, ...]:
    """Why the siteswap juggler cannot play ``siteswap`` (empty: it can, at a tempo
    :func:`choose_beat` finds); ``ValueError`` for a text that is no siteswap."""
    throws = parse_siteswap(siteswap)
    balls = siteswap_balls(throws)
    reasons = []
    if 0 in throws:
        reasons.append("it has empty beats (throws of 0), which the juggler does not model")
    if balls > MAX_SITESWAP_BALLS:
        reasons.append(f"it has {balls} balls; the world holds at most {MAX_SITESWAP_BALLS}")
    if balls < 2:
        reasons.append(f"it has {balls} ball{'' if balls == 1 else 's'}; two hands juggle 2 to 5")
    return tuple(reasons)


def peak(c: FloatArray, duration: float, order: int) -> float:
    """The largest norm of the quintic ``c``'s derivative ``order`` over ``[0, T]`` (31
    samples)."""
    t = np.linspace(0.0, duration, 31)
    return float(np.linalg.norm(quintic_evaluate(c, t, order), axis=1).max())


@dataclass(frozen=True)
class SiteswapTiming:
    """The pattern's tempo: ``beat`` ``b`` and ``dwell`` ``D`` (s), the throws and the
    pass's flight share; :meth:`flight` and :meth:`hold` per throw value (module
    docstring)."""

    throws: tuple[int, ...]
    beat: float
    dwell: float
    pass_flight: float

    def value(self, k: int) -> int:
        """The throw value on beat ``k`` (any integer)."""
        return self.throws[k % len(self.throws)]

    def hold(self, h: int) -> float:
        """s the catching hand holds a ball thrown with value ``h`` (``D_h``)."""
        return (1.0 - self.pass_flight) * self.beat if h == 1 else self.dwell

    def flight(self, h: int) -> float:
        """s, the flight of a throw of ``h`` (``h b - D_h``; 0 for a hold)."""
        return 0.0 if h == 2 else h * self.beat - self.hold(h)

    def source(self, landing: int) -> int:
        """The beat whose throw lands on beat ``landing``."""
        for j in range(landing - max(self.throws), landing + 1):
            if j + self.value(j) == landing:
                return j
        raise ValueError(f"no throw lands on beat {landing}")  # not for a valid siteswap


class SiteswapPlan:
    """The nominal pattern of ``siteswap`` at ``beat`` and ``dwell_ratio`` (module
    docstring): throw velocities, catch points and the nominal quintics; own frames."""

    def __init__(
        self,
        siteswap: str,
        beat: float,
        dwell_ratio: float,
        style: SiteswapStyle,
        task: JugglingTask,
    ) -> None:
        throws = parse_siteswap(siteswap)
        self.balls = siteswap_balls(throws)
        self.style = style
        self.task = task
        self.gravity = task.gravity
        self.timing = SiteswapTiming(throws, beat, dwell_ratio * 2.0 * beat, style.pass_flight)
        for h in set(throws) - {2}:
            if self.timing.flight(h) <= 0:
                raise ValueError(
                    f"a throw of {h} would fly {self.timing.flight(h):.3f} s at beat {beat:.3f} s "
                    f"and dwell {self.timing.dwell:.3f} s"
                )
        self.release = np.array(style.release)
        #: the first release (beat 0), s: the right hand's carry from rest
        self.first_release = 0.9 * beat

    @property
    def beat(self) -> float:
        """s between two throws."""
        return self.timing.beat

    def time(self, k: int) -> float:
        """s, beat ``k``'s time."""
        return self.first_release + k * self.timing.beat

    def catch_point(self, h: int) -> FloatArray:
        """Own frame: where a ball thrown with value ``h`` is caught."""
        if h == 1:
            return np.array((self.style.pass_x, self.style.release[1] + self.style.pass_rise))
        return np.array(self.style.catch)

    def throw_velocity(self, h: int, release: FloatArray | None = None) -> FloatArray:
        """Own frame: the release velocity of a throw of ``h`` from ``release`` (None: the
        release point) to its landing hand's catch point (module docstring)."""
        p = self.release if release is None else release
        f = self.timing.flight(h)
        target = self.catch_point(h)
        if h % 2 == 1:  # crosses: the catcher's own frame mirrored
            target = target * (-1.0, 1.0)
        return np.array(((target[0] - p[0]) / f, (target[1] - p[1]) / f + 0.5 * self.gravity * f))

    def release_state(
        self, h: int, release: FloatArray | None = None
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Own frame ``(p, v, a)`` at the release of a throw of ``h``
        (:meth:`release_acceleration`)."""
        p = self.release if release is None else release
        v = self.throw_velocity(h, p)
        return p.copy(), v, self.release_acceleration(h, v)

    def release_acceleration(self, h: int, v: FloatArray) -> FloatArray:
        """Own frame: the hand's acceleration at the release of a throw of ``h`` with
        velocity ``v``: braking vertically at ``release_brake`` toss thresholds (the
        world's release rule fires there) and, for a pass, as hard horizontally against
        the pass's direction (the hand stops under the ball instead of carrying it
        along: a pass's ball barely rises off the palm)."""
        brake = self.style.release_brake * self.task.toss_threshold
        ax = -brake * float(np.sign(v[0])) if h == 1 else 0.0
        return np.array((ax, -brake))

    def catch_state(self, h: int) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Own frame ``(p, v, a)`` of the nominal catch of a ball thrown with ``h``."""
        p = self.catch_point(h)
        v_ball = self.throw_velocity(h) * (-1.0 if h % 2 else 1.0, 1.0)
        v_ball[1] -= self.gravity * self.timing.flight(h)
        return p, self.style.catch_follow * v_ball, np.zeros(2)

    def ball_at(self, k: int, t: float) -> tuple[FloatArray, FloatArray]:
        """World ``(p, v)`` at ``t`` of the ball thrown on beat ``k`` from its nominal
        release."""
        h = self.timing.value(k)
        p, v, _ = self.release_state(h)
        s = t - self.time(k)
        sign = np.array((-1.0 if k % 2 else 1.0, 1.0))
        return ballistic_position(p, v, s, self.gravity) * sign, (
            v - (0.0, self.gravity * s)
        ) * sign

    def home(self) -> FloatArray:
        """Own frame: where the hands rest at time 0 (the right hand's first carry, from
        rest there, reaches the release at a constant acceleration)."""
        v = self.throw_velocity(self.timing.value(0))
        return self.release - 0.5 * v * self.first_release

    def nominal_segments(self) -> list[tuple[str, FloatArray, float]]:
        """The steady pattern's quintics over two of its periods (each hand's beats):
        ``(kind, coefficients, duration)``, ``kind`` ``"carry"`` or ``"vacant"``."""
        tm = self.timing
        out: list[tuple[str, FloatArray, float]] = []
        period = 2 * len(tm.throws)
        for k in range(period, 2 * period):
            h = tm.value(k)
            if h == 2:
                continue
            # the vacant movement: release on beat k to the catch of the ball landing on k + 2
            j = tm.source(k + 2)
            hj = tm.value(j)
            t_catch = self.time(k + 2) - tm.hold(hj)
            r, c = self.release_state(h), self.catch_state(hj)
            dv = t_catch - self.time(k)
            out.append(("vacant", quintic(*r, *c, dv), dv))
            # the carry: that catch to the next release of the hand (after its holds)
            nxt = k + 2
            while tm.value(nxt) == 2:
                nxt += 2
            dc = self.time(nxt) - t_catch
            out.append(("carry", quintic(*c, *self.release_state(tm.value(nxt)), dc), dc))
        return out

    def peaks(self) -> tuple[float, float]:
        """The nominal pattern's peak speed (m/s) and acceleration (m/s^2)."""
        segs = self.nominal_segments()
        return max(peak(c, d, 1) for _, c, d in segs), max(peak(c, d, 2) for _, c, d in segs)


def choose_beat(
    siteswap: str,
    dwell_ratio: float,
    style: SiteswapStyle,
    task: JugglingTask,
    speed_limit: float = HAND_SPEED_LIMIT,
    accel_limit: float = HAND_ACCEL_LIMIT,
) -> SiteswapPlan:
    """The plan at the beat of :data:`BEATS` (or ``style.beat``) whose nominal peak
    acceleration is least (module docstring); ``ValueError`` in one line with the reason
    when the siteswap cannot be played or no beat keeps the plan within ``limit_share``
    of the hand's limits."""
    reasons = siteswap_reasons(siteswap)
    if reasons:
        raise ValueError(f"siteswap {siteswap!r} cannot be played: " + "; ".join(reasons))
    scale = math.sqrt(9.81 / task.gravity)  # the beats are for 9.81 m/s^2
    beats = [style.beat] if style.beat is not None else [b * scale for b in BEATS]
    found: list[tuple[float, float, SiteswapPlan]] = []
    for b in beats:
        try:
            plan = SiteswapPlan(siteswap, b, dwell_ratio, style, task)
        except ValueError:
            continue
        speed, accel = plan.peaks()
        if speed <= style.limit_share * speed_limit:
            found.append((speed, accel, plan))
    best = None
    if found:  # the fastest beat within TEMPO_SLACK of the least peak acceleration
        least = min(a for _, a, _ in found)
        best = next(f for f in found if f[1] <= (1.0 + TEMPO_SLACK) * least)
    if best is None or best[1] > style.limit_share * accel_limit:
        got = (
            "no beat keeps its peak speed within the limit"
            if best is None
            else (f"its least peak acceleration is {best[1]:.0f} m/s^2 (beat {best[2].beat:.3f} s)")
        )
        raise ValueError(
            f"siteswap {siteswap!r} at dwell ratio {dwell_ratio:.2f}: {got}, above "
            f"{style.limit_share:g} of the hand's limits ({speed_limit:g} m/s, "
            f"{accel_limit:g} m/s^2)"
        )
    return best[2]


#: Persons of :func:`siteswap_demonstrations` (by default) and how much each varies the
#: plan: its beat (relative), dwell ratio and points (m), uniformly within these.
DEMO_PERSONS = 4
DEMO_VARIATION = {"beat": 0.03, "dwell_ratio": 0.02, "point": 0.015}


def _hand_segments(
    plan: SiteswapPlan, hand: int, periods: int
) -> list[tuple[str, FloatArray, float, float]]:
    """Hand ``hand``'s nominal movements over ``periods`` of the pattern from its first
    catch: ``(kind, coefficients, start, duration)``."""
    tm = plan.timing
    out: list[tuple[str, FloatArray, float, float]] = []
    k = 2 * len(tm.throws) + hand
    end = k + 2 * len(tm.throws) * periods
    while k < end:
        if tm.value(k) == 2:
            k += 2
            continue
        j = tm.source(k + 2)
        hj = tm.value(j)
        t_catch = plan.time(k + 2) - tm.hold(hj)
        r, c = plan.release_state(tm.value(k)), plan.catch_state(hj)
        out.append(
            (
                "vacant",
                quintic(*r, *c, t_catch - plan.time(k)),
                plan.time(k),
                t_catch - plan.time(k),
            )
        )
        nxt = k + 2
        while tm.value(nxt) == 2:
            nxt += 2
        d = plan.time(nxt) - t_catch
        out.append(("carry", quintic(*c, *plan.release_state(tm.value(nxt)), d), t_catch, d))
        k = nxt
    return out


def siteswap_demonstrations(
    siteswap: str,
    dwell_ratio: float,
    style: SiteswapStyle,
    task: JugglingTask,
    persons: int = DEMO_PERSONS,
    periods: int = 12,
    seed: int = 0,
) -> JugglingDemos:
    """SIMULATED demonstrations of ``siteswap``: the siteswap juggler's nominal pattern
    (:class:`SiteswapPlan` at :func:`choose_beat`'s tempo) played by ``persons`` seeded
    persons, each varying the beat, the dwell ratio and the release and catch points
    uniformly within :data:`DEMO_VARIATION`; per person two recordings (each hand in its
    own frame) of ``periods`` periods sampled at the control period, labelled as the
    juggler labels its phases (the carry: ``return``, then ``toss`` in its last
    ``toss_share``; the vacant movement: ``go_down``, then ``catch`` in its second half).
    Kinematic: no world, no ball is dropped. Seeded."""
    base = choose_beat(siteswap, dwell_ratio, style, task)
    root = np.random.SeedSequence(seed)
    recordings = []
    tag = f"siteswap-{siteswap}"
    for person, ss in enumerate(root.spawn(persons)):
        u = np.random.default_rng(ss).uniform
        var = DEMO_VARIATION
        pt = var["point"]
        own = replace(
            style,
            release=(style.release[0] + u(-pt, pt), style.release[1] + u(-pt, pt)),
            catch=(style.catch[0] + u(-pt, pt), style.catch[1] + u(-pt, pt)),
        )
        plan = SiteswapPlan(
            siteswap,
            base.beat * (1.0 + u(-var["beat"], var["beat"])),
            dwell_ratio + u(-var["dwell_ratio"], var["dwell_ratio"]),
            own,
            task,
        )
        for h, name in enumerate(("right", "left")):
            segs = _hand_segments(plan, h, periods)
            t0, t1 = segs[0][2], segs[-1][2] + segs[-1][3]
            t = np.arange(0.0, t1 - t0, task.dt)
            y = np.empty((t.size, 2))
            label = np.empty(t.size, dtype="<U8")
            for kind, c, start, d in segs:
                k = (t + t0 >= start - 1e-12) & (t + t0 < start + d - 1e-12)
                s = t[k] + t0 - start
                y[k] = quintic_evaluate(c, s)
                first, second = ("return", "toss") if kind == "carry" else ("go_down", "catch")
                split = (1.0 - style.toss_share) * d if kind == "carry" else 0.5 * d
                label[k] = np.where(s < split, first, second)
            recordings.append(
                JugglingRecording(
                    name=f"simulated-{tag}-person-{person}-{name}",
                    t=t,
                    hand=y,
                    phase=label.astype(str),
                    person=f"simulated-{tag}-person-{person}",
                )
            )
    return JugglingDemos(
        name=f"simulated-{tag}(seed={seed})",
        recordings=tuple(recordings),
        simulated=True,
        task=task,
    )
