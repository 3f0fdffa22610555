"""Error criteria between a reference and a predicted position trajectory.

All functions take ``truth`` and ``pred`` of shape ``(..., K, D)`` sampled on the same
``K`` instants (the benchmark uses a common normalised-time grid) and return ``(...,)``.

* :func:`max_error`: ``max_k |y_k - yhat_k|`` (Euclidean); the papers' per-trajectory
  criterion (Faraway & Choe; Lippi et al. report it through the median over
  trajectories).
* :func:`rmse`: ``sqrt(mean_k |y_k - yhat_k|^2)``.
* :func:`dtw_distance`: dynamic time warping with Euclidean local cost,
  ``C(i, j) = |y_i - yhat_j| + min(C(i-1, j), C(i, j-1), C(i-1, j-1))``, ``C(0, 0) =
  |y_0 - yhat_0|``; returns ``C(K-1, K-1)`` (a sum over the warping path, so it grows
  with ``K``: compare only on the same grid).
* :func:`swept_error_area`: the swept error area of Khansari-Zadeh & Billard (2014),
  ``sum_k area(quadrilateral y_k, y_{k+1}, yhat_{k+1}, yhat_k)``. Each quadrilateral is
  split along its diagonal ``y_k - yhat_{k+1}`` into two triangles whose areas
  ``|a||b| sin / 2 = sqrt(|a|^2 |b|^2 - (a.b)^2) / 2`` (Gram determinant) are added;
  this is the exact planar area for convex quadrilaterals in 2-D and, in 3-D, the area of
  that two-triangle surface between the curves.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from motion_envs._typing import FloatArray

__all__ = ["CRITERIA", "dtw_distance", "max_error", "rmse", "swept_error_area"]


def _pair(truth: ArrayLike, pred: ArrayLike) -> tuple[FloatArray, FloatArray]:
    y = np.asarray(truth, dtype=np.float64)
    p = np.asarray(pred, dtype=np.float64)
    if y.ndim < 2 or y.shape != p.shape:
        raise ValueError(
            f"truth and pred must both be (..., K, D) of the same shape; got {y.shape}, {p.shape}"
        )
    if y.shape[-2] < 2:
        raise ValueError(f"need at least 2 samples; got {y.shape[-2]}")
    if not (np.all(np.isfinite(y)) and np.all(np.isfinite(p))):
        raise ValueError("truth or pred contains NaN or infinite values")
    return y, p


def max_error(truth: ArrayLike, pred: ArrayLike) -> FloatArray:
    """``max_k |y_k - yhat_k|``."""
    y, p = _pair(truth, pred)
    return np.max(np.linalg.norm(y - p, axis=-1), axis=-1)


def rmse(truth: ArrayLike, pred: ArrayLike) -> FloatArray:
    """``sqrt(mean_k |y_k - yhat_k|^2)``."""
    y, p = _pair(truth, pred)
    return np.sqrt(np.mean(np.sum((y - p) ** 2, axis=-1), axis=-1))


def dtw_distance(truth: ArrayLike, pred: ArrayLike) -> FloatArray:
    """DTW accumulated Euclidean cost (batched; one anti-diagonal per numpy step)."""
    y, p = _pair(truth, pred)
    batch = y.shape[:-2]
    k = y.shape[-2]
    cost = np.linalg.norm(y[..., :, None, :] - p[..., None, :, :], axis=-1)  # (..., K, K)
    cost = cost.reshape(-1, k, k)
    acc = np.full((cost.shape[0], k + 1, k + 1), np.inf)
    acc[:, 0, 0] = 0.0
    for s in range(2, 2 * k + 1):  # s = i + j over the padded (1-based) indices
        i = np.arange(max(1, s - k), min(k, s - 1) + 1)
        j = s - i
        best = np.minimum(np.minimum(acc[:, i - 1, j], acc[:, i, j - 1]), acc[:, i - 1, j - 1])
        acc[:, i, j] = cost[:, i - 1, j - 1] + best
    return acc[:, k, k].reshape(batch)


def _triangle_area(a: FloatArray, b: FloatArray) -> FloatArray:
    aa = np.sum(a * a, axis=-1)
    bb = np.sum(b * b, axis=-1)
    ab = np.sum(a * b, axis=-1)
    return 0.5 * np.sqrt(np.maximum(aa * bb - ab * ab, 0.0))


def swept_error_area(truth: ArrayLike, pred: ArrayLike) -> FloatArray:
    """Swept error area: sum of the quadrilaterals between consecutive sample pairs."""
    y, p = _pair(truth, pred)
    y0, y1, p0, p1 = y[..., :-1, :], y[..., 1:, :], p[..., :-1, :], p[..., 1:, :]
    area = _triangle_area(y1 - y0, p1 - y0) + _triangle_area(p1 - y0, p0 - y0)
    return np.sum(area, axis=-1)


#: Criterion name -> function, in the order the benchmark reports them.
CRITERIA = {
    "max_error": max_error,
    "rmse": rmse,
    "dtw": dtw_distance,
    "swept_area": swept_error_area,
}
