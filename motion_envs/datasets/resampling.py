"""Resampling recorded trajectories onto the common normalised-time grid.

Orientation trajectories (:class:`~motion_envs.datasets.ragged.RaggedTrajectories`) are
resampled by slerp between neighbouring samples, any per-sample quantity by linear
interpolation, position trajectories by linear interpolation of each coordinate on
``tau = (t - t_0) / (t_n - t_0)``. Every function handles all trajectories at once.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from motion_envs._typing import FloatArray
from motion_envs.datasets.ragged import DEFAULT_N_POINTS, RaggedTrajectories
from motion_envs.geometry import quaternion as quat
from motion_envs.geometry import sine_series as ss

__all__ = ["interpolate_on_grid", "resample_orientations", "resample_positions"]


def interpolate_on_grid(traj: RaggedTrajectories, values: ArrayLike, grid: ArrayLike) -> FloatArray:
    """Linear interpolation of per-sample ``values`` ``(N_total, c)`` onto ``grid`` per trajectory.

    Returns ``(L, len(grid), c)``. One ``np.interp`` call per column for all
    trajectories, using the increasing global abscissa ``tau + 2 l``.
    """
    v = np.asarray(values, dtype=np.float64)
    g = np.asarray(grid, dtype=np.float64)
    L = traj.n_trajectories
    x, xq = traj.global_abscissae(g)
    out = np.empty((xq.size, v.shape[1]))
    for c in range(v.shape[1]):
        out[:, c] = np.interp(xq, x, v[:, c])
    return out.reshape(L, g.size, v.shape[1])


def resample_orientations(traj: RaggedTrajectories, grid: ArrayLike) -> FloatArray:
    """Orientation of every trajectory at normalised times ``grid``, shape ``(L, n, 4)``.

    The orientation at a grid time ``g`` with ``tau_j <= g <= tau_{j+1}`` is
    ``slerp(q_j, q_{j+1}, (g - tau_j) / (tau_{j+1} - tau_j))``.
    """
    g = np.asarray(grid, dtype=np.float64)
    L = traj.n_trajectories
    x, xq = traj.global_abscissae(g)
    # right neighbour index, kept inside each trajectory
    j1 = np.searchsorted(x, xq, side="left")
    first = np.repeat(traj.offsets[:-1], g.size)
    last = np.repeat(traj.offsets[1:] - 1, g.size)
    j1 = np.clip(j1, first + 1, last)
    j0 = j1 - 1
    frac = np.clip((xq - x[j0]) / (x[j1] - x[j0]), 0.0, 1.0)
    q = quat.slerp(traj.quaternions[j0], traj.quaternions[j1], frac, validate=False)
    return q.reshape(L, g.size, 4)


def resample_positions(
    dataset: Any, n_points: int = DEFAULT_N_POINTS
) -> tuple[FloatArray, FloatArray]:
    """Every trajectory linearly interpolated on ``n_points`` uniform ``tau = (t - t_0)/T``.

    ``dataset`` is anything with ``positions``, ``times`` (per trajectory) and
    ``n_dims``, e.g. a :class:`~motion_envs.datasets.PositionDataset`. Returns
    ``(L, n_points, D)`` positions and ``(L,)`` durations ``T`` (the resampling of
    ``motion-bench position`` and ``PositionReach-v0``).
    """
    if n_points < 5:
        raise ValueError(f"n_points must be >= 5; got {n_points}")
    tau = np.linspace(0.0, 1.0, n_points)
    out = np.empty((len(dataset), n_points, dataset.n_dims))
    for i, (y, t) in enumerate(zip(dataset.positions, dataset.times, strict=True)):
        src = ss.normalised_time(t)
        for j in range(y.shape[1]):
            out[i, :, j] = np.interp(tau, src, y[:, j])
    durations = np.array([t[-1] - t[0] for t in dataset.times])
    return out, durations
