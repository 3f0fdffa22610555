"""Bézier curves whose two end control points sit at the origin.

A Bézier curve of degree ``d`` with control points ``P_0 .. P_d`` is::

    C(t) = sum_{i=0}^{d} P_i B^d_i(t),   B^d_i(t) = binom(d, i) t^i (1 - t)^(d - i),   t in [0, 1]

For slerp residuals (Faraway & Choe, section 3.4) ``P_0 = P_d = 0``, so only the
interior points ``P_1 .. P_{d-1}`` are free and ``C(t) = B(t) P`` with ``B`` the
``n x (d-1)`` matrix of interior Bernstein columns. Fitting many curves sampled on one
common grid is a single least-squares problem: ``P_l = pinv(B) Z_l`` for every curve
``l`` at once, with one shared pseudo-inverse.

Arrays: curves ``Z`` have shape ``(..., n_points, dim)``; control points ``P`` have
shape ``(..., d - 1, dim)`` (interior points only).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike
from scipy.special import comb

from motion_envs._typing import FloatArray

__all__ = [
    "bernstein_interior",
    "check_degree",
    "evaluate",
    "fit",
    "fit_operator",
]


def check_degree(degree: Any) -> int:
    """``degree`` as an ``int``: a Bézier degree is an integer >= 1 (``ValueError`` else)."""
    if isinstance(degree, bool) or not isinstance(degree, (int, np.integer)) or degree < 1:
        raise ValueError(f"degree must be an integer >= 1; got {degree!r}")
    return int(degree)


def bernstein_interior(t: ArrayLike, degree: int) -> FloatArray:
    """Design matrix of the interior Bernstein polynomials ``B^d_1 .. B^d_{d-1}`` at ``t``.

    Returns shape ``t.shape + (degree - 1,)``; for ``degree == 1`` the last axis is empty
    (the curve is identically zero: the plain slerp).
    """
    d = check_degree(degree)
    t = np.asarray(t, dtype=np.float64)
    if not np.all(np.isfinite(t)):
        raise ValueError("t contains NaN or infinite values")
    i = np.arange(1, d)
    tt = t[..., None]
    return comb(d, i) * tt**i * (1.0 - tt) ** (d - i)


def evaluate(control_points: ArrayLike, t: ArrayLike, degree: int | None = None) -> FloatArray:
    """Evaluate curves ``C(t) = sum_{i=1}^{d-1} P_i B^d_i(t)`` (end points at the origin).

    ``control_points`` has shape ``(..., d - 1, dim)``; ``t`` is a 1-D grid of length
    ``n``. Returns ``(..., n, dim)``. ``degree`` defaults to ``control_points.shape[-2] + 1``.
    """
    P = np.asarray(control_points, dtype=np.float64)
    if P.ndim < 2:
        raise ValueError(
            f"control_points must have shape (..., degree - 1, dim); got shape {P.shape}"
        )
    d = P.shape[-2] + 1 if degree is None else check_degree(degree)
    if P.shape[-2] != d - 1:
        raise ValueError(
            f"control_points has {P.shape[-2]} interior points but degree {d} needs {d - 1}"
        )
    t = np.asarray(t, dtype=np.float64)
    if t.ndim != 1:
        raise ValueError(f"t must be a 1-D grid; got shape {t.shape}")
    B = bernstein_interior(t, d)  # (n, d-1)
    return np.matmul(B, P)  # (n, k) @ (..., k, c) -> (..., n, c)


def fit_operator(t: ArrayLike, degree: int) -> FloatArray:
    """The shared least-squares operator ``pinv(B)`` of shape ``(d - 1, n)`` for grid ``t``.

    Only interior samples carry information (both ``B`` and the curves vanish at the
    ends), so including the end samples does not change the fit. Raises ``ValueError``
    when the grid has fewer distinct interior points than free control points.
    """
    d = check_degree(degree)
    t = np.asarray(t, dtype=np.float64)
    if t.ndim != 1:
        raise ValueError(f"t must be a 1-D grid; got shape {t.shape}")
    B = bernstein_interior(t, d)
    # pinv(B) = V diag(1/s) U^T from one thin SVD, which also gives the rank.
    U, sv, Vt = np.linalg.svd(B, full_matrices=False)
    tol = sv.max(initial=0.0) * max(B.shape) * np.finfo(np.float64).eps
    if d > 1 and np.count_nonzero(sv > tol) < d - 1:
        raise ValueError(
            f"degree {d} needs at least {d - 1} distinct interior time points; the grid has "
            f"{np.unique(t[(t > 0) & (t < 1)]).size}"
        )
    return (Vt.T / sv) @ U.T


def fit(curves: ArrayLike, t: ArrayLike, degree: int) -> FloatArray:
    """Least-squares interior control points of every curve at once.

    Minimises ``SS_l = sum_i |Z_l(t_i) - C(t_i; P_l)|^2`` for each curve ``l``; the
    solution is ``P_l = pinv(B) Z_l`` with one shared ``pinv(B)``. ``curves`` has shape
    ``(..., n, dim)`` sampled on the 1-D grid ``t`` of length ``n``; returns
    ``(..., d - 1, dim)``.
    """
    Z = np.asarray(curves, dtype=np.float64)
    t = np.asarray(t, dtype=np.float64)
    if Z.ndim < 2 or Z.shape[-2] != t.shape[0]:
        raise ValueError(
            f"curves must have shape (..., {t.shape[0]}, dim) to match t; got shape {Z.shape}"
        )
    if not np.all(np.isfinite(Z)):
        raise ValueError("curves contains NaN or infinite values")
    op = fit_operator(t, degree)
    return np.matmul(op, Z)  # (k, n) @ (..., n, c) -> (..., k, c)
