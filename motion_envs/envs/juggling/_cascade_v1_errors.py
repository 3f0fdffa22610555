"""Cascade-v1's task-error vectors: per catch (:func:`catch_errors`) and, at a drop, the
miss of the dropped ball (:class:`MissTracker`), Juggling-v2's vectors per hand; and what
Juggling-v2 and Cascade-v1 observe of them with ``observe_task_error=True``, each hand's
last catch's vector held until its next catch (:class:`HeldTaskErrors`)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from motion_envs.datasets.juggling import CASCADE_HANDS
from motion_envs.models.juggling import CascadeState

__all__ = [
    "TASK_ERROR_ENTRIES",
    "HeldTaskErrors",
    "MissTracker",
    "catch_errors",
    "check_observe_task_error",
]

#: Observation entries per hand with ``observe_task_error=True`` (:class:`HeldTaskErrors`).
TASK_ERROR_ENTRIES = 4
#: m: the observed offset's bound (the other positions' margin around the home).
_OFFSET_BOUND = 10.0


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


def check_observe_task_error(value: Any) -> bool:
    """``observe_task_error`` as a bool (True/False, also numpy's); else a one-line
    ValueError naming the argument."""
    if not isinstance(value, (bool, np.bool_)):
        raise ValueError(f"observe_task_error must be True or False; got {value!r}")
    return bool(value)


class HeldTaskErrors:
    """The observation entries of ``observe_task_error=True``: per hand, its LAST catch's
    task error held until its next catch, ``(offset, timing, timed, catches)``: the
    catch's ``(offset, timing)`` as ``info["task_error"]`` gave it (m, s), the timing 0
    and ``timed`` 0 where it is NaN (a catch outside the hand's catch phase, no planned
    time; else ``timed`` 1), and the hand's catches so far (at most ``max_catches``);
    all zeros after a reset (``catches`` 0: no error yet)."""

    def __init__(self, hands: int, max_catches: int) -> None:
        self.max_catches = max_catches
        #: ``(hands, TASK_ERROR_ENTRIES)``: the entries now
        self.values = np.zeros((hands, TASK_ERROR_ENTRIES))

    def bounds(self, time_limit: float) -> tuple[list[float], list[float]]:
        """The entries' ``(low, high)``: the offset within 10 m, the timing within the
        time limit ``time_limit`` (s) either way, the flag in [0, 1], the catches in [0,
        ``max_catches``]."""
        hands = len(self.values)
        low = [-_OFFSET_BOUND, -time_limit, 0.0, 0.0] * hands
        high = [_OFFSET_BOUND, time_limit, 1.0, float(self.max_catches)] * hands
        return low, high

    def reset(self) -> None:
        """A new episode: no catch yet."""
        self.values[:] = 0.0

    def record(self, errors: NDArray[np.float64]) -> None:
        """A step's catches: ``errors`` ``(hands, 2)`` as ``info["task_error"]`` (a row
        with a NaN offset: that hand did not catch)."""
        for h, (offset, timing) in enumerate(np.asarray(errors).reshape(-1, 2).tolist()):
            if math.isnan(offset):
                continue
            timed = not math.isnan(timing)
            catches = min(self.values[h, 3] + 1.0, self.max_catches)
            self.values[h] = (offset, timing if timed else 0.0, float(timed), catches)

    def entries(self) -> list[float]:
        """The entries, hand by hand."""
        return [float(v) for v in self.values.ravel()]
