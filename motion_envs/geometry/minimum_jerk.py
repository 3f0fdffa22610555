"""The minimum-jerk movement between two rest states (Flash & Hogan 1985).

Among all movements from ``s`` to ``e`` in time ``T`` that start and end at rest (zero
velocity and acceleration), the one minimising ``int_0^T |d3y/dt3|^2 dt`` is, on
normalised time ``u = t / T``::

    y(u) = s + (e - s) (10 u^3 - 15 u^4 + 6 u^5)

with peak speed ``1.875 |e - s| / T`` at ``u = 1/2``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["minimum_jerk", "minimum_jerk_profile"]

FloatArray = NDArray[np.float64]


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
