"""What a Cascade-v1 row reads from the observation: per hand, the velocity of the ball
it is about to catch (:func:`catching_velocities`), shared by ``velocity_x_mean_delay``
(:mod:`baselines.juggling_bench.cascade_v1`) and the task-error learner
(:mod:`baselines.juggling_bench.cascade_v1_ilc`)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from baselines.juggling_bench import v2

__all__ = ["FRESH_FRAME", "catching_velocities"]

#: s; ``velocity_x_mean_delay`` reads a ball's frames only while its newest arrived this
#: recently (older ones are of its previous flight, or it is held), declared before any run.
FRESH_FRAME = 0.1
#: Observation entries per hand, and within a hand's the catch phase's one-hot and the
#: plan's end point (CascadeV1Env's docstring).
_PER_HAND, _CATCH, _PLAN_END = 16, 7, 13


def catching_velocities(obs: NDArray[np.floating], balls: int) -> list[NDArray[np.float64] | None]:
    """Per hand, the velocity ``(2,)`` (m/s, world frame) of the ball it is about to
    catch, read from the observation, or None (the hand is not in its catch phase, or no
    ball qualifies): of the balls not held, with a velocity
    (:func:`baselines.juggling_bench.v2.frame_velocity`), falling, and whose newest frame
    arrived within :data:`FRESH_FRAME` s, the one whose newest frame is nearest to the
    hand's planned catch point (the observation's plan end)."""
    o = np.asarray(obs, dtype=np.float64)
    n, hand = int(balls), _PER_HAND
    held = o[2 * hand : 2 * hand + 2 * n].reshape(n, 2).max(axis=1) > 0.5
    base = 2 * hand + 2 * n  # the frames (any entries after them are ignored)
    frames = o[base : base + 16 * n].reshape(n, 4, 4)
    v, ok = v2.frame_velocity(frames)
    ok &= ~held & (v[:, 1] < 0) & (frames[:, 0, 2] <= FRESH_FRAME)
    out: list[NDArray[np.float64] | None] = [None, None]
    for h in range(2):
        row = o[h * hand : (h + 1) * hand]
        if row[_CATCH] < 0.5 or not ok.any():
            continue
        d = np.hypot(*(frames[:, 0, :2] - row[_PLAN_END : _PLAN_END + 2]).T)
        out[h] = v[int(np.argmin(np.where(ok, d, np.inf)))].copy()
    return out
