"""The juggling world's rules, written once for one ball and for a batch.

Every function is plain arithmetic and comparisons: called with Python floats and bools
it serves one ball (the pure-model world, the MuJoCo scene's bookkeeping), with numpy
arrays of shape ``(N,)`` a batch (the vectorised runner) or a recording (the
demonstration generator, the segmentation). Both evaluate the same expressions in the
same order, so one ball and a batch agree bit for bit (tested). Booleans combine with
``&``, ``|`` and ``^ True`` (not), which Python bools and numpy bool arrays both support.

One control period ``k`` of the world (period ``dt``), in this order:

1. the hand is at ``h_k``; :func:`hand_velocity` ``v_k = (h_k - h_{k-1}) / dt`` and
   :func:`hand_acceleration` ``a_k = (z_k - 2 z_{k-1} + z_{k-2}) / dt^2`` (backward
   differences; the hand rests at its reset position before time 0);
2. a held ball is released (:func:`release_fires`) when the release is armed and
   ``a_k < -toss_threshold``; it leaves with :func:`release_velocity` ``v_k * f``
   (``f = 1 + release * N(0, 1)`` per component, drawn at reset); a held ball that is
   not released follows the hand (``h_k``, ``v_k``);
3. a free ball flies (:func:`flight`, the closed-form parabola from the release);
   once it has been farther than ``catch_radius`` from the hand (:func:`has_left`), a
   distance ``<= catch_radius`` is a catch (:func:`catch_fires`; the ball is held again,
   its state copied from the hand). The worlds test the catch between samples, not only
   at them: the distance is :func:`swept_distance`, the closest approach of ball and
   hand over the control period (both moving linearly from sample ``k-1`` to ``k``), so
   a fast ball cannot pass through the hand between two samples; a free ball whose centre is below
   ``floor_z`` is dropped (:func:`drop_fires`, sticky until reset; a dropped ball is not
   caught).
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = [
    "catch_fires",
    "drop_fires",
    "flight",
    "hand_acceleration",
    "hand_velocity",
    "has_left",
    "release_fires",
    "release_velocity",
    "swept_distance",
]


def hand_velocity(x: Any, x_prev: Any, dt: float) -> Any:
    """``(x_k - x_{k-1}) / dt``: the hand's (or ball's) velocity, backward difference."""
    return (x - x_prev) / dt


def hand_acceleration(z: Any, z_prev: Any, z_prev2: Any, dt: Any, dt_prev: Any = None) -> Any:
    """``(z_k - 2 z_{k-1} + z_{k-2}) / (dt dt_prev)``: second backward difference.

    ``dt_prev`` (default ``dt``) is the previous sampling interval, for recordings whose
    samples are not equally spaced.
    """
    return (z - 2.0 * z_prev + z_prev2) / (dt * (dt if dt_prev is None else dt_prev))


def release_fires(armed: Any, acceleration: Any, threshold: float) -> Any:
    """The toss: armed and the vertical hand acceleration below ``-threshold``."""
    return armed & (acceleration < -threshold)


def release_velocity(vx: Any, vz: Any, factor_x: Any, factor_z: Any) -> tuple[Any, Any]:
    """The ball's velocity at the release: the hand's times the episode's release factor
    ``f = 1 + release * N(0, 1)`` (per component)."""
    return vx * factor_x, vz * factor_z


def flight(
    release: tuple[Any, Any, Any, Any, Any], time: Any, gravity: float
) -> tuple[Any, Any, Any, Any]:
    """Position and velocity ``(x, z, vx, vz)`` at ``time`` of a ball released at
    ``release = (t_r, x_r, z_r, vx_r, vz_r)``: ``x = x_r + vx_r s``,
    ``z = z_r + vz_r s - g s^2 / 2``, ``vz = vz_r - g s`` with ``s = time - t_r``."""
    t_r, x_r, z_r, vx, vz = release
    s = time - t_r
    return x_r + vx * s, z_r + vz * s - 0.5 * gravity * s * s, vx, vz - gravity * s


def swept_distance(dx0: Any, dz0: Any, dx1: Any, dz1: Any) -> Any:
    """Closest approach over a control period of the ball's offset from the hand, moving
    linearly from ``(dx0, dz0)`` (sample ``k-1``) to ``(dx1, dz1)`` (sample ``k``):
    ``min over s in [0, 1] of |d0 + s (d1 - d0)|``."""
    ex, ez = dx1 - dx0, dz1 - dz0
    s = np.clip(-(dx0 * ex + dz0 * ez) / (ex * ex + ez * ez + 1e-300), 0.0, 1.0)
    px, pz = dx0 + s * ex, dz0 + s * ez
    return np.sqrt(px * px + pz * pz)


def catch_fires(distance: Any, left: Any, dropped: Any, radius: float) -> Any:
    """The catch: the ball has left the hand, is back within ``radius`` and not dropped."""
    return left & (distance <= radius) & (dropped ^ True)


def has_left(distance: Any, left: Any, caught: Any, radius: float) -> Any:
    """Whether the ball has been farther than ``radius`` from the hand (sticky; not at a
    catch)."""
    return left | ((caught ^ True) & (distance > radius))


def drop_fires(ball_z: Any, held: Any, floor_z: float) -> Any:
    """The drop: a free ball whose centre is below ``floor_z``."""
    return (held ^ True) & (ball_z < floor_z)
