"""The sine-series trajectory representation of Lippi, Avizzano & Ruffaldi (2011).

One phase ``Y(t)``, ``0 <= t <= T``, of any number ``D`` of coordinates is written on
normalised time ``tau = t / T`` as ``Y(tau) = Phi(tau) . P`` with the basis (eq. 2)::

    Phi(tau) = [1, tau, sin(pi tau), sin(2 pi tau), ..., sin(N pi tau)]      (N + 2,)

and coefficients ``P`` of shape ``(N + 2, D)`` (one column per coordinate; coordinates are
independent). The first two rows are exact, not fitted::

    P[0] = Y(0),   P[1] = Y(1) - Y(0)

and the sine rows ``b_1 .. b_N`` are the sine coefficients of the residual (eq. 3)::

    D(tau) = Y(tau) - Y(0) - tau (Y(1) - Y(0)),       D(0) = D(1) = 0,

extended to period 2 as an odd function, ``p(tau) = -D(2 - tau)`` on ``(1, 2]`` (the
paper's eq. 4 prints ``-D(1 - tau)``, a typo: only ``-D(2 - tau)`` is odd about 0 and 1).
On ``M + 1`` uniform samples ``tau_k = k / M`` these are a type-I discrete sine transform
of the interior residuals::

    b_n = (2 / M) sum_{k=1}^{M-1} D(tau_k) sin(n pi k / M) = scipy.fft.dst(D[1:-1], type=1)[n-1] / M

Because the sine columns are orthogonal on the uniform interior grid
(``sum_k sin(n pi k/M) sin(m pi k/M) = (M/2) delta_nm`` for ``1 <= n, m <= M-1``) the
first ``N <= M - 1`` DST coefficients are also the least-squares fit of ``D`` by ``N``
sines; on non-uniform samples only the least-squares form applies.

Arrays carry leading batch axes: ``tau`` is ``(..., K)``, positions ``(..., K, D)``,
coefficients ``(..., N + 2, D)``.
"""

from __future__ import annotations

import numpy as np
import scipy.fft
from numpy.typing import ArrayLike

from motion_envs._typing import FloatArray

__all__ = [
    "acceleration",
    "basis",
    "basis_derivative",
    "basis_second_derivative",
    "dst_coefficients",
    "evaluate",
    "fit_coefficients",
    "is_uniform",
    "lstsq_coefficients",
    "normalised_time",
    "residual",
    "velocity",
]


def _check_n_sines(n_sines: int) -> int:
    if isinstance(n_sines, bool) or not isinstance(n_sines, (int, np.integer)) or n_sines < 0:
        raise ValueError(f"n_sines must be a non-negative integer; got {n_sines!r}")
    return int(n_sines)


def _as_tau(tau: ArrayLike) -> FloatArray:
    tau = np.asarray(tau, dtype=np.float64)
    if not np.all(np.isfinite(tau)):
        raise ValueError("tau contains NaN or infinite values")
    return tau


def basis(tau: ArrayLike, n_sines: int) -> FloatArray:
    """``Phi(tau) = [1, tau, sin(pi tau), ..., sin(N pi tau)]``, shape ``tau.shape + (N + 2,)``."""
    n_sines = _check_n_sines(n_sines)
    tau = _as_tau(tau)
    n = np.arange(1, n_sines + 1, dtype=np.float64)
    return np.concatenate(
        [np.ones((*tau.shape, 1)), tau[..., None], np.sin(np.pi * tau[..., None] * n)], axis=-1
    )


def basis_derivative(tau: ArrayLike, n_sines: int) -> FloatArray:
    """``dPhi/dtau = [0, 1, pi cos(pi tau), ..., N pi cos(N pi tau)]``, shape ``(..., N + 2)``."""
    n_sines = _check_n_sines(n_sines)
    tau = _as_tau(tau)
    n = np.arange(1, n_sines + 1, dtype=np.float64)
    return np.concatenate(
        [
            np.zeros((*tau.shape, 1)),
            np.ones((*tau.shape, 1)),
            np.pi * n * np.cos(np.pi * tau[..., None] * n),
        ],
        axis=-1,
    )


