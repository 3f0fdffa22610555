"""Cascade-v1's task-error vectors: per catch (:func:`catch_errors`) and, at a drop, the
miss of the dropped ball (:class:`MissTracker`), Juggling-v2's vectors per hand."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from motion_envs.datasets.juggling import CASCADE_HANDS
from motion_envs.models.juggling import CascadeState

__all__ = ["MissTracker", "catch_errors"]


def catch_errors(
    before: tuple[NDArray[np.float64], NDArray[np.float64]],
    true: CascadeState,
    planned: list[float],
    dt: float,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Per hand, the catch's ``(offset, timing)`` and meeting speed (NaN for a hand that
    did not catch) from the MuJoCo state ``before`` ``(qpos, qvel)`` at the period's
    start: the relative motion of the ball and the palm, linear over the period, meets
    the palm's top (the ball's centre level with the hand's origin) at ``s`` in ``[0,
    dt]``; the offset is along ``x`` (world frame), the timing the meeting time minus
    the plan's catch time ``planned[h]`` (NaN outside the hand's catch phase)."""
    q, v = before
    t0 = true.time - dt
    errors = np.full((CASCADE_HANDS, 2), np.nan)
    speeds = np.full(CASCADE_HANDS, np.nan)
    for h, b in enumerate(true.caught):
        if b < 0:
            continue
        hb, bb = 2 * h, 2 * CASCADE_HANDS + 2 * b
        rx, rz = q[bb] - q[hb], q[bb + 1] - q[hb + 1]
        vx, vz = v[bb] - v[hb], v[bb + 1] - v[hb + 1]
        s = min(max(-rz / vz, 0.0), dt) if vz < 0 else 0.0
        errors[h] = (rx + vx * s, t0 + s - planned[h])
        speeds[h] = math.hypot(vx, vz)
    return errors, speeds


class MissTracker:
    """Each ball's closest approach, since its last release, to the origin of a hand in
    its catch phase while the ball falls (sampled every control period): ``(distance,
    hand, x offset, time minus that hand's planned catch time, relative speed)``."""

    def __init__(self, balls: int) -> None:
        self.closest: list[tuple[float, int, float, float, float] | None] = [None] * balls

    def reset(self) -> None:
        """A new episode."""
        self.closest = [None] * len(self.closest)

    def update(self, true: CascadeState, phases: list[str], planned: list[float]) -> None:
        """After a control period: a released ball starts afresh; each falling ball's
        approach to each hand in its catch phase (``planned[h]`` its catch time)."""
        for b in true.released:
            if b >= 0:
                self.closest[b] = None
        for i, holder in enumerate(true.holder):
            if holder >= 0 or true.ball_vel[i, 1] >= 0:
                continue
            for h in range(CASCADE_HANDS):
                if phases[h] != "catch":
                    continue
                rel = true.ball_pos[i] - true.hand_pos[h]
                dist = math.hypot(float(rel[0]), float(rel[1]))
                best = self.closest[i]
                if best is None or dist < best[0]:
                    rv = true.ball_vel[i] - true.hand_vel[h]
                    self.closest[i] = (dist, h, float(rel[0]), true.time - planned[h],
                                       math.hypot(float(rv[0]), float(rv[1])))  # fmt: skip

    def miss(self, true: CascadeState) -> dict[str, Any]:
        """At the step of a drop: the first dropped ball's ``miss_error`` ``(offset,
        timing)``, ``miss_speed`` and ``miss_hand`` at its closest approach; empty when
        it never fell past a hand in its catch phase."""
        for i, dropped in enumerate(true.dropped):
            best = self.closest[i]
            if dropped and best is not None:
                _, h, offset, timing, speed = best
                return {"miss_error": np.array([offset, timing]), "miss_speed": speed,
                        "miss_hand": h}  # fmt: skip
        return {}
