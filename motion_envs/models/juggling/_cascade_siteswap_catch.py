r"""The siteswap juggler's catch planned for the capture rule: the palm arrives early at
the meeting point and waits there (or descends slowly) while the ball falls in.

**Why** (BENCHMARKS, *Cascade-v1: a catch plan for the siteswap juggler*). The siteswap
juggler (:class:`~motion_envs.models.juggling.SiteswapController`) re-plans its vacant
quintic every period to the ball's predicted position AT the intercept time ``t*``. In
the last periods before ``t*`` a re-plan over 10-20 ms turns a centimetre of change in
the estimate (a 5 ms error in a frame's believed time moves a five-ball cascade's ball,
falling at about 4 m/s, by 2 cm) into a command swinging up and down by metres per
second; the servo follows it, and the palm meets the ball RISING, faster than the
capture speed: the ball bounces. Telling the juggler the ball ``lead`` ahead
(Cascade-v1's catch plan for the fitted juggler) does not help it: it moves the whole
intercept, and a hand past ``t*`` follows the told ball down, ``lead`` below it.

**The plan** (a :class:`~motion_envs.models.juggling.CatchPlan`, ``lead`` and
``descent``; Juggling-v2's, in the siteswap juggler's terms): the hand chooses its
meeting time ``t_m`` on the ball's flight ``B(t)`` as the juggler chooses ``t*``
(:meth:`SiteswapCatchController._choose`, the reach ending ``lead`` earlier), and

* the vacant quintic ends at ``t_e = t_m - lead`` at ``E = B(t_m) + (0, descent lead)``,
  moving straight down at ``descent`` (no acceleration); it is re-planned every period
  while ``t_e`` is more than :data:`FREEZE` periods away (never in the last ones);
* from ``t_e`` the hand moves straight down at ``descent`` m/s (at rest for
  ``descent = 0``), through ``M = B(t_m)`` at ``t_m``, until ``t_m + lead``; then, without
  a catch, it follows the ball down as the juggler does;

so a ball that comes a little early or late still meets a palm that is not rising, at
the relative speed :meth:`~motion_envs.models.juggling.CatchPlan.meeting_speed`
(``|B'(t_m) + (0, descent)|``). The catch phase ends at ``t_m`` (the planned catch time
of ``info["task_error"]``); the plan end point shown is ``M``.

``lead = 0`` with ``descent = 0`` is not the plain juggler: the reach ends at rest at the
ball's point, not moving with ``catch_follow`` of its velocity.
"""

from __future__ import annotations

import numpy as np

from motion_envs._typing import FloatArray
from motion_envs.geometry.minimum_jerk import quintic
from motion_envs.models.juggling._cascade import CascadeState
from motion_envs.models.juggling._cascade_siteswap import SiteswapPlan, peak
from motion_envs.models.juggling._cascade_siteswap_control import (
    SiteswapController,
    SiteswapHand,
)
from motion_envs.models.juggling._v2_catch import CatchPlan

__all__ = ["FREEZE", "SiteswapCatchController", "meeting_point"]

#: Control periods before the reach's end ``t_e`` in which it is no longer re-planned.
FREEZE = 2


def meeting_point(
    ball: tuple[float, FloatArray, FloatArray], t_m: float, gravity: float
) -> tuple[FloatArray, FloatArray]:
    """``(B(t_m), B'(t_m))``: the ballistic flight of ``ball`` ``(time, position,
    velocity)`` at ``t_m``."""
    t_b, p, v = ball
    s = t_m - t_b
    return (
        np.array((p[0] + v[0] * s, p[1] + v[1] * s - 0.5 * gravity * s * s)),
        np.array((v[0], v[1] - gravity * s)),
    )