def basis_second_derivative(tau: ArrayLike, n_sines: int) -> FloatArray:
    """``d2Phi/dtau2 = [0, 0, -pi^2 sin(pi tau), ..., -(N pi)^2 sin(N pi tau)]``."""
    n_sines = _check_n_sines(n_sines)
    tau = _as_tau(tau)
    n = np.arange(1, n_sines + 1, dtype=np.float64)
    return np.concatenate(
        [np.zeros((*tau.shape, 2)), -((np.pi * n) ** 2) * np.sin(np.pi * tau[..., None] * n)],
        axis=-1,
    )


def _check_coefficients(coefficients: ArrayLike) -> FloatArray:
    p = np.asarray(coefficients, dtype=np.float64)
    if p.ndim < 2 or p.shape[-2] < 2:
        raise ValueError(f"coefficients must be (..., N + 2, D) with N >= 0; got {p.shape}")
    return p


def _check_positive(duration: ArrayLike) -> FloatArray:
    d = np.asarray(duration, dtype=np.float64)
    if np.any(~np.isfinite(d)) or np.any(d <= 0):
        raise ValueError(f"duration must be finite and > 0; got {d}")
    return d


def _per_time(values: FloatArray, tau: FloatArray, duration: FloatArray, power: int) -> FloatArray:
    """``values / T**power`` with ``T`` broadcast against the batch axes of ``values``."""
    scale = duration**power
    return values / (scale[..., None] if tau.ndim == 0 else scale[..., None, None])


def evaluate(coefficients: ArrayLike, tau: ArrayLike) -> FloatArray:
    """Positions ``Y(tau) = Phi(tau) . P``.

    Shape rule (shared by :func:`evaluate`, :func:`velocity` and :func:`acceleration`):
    ``coefficients`` is ``(..., N + 2, D)``; a scalar ``tau`` gives ``(..., D)``, an array
    ``tau`` of shape ``(K,)`` (or ``(..., K)``, broadcast against the batch axes) gives
    ``(..., K, D)``.
    """
    p = _check_coefficients(coefficients)
    return basis(tau, p.shape[-2] - 2) @ p


def velocity(coefficients: ArrayLike, tau: ArrayLike, duration: ArrayLike = 1.0) -> FloatArray:
    """Velocities ``dY/dt = dPhi/dtau(tau) . P / T`` (``T`` = ``duration``).

    Same shape rule as :func:`evaluate`: scalar ``tau`` -> ``(..., D)``, ``(K,)`` ->
    ``(..., K, D)``; ``duration`` is a scalar or one per batch entry.
    """
    p = _check_coefficients(coefficients)
    d = _check_positive(duration)
    t = _as_tau(tau)
    return _per_time(basis_derivative(t, p.shape[-2] - 2) @ p, t, d, 1)


def acceleration(coefficients: ArrayLike, tau: ArrayLike, duration: ArrayLike = 1.0) -> FloatArray:
    """Accelerations ``d2Y/dt2 = d2Phi/dtau2(tau) . P / T**2``, shapes as :func:`evaluate`."""
    p = _check_coefficients(coefficients)
    d = _check_positive(duration)
    t = _as_tau(tau)
    return _per_time(basis_second_derivative(t, p.shape[-2] - 2) @ p, t, d, 2)


def normalised_time(times: ArrayLike) -> FloatArray:
    """``tau = (t - t_0) / (t_last - t_0)`` along the last axis; times must strictly increase."""
    t = np.asarray(times, dtype=np.float64)
    if t.ndim < 1 or t.shape[-1] < 2:
        raise ValueError(f"times must have at least 2 samples on the last axis; got {t.shape}")
    if not np.all(np.isfinite(t)):
        raise ValueError("times contains NaN or infinite values")
    if np.any(np.diff(t, axis=-1) <= 0):
        raise ValueError("times must be strictly increasing")
    return (t - t[..., :1]) / (t[..., -1:] - t[..., :1])


def is_uniform(tau: ArrayLike, rtol: float = 1e-9) -> bool:
    """True when the samples ``tau`` (last axis) are ``k / M``, ``k = 0 .. M``, to ``rtol``."""
    tau = _as_tau(tau)
    m = tau.shape[-1] - 1
    return m >= 1 and bool(np.allclose(tau, np.linspace(0.0, 1.0, m + 1), rtol=0, atol=rtol))


