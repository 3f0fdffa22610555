"""The Beta speed profile of a movement on normalised time (Faraway & Choe, step 3).

The cumulative fraction ``alpha(tau)`` of the movement done by normalised time
``tau in [0, 1]`` (0 at ``tau = 0``, 1 at ``tau = 1``) is modelled as the Beta
distribution function, so the speed profile ``d alpha / d tau`` is a Beta density::

    alpha(tau; a, b) = I_tau(a, b)                 (regularised incomplete beta)
    d alpha / d tau  = tau^(a-1) (1 - tau)^(b-1) / B(a, b)

Both functions broadcast over ``tau``, ``a`` and ``b``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike
from scipy import special

from motion_envs._typing import FloatArray

__all__ = ["beta_alpha", "beta_speed"]


def _check_shapes(a: ArrayLike, b: ArrayLike) -> tuple[FloatArray, FloatArray]:
    a_arr = np.asarray(a, dtype=np.float64)
    b_arr = np.asarray(b, dtype=np.float64)
    if np.any(~np.isfinite(a_arr) | (a_arr <= 0)) or np.any(~np.isfinite(b_arr) | (b_arr <= 0)):
        raise ValueError("Beta shape parameters a and b must be finite and > 0")
    return a_arr, b_arr


def beta_alpha(tau: ArrayLike, a: ArrayLike, b: ArrayLike) -> FloatArray:
    """Cumulative fraction ``alpha(tau) = I_tau(a, b)`` (the Beta CDF); broadcasts.

    ``tau`` is clipped to ``[0, 1]``; ``a`` and ``b`` must be finite and positive.
    """
    a_arr, b_arr = _check_shapes(a, b)
    t = np.clip(np.asarray(tau, dtype=np.float64), 0.0, 1.0)
    out: FloatArray = special.betainc(a_arr, b_arr, t)
    return out


def beta_speed(tau: ArrayLike, a: ArrayLike, b: ArrayLike) -> FloatArray:
    """Speed profile ``d alpha / d tau``: the Beta density at ``tau``; broadcasts."""
    from scipy.stats import beta as beta_dist

    t = np.asarray(tau, dtype=np.float64)
    out: FloatArray = beta_dist.pdf(t, a, b)
    return out
