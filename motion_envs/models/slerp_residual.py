"""The slerp residual of orientation trajectories (Faraway & Choe 2008, section 3.3).

For one observed trajectory ``q_0 .. q_n`` (unit quaternions ``(w, x, y, z)``) at times
``t_0 .. t_n``:

1. continuity: flip ``q_i`` to ``-q_i`` when ``q_i . q_{i-1} < 0``;
2. step lengths ``s_i = arccos|q_i . q_{i-1}|`` (half the geodesic angle) and the
   cumulative fraction ``alpha_i = sum_{j<=i} s_j / sum_j s_j`` (``alpha_0 = 0``,
   ``alpha_n = 1``): the observed speed profile;
3. empirical slerp ``e_i = slerp(q_0, q_n, alpha_i)``;
4. residual rotation ``r_i = conj(e_i) * q_i`` (identity at both ends);
5. tangent vectors ``logmap(r_i)`` in R^3;
6. resampling to ``n_points`` (50) on normalised time ``tau = (t - t_0) / (t_n - t_0)``
   by linear interpolation of each tangent coordinate.

The result ``r(tau)`` is an ``n_points x 3`` array whose first and last rows are 0.

Variable-length trajectories are processed together: all samples are concatenated
into one flat array and every step is a single vectorised numpy call (no Python loop
over trajectories). Interpolation uses the offset trick ``tau + 2 l`` for trajectory
``l``, which keeps the concatenated time axis increasing so one ``np.interp`` serves all.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from motion_envs._typing import FloatArray
from motion_envs.datasets.ragged import (
    DEFAULT_N_POINTS,
    MIN_SAMPLES,
    RaggedTrajectories,
    normalised_grid,
)
from motion_envs.datasets.resampling import interpolate_on_grid, resample_orientations
from motion_envs.geometry import quaternion as quat

# The container, the grid and the resampling live in the datasets layer; they are
# re-exported here because the residual pipeline is where users meet them.
#: ``RaggedTrajectories`` is used here and importable from here, but its public homes are
#: ``motion_envs.datasets.ragged`` and ``motion_envs.models``: a class re-exported by two
#: pages of the API reference is described twice as an alias, which Sphinx's parallel
#: build reports as a duplicate when both land in one worker.
__all__ = [
    "DEFAULT_N_POINTS",
    "MIN_SAMPLES",
    "interpolate_on_grid",
    "normalised_grid",
    "resample_orientations",
    "residuals_against_profiles",
    "slerp_residuals",
    "speed_fractions",
]


def speed_fractions(traj: RaggedTrajectories) -> FloatArray:
    """Cumulative rotation fraction ``alpha_i`` of every sample (step 2), flat ``(N_total,)``.

    ``s_i = arccos|q_i . q_{i-1}|`` is computed as half the geodesic angle
    (``atan2`` form, exact near 0); ``alpha_i = sum_{j<=i} s_j / sum_j s_j``. A trajectory
    that does not rotate at all (every ``s_i = 0``) gets ``alpha = tau`` (uniform speed).
    """
    q = traj.quaternions
    idx = traj.trajectory_index()
    steps = np.zeros(q.shape[0])
    rel = quat.multiply(quat.conjugate(q[:-1]), q[1:])
    vec = np.sqrt(np.einsum("ni,ni->n", rel[:, 1:], rel[:, 1:]))
    steps[1:] = np.arctan2(vec, np.abs(rel[:, 0]))
    steps[traj.offsets[:-1]] = 0.0  # no step across trajectory boundaries
    cum = np.cumsum(steps)
    base = cum[traj.offsets[:-1]]
    total = cum[traj.offsets[1:] - 1] - base
    cum = cum - base[idx]
    still = total <= 0.0
    alpha = cum / np.where(still, 1.0, total)[idx]
    alpha = np.where(still[idx], traj.tau, alpha)
    # the last sample is exactly 1, not 1 - rounding
    alpha[traj.offsets[1:] - 1] = 1.0
    return alpha


def slerp_residuals(
    traj: RaggedTrajectories,
    n_points: int = DEFAULT_N_POINTS,
    average_alpha: ArrayLike | None = None,
) -> FloatArray:
    """Slerp residual curves ``r_l(tau)`` of every trajectory, shape ``(L, n_points, 3)``.

    With ``average_alpha=None`` (the paper's "empirical" slerp) steps 1-6 of the module
    docstring are applied to each trajectory's own speed profile.

    With ``average_alpha`` (shape ``(n_points,)``, the mean speed profile on the grid;
    see :func:`motion_envs.models.speed_profile.average_speed_profile`) the observed
    orientation is first resampled to the grid (:func:`resample_orientations`) and the
    residual is ``logmap(conj(slerp(q_0, q_n, alpha_bar(tau))) * q(tau))`` ("Slerp,
    average" in Table 1).
    """
    grid = normalised_grid(n_points)
    q0 = traj.starts
    qn = traj.ends
    if average_alpha is None:
        alpha = speed_fractions(traj)
        idx = traj.trajectory_index()
        e = quat.slerp(q0[idx], qn[idx], alpha, validate=False)
        r = quat.multiply(quat.conjugate(e), traj.quaternions)
        v = quat.logmap(r, validate=False)
        out = interpolate_on_grid(traj, v, grid)
    else:
        abar = np.asarray(average_alpha, dtype=np.float64)
        if abar.shape != (n_points,):
            raise ValueError(f"average_alpha must have shape ({n_points},); got {abar.shape}")
        q_grid = resample_orientations(traj, grid)
        e = quat.slerp(q0[:, None, :], qn[:, None, :], abar[None, :], validate=False)
        r = quat.multiply(quat.conjugate(e), q_grid)
        out = quat.logmap(r, validate=False)
    # ends are exactly 0 by construction; remove rounding so the Bézier end conditions hold.
    out[:, 0] = 0.0
    if average_alpha is None or np.isclose(np.asarray(average_alpha)[-1], 1.0):
        out[:, -1] = 0.0
    return out


def residuals_against_profiles(
    q_grid: ArrayLike, starts: ArrayLike, ends: ArrayLike, alpha: ArrayLike
) -> FloatArray:
    """Residuals ``logmap(conj(slerp(q_s, q_e, alpha_l(tau))) q_l(tau))`` on the grid.

    ``q_grid`` ``(L, n, 4)`` are the orientations resampled to the grid
    (:func:`resample_orientations`), ``starts``/``ends`` ``(L, 4)``, ``alpha`` a speed
    profile ``(n,)`` for all or ``(L, n)`` one per trajectory (a *predicted* timing);
    returns ``(L, n, 3)`` with both end rows exactly 0.
    """
    q = np.asarray(q_grid, dtype=np.float64)
    a = np.broadcast_to(np.asarray(alpha, dtype=np.float64), q.shape[:2])
    s = np.asarray(starts, dtype=np.float64)[:, None, :]
    e = quat.slerp(s, np.asarray(ends, dtype=np.float64)[:, None, :], a, validate=False)
    out = quat.logmap(quat.multiply(quat.conjugate(e), q), validate=False)
    out[:, 0] = 0.0
    out[:, -1] = 0.0
    return out
