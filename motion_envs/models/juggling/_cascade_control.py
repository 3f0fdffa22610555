"""The analytic cascade juggler: two of the one-ball juggler's hands, scheduled by the
pattern (an odd cascade of ``balls`` balls, Shannon's theorem with ``H = 2``).

**Control** (:class:`CascadeController`): each hand runs the one-ball juggler's episode
controller (:class:`~motion_envs.models.juggling.JugglingController`: eq. 9 toss, catch
planned on the predicted flight with the eq. 10 correction) in its own frame, the left
hand's mirrored (:class:`~motion_envs.models.juggling.CascadeHand`). What the pattern
changes:

* the beat: the hands release in turn, a beat ``C / 2`` apart; after a catch a hand's
  return (the carry) lasts until ``lead`` (the nominal toss's time from the toss start to
  the release) before its next beat, at least the shortest training return; its next
  beat is the mean of its own (its last release plus two beats) and the other hand's
  (the other hand's last release plus the odd number of beats nearest to its own), so
  the hands stay in turn while the tempo may drift;
* the ball a hand catches is the one whose throw lands in it (in a cascade the other
  hand's): at each release the thrower's efference copy (its last command and the
  velocity of its last two commands) is queued, mirrored into the catcher's frame, for
  the catching hand; a hand plans its go-down and catch on the oldest ball in its queue
  and corrects the catch from that ball's (delayed, noisy) measurement;
* the go-down lasts until the preferred catch duration before the queued ball reaches the
  preferred catch point (within the training go-down durations);
* the catch duration is chosen up to ``catch_window`` beats beyond the longest training
  catch; an empty hand re-aims its catch when its ball went elsewhere or its plan ended
  ``reaim_after`` beats ago; a ball caught early (in the go-down) ends the catch;
* the release is armed from ``release_armed`` of the nominal toss's release time on;
* a toss moves aside from the hand's own last ball: when that ball's measured flight
  comes down within ``toss_clearance`` of the toss's column (a near-vertical toss: the
  cycle is about the flight, so such a ball falls back over its thrower while the
  thrower tosses its next ball), the hand's return and toss end points move along ``x``
  until it clears (:meth:`CascadeHand.toss_shift`), the toss on the side its return took.

The four tunables are the fields of :class:`CascadeTunables` (a frozen dataclass passed to
the controller; no module globals).

**Start** (:meth:`CascadeController.start`): the right hand's first release is beat 0, at
``lead``; the ball landing on beat 0 is in the right hand (ball 0), the one landing on
beat 1 in the left (ball 1), and each ball landing on beat ``L = 2 .. N - 1`` (ball
``L``) is in flight, thrown on beat ``L - N`` by the hand of that beat (its nominal
release, ``(L - N)`` beats from the first). For the three-ball cascade: ball 2 in flight
towards the right hand, thrown by the left hand one beat before the right hand's first
release.

The latency-aware variant (``"juggler_latency_aware"``) is the same juggler fed each
flying ball's measurement predicted forward by the known latency; the two trivial ones
(``"fixed_point"``, ``"commanded_intercept"``) replace each hand's catch by a minimum-jerk
reach, blind to the ball, to the training mean catch point or to the intercept predicted
from the thrower's commanded release, as in Juggling-v1 (:func:`make_cascade_controller`);
the rest of their hands' cycle is the juggler's (their tosses move aside too).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from motion_envs.datasets.juggling import (
    CASCADE_HANDS,
    JugglingState,
    ballistic_position,
    mirror_x,
)
from motion_envs.geometry.minimum_jerk import minimum_jerk
from motion_envs.models.juggling._cascade import CascadeFit, CascadeState
from motion_envs.models.juggling._cascade_hand import (
    DEFAULT_TUNABLES,
    CascadeHand,
    CascadeTunables,
)
from motion_envs.models.juggling._controller import ControlOptions
from motion_envs.models.juggling._levels import CONTROLLERS
from motion_envs.models.juggling._sensor import predict_forward

__all__ = [
    "CASCADE_CONTROLLERS",
    "CascadeController",
    "CascadeStart",
    "make_cascade_controller",
]

FloatArray = NDArray[np.float64]
#: A ball queued for a hand: ``(ball, release time, position, velocity)`` (own frame).
Queued = tuple[int, float, FloatArray, FloatArray]

#: The cascade's reference controllers (Juggling-v1's names).
CASCADE_CONTROLLERS: tuple[str, ...] = CONTROLLERS


@dataclass(frozen=True)
class CascadeStart:
    """The world at ``t = 0`` (world frame; :meth:`CascadeController.start`):
    ``holder[b]`` the hand holding ball ``b`` or -1 (flying), ``thrower[b]`` the hand
    that threw a flying ball (-1 for a held one), ``ball_pos``, ``ball_vel`` ``(B, 2)``
    (a held ball's rows are zero: it sits in its hand), ``releases[b]`` the throw
    ``(time, x, z)`` a flying ball left its thrower's hand with (its time before 0; None
    for a held ball; empty: not known). The throws are the juggler's own: what a release
    estimator may anchor the starting balls on."""

    holder: tuple[int, ...]
    thrower: tuple[int, ...]
    ball_pos: FloatArray
    ball_vel: FloatArray
    releases: tuple[tuple[float, float, float] | None, ...] = ()


def _own(h: int, xz: FloatArray) -> FloatArray:
    """``(2,)`` world <-> hand ``h``'s own frame (the left hand's is mirrored)."""
    x, z = float(xz[0]), float(xz[1])
    return np.array((-x if h == 1 else x, z))


class CascadeController:
    """The analytic cascade juggler for one episode at a time (module docstring).

    Parameters
    ----------
    fit:
        The cascade fit (:func:`cascade_fit`).
    dwell_ratio:
        ``D / (V + D)``; None: the training cycles' median. The flight is kept, the period
        follows from Shannon's theorem.
    latency:
        s, the delay of the ball measurements (used by the latency-aware variant only).
    options:
        The hands' :class:`~motion_envs.models.juggling.ControlOptions` (default: the fit's,
        the release armed from ``tunables.release_armed`` of the nominal toss's release).
    tunables:
        The controller's :class:`CascadeTunables`.
    """

    #: The native vector env compiles this controller's events (its hands' plans are
    #: grids indexed between them).
    compiled_events = True

    def __init__(
        self,
        fit: CascadeFit,
        dwell_ratio: float | None = None,
        latency: float = 0.0,
        options: ControlOptions | None = None,
        tunables: CascadeTunables = DEFAULT_TUNABLES,
    ) -> None:
        self.fit = fit
        self.task = fit.juggler.task
        self.pattern = fit.pattern
        self.tunables = tunables
        #: balls of the cascade (odd): every throw lands in the other hand
        self.balls = fit.pattern.balls
        self.dwell_ratio = fit.pattern.dwell_ratio if dwell_ratio is None else float(dwell_ratio)
        self.period, self.beat = fit.pattern.timing(self.dwell_ratio)
        self.latency = float(latency)
        # armed from release_armed of the nominal toss's release on (the nominal is
        # unchanged: its threshold is first crossed at its release): a toss started from a
        # hand still moving must not release early and low
        armed_from = tunables.release_armed * self.pattern.lead
        self.options = (
            replace(fit.juggler.options, release_after=armed_from) if options is None else options
        )
        #: s, the right hand's first release (its toss starts at 0)
        self.first_release = self.pattern.lead
        self.hands: list[CascadeHand] = []

    @property
    def home(self) -> FloatArray:
        """``(2, 2)``: each hand's home (the training tosses' mean start) in the world."""
        h = self.fit.juggler.home_
        return np.stack([_own(0, h), _own(1, h)])

    def _initial_throws(self) -> list[tuple[int, int, float]]:
        """``(ball, thrower, release time)`` of each ball in flight at ``t = 0`` (module
        docstring): ball ``L`` thrown on beat ``L - N``."""
        n = self.balls
        return [(b, (b - n) % 2, self.first_release + (b - n) * self.beat) for b in range(2, n)]

    def start(
        self,
        release_noise: tuple[float, float] = (0.0, 0.0),
        rng: np.random.Generator | None = None,
    ) -> CascadeStart:
        """The world at ``t = 0`` (module docstring; world frame): each flying ball where
        its thrower's nominal release puts it ``-t_r`` after the release at ``t_r``. The
        fitted juggler's balls fly nominally (``release_noise`` and ``rng`` unused: its
        seeded rollouts are those of before the siteswap juggler's scattered start)."""
        del release_noise, rng
        n, g = self.balls, self.task.gravity
        pos, vel = np.zeros((n, 2)), np.zeros((n, 2))
        thrower = [-1] * n
        releases: list[tuple[float, float, float] | None] = [None] * n
        for b, h, t_r in self._initial_throws():
            p = _own(h, self.pattern.release_position)
            v = _own(h, self.pattern.release_velocity)
            s = -t_r
            pos[b], vel[b] = ballistic_position(p, v, s, g), v - [0.0, g * s]
            thrower[b] = h
            releases[b] = (float(t_r), float(p[0]), float(p[1]))
        holder = (0, 1) + (-1,) * (n - 2)
        return CascadeStart(holder, tuple(thrower), pos, vel, tuple(releases))

    # -- episode --------------------------------------------------------------------
    def reset(self, state: CascadeState, rng: np.random.Generator | None = None) -> None:
        """Start an episode from the (measured) state of :meth:`start`: each flying ball
        queued, as its thrower's nominal release, for the hand it lands in."""
        rng = rng if rng is not None else np.random.default_rng(0)
        rngs = rng.spawn(2)
        rp, rv = self.pattern.release_position, self.pattern.release_velocity
        queues: list[list[Queued]] = [[], []]
        for b, h, t_r in self._initial_throws():
            to = self._catcher(h)
            p, v = (rp, rv) if to == h else (mirror_x(rp), mirror_x(rv))
            queues[to].append((b, t_r, p, v))
        self.hands = []
        self.held = [0, 1]
        for h in range(CASCADE_HANDS):
            hand = CascadeHand(
                self.fit.juggler,
                self.options,
                self.pattern,
                h,
                self.beat,
                self.first_release + h * self.beat,
                self.tunables,
            )
            hand.reset_hand(self._view(state, h, hand, queues[h]), rngs[h], queues[h])
            self.hands.append(hand)

    def _ball_measurement(self, state: CascadeState, ball: int) -> tuple[FloatArray, FloatArray]:
        return state.ball_pos[ball], state.ball_vel[ball]

    def _view(
        self,
        state: CascadeState,
        h: int,
        hand: CascadeHand | None = None,
        queue: list[Queued] | None = None,
    ) -> JugglingState:
        """Hand ``h``'s one-ball view (own frame): its held ball, else the oldest ball
        queued for it."""
        held = h in state.holder
        if held:
            i = state.holder.index(h)
            bp, bv = state.ball_pos[i], state.ball_vel[i]
        else:
            q = queue if queue is not None else (hand.incoming if hand is not None else [])
            if q:
                bp, bv = self._ball_measurement(state, q[0][0])
            else:
                bp, bv = state.hand_pos[h], state.hand_vel[h]
        return JugglingState(
            time=state.time,
            hand_pos=_own(h, state.hand_pos[h]),
            hand_vel=_own(h, state.hand_vel[h]),
            ball_pos=_own(h, bp),
            ball_vel=_own(h, bv),
            held=held,
            released=state.released[h] >= 0,
            caught=state.caught[h] >= 0,
            dropped=state.any_dropped,
        )

    def _catcher(self, h: int) -> int:
        """The hand a throw of hand ``h`` lands in (an odd throw crosses)."""
        return (h + self.balls) % 2

    def command(self, state: CascadeState) -> tuple[FloatArray, tuple[bool, bool]]:
        """Both hands' next targets ``(2, 2)`` (world) and release arming, given the
        (measured) state."""
        for caught in state.caught:  # a caught ball is no longer expected by either hand
            if caught >= 0:
                for hand in self.hands:
                    hand.incoming[:] = [e for e in hand.incoming if e[0] != caught]
        targets = np.empty((CASCADE_HANDS, 2))
        armed = [False, False]
        for h, hand in enumerate(self.hands):
            b = hand.own_ball
            if b >= 0 and state.holder[b] < 0:
                p, v = self._ball_measurement(state, b)
                hand.own_flight = (_own(h, p), _own(h, v))
            else:
                hand.own_flight = None
        for h, hand in enumerate(self.hands):
            target, arm = self._hand_command(h, hand, state)
            targets[h] = _own(h, target)
            armed[h] = bool(arm)
            if hand.outgoing is not None:  # released this step: queue it for its catcher
                t_r, p, v = hand.outgoing
                ball = state.released[h]
                hand.own_ball = ball
                to = self._catcher(h)
                if to != h:
                    p, v = mirror_x(p), mirror_x(v)
                self.hands[to].incoming.append((ball, t_r, p, v))
                self.hands[1 - h].other_release = t_r
                hand.outgoing = None
        return targets, (armed[0], armed[1])

    def _hand_command(
        self, h: int, hand: CascadeHand, state: CascadeState
    ) -> tuple[FloatArray, bool]:
        return hand.command(self._view(state, h, hand))

    # -- what the env's observation shows ---------------------------------------------
    def phase(self, h: int) -> str:
        """Hand ``h``'s phase."""
        return self.hands[h].phase

    def phase_time(self, h: int) -> float:
        """s in hand ``h``'s phase."""
        return self.hands[h].phase_time

    def duration(self, h: int) -> float:
        """s, hand ``h``'s phase plan's duration."""
        return float(self.hands[h].duration)

    def plan_end(self, h: int) -> FloatArray:
        """Hand ``h``'s plan end point (world)."""
        return _own(h, np.asarray(self.hands[h].end, dtype=np.float64))

    def nominal_next(self, h: int) -> FloatArray:
        """Hand ``h``'s next target without events (world)."""
        return _own(h, self.hands[h].nominal_next())


