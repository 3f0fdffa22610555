"""Across seeds and sweeps: interquartile mean, its interval, probability of improvement.

Thin wrappers of ``rliable`` (Agarwal et al., 2021, "Deep RL at the edge of the
statistical precipice"): scores are ``(n_runs, n_tasks)`` matrices (runs = seeds,
tasks = people, shapes or environments). rliable assumes higher is better; our criteria
are errors, so the probability of improvement is computed on negated scores (the IQM
does not depend on the sign). The interval of the IQM is rliable's scheme, a stratified
bootstrap (runs resampled within each task, percentile, 95 %, seeded), drawn by
:func:`baselines.stats.group_bootstrap`: ``rliable.library`` needs ``arch < 8``, whose
7.x releases do not import under pandas 3, so only ``rliable.metrics`` (numpy and scipy)
is used.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["iqm_intervals", "probability_of_improvement"]


def _matrix(scores: ArrayLike, name: str) -> NDArray[np.float64]:
    m = np.asarray(scores, dtype=np.float64)
    if m.ndim == 1:
        m = m[:, None]
    if m.ndim != 2 or m.size == 0 or not np.all(np.isfinite(m)):
        raise ValueError(f"{name} must be a finite (n_runs, n_tasks) array; got {m.shape}")
    return m


def iqm_intervals(
    scores: Mapping[str, ArrayLike], reps: int = 2000, seed: int = 0
) -> dict[str, dict[str, Any]]:
    """Per method: ``{"iqm": value, "ci95": [low, high]}`` of its ``(n_runs, n_tasks)``
    scores (rliable's ``aggregate_iqm``; runs resampled within each task)."""
    from rliable import metrics

    from baselines.stats._intervals import group_bootstrap

    out: dict[str, dict[str, Any]] = {}
    for name, value in scores.items():
        m = _matrix(value, name)
        flat = m.ravel()  # row-major: cell (run, task) -> run * n_tasks + task
        tasks = np.tile(np.arange(m.shape[1]), m.shape[0])

        def iqm(rows: NDArray[np.int64], f: NDArray[np.float64] = flat) -> float:
            return float(metrics.aggregate_iqm(f[rows]))

        point, lo, hi = group_bootstrap(
            iqm, np.arange(flat.size), strata=tasks, n_resamples=reps, seed=seed
        )
        out[name] = {"iqm": point, "ci95": [lo, hi]}
    return out


def probability_of_improvement(
    scores_a: ArrayLike, scores_b: ArrayLike, lower_is_better: bool = True
) -> float:
    """P(a run of A scores better than a run of B), averaged over tasks (rliable's
    Mann-Whitney form; ties count one half)."""
    from rliable import metrics

    a, b = _matrix(scores_a, "scores_a"), _matrix(scores_b, "scores_b")
    if a.shape[1] != b.shape[1]:
        raise ValueError(f"scores_a and scores_b need the same tasks; got {a.shape}, {b.shape}")
    sign = -1.0 if lower_is_better else 1.0
    return float(metrics.probability_of_improvement(sign * a, sign * b))
