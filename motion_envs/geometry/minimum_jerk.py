"""The minimum-jerk movement between two rest states (Flash & Hogan 1985).

Among all movements from ``s`` to ``e`` in time ``T`` that start and end at rest (zero
velocity and acceleration), the one minimising ``int_0^T |d3y/dt3|^2 dt`` is, on
normalised time ``u = t / T``::

    y(u) = s + (e - s) (10 u^3 - 15 u^4 + 6 u^5)

with peak speed ``1.875 |e - s| / T`` at ``u = 1/2``. Between any two states (position,
velocity and acceleration at ``0`` and at ``T``) the minimiser is the quintic
``y(t) = sum_j c_j t^j``, ``j = 0 .. 5``, whose coefficients solve the 6 x 6
boundary-value system (:func:`quintic`, :func:`quintic_evaluate`); with zero end
velocities and accelerations it is :func:`minimum_jerk` (to round-off).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from motion_envs._typing import FloatArray

__all__ = ["minimum_jerk", "minimum_jerk_profile", "quintic", "quintic_evaluate"]


def minimum_jerk_profile(tau: ArrayLike) -> FloatArray:
    """The normalised path ``10 u^3 - 15 u^4 + 6 u^5`` (0 to 1), same shape as ``tau``."""
    u = np.asarray(tau, dtype=np.float64)
    return np.asarray(10 * u**3 - 15 * u**4 + 6 * u**5, dtype=np.float64)


def minimum_jerk(start: ArrayLike, end: ArrayLike, tau: ArrayLike) -> FloatArray:
    """Minimum-jerk movement between rest states: ``s + (e - s)(10 u^3 - 15 u^4 + 6 u^5)``.

    ``start``, ``end`` ``(D,)`` (or ``(m, D)``), ``tau`` ``(K,)`` normalised time; returns
    ``(K, D)`` (or ``(m, K, D)``).
    """
    s = np.asarray(start, dtype=np.float64)
    e = np.asarray(end, dtype=np.float64)
    shape = minimum_jerk_profile(tau)
    return np.asarray(s[..., None, :] + (e - s)[..., None, :] * shape[:, None], dtype=np.float64)


def quintic(
    p0: ArrayLike,
    v0: ArrayLike,
    a0: ArrayLike,
    p1: ArrayLike,
    v1: ArrayLike,
    a1: ArrayLike,
    duration: float,
) -> FloatArray:
    """Coefficients ``(6, D)`` of the quintic with the given end states over ``[0, T]``.

    The minimum-jerk movement between two states: ``y(t) = sum_j c_j t^j`` with
    ``y, y', y''`` equal to ``(p0, v0, a0)`` at 0 and ``(p1, v1, a1)`` at ``T``.
    """
    t = float(duration)
    m = np.array(
        [
            [1, 0, 0, 0, 0, 0],
            [0, 1, 0, 0, 0, 0],
            [0, 0, 2, 0, 0, 0],
            [1, t, t**2, t**3, t**4, t**5],
            [0, 1, 2 * t, 3 * t**2, 4 * t**3, 5 * t**4],
            [0, 0, 2, 6 * t, 12 * t**2, 20 * t**3],
        ],
        dtype=np.float64,
    )
    rhs = np.stack([p0, v0, a0, p1, v1, a1]).astype(np.float64)
    return np.linalg.solve(m, rhs).astype(np.float64, copy=False)


def quintic_evaluate(c: ArrayLike, t: ArrayLike, order: int = 0) -> FloatArray:
    """Position (order 0), velocity (1) or acceleration (2) of the quintic with
    coefficients ``c`` ``(6, D)`` at times ``t`` (scalar or ``(K,)``): ``(D,)``/``(K, D)``."""
    t = np.asarray(t, dtype=np.float64)
    powers = np.arange(6)
    coef = np.ones(6)
    for k in range(order):
        coef = coef * np.maximum(powers - k, 0)
    exps = np.maximum(powers - order, 0)
    out: FloatArray = (coef * t[..., None] ** exps) @ np.asarray(c, dtype=np.float64)
    return out