class _LatencyAware(CascadeController):
    def _ball_measurement(self, state: CascadeState, ball: int) -> tuple[FloatArray, FloatArray]:
        p, v = state.ball_pos[ball], state.ball_vel[ball]
        if self.latency <= 0 or state.holder[ball] >= 0:
            return p, v
        return predict_forward(p, v, self.latency, self.task.gravity)


class _MinimumJerkCatch(CascadeController):
    """The cascade juggler without eq. 10, each catch a minimum-jerk reach from the catch
    start to :meth:`_catch_point` (own frame) over the planned duration."""

    def __init__(self, fit: CascadeFit, dwell_ratio: float | None = None, latency: float = 0.0,
                 options: ControlOptions | None = None,
                 tunables: CascadeTunables = DEFAULT_TUNABLES) -> None:  # fmt: skip
        super().__init__(fit, dwell_ratio, latency, options, tunables)
        base = self.options
        self.options = ControlOptions(False, base.correction_tolerance, base.release_after,
                                      base.reach_tolerance)  # fmt: skip
        self._catch: list[tuple[FloatArray, FloatArray, float] | None] = [None, None]

    def reset(self, state: CascadeState, rng: np.random.Generator | None = None) -> None:
        super().reset(state, rng)
        self._catch = [None, None]

    def _catch_point(self, hand: CascadeHand) -> FloatArray:
        raise NotImplementedError

    def _hand_command(
        self, h: int, hand: CascadeHand, state: CascadeState
    ) -> tuple[FloatArray, bool]:
        view = self._view(state, h, hand)
        target, armed = hand.command(view)
        if hand.phase != "catch":
            self._catch[h] = None
            return target, armed
        if self._catch[h] is None:
            start = np.asarray(view.hand_pos, dtype=np.float64)
            self._catch[h] = (start, self._catch_point(hand), float(hand.duration))
        start, end, duration = self._catch[h]  # type: ignore[misc]
        tau = min(hand.phase_time / duration, 1.0)
        return minimum_jerk(start, end, np.array([tau]))[0], armed

    def plan_end(self, h: int) -> FloatArray:
        c = self._catch[h]
        return super().plan_end(h) if c is None else _own(h, c[1])

    def nominal_next(self, h: int) -> FloatArray:
        c = self._catch[h]
        if c is None:
            return super().nominal_next(h)
        start, end, duration = c
        tau = min((self.hands[h].phase_time + self.task.dt) / duration, 1.0)
        return _own(h, minimum_jerk(start, end, np.array([tau]))[0])


class _FixedPoint(_MinimumJerkCatch):
    def _catch_point(self, hand: CascadeHand) -> FloatArray:
        return np.asarray(hand.model.phases_["catch"].end_mean, dtype=np.float64).copy()


class _CommandedIntercept(_MinimumJerkCatch):
    def _catch_point(self, hand: CascadeHand) -> FloatArray:
        return np.asarray(hand.end, dtype=np.float64).copy()


def make_cascade_controller(
    name: str,
    fit: CascadeFit,
    latency: float = 0.0,
    dwell_ratio: float | None = None,
    tunables: CascadeTunables = DEFAULT_TUNABLES,
) -> CascadeController:
    """The cascade controller ``name`` (one of :data:`CASCADE_CONTROLLERS`) with
    ``tunables``."""
    classes: dict[str, type[CascadeController]] = {
        "juggler": CascadeController,
        "juggler_latency_aware": _LatencyAware,
        "fixed_point": _FixedPoint,
        "commanded_intercept": _CommandedIntercept,
    }
    if name not in classes:
        raise ValueError(f"controller must be one of {list(CASCADE_CONTROLLERS)}; got {name!r}")
    return classes[name](fit, dwell_ratio, latency, None, tunables)
