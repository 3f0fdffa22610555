"""What the models' scikit-learn-order ``fit(X, y)`` and ``score(X, y)`` share.

``X`` holds one row per movement (its conditions, start and end, labels or predictors),
``y`` the movements themselves (one recording per row, ragged). ``score`` is the
negative of the papers' criterion, ``-median_l max_t e_l(t)``.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from motion_envs._typing import FloatArray
from motion_envs.geometry.resampling import recording_times

__all__ = ["batch_row", "check_order", "criterion_score", "negative_criterion", "score_times"]


def _looks_like_movements(X: Any) -> bool:
    """True when ``X`` is a sequence of 2-D arrays or a 3-D array: recordings, not rows."""
    if isinstance(X, np.ndarray):
        return X.ndim == 3
    if isinstance(X, (list, tuple)) and len(X) > 0:
        return bool(np.ndim(X[0]) == 2)
    return False


def _rows(X: Any) -> int | None:
    """Rows of ``X`` (a mapping of named columns: the length of a column; None: None)."""
    if X is None:
        return None
    if isinstance(X, Mapping):
        return len(next(iter(X.values()))) if len(X) else None
    return len(X)


def check_order(X: Any, y: Sequence[ArrayLike], model: str, x_what: str) -> int:
    """The number of movements, after checking that ``fit``/``score`` got ``(X, y)``.

    ``ValueError`` when ``X`` looks like the movements (the order before scikit-learn's:
    ``fit(movements, conditions)``) or ``X`` and ``y`` differ in length.
    """
    if y is None:
        raise ValueError(
            f"{model} requires y to be passed, but the target y is None (y: the movements)"
        )
    if _looks_like_movements(X):
        raise ValueError(
            f"{model}.fit(X, y) and .score(X, y) take scikit-learn's order: X {x_what}, one "
            "row per movement, and y the movements (one (n_i, D) array each); X looks like "
            "movements"
        )
    if isinstance(y, np.ndarray) and y.ndim < 2:
        raise ValueError(
            f"{model}: y must be the movements, one (n_i, D) array each; got shape {y.shape}"
        )
    n = len(y)
    if n == 0:
        raise ValueError(f"{model}: y must hold at least one movement")
    rows = _rows(X)
    if rows is not None and rows != n:
        raise ValueError(f"{model}: X has {rows} rows and y {n} movements; one row each")
    return n


def score_times(
    y: Sequence[ArrayLike], times: Sequence[ArrayLike] | None, rate: float | None
) -> list[FloatArray]:
    """Each movement's times in seconds (``times`` or ``rate``); with neither, the sample
    numbers ``0, 1, ..`` (every model predicts on ``tau = t / T``, so the criterion is
    the same for any uniform rate)."""
    if times is None and rate is None:
        return [np.arange(np.shape(v)[0], dtype=np.float64) for v in y]
    return recording_times(y, times, rate)


def negative_criterion(max_errors: Sequence[float] | FloatArray) -> float:
    """``-median_l max_t e_l(t)`` from each movement's largest error: greater is better."""
    return -float(np.median(np.asarray(max_errors, dtype=np.float64)))


def criterion_score(
    times: Sequence[FloatArray], errors: Callable[[int, FloatArray], FloatArray]
) -> float:
    """``score``'s ``-median_l max_t e_l(t)``: ``errors(l, t)`` are movement ``l``'s errors
    ``e_l`` at ``t = times[l] - times[l][0]`` (s since its first sample; ``times`` from
    :func:`score_times`)."""
    return negative_criterion([float(np.max(errors(i, t - t[0]))) for i, t in enumerate(times)])


def batch_row(values: Any, i: int) -> Any:
    """Row ``i`` of labels or predictors as a batch of one (a mapping of named columns:
    each column's row; None stays None)."""
    if values is None:
        return None
    if isinstance(values, Mapping):
        return {k: np.asarray(v)[i : i + 1] for k, v in values.items()}
    return np.asarray(values)[i : i + 1]
