"""Speed profiles of orientation trajectories: the Beta model (Faraway & Choe, step 3).

The cumulative rotation fraction ``alpha(tau)`` (0 at ``tau = 0``, 1 at ``tau = 1``) is
modelled as the Beta distribution function, so the angular speed profile
``d alpha / d tau`` is a Beta density::

    alpha(tau; a, b) = I_tau(a, b)                 (regularised incomplete beta)
    d alpha / d tau  = tau^(a-1) (1 - tau)^(b-1) / B(a, b)

Two fits are offered, both batched over trajectories sampled on one common grid:

* ``"moments"``: treat the speed profile as a distribution over ``tau`` and match its
  mean ``m`` and variance ``v``: ``a = m c``, ``b = (1 - m) c`` with
  ``c = m (1 - m) / v - 1``. Closed form, no optimiser.
* ``"least_squares"`` (default): minimise ``sum_k (alpha_k - I_{tau_k}(a, b))^2`` over
  ``log a, log b`` with ``scipy.optimize.least_squares``, started from the moments fit.

``beta_alpha`` and ``beta_speed`` live in :mod:`motion_envs.geometry.beta_profile`
and are re-exported here. The "average speed profile" of Table 1 is the mean of the
``alpha`` curves on the grid.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike
from scipy import optimize, special

from motion_envs._typing import FloatArray
from motion_envs.datasets.ragged import DEFAULT_N_POINTS, RaggedTrajectories, normalised_grid
from motion_envs.datasets.resampling import interpolate_on_grid
from motion_envs.geometry.beta_profile import beta_alpha, beta_speed
from motion_envs.models.slerp_residual import speed_fractions

__all__ = [
    "average_speed_profile",
    "beta_alpha",
    "beta_speed",
    "fit_beta_speed_profile",
    "speed_fractions_on_grid",
]

_MIN_SHAPE = 1e-3
_MAX_SHAPE = 1e3


def speed_fractions_on_grid(
    traj: RaggedTrajectories, n_points: int = DEFAULT_N_POINTS
) -> FloatArray:
    """Each trajectory's ``alpha`` interpolated linearly onto the common grid, ``(L, n_points)``."""
    alpha = speed_fractions(traj)
    return interpolate_on_grid(traj, alpha[:, None], normalised_grid(n_points))[..., 0]


def average_speed_profile(traj: RaggedTrajectories, n_points: int = DEFAULT_N_POINTS) -> FloatArray:
    """Mean of the trajectories' ``alpha`` curves on the common grid, shape ``(n_points,)``."""
    return speed_fractions_on_grid(traj, n_points).mean(axis=0)


def _moments_fit(alpha: FloatArray, tau: FloatArray) -> tuple[FloatArray, FloatArray]:
    # speed mass of each grid interval, placed at its midpoint
    mass = np.diff(alpha, axis=-1)
    mass = np.clip(mass, 0.0, None)
    total = mass.sum(axis=-1, keepdims=True)
    if np.any(total <= 0):
        raise ValueError("alpha must increase from 0 to 1 along each curve")
    w = mass / total
    mid = 0.5 * (tau[1:] + tau[:-1])
    m = (w * mid).sum(axis=-1)
    # add the within-interval variance of a uniform spread (h^2/12) to the discrete one
    h2 = np.diff(tau) ** 2 / 12.0
    v = (w * (mid - m[..., None]) ** 2).sum(axis=-1) + (w * h2).sum(axis=-1)
    c = m * (1.0 - m) / v - 1.0
    c = np.maximum(c, 2 * _MIN_SHAPE)
    a = np.clip(m * c, _MIN_SHAPE, _MAX_SHAPE)
    b = np.clip((1.0 - m) * c, _MIN_SHAPE, _MAX_SHAPE)
    return a, b


def fit_beta_speed_profile(
    alpha: ArrayLike,
    tau: ArrayLike | None = None,
    method: str = "least_squares",
) -> tuple[FloatArray, FloatArray]:
    """Fit Beta shape parameters ``(a, b)`` to cumulative-fraction curves.

    Parameters
    ----------
    alpha:
        ``(L, n)`` or ``(n,)`` cumulative fractions on the grid ``tau`` (0 to 1,
        non-decreasing), e.g. from :func:`speed_fractions_on_grid`.
    tau:
        ``(n,)`` grid; defaults to the uniform grid of ``n`` points on ``[0, 1]``.
    method:
        ``"least_squares"`` or ``"moments"`` (see the module docstring).

    Returns
    -------
    a, b:
        Arrays of shape ``(L,)`` (or scalars' shape ``()`` for a single curve).
    """
    alpha = np.asarray(alpha, dtype=np.float64)
    single = alpha.ndim == 1
    alpha2 = np.atleast_2d(alpha)
    if alpha2.ndim != 2 or alpha2.shape[1] < 3:
        raise ValueError(f"alpha must have shape (L, n) with n >= 3; got {alpha.shape}")
    if not np.all(np.isfinite(alpha2)):
        raise ValueError("alpha contains NaN or infinite values")
    tau = normalised_grid(alpha2.shape[1]) if tau is None else np.asarray(tau, dtype=np.float64)
    if tau.shape != (alpha2.shape[1],):
        raise ValueError(f"tau must have shape ({alpha2.shape[1]},); got {tau.shape}")
    if method not in ("least_squares", "moments"):
        raise ValueError(f"method must be 'least_squares' or 'moments'; got {method!r}")
    a, b = _moments_fit(alpha2, tau)
    if method == "least_squares":
        lo, hi = np.log(_MIN_SHAPE), np.log(_MAX_SHAPE)
        for l in range(alpha2.shape[0]):
            target = alpha2[l]

            def resid(p: FloatArray, target: FloatArray = target) -> FloatArray:
                return special.betainc(np.exp(p[0]), np.exp(p[1]), tau) - target

            x0 = np.clip(np.log([a[l], b[l]]), lo + 1e-9, hi - 1e-9)
            sol = optimize.least_squares(resid, x0, bounds=(lo, hi), method="trf")
            a[l], b[l] = np.exp(sol.x)
    if single:
        return a[0], b[0]
    return a, b
