"""The siteswap juggler: two hands playing any vanilla siteswap of 2 to 5 balls on the
plan of :mod:`~motion_envs.models.juggling._cascade_siteswap` (each throw value's own
flight and landing hand, quintic movements within the hand's limits).

**Control** (:class:`SiteswapController`), per hand, in its own frame (the left hand's
mirrored), on a metronome (beat ``k`` at ``t_0 + k b``):

* **carry**: from the catch (or from rest at the start) to the release of the hand's next
  throw (its next beat whose value is not a hold, ``2``; over a hold: to rest
  :data:`HOLD_DEPTH` below the release point, then a toss of one dwell): a quintic from
  the commanded state to the release state (the release point, the throw's velocity, decelerating at
  ``release_brake`` toss thresholds), timed to the beat (at least ``MIN_CARRY`` of the
  dwell after a late catch); the throw's velocity flies the ball to its landing hand's
  catch point by that ball's nominal catch time (Shannon's theorem for its value). The
  release is armed in the carry's last ``toss_share`` (the toss phase) and after it
  while the hand still holds the ball;
* **vacant**: from the release to the catch of the ball landing on the hand's beat two
  beats later (the siteswap says which ball): the hand chooses the intercept time
  ``t*`` on that ball's predicted flight (descending, above ``MIN_CATCH_HEIGHT`` over the
  floor) at which the vacant quintic's and the following carry's peak accelerations
  summed are least, among :data:`INTERCEPT_CANDIDATES` times from half a vacant time
  before the nominal catch to half a dwell after it (ending before the hand's next
  release less ``MIN_CARRY`` of the dwell); it re-plans its quintic every period to the
  ball's predicted position at ``t*`` (moving with ``catch_follow`` of the ball's
  velocity), from the commanded position, velocity and acceleration. Before its ball is
  thrown (a pass not yet made) it aims at the nominal catch. Past ``t*`` without a catch
  it follows the ball down (the ball predicted one period ahead);
* **clearance**: when a falling ball would come within ``clearance`` of the carrying
  palm (across, and from just below the palm to ``clearance`` above it), the carry's
  release point moves along ``x`` (:data:`_SHIFTS`) until the path clears it, the throw's
  velocity recomputed from there;
* **which ball**: each release registers the ball for the beat it lands on (the thrower's
  beat plus the throw value).

What the ball is to the hand: the measured flight (``"juggler"``), the measurement
predicted forward by the sensor's latency (``"juggler_latency_aware"``), the thrower's
commanded release state, never a measurement (``"commanded_intercept"``), or nothing:
the nominal catch point and time (``"fixed_point"``); the rest of the hand's cycle is the
juggler's.
"""

from __future__ import annotations

import math

import numpy as np

from motion_envs._typing import FloatArray
from motion_envs.datasets.juggling import CASCADE_HANDS, PHASES, ballistic_position
from motion_envs.geometry.minimum_jerk import quintic, quintic_evaluate
from motion_envs.models.juggling._cascade import CascadeState
from motion_envs.models.juggling._cascade_control import CascadeStart
from motion_envs.models.juggling._cascade_siteswap import SiteswapPlan, peak
from motion_envs.models.juggling._sensor import perturb_release, predict_forward

__all__ = [
    "HOLD_DEPTH",
    "INTERCEPT_CANDIDATES",
    "MIN_CARRY",
    "MIN_CATCH_HEIGHT",
    "MIN_RELEASE_X",
    "SiteswapController",
    "SiteswapHand",
]

#: Intercept times a hand compares.
INTERCEPT_CANDIDATES = 25
#: The shortest carry, in dwells (after a late catch the release waits).
MIN_CARRY = 0.4
#: m above the floor: the lowest intercept.
MIN_CATCH_HEIGHT = 0.2
_SIGN = (np.array((1.0, 1.0)), np.array((-1.0, 1.0)))
#: m: the release points a carry tries, in order, until its path clears the falling balls
#: (the last one is taken if none does).
_SHIFTS = (0.0, 0.05, -0.05, 0.1, -0.1, 0.15, -0.15)
#: m, own ``x``: a release point moved inwards stays on its own side of the midline.
MIN_RELEASE_X = 0.03
#: m: a ball held over a beat (a 2) rests this far below the release point before its
#: toss (one dwell long).
HOLD_DEPTH = 0.2


