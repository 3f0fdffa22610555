"""A speed-profile model: ``alpha(tau)`` predicted from conditions known before the movement.

The cumulative rotation fraction ``alpha(tau)`` of a trajectory (0 at ``tau = 0``, 1 at
``tau = 1``, non-decreasing; :func:`motion_envs.models.speed_profile.speed_fractions_on_grid`)
is unknown before the movement. The paper's "average" profile predicts the same mean
curve for everyone; this model lets it depend on pre-movement conditions ``x`` (by
default the log duration and the start-to-goal rotation angle).

Monotone parametrisation: the ``n - 1`` increments of ``alpha`` on the grid are a
softmax of logits ``z``::

    alpha_0 = 0,  alpha_k = sum_{j<=k} softmax(z)_j   (k = 1 .. n-1)

so every prediction is strictly increasing, starts at exactly 0 and ends at 1 (the last
value is set to 1.0 to remove rounding). Training targets are the centred log
increments ``z_l = log(max(diff alpha_l, floor)) - mean(...)`` of each curve (the
softmax is invariant to the centring); ``z`` is a ridge regression on standardised
conditions::

    z(x) = z_bar + B^T (x - mu) / sd,   B = argmin |Z - z_bar - X_std B|^2 + lam |B|^2

where ``z_bar`` is chosen so that ``softmax(z_bar)`` is the *mean* increment of the
training curves: with ``B = 0`` (or ``x`` at the training mean) the model predicts the
paper's average speed profile exactly. The penalty ``lam`` is chosen among ``lambdas``
by leave-one-out cross-validation on the training curves alone (the closed form of
the ridge hat matrix), or by the caller.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from motion_envs._typing import FloatArray
from motion_envs.models._sklearn import negative_criterion
from motion_envs.models.estimator import check_is_fitted
from motion_envs.models.serialization import SerializableModel, State

__all__ = ["DEFAULT_LAMBDAS", "SpeedProfileModel", "timing_features"]

#: Ridge penalties tried by leave-one-out cross-validation (standardised features).
DEFAULT_LAMBDAS: tuple[float, ...] = (0.1, 1.0, 10.0, 100.0, 1000.0, 1e4)
_INCREMENT_FLOOR = 1e-4


def timing_features(durations: ArrayLike, angles: ArrayLike) -> FloatArray:
    """Default conditions ``(L, 2)``: ``log(duration)`` and the rotation angle (radians)."""
    d = np.asarray(durations, dtype=np.float64)
    a = np.asarray(angles, dtype=np.float64)
    if d.shape != a.shape or d.ndim != 1:
        raise ValueError(f"durations and angles must be (L,) each; got {d.shape} and {a.shape}")
    if np.any(~np.isfinite(d) | (d <= 0)):
        raise ValueError("durations must be finite and > 0")
    return np.stack([np.log(d), a], axis=1)


def _softmax_cumsum(z: FloatArray) -> FloatArray:
    z = z - z.max(axis=-1, keepdims=True)
    e = np.exp(z)
    inc = e / e.sum(axis=-1, keepdims=True)
    out = np.concatenate([np.zeros((*z.shape[:-1], 1)), np.cumsum(inc, axis=-1)], axis=-1)
    out[..., -1] = 1.0
    return out


class SpeedProfileModel(SerializableModel):
    """Ridge regression of the speed profile on pre-movement conditions (monotone, pinned).

    Parameters
    ----------
    lam:
        Ridge penalty, or ``None`` to choose it among ``lambdas`` by leave-one-out
        cross-validation on the training curves (squared error of ``alpha``).
    lambdas:
        Candidates for ``lam=None``.

    Fitted attributes: ``intercept_`` ``(n - 1,)`` logits, ``coef_`` ``(p, n - 1)``,
    ``mean_``/``scale_`` ``(p,)`` feature standardisation, ``lam_``, ``n_points_``.
    """

    def __init__(self, lam: float | None = None, lambdas: Sequence[float] = DEFAULT_LAMBDAS):
        if lam is not None and not (np.isfinite(lam) and lam >= 0):
            raise ValueError(f"lam must be a finite number >= 0 or None; got {lam!r}")
        if len(lambdas) == 0 or any(not (np.isfinite(v) and v >= 0) for v in lambdas):
            raise ValueError(f"lambdas must be finite numbers >= 0; got {lambdas!r}")
        self.lam = lam
        self.lambdas = lambdas

    @staticmethod
    def _check(features: ArrayLike, alpha: ArrayLike | None = None) -> tuple[FloatArray, Any]:
        X = np.asarray(features, dtype=np.float64)
        if X.ndim == 1:
            X = X[:, None]
        if X.ndim != 2 or not np.all(np.isfinite(X)):
            raise ValueError(f"features must be a finite (L, p) array; got shape {X.shape}")
        if alpha is None:
            return X, None
        A = np.asarray(alpha, dtype=np.float64)
        if A.ndim != 2 or A.shape[0] != X.shape[0] or A.shape[1] < 3:
            raise ValueError(f"alpha must have shape ({X.shape[0]}, n >= 3); got {A.shape}")
        if not np.all(np.isfinite(A)):
            raise ValueError("alpha contains NaN or infinite values")
        return X, A

    def fit(self, features: ArrayLike, alpha: ArrayLike) -> SpeedProfileModel:
        """Fit to conditions ``(L, p)`` and observed ``alpha`` curves ``(L, n)``; returns self."""
        if alpha is None:
            raise ValueError(
                "SpeedProfileModel requires y to be passed, but the target y is None "
                "(y: the alpha curves)"
            )
        X, A = self._check(features, alpha)
        inc = np.maximum(np.diff(A, axis=1), _INCREMENT_FLOOR)
        inc = inc / inc.sum(axis=1, keepdims=True)
        Z = np.log(inc)
        Z -= Z.mean(axis=1, keepdims=True)
        self.mean_ = X.mean(axis=0)
        sd = X.std(axis=0)
        self.scale_ = np.where(sd > 0, sd, 1.0)
        Xs = (X - self.mean_) / self.scale_
        Zc = Z - Z.mean(axis=0)
        # the logits whose softmax is the mean increment: the average profile at x = mean
        self.intercept_ = np.log(np.maximum(np.diff(A, axis=1).mean(axis=0), _INCREMENT_FLOOR))
        lam = self.lam if self.lam is not None else self._select(Xs, Zc, A, self.intercept_)
        p = Xs.shape[1]
        self.coef_ = np.linalg.solve(Xs.T @ Xs + lam * np.eye(p), Xs.T @ Zc)
        self.lam_ = float(lam)
        self.n_points_ = int(A.shape[1])
        return self

    def _select(self, Xs: FloatArray, Zc: FloatArray, A: FloatArray, zbar: FloatArray) -> float:
        """Penalty with the least leave-one-out squared error of ``alpha`` (training only)."""
        best, best_err = self.lambdas[0], np.inf
        p = Xs.shape[1]
        for lam in self.lambdas:
            H = Xs @ np.linalg.solve(Xs.T @ Xs + lam * np.eye(p), Xs.T)
            fitted = H @ Zc
            h = np.clip(np.diag(H), None, 1.0 - 1e-9)
            loo = Zc - (Zc - fitted) / (1.0 - h)[:, None]
            err = float(np.mean((_softmax_cumsum(zbar + loo) - A) ** 2))
            if err < best_err:
                best, best_err = lam, err
        return best

    def predict(self, features: ArrayLike) -> FloatArray:
        """Predicted ``alpha`` curves ``(L, n_points)``: strictly increasing, 0 to 1."""
        check_is_fitted(self, "coef_")
        X, _ = self._check(features)
        if X.shape[1] != self.mean_.size:
            raise ValueError(f"features must have {self.mean_.size} columns; got {X.shape[1]}")
        Xs = (X - self.mean_) / self.scale_
        return _softmax_cumsum(self.intercept_ + Xs @ self.coef_)

    def score(self, X: ArrayLike, y: ArrayLike) -> float:
        """``-median_l max_tau |alpha_l(tau) - alphahat_l(tau)|``: the papers' criterion
        (median over movements of the largest error over time) of the predicted speed
        profiles, negated so that greater is better. ``X`` the conditions ``(L, p)``,
        ``y`` the observed ``alpha`` curves ``(L, n_points)``."""
        _, A = self._check(X, y)
        errors = np.max(np.abs(self.predict(X) - A), axis=1)
        return negative_criterion(errors)

    def _get_state(self) -> State:
        return (
            {"lam": self.lam, "lambdas": [float(v) for v in self.lambdas]},
            {
                "intercept_": self.intercept_,
                "coef_": self.coef_,
                "mean_": self.mean_,
                "scale_": self.scale_,
            },
            {"lam_": self.lam_, "n_points_": self.n_points_},
        )

    def _set_state(self, arrays: dict[str, NDArray[Any]], attributes: dict[str, Any]) -> None:
        for key in ("intercept_", "coef_", "mean_", "scale_"):
            setattr(self, key, arrays[key])
        self.lam_ = float(attributes["lam_"])
        self.n_points_ = int(attributes["n_points_"])
