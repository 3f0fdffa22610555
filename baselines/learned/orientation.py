"""Features, targets and the ridge regressor of the learned orientation rows.

Pre-movement conditions of a reach (feature encoding, in this order):

* ``qs_w, qs_x, qs_y, qs_z``: start orientation, sign chosen so that ``w >= 0``;
* ``qe_w .. qe_z``: goal orientation, sign-continuous with the start;
* ``rel_x, rel_y, rel_z``: relative rotation ``logmap(conj(q_s) q_e)`` in the start frame;
* ``log_duration``: ``log`` of the clock duration (known before the movement in a paced
  task; the paper's data and vr-kitchen record it);
* ``angle``: start-to-goal angle (radians);
* ``task=<label>``: one-hot task (the target reached for), levels from the training data.

No subject encoding: the rows hold whole subjects out.

Targets: the residual curve in the path frame (:mod:`motion_envs.models.path_frame`),
as ``K`` sine coefficients per coordinate, ``p(tau) = sum_k c_k sin(k pi tau)``
(least squares on the grid): every predicted curve is exactly zero at both ends.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from motion_envs._typing import FloatArray
from motion_envs.geometry import quaternion as quat

__all__ = [
    "DEFAULT_N_SINES",
    "RIDGE_ALPHAS",
    "feature_names",
    "orientation_features",
    "ridge_nested",
    "sine_basis",
    "sine_curves",
    "sine_targets",
]

#: Sine terms per coordinate of the residual targets.
DEFAULT_N_SINES = 8
#: Ridge penalties searched by the inner folds (features standardised).
RIDGE_ALPHAS: tuple[float, ...] = (0.1, 1.0, 10.0, 100.0, 1000.0, 1e4)


def feature_names(task_levels: Sequence[str]) -> list[str]:
    """Names of the columns of :func:`orientation_features`."""
    base = [f"qs_{c}" for c in "wxyz"] + [f"qe_{c}" for c in "wxyz"]
    base += ["rel_x", "rel_y", "rel_z", "log_duration", "angle"]
    return base + [f"task={t}" for t in task_levels]


def orientation_features(
    starts: ArrayLike,
    ends: ArrayLike,
    durations: ArrayLike,
    tasks: ArrayLike,
    task_levels: Sequence[str],
) -> FloatArray:
    """Condition matrix ``(L, 13 + n_tasks)`` (encoding in the module docstring).

    A task not among ``task_levels`` gets an all-zero one-hot block.
    """
    qs = quat.as_unit(starts, name="starts")
    qe = quat.as_unit(ends, name="ends")
    sign = np.where(qs[:, :1] < 0, -1.0, 1.0)
    qs = qs * sign
    qe = qe * np.where(np.einsum("li,li->l", qs, qe)[:, None] < 0, -1.0, 1.0)
    rel = quat.logmap(quat.multiply(quat.conjugate(qs), qe), validate=False)
    d = np.asarray(durations, dtype=np.float64)
    if np.any(~np.isfinite(d) | (d <= 0)):
        raise ValueError("durations must be finite and > 0")
    t = np.asarray(tasks).astype(str)
    levels = np.asarray(list(task_levels), dtype=str)
    onehot = (t[:, None] == levels[None, :]).astype(np.float64)
    angle = np.linalg.norm(rel, axis=1)
    return np.column_stack([qs, qe, rel, np.log(d), angle, onehot])


def sine_basis(n_points: int, n_sines: int) -> FloatArray:
    """``(n_points, n_sines)`` columns ``sin(k pi tau)`` on the uniform grid."""
    tau = np.linspace(0.0, 1.0, n_points)
    return np.sin(np.pi * tau[:, None] * np.arange(1, n_sines + 1))


def sine_targets(curves: ArrayLike, n_sines: int = DEFAULT_N_SINES) -> FloatArray:
    """Least-squares sine coefficients of curves ``(L, n, 3)`` -> ``(L, 3 n_sines)``."""
    C = np.asarray(curves, dtype=np.float64)
    basis = sine_basis(C.shape[1], n_sines)
    coef = np.linalg.lstsq(basis, C.transpose(1, 0, 2).reshape(C.shape[1], -1), rcond=None)[0]
    out = coef.reshape(n_sines, C.shape[0], 3).transpose(1, 0, 2).reshape(C.shape[0], -1)
    return np.asarray(out, dtype=np.float64)


def sine_curves(coefficients: ArrayLike, n_points: int) -> FloatArray:
    """Curves ``(L, n_points, 3)`` from coefficients ``(L, 3 K)`` (zero at both ends)."""
    c = np.asarray(coefficients, dtype=np.float64)
    K = c.shape[1] // 3
    out = np.einsum("tk,lkc->ltc", sine_basis(n_points, K), c.reshape(-1, K, 3))
    out[:, 0] = 0.0
    out[:, -1] = 0.0
    curves: FloatArray = out
    return curves


def ridge_nested(
    X: FloatArray,
    Y: FloatArray,
    groups: NDArray[Any],
    folds: Sequence[tuple[NDArray[np.int64], NDArray[np.int64]]],
    alphas: Sequence[float] = RIDGE_ALPHAS,
    inner_splits: int = 4,
) -> tuple[FloatArray, list[dict[str, Any]]]:
    """Ridge (standardised features) with ``alpha`` chosen by inner group folds per outer fold.

    ``Y`` is ``(N, m)`` or ``(n_folds, N, m)`` (targets per outer fold). Returns the
    ``(N, m)`` predictions of every fold's scored rows (NaN elsewhere) and the chosen
    ``alpha`` of each fold. The inner folds come from
    :func:`baselines.learned.nested.inner_folds` on the outer training rows only.
    """
    from sklearn.linear_model import Ridge
    from sklearn.model_selection import GridSearchCV
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import StandardScaler

    from baselines.learned.nested import inner_folds

    pred = np.full((X.shape[0], Y.shape[-1]), np.nan)
    chosen = []
    for o, (train, scored) in enumerate(folds):
        Yo = Y[o] if Y.ndim == 3 else Y
        local = np.arange(X.shape[0])
        position = np.empty(X.shape[0], dtype=np.int64)
        position[train] = np.arange(train.size)
        cv = [
            (position[a], position[b]) for a, b in inner_folds(local[train], groups, inner_splits)
        ]
        search = GridSearchCV(
            make_pipeline(StandardScaler(), Ridge()),
            {"ridge__alpha": list(alphas)},
            cv=cv,
            scoring="neg_mean_squared_error",
        )
        search.fit(X[train], Yo[train])
        pred[scored] = search.predict(X[scored])
        chosen.append({"alpha": float(search.best_params_["ridge__alpha"])})
    return pred, chosen