class SiteswapCatchController(SiteswapController):
    """The siteswap juggler with the catch ``catch`` (module docstring); its other
    arguments are :class:`SiteswapController`'s."""

    def __init__(
        self, plan: SiteswapPlan, catch: CatchPlan, variant: str = "juggler",
        latency: float = 0.0,
    ) -> None:  # fmt: skip
        super().__init__(plan, variant, latency)
        self.catch = catch
        self._meet: list[FloatArray | None] = [None, None]

    def reset(self, state: CascadeState, rng: np.random.Generator | None = None) -> None:
        """:meth:`SiteswapController.reset`, no meeting planned."""
        self._meet = [None, None]
        super().reset(state, rng)

    def _reach(self, hand: SiteswapHand, ball: tuple[float, FloatArray, FloatArray], t_m: float
               ) -> tuple[FloatArray, FloatArray, FloatArray]:  # fmt: skip
        """Own frame ``(E, (0, -descent), M)``: the reach's end state and the meeting
        point for a meeting at ``t_m``."""
        m, _ = meeting_point(ball, t_m, self.task.gravity)
        d, lead = self.catch.descent, self.catch.lead
        return m + np.array((0.0, d * lead)), np.array((0.0, -d)), m

    @property
    def reach_lead(self) -> float:  # type: ignore[override]
        """s, the reach ends the plan's ``lead`` before the meeting it chooses."""
        return self.catch.lead

    def _cost(
        self,
        hand: SiteswapHand,
        ball: tuple[float, FloatArray, FloatArray],
        ts: float,
        t: float,
        now: tuple[FloatArray, FloatArray, FloatArray],
        rel: tuple[FloatArray, FloatArray, FloatArray],
        t_rel: float,
    ) -> float:
        """A meeting at ``ts``'s cost (:meth:`SiteswapController._choose`'s, the juggler's
        window, height band and fallback, the reach ending ``lead`` early): the reach's
        (to ``E`` at ``ts - lead``) and the carry's (from ``M`` moving at ``(0,
        -descent)``) peak accelerations summed."""
        e, ve, m = self._reach(hand, ball, ts)
        d1, d2 = ts - self.catch.lead - t, t_rel - ts
        cost = peak(quintic(*now, e, ve, np.zeros(2), d1), d1, 2)
        cost += peak(quintic(m, ve, np.zeros(2), *rel, d2), d2, 2)
        return cost

    def _vacant(self, hand: SiteswapHand, state: CascadeState) -> None:
        """The reach to ``E`` by ``t_e``, re-planned until :data:`FREEZE` periods before
        it; then the wait (or descent) until ``t_m + lead``; then the juggler's (module
        docstring). Before its ball is known: the juggler's."""
        b = self.ball_of.get(hand.landing, -1)
        ball = self._ball(b, state, hand)
        if ball is None:
            self._meet[hand.index] = None
            super()._vacant(hand, state)
            return
        t, dt, lead = state.time, self.task.dt, self.catch.lead
        if hand.known != b:
            hand.t_star = self._choose(hand, ball, t)
            hand.known = b
        t_m = hand.t_star
        t_e = t_m - lead
        if t_e - t > FREEZE * dt:
            e, ve, m = self._reach(hand, ball, t_m)
            p0, v0, a0 = hand.state(t)
            hand.set(quintic(p0, v0, a0, e, ve, np.zeros(2), t_e - t), t, t_e - t)
            self._meet[hand.index] = m
        elif t > t_m + lead:  # late: the juggler's (it follows the ball down)
            self._meet[hand.index] = None
            super()._vacant(hand, state)
            return
        start = hand.labels[0][1] if hand.labels else t
        mid = 0.5 * (start + t_m)
        hand.labels = [("go_down", start, mid - start), ("catch", mid, t_m - mid)]

    def plan_end(self, h: int) -> FloatArray:
        """Hand ``h``'s plan end point (world): the planned meeting point ``M`` while it
        reaches for or waits at it, else the juggler's."""
        hand, m = self.hands[h], self._meet[h]
        if hand.mode == "vacant" and m is not None:
            out: FloatArray = m * hand.sign
            return out
        return super().plan_end(h)