def _as_positions(positions: ArrayLike, name: str = "positions") -> FloatArray:
    y = np.asarray(positions, dtype=np.float64)
    if y.ndim < 2:
        raise ValueError(f"{name} must be (..., K, D); got shape {y.shape}")
    if not np.all(np.isfinite(y)):
        raise ValueError(f"{name} contains NaN or infinite values")
    return y


def residual(tau: ArrayLike, positions: ArrayLike) -> FloatArray:
    """``D(tau) = Y(tau) - Y(0) - tau (Y(1) - Y(0))`` (eq. 3)."""
    tau = _as_tau(tau)
    y = _as_positions(positions)
    return y - y[..., :1, :] - tau[..., :, None] * (y[..., -1:, :] - y[..., :1, :])


def dst_coefficients(positions: ArrayLike, n_sines: int) -> FloatArray:
    """Coefficients ``P`` from ``M + 1`` uniform samples ``tau_k = k / M`` by a type-I DST.

    ``positions`` is ``(..., M + 1, D)``; returns ``(..., N + 2, D)`` with
    ``P[0] = Y_0``, ``P[1] = Y_M - Y_0`` and
    ``b_n = (2/M) sum_{k=1}^{M-1} D_k sin(n pi k / M) = dst(D[1:-1], type=1)[n-1] / M``.
    Needs ``N <= M - 1``.
    """
    n_sines = _check_n_sines(n_sines)
    y = _as_positions(positions)
    m = y.shape[-2] - 1
    if m < 2:
        raise ValueError(f"positions must have at least 3 samples; got {m + 1}")
    if n_sines > m - 1:
        raise ValueError(f"n_sines must be <= M - 1 = {m - 1} for {m + 1} samples; got {n_sines}")
    tau = np.linspace(0.0, 1.0, m + 1)
    d = residual(tau, y)
    b = scipy.fft.dst(d[..., 1:-1, :], type=1, axis=-2)[..., :n_sines, :] / m
    return np.concatenate([y[..., :1, :], y[..., -1:, :] - y[..., :1, :], b], axis=-2)


def lstsq_coefficients(tau: ArrayLike, positions: ArrayLike, n_sines: int) -> FloatArray:
    """Coefficients ``P`` from samples at any ``tau`` in ``[0, 1]`` by least squares.

    ``P[0] = Y(0)``, ``P[1] = Y(1) - Y(0)`` exactly; the sines minimise
    ``sum_k |D(tau_k) - sum_n b_n sin(n pi tau_k)|^2`` via ``pinv`` of the sine columns
    (batched). ``tau`` is ``(K,)`` or ``(..., K)``, ``positions`` ``(..., K, D)``. Raises
    ``ValueError`` when the sine columns are rank-deficient on these samples (too few
    distinct interior samples for ``N`` sines).
    """
    n_sines = _check_n_sines(n_sines)
    tau = _as_tau(tau)
    y = _as_positions(positions)
    if tau.shape[-1] != y.shape[-2]:
        raise ValueError(
            f"tau and positions disagree on the number of samples: {tau.shape} vs {y.shape}"
        )
    if not (np.allclose(tau[..., 0], 0.0) and np.allclose(tau[..., -1], 1.0)):
        raise ValueError("tau must start at 0 and end at 1 (use normalised_time)")
    d = residual(tau, y)
    s = basis(tau, n_sines)[..., 2:]
    if n_sines:
        rank = np.linalg.matrix_rank(s)
        if np.any(rank < n_sines):
            raise ValueError(
                f"positions: {tau.shape[-1]} samples cannot determine {n_sines} sine "
                f"coefficients (sine design rank {np.min(rank)}); lower n_sines"
            )
    b = np.linalg.pinv(s) @ d
    return np.concatenate([y[..., :1, :], y[..., -1:, :] - y[..., :1, :], b], axis=-2)


def fit_coefficients(tau: ArrayLike, positions: ArrayLike, n_sines: int) -> FloatArray:
    """DST (:func:`dst_coefficients`) on uniform samples, least squares otherwise."""
    tau = _as_tau(tau)
    if tau.ndim == 1 and is_uniform(tau) and n_sines <= tau.shape[0] - 2:
        return dst_coefficients(positions, n_sines)
    return lstsq_coefficients(tau, positions, n_sines)