class _Hand:
    """One hand's plan: the current quintic ``c`` from ``t0`` over ``T`` (own frame)."""

    def __init__(self, index: int, here: FloatArray, t: float) -> None:
        self.index = index
        self.sign = _SIGN[index]
        self.c = quintic(here, np.zeros(2), np.zeros(2), here, np.zeros(2), np.zeros(2), 1.0)
        self.t0, self.T = t, 1.0
        self.mode = "carry"
        self.beat = index  # the next beat it releases on
        self.pending = -1  # the beat of the ball in hand not yet released (-1: none)
        self.landing = -1  # the beat whose ball it catches next
        self.t_star = math.nan
        self.known = -1  # the ball t_star was chosen for (-1: the nominal)
        self.labels: list[tuple[str, float, float]] = []  # (phase, start, duration)
        #: a quintic before ``c`` (a held ball's rest before its toss), or None
        self.before: tuple[FloatArray, float] | None = None

    def state(self, t: float) -> tuple[FloatArray, FloatArray, FloatArray]:
        if self.before is not None and t < self.t0:
            c, t0 = self.before
            s0 = max(t - t0, 0.0)
            return (quintic_evaluate(c, s0), quintic_evaluate(c, s0, 1), quintic_evaluate(c, s0, 2))
        s = min(max(t - self.t0, 0.0), self.T)
        p, v, a = (quintic_evaluate(self.c, s, k) for k in range(3))
        if t - self.t0 > self.T:  # past the end: coast at the end velocity
            p = p + v * (t - self.t0 - self.T)
        return p, v, a

    def set(self, c: FloatArray, t0: float, duration: float) -> None:
        self.c, self.t0, self.T = c, t0, duration
        self.before = None


#: One hand's plan (the type a controller's hands have; for subclasses' signatures).
SiteswapHand = _Hand


