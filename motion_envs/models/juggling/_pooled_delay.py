r"""The pooled release-anchored delay: one least-squares delay for all of an episode's
anchored flights (a :class:`~motion_envs.models.juggling.DelayRule`).

The default rule (:func:`~motion_envs.models.juggling.mean_flight_delay`) finds each
flight's least-residual delay on the 5 ms grid and averages them: each flight's estimate
is rounded to the grid, and a flight whose few frames fit badly weighs as much as one
that fits well. The pooled rule fits the ONE delay the episode has to every flight at
once, each flight with its own velocity:

.. math::

    R(d) = \sum_f r_f(d), \qquad
    r_f(d) = \min_{v_f} \sum_i \lvert q_{f,i} + (0, g s_{f,i}^2 / 2) - v_f s_{f,i}\rvert^2,
    \quad s_{f,i} = a_{f,i} - d,

(:func:`~motion_envs.models.juggling.release_residuals`: ``a`` a frame's arrival minus
its flight's release time, ``q`` its position minus the release point), the joint least
squares of a common delay under white position noise of one std (the camera's, the same
for every frame). ``R`` is evaluated on the grid (:data:`DELAY_GRID`; ``inf`` where a
flight's frame would precede its release, so a flight bounds the delay by its first
arrival; a flight with no valid delay at all is left out, as the default rule leaves it
out); its least grid point ``i`` is refined below the grid by the parabola through
``R`` at ``d_{i-1}, d_i, d_{i+1}`` (:func:`parabolic_minimum`):

.. math::

    \hat d = d_i + \frac{h}{2} \frac{R_{i-1} - R_{i+1}}{R_{i-1} - 2 R_i + R_{i+1}},

``h`` the grid step; within ``h / 2`` of ``d_i`` since ``R_i`` is the least of the
three. At a grid end, or next to an ``inf``, the grid point itself.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from motion_envs._typing import FloatArray
from motion_envs.models.juggling._camera import DELAY_GRID, AnchoredFlight, release_residuals

__all__ = ["parabolic_minimum", "pooled_flight_delay", "pooled_residuals"]


def pooled_residuals(
    flights: Sequence[AnchoredFlight], gravity: float, grid: FloatArray = DELAY_GRID
) -> FloatArray | None:
    """``R(d)`` on ``grid`` (module docstring): the flights' residuals summed, the
    flights without any valid delay left out; None when no flight has one."""
    total: FloatArray | None = None
    for s0, q in flights:
        r = release_residuals(s0, q, gravity, grid)
        if not np.isfinite(r).any():
            continue
        total = r if total is None else total + r
    return total


def parabolic_minimum(grid: FloatArray, values: FloatArray) -> float | None:
    """The least of ``values`` on the uniform ``grid`` refined by the parabola through
    it and its two neighbours (module docstring); the grid point itself at an end, next
    to a non-finite value or where the three are collinear; None when no value is
    finite."""
    values = np.asarray(values, dtype=np.float64)
    grid = np.asarray(grid, dtype=np.float64)
    if grid.shape != values.shape or grid.ndim != 1:
        raise ValueError(f"grid and values must be 1-d of one length; got {grid.shape}, "
                         f"{values.shape}")  # fmt: skip
    if not np.isfinite(values).any():
        return None
    i = int(np.argmin(np.where(np.isfinite(values), values, np.inf)))
    d = float(grid[i])
    if i == 0 or i == len(grid) - 1:
        return d
    lo, mid, hi = values[i - 1], values[i], values[i + 1]
    curvature = lo - 2.0 * mid + hi
    if not (np.isfinite(lo) and np.isfinite(hi)) or curvature <= 0.0:
        return d
    h = 0.5 * float(grid[i + 1] - grid[i - 1])
    return d + 0.5 * h * float(lo - hi) / float(curvature)


def pooled_flight_delay(flights: Sequence[AnchoredFlight], gravity: float) -> float | None:
    """s; the episode's one delay fitted to all its anchored ``flights`` at once on
    :data:`DELAY_GRID`, refined below the grid (module docstring); None when no flight
    tells one. A :class:`~motion_envs.models.juggling.DelayRule`."""
    total = pooled_residuals(flights, gravity)
    return None if total is None else parabolic_minimum(DELAY_GRID, total)
