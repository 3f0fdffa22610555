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

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from motion_envs.geometry import quaternion as quat

__all__ = [
    "DEFAULT_N_POINTS",
    "MIN_SAMPLES",
    "RaggedTrajectories",
    "interpolate_on_grid",
    "normalised_grid",
    "resample_orientations",
    "slerp_residuals",
    "speed_fractions",
]

FloatArray = NDArray[np.float64]

#: Number of points on the common normalised-time grid (the paper's 50).
DEFAULT_N_POINTS = 50
#: Fewest samples accepted for one trajectory.
MIN_SAMPLES = 5


def normalised_grid(n_points: int = DEFAULT_N_POINTS) -> FloatArray:
    """The uniform normalised-time grid ``tau_k = k / (n_points - 1)``, ``k = 0 .. n_points-1``."""
    if n_points < 2:
        raise ValueError(f"n_points must be >= 2; got {n_points}")
    return np.linspace(0.0, 1.0, n_points)


@dataclass(frozen=True)
class RaggedTrajectories:
    """Variable-length orientation trajectories stored flat.

    Attributes
    ----------
    quaternions:
        ``(N_total, 4)`` unit quaternions ``(w, x, y, z)``, made sign-continuous within
        each trajectory.
    tau:
        ``(N_total,)`` normalised time in ``[0, 1]`` within each trajectory.
    offsets:
        ``(L + 1,)`` start index of each trajectory; trajectory ``l`` is
        ``offsets[l]:offsets[l + 1]``.
    durations:
        ``(L,)`` clock duration ``t_n - t_0`` in the time unit given.
    """

    quaternions: FloatArray
    tau: FloatArray
    offsets: NDArray[np.int64]
    durations: FloatArray

    @property
    def n_trajectories(self) -> int:
        return int(self.offsets.size - 1)

    @property
    def lengths(self) -> NDArray[np.int64]:
        return np.diff(self.offsets)

    @property
    def starts(self) -> FloatArray:
        """``(L, 4)`` first orientation of each trajectory."""
        return self.quaternions[self.offsets[:-1]]

    @property
    def ends(self) -> FloatArray:
        """``(L, 4)`` last orientation of each trajectory (sign-continuous with the start)."""
        return self.quaternions[self.offsets[1:] - 1]

    def trajectory_index(self) -> NDArray[np.int64]:
        """``(N_total,)`` index ``l`` of the trajectory each sample belongs to."""
        return np.repeat(np.arange(self.n_trajectories), self.lengths)

    @classmethod
    def from_sequences(
        cls,
        quaternions: Sequence[ArrayLike],
        times: Sequence[ArrayLike],
        min_samples: int = MIN_SAMPLES,
    ) -> RaggedTrajectories:
        """Validate and pack trajectories given as lists of ``(n_l, 4)`` and ``(n_l,)`` arrays.

        Raises ``ValueError`` naming the trajectory for: a length mismatch, fewer than
        ``min_samples`` samples, NaN, non-unit quaternions, or times that do not strictly
        increase.
        """
        if len(quaternions) != len(times):
            raise ValueError(
                f"quaternions and times must have the same number of trajectories; "
                f"got {len(quaternions)} and {len(times)}"
            )
        if len(quaternions) == 0:
            raise ValueError("quaternions must contain at least one trajectory")
        qs, taus, lengths, durations = [], [], [], []
        for l, (q, t) in enumerate(zip(quaternions, times, strict=True)):
            q = quat.as_unit(q, name=f"quaternions[{l}]")
            t = np.asarray(t, dtype=np.float64)
            if q.ndim != 2 or t.ndim != 1 or t.shape[0] != q.shape[0]:
                raise ValueError(
                    f"trajectory {l}: quaternions must be (n, 4) and times (n,); got "
                    f"{q.shape} and {t.shape}"
                )
            if q.shape[0] < min_samples:
                raise ValueError(
                    f"trajectory {l}: has {q.shape[0]} samples, at least {min_samples} needed"
                )
            if not np.all(np.isfinite(t)):
                raise ValueError(f"times[{l}] contains NaN or infinite values")
            if np.any(np.diff(t) <= 0.0):
                raise ValueError(f"times[{l}] must be strictly increasing")
            qs.append(quat.make_continuous(q))
            duration = t[-1] - t[0]
            taus.append((t - t[0]) / duration)
            lengths.append(q.shape[0])
            durations.append(duration)
        offsets = np.concatenate([[0], np.cumsum(lengths)]).astype(np.int64)
        return cls(
            quaternions=np.concatenate(qs),
            tau=np.concatenate(taus),
            offsets=offsets,
            durations=np.asarray(durations, dtype=np.float64),
        )


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


def _global_abscissae(traj: RaggedTrajectories, grid: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Samples' ``tau + 2 l`` (increasing across trajectories) and the grid's, ``(L * n,)``."""
    x = traj.tau + 2.0 * traj.trajectory_index()
    xq = (grid[None, :] + 2.0 * np.arange(traj.n_trajectories)[:, None]).ravel()
    return x, xq


def interpolate_on_grid(traj: RaggedTrajectories, values: ArrayLike, grid: ArrayLike) -> FloatArray:
    """Linear interpolation of per-sample ``values`` ``(N_total, c)`` onto ``grid`` per trajectory.

    Returns ``(L, len(grid), c)``. One ``np.interp`` call per column for all
    trajectories, using the increasing global abscissa ``tau + 2 l``.
    """
    values = np.asarray(values, dtype=np.float64)
    grid = np.asarray(grid, dtype=np.float64)
    L = traj.n_trajectories
    x, xq = _global_abscissae(traj, grid)
    out = np.empty((xq.size, values.shape[1]))
    for c in range(values.shape[1]):
        out[:, c] = np.interp(xq, x, values[:, c])
    return out.reshape(L, grid.size, values.shape[1])


def resample_orientations(traj: RaggedTrajectories, grid: ArrayLike) -> FloatArray:
    """Orientation of every trajectory at normalised times ``grid``, shape ``(L, n, 4)``.

    The orientation at a grid time ``g`` with ``tau_j <= g <= tau_{j+1}`` is
    ``slerp(q_j, q_{j+1}, (g - tau_j) / (tau_{j+1} - tau_j))``.
    """
    grid = np.asarray(grid, dtype=np.float64)
    L = traj.n_trajectories
    x, xq = _global_abscissae(traj, grid)
    # right neighbour index, kept inside each trajectory
    j1 = np.searchsorted(x, xq, side="left")
    first = np.repeat(traj.offsets[:-1], grid.size)
    last = np.repeat(traj.offsets[1:] - 1, grid.size)
    j1 = np.clip(j1, first + 1, last)
    j0 = j1 - 1
    frac = np.clip((xq - x[j0]) / (x[j1] - x[j0]), 0.0, 1.0)
    q = quat.slerp(traj.quaternions[j0], traj.quaternions[j1], frac, validate=False)
    return q.reshape(L, grid.size, 4)


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