class SiteswapController:
    """The siteswap juggler (module docstring) for one episode at a time; ``variant`` one
    of ``"juggler"``, ``"juggler_latency_aware"``, ``"commanded_intercept"``,
    ``"fixed_point"``; ``latency`` s (the latency-aware variant's)."""

    #: The native vector env runs this controller in Python (its compiled events are the
    #: fitted cascade juggler's).
    compiled_events = False
    #: s the reach ends before the intercept it chooses (0; a catch plan's lead,
    #: :class:`~motion_envs.models.juggling.SiteswapCatchController`).
    reach_lead = 0.0

    def __init__(self, plan: SiteswapPlan, variant: str = "juggler", latency: float = 0.0) -> None:
        self.plan = plan
        self.task = plan.task
        self.variant = variant
        self.latency = float(latency)
        self.balls = plan.balls
        self.beat = plan.beat
        self.dwell_ratio = plan.timing.dwell / (2.0 * plan.beat)
        self.hands: list[_Hand] = []

    @property
    def home(self) -> FloatArray:
        """``(2, 2)``: each hand's rest point at time 0 (world)."""
        h = self.plan.home()
        return np.stack([h, h * _SIGN[1]])

    # -- the start ------------------------------------------------------------------
    def _past(self) -> list[tuple[int, int]]:
        """``(landing beat, throw beat)`` of every ball at time 0, by landing beat."""
        tm = self.plan.timing
        out = [(k + tm.value(k), k) for k in range(-max(tm.throws), 0) if k + tm.value(k) >= 0]
        return sorted(out)

    def start(
        self,
        release_noise: tuple[float, float] = (0.0, 0.0),
        rng: np.random.Generator | None = None,
    ) -> CascadeStart:
        """The world at ``t = 0``: the ball landing on beat 0 in the right hand, the one
        landing on beat 1 in the left, every other ball where its throw on beat ``k < 0``
        (by that beat's hand, from the release point) has flown it, thrown with the world's
        release scatter ``release_noise`` (relative speed std, angle std in radians;
        :func:`~motion_envs.models.juggling.perturb_release`, drawn from ``rng`` ball by
        ball), as every ball the world releases: a blind hand does not get the start's
        balls for free."""
        n = self.balls
        pos, vel = np.zeros((n, 2)), np.zeros((n, 2))
        holder, thrower = [-1] * n, [-1] * n
        releases: list[tuple[float, float, float] | None] = [None] * n
        g = self.task.gravity
        for b, (land, k) in enumerate(self._past()):
            if land <= 1:
                holder[b] = land
                continue
            p, v = self.plan.ball_at(k, self.plan.time(k))  # at its release
            v = perturb_release(v, release_noise[0], release_noise[1], rng)
            s = -self.plan.time(k)
            pos[b], vel[b] = ballistic_position(p, v, s, g), v - np.array((0.0, g * s))
            thrower[b] = k % 2
            releases[b] = (float(self.plan.time(k)), float(p[0]), float(p[1]))
        return CascadeStart(tuple(holder), tuple(thrower), pos, vel, tuple(releases))

    def reset(self, state: CascadeState, rng: np.random.Generator | None = None) -> None:
        """Start an episode from the (measured) state of :meth:`start` (``rng`` unused:
        the juggler draws nothing)."""
        del rng
        self.ball_of: dict[int, int] = {land: b for b, (land, _) in enumerate(self._past())}
        self.commanded: dict[int, tuple[float, FloatArray, FloatArray]] = {}
        self.hands = []
        for h in range(CASCADE_HANDS):
            here = state.hand_pos[h] * _SIGN[h]
            hand = _Hand(h, here, state.time)
            self.hands.append(hand)
            self._plan_carry(hand, state)
            hand.pending = hand.beat
        self._time = state.time

    # -- planning -------------------------------------------------------------------
    def _next_release(self, k: int) -> int:
        tm = self.plan.timing
        while tm.value(k) == 2:
            k += 2
        return k

    def _plan_carry(self, hand: _Hand, state: CascadeState) -> None:
        """The carry from the commanded state at the state's time to the release on the
        hand's next beat, its release point moved aside from falling balls
        (:meth:`_clearance`; module docstring)."""
        plan, tm = self.plan, self.plan.timing
        t = state.time
        hand.beat = self._next_release(hand.beat)
        k = hand.beat
        h = tm.value(k)
        t_rel = max(plan.time(k), t + MIN_CARRY * tm.dwell)
        t_land = plan.time(k + h) - tm.hold(h)  # the ball's nominal catch time
        flight = max(t_land - t_rel, 0.7 * tm.flight(h))
        p0, v0, a0 = hand.state(t)
        duration = t_rel - t
        # a carry over a hold (longer than a dwell and a beat): to rest HOLD_DEPTH below
        # the release point, then a toss of one dwell (one quintic would dip to the floor)
        held = duration > tm.dwell + plan.beat
        toss_time = tm.dwell if held else duration
        falling = self._falling(hand, state)
        home = plan.release[0]
        shifts = [dx for dx in _SHIFTS if home + dx >= MIN_RELEASE_X] if falling else [0.0]
        for dx in shifts:
            p, v, a = plan.release_state(h)
            p = p + np.array((dx, 0.0))
            v = _velocity(plan, h, p, flight)
            a = plan.release_acceleration(h, v)
            start = (
                (p - np.array((0.0, HOLD_DEPTH)), np.zeros(2), np.zeros(2))
                if held
                else (p0, v0, a0)
            )
            c = quintic(start[0], start[1], start[2], p, v, a, toss_time)
            if self._clear(c, toss_time, falling, duration - toss_time):
                break
        if held:
            rest = quintic(p0, v0, a0, start[0], np.zeros(2), np.zeros(2), duration - toss_time)
            hand.set(c, t_rel - toss_time, toss_time)
            hand.before = (rest, t)
        else:
            hand.set(c, t, duration)
        hand.mode = "carry"
        toss = plan.style.toss_share * duration
        hand.labels = [("return", t, duration - toss), ("toss", t_rel - toss, toss)]

    def _falling(self, hand: _Hand, state: CascadeState) -> list[tuple[FloatArray, FloatArray]]:
        """Own frame ``(position, velocity)`` now of the flying balls as the variant knows
        them (``fixed_point``: none)."""
        out = []
        g = self.task.gravity
        for b in range(self.balls):
            seen = self._ball(b, state, hand)
            if seen is not None:
                t_b, p, v = seen
                s = state.time - t_b
                out.append((ballistic_position(p, v, s, g), v - np.array((0.0, g * s))))
        return out

    def _clear(
        self,
        c: FloatArray,
        duration: float,
        falling: list[tuple[FloatArray, FloatArray]],
        after: float = 0.0,
    ) -> bool:
        """Whether the carry ``c`` (starting ``after`` s from now, over ``duration``) keeps
        every falling ball
        off its palm: no ball, falling, within ``clearance`` across and from just below
        the palm to ``clearance`` above it."""
        clr = self.plan.style.clearance
        s = np.linspace(0.0, duration, 24)
        hand = quintic_evaluate(c, s)
        g = self.task.gravity
        for p, v in falling:
            ball = ballistic_position(p, v, s + after, g)  # the quintic starts ``after`` s on
            down = v[1] - g * (s + after) < 0
            dz = ball[:, 1] - hand[:, 1]
            near = down & (np.abs(ball[:, 0] - hand[:, 0]) < clr) & (dz > -0.02) & (dz < clr)
            if near.any():
                return False
        return True

    def _ball(
        self, b: int, state: CascadeState, hand: _Hand
    ) -> tuple[float, FloatArray, FloatArray] | None:
        """``(time, position, velocity)`` of ball ``b`` as the variant knows it (own
        frame of ``hand``), or None (not thrown, or not known)."""
        if b < 0 or self.variant == "fixed_point" or state.holder[b] >= 0:
            return None
        if self.variant == "commanded_intercept":
            if b not in self.commanded:
                return None
            t, p, v = self.commanded[b]
            return t, p * hand.sign, v * hand.sign
        p, v = state.ball_pos[b], state.ball_vel[b]
        if self.variant == "juggler_latency_aware" and self.latency > 0:
            p, v = predict_forward(p, v, self.latency, self.task.gravity)
        return state.time, p * hand.sign, v * hand.sign

    def _target(
        self, hand: _Hand, ball: tuple[float, FloatArray, FloatArray] | None, t: float
    ) -> tuple[FloatArray, FloatArray]:
        """Own-frame position and velocity the hand meets at ``t``: the ball's (its
        velocity times ``catch_follow``) or the nominal catch's."""
        follow = self.plan.style.catch_follow
        if ball is None:
            h = self.plan.timing.value(self.plan.timing.source(hand.landing))
            p, v, _ = self.plan.catch_state(h)
            return p, v
        t_b, p_b, v_b = ball
        s = t - t_b
        g = self.task.gravity
        return ballistic_position(p_b, v_b, s, g), follow * (v_b - np.array((0.0, g * s)))

    def _choose(self, hand: _Hand, ball: tuple[float, FloatArray, FloatArray], t: float) -> float:
        """The intercept time (module docstring)."""
        plan, tm = self.plan, self.plan.timing
        h = tm.value(tm.source(hand.landing))
        t_nom = plan.time(hand.landing) - tm.hold(h)
        vacant = 2.0 * plan.beat - tm.hold(h)
        nxt = self._next_release(hand.landing)
        t_rel = plan.time(nxt)
        lo = max(t + 4 * self.task.dt + self.reach_lead, t_nom - 0.5 * vacant)
        hi = min(t_nom + 0.5 * tm.hold(h), t_rel - MIN_CARRY * tm.hold(h))
        t_b, p_b, v_b = ball
        g, floor = self.task.gravity, self.task.floor_z + MIN_CATCH_HEIGHT
        z_c = plan.catch_point(h)[1]
        low = max(floor, z_c - plan.style.catch_below)
        high = z_c + plan.style.catch_above
        p0, v0, a0 = hand.state(t)
        rel = plan.release_state(tm.value(nxt))
        best, best_t = math.inf, math.nan
        for ts in np.linspace(lo, hi, INTERCEPT_CANDIDATES) if hi > lo else []:
            s = float(ts) - t_b
            z = p_b[1] + v_b[1] * s - 0.5 * g * s * s
            if v_b[1] - g * s >= 0 or not low <= z <= high:
                continue
            cost = self._cost(hand, ball, float(ts), t, (p0, v0, a0), rel, t_rel)
            if cost < best:
                best, best_t = cost, float(ts)
        if math.isnan(best_t):  # no candidate: where it falls through the catch height
            z = plan.catch_point(h)[1]
            disc = v_b[1] ** 2 + 2.0 * g * (p_b[1] - z)
            best_t = t_b + (v_b[1] + math.sqrt(max(disc, 0.0))) / g
            best_t = max(best_t, t + 4 * self.task.dt + self.reach_lead)
        return best_t

    def _cost(
        self,
        hand: _Hand,
        ball: tuple[float, FloatArray, FloatArray],
        ts: float,
        t: float,
        now: tuple[FloatArray, FloatArray, FloatArray],
        rel: tuple[FloatArray, FloatArray, FloatArray],
        t_rel: float,
    ) -> float:
        """An intercept at ``ts``'s cost: the vacant quintic's (from the commanded state
        ``now`` at ``t``) and the following carry's (to the release state ``rel`` at
        ``t_rel``) peak accelerations summed."""
        p, v = self._target(hand, ball, ts)
        d1, d2 = ts - t, t_rel - ts
        cost = peak(quintic(*now, p, v, np.zeros(2), d1), d1, 2)
        cost += peak(quintic(p, v, np.zeros(2), *rel, d2), d2, 2)
        return cost

    def _vacant(self, hand: _Hand, state: CascadeState) -> None:
        """Re-plan the vacant movement (module docstring)."""
        t = state.time
        b = self.ball_of.get(hand.landing, -1)
        ball = self._ball(b, state, hand)
        plan, tm = self.plan, self.plan.timing
        if ball is None:
            h = tm.value(tm.source(hand.landing))
            t_star = plan.time(hand.landing) - tm.hold(h)
            hand.known = -1
        else:
            if hand.known != b:
                hand.t_star = self._choose(hand, ball, t)
                hand.known = b
            t_star = hand.t_star
        if t_star - t > 2 * self.task.dt:
            p, v = self._target(hand, ball, t_star)
            p0, v0, a0 = hand.state(t)
            hand.set(quintic(p0, v0, a0, p, v, np.zeros(2), t_star - t), t, t_star - t)
        elif ball is not None and t > hand.t0 + hand.T:  # late: follow the ball down
            p, v = self._target(hand, ball, t + self.task.dt)
            p[1] = max(p[1], self.task.floor_z + 0.5 * MIN_CATCH_HEIGHT)
            p0 = hand.state(t)[0]
            hand.set(quintic(p0, v, np.zeros(2), p, v, np.zeros(2), self.task.dt), t, self.task.dt)
        start = hand.labels[0][1] if hand.labels else t
        mid = 0.5 * (start + t_star)
        hand.labels = [("go_down", start, mid - start), ("catch", mid, t_star - mid)]

    # -- the step -------------------------------------------------------------------
    def command(self, state: CascadeState) -> tuple[FloatArray, tuple[bool, bool]]:
        """Both hands' next targets ``(2, 2)`` (world) and release arming, given the
        (measured) state."""
        t = state.time
        targets = np.empty((CASCADE_HANDS, 2))
        armed = [False, False]
        for h, hand in enumerate(self.hands):
            b = state.released[h]
            if b >= 0 and hand.pending >= 0:  # the ball of beat `pending` flies
                k = hand.pending
                self.ball_of[k + self.plan.timing.value(k)] = b
                p, v, _ = hand.state(t)
                self.commanded[b] = (t, p * hand.sign, v * hand.sign)
                hand.pending = -1
        for h, hand in enumerate(self.hands):
            holding = h in state.holder
            if hand.mode == "carry" and t >= hand.t0 + hand.T - 1e-9:
                hand.mode = "vacant"  # the release is due: on to the next catch
                hand.landing = hand.beat + 2
                hand.beat += 2
                hand.known = -1
                hand.labels = [("go_down", t, 0.0)]
            elif hand.mode == "vacant" and (state.caught[h] >= 0 or (holding and hand.pending < 0)):
                hand.pending = self._next_release(hand.beat)
                self._plan_carry(hand, state)
            if hand.mode == "vacant":
                self._vacant(hand, state)
            p = hand.state(t + self.task.dt)[0]
            targets[h] = p * hand.sign
            toss = hand.labels[-1][0] == "toss" and t >= hand.labels[-1][1]
            armed[h] = holding and (toss or hand.mode == "vacant")
        self._time = t + self.task.dt
        return targets, (armed[0], armed[1])

    # -- what the env's observation shows ---------------------------------------------
    def _label(self, h: int) -> tuple[str, float, float]:
        labels = self.hands[h].labels
        now = [lab for lab in labels if lab[1] <= self._time] or labels[:1]
        return now[-1]

    def phase(self, h: int) -> str:
        """Hand ``h``'s phase (one of ``PHASES``)."""
        name = self._label(h)[0]
        assert name in PHASES
        return name

    def phase_time(self, h: int) -> float:
        """s in hand ``h``'s phase."""
        return max(self._time - self._label(h)[1], 0.0)

    def duration(self, h: int) -> float:
        """s, hand ``h``'s phase's planned duration."""
        return max(self._label(h)[2], 0.0)

    def plan_end(self, h: int) -> FloatArray:
        """Hand ``h``'s plan end point (world)."""
        hand = self.hands[h]
        out: FloatArray = quintic_evaluate(hand.c, hand.T) * hand.sign
        return out

    def nominal_next(self, h: int) -> FloatArray:
        """Hand ``h``'s next target without events (world)."""
        hand = self.hands[h]
        return hand.state(self._time + self.task.dt)[0] * hand.sign


def _velocity(plan: SiteswapPlan, h: int, p: FloatArray, flight: float) -> FloatArray:
    """Own frame: the release velocity from ``p`` that flies a throw of ``h`` to its
    landing hand's catch point in ``flight`` s."""
    target = plan.catch_point(h) * (-1.0 if h % 2 else 1.0, 1.0)
    g = plan.gravity
    return np.array(((target[0] - p[0]) / flight, (target[1] - p[1]) / flight + 0.5 * g * flight))
