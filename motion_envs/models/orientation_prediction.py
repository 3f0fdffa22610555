"""Predicting whole orientation trajectories (Faraway & Choe, sections 3.3-3.4).

Given a start ``q_s``, an end ``q_e`` (unit quaternions ``(w, x, y, z)``), a speed
profile ``alpha(tau)`` and interior Bézier control points ``P`` of the slerp residual::

    q(tau) = slerp(q_s, q_e, alpha(tau)) * expmap(C(tau; P))

with ``C`` the Bézier curve whose end control points are at the origin, so the
prediction starts at ``q_s`` and ends at ``q_e`` exactly. ``alpha`` may be given as
values on the grid or as Beta shape parameters ``(a, b)`` (``alpha = I_tau(a, b)``).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from motion_envs._typing import FloatArray
from motion_envs.datasets.ragged import DEFAULT_N_POINTS, normalised_grid
from motion_envs.geometry import bezier
from motion_envs.geometry import quaternion as quat
from motion_envs.geometry.beta_profile import beta_alpha

__all__ = ["predict_orientations"]


def predict_orientations(
    q_start: ArrayLike,
    q_end: ArrayLike,
    control_points: ArrayLike | None = None,
    alpha: ArrayLike | None = None,
    beta: tuple[float, float] | ArrayLike | None = None,
    n_points: int = DEFAULT_N_POINTS,
) -> FloatArray:
    """Predicted orientations ``q(tau)`` on the uniform grid of ``n_points``.

    Parameters
    ----------
    q_start, q_end:
        ``(4,)`` or ``(B, 4)`` unit quaternions ``(w, x, y, z)``.
    control_points:
        Interior Bézier control points, ``(d - 1, 3)`` shared or ``(B, d - 1, 3)``;
        ``None`` means the plain slerp (``d = 1``).
    alpha:
        Speed profile on the grid, ``(n_points,)`` or ``(B, n_points)``, from 0 to 1.
    beta:
        Alternatively Beta shape parameters ``(a, b)``, scalars or ``(B, 2)``.
        Exactly one of ``alpha`` and ``beta`` may be given; neither means uniform
        speed (``alpha = tau``).

    Returns
    -------
    ``(n_points, 4)`` for a single start/end pair, else ``(B, n_points, 4)``.
    """
    qs = quat.as_unit(q_start, "q_start")
    qe = quat.as_unit(q_end, "q_end")
    single = qs.ndim == 1 and qe.ndim == 1
    qs2 = np.atleast_2d(qs)
    qe2 = np.atleast_2d(qe)
    batch = np.broadcast_shapes(qs2.shape[:-1], qe2.shape[:-1])
    if len(batch) != 1:
        raise ValueError(f"q_start and q_end must be (4,) or (B, 4); got {qs.shape} and {qe.shape}")
    grid = normalised_grid(n_points)
    if alpha is not None and beta is not None:
        raise ValueError("give either alpha or beta, not both")
    if beta is not None:
        ab = np.asarray(beta, dtype=np.float64)
        if ab.shape[-1] != 2:
            raise ValueError(f"beta must be (a, b) or (B, 2); got shape {ab.shape}")
        a_grid = beta_alpha(grid, ab[..., 0, None], ab[..., 1, None])
    elif alpha is not None:
        a_grid = np.asarray(alpha, dtype=np.float64)
        if a_grid.shape[-1] != n_points:
            raise ValueError(
                f"alpha must have {n_points} values on its last axis; got {a_grid.shape}"
            )
        if not np.all(np.isfinite(a_grid)):
            raise ValueError("alpha contains NaN or infinite values")
    else:
        a_grid = grid
    a_grid = np.broadcast_to(a_grid, (*batch, n_points))
    path = quat.slerp(qs2[:, None, :], qe2[:, None, :], a_grid, validate=False)
    if control_points is not None:
        P = np.asarray(control_points, dtype=np.float64)
        if P.ndim not in (2, 3) or P.shape[-1] != 3:
            raise ValueError(
                f"control_points must be (d - 1, 3) or (B, d - 1, 3); got shape {P.shape}"
            )
        curve = bezier.evaluate(P, grid)
        path = quat.multiply(path, quat.expmap(np.broadcast_to(curve, (*batch, n_points, 3))))
    return path[0] if single else path
