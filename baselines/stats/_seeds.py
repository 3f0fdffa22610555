"""Across seeds and sweeps: interquartile mean, its interval, probability of improvement.

The aggregate metrics of Agarwal et al. (2021, "Deep RL at the edge of the statistical
precipice"), written on scipy and numpy (the ``rliable`` package that first shipped them
was archived in 2025; ``tests/test_stats_intervals.py`` checks these functions against
its numbers on the same inputs when it is installed). Scores are ``(n_runs, n_tasks)``
matrices (runs = seeds, tasks = people, shapes or environments).

* :func:`iqm`: the interquartile mean of all runs and tasks pooled,
  :func:`scipy.stats.trim_mean` with a quarter cut at each end (``int(n / 4)`` scores,
  as rliable's ``aggregate_iqm``).
* :func:`iqm_intervals`: the IQM with its 95 % stratified bootstrap interval (runs
  resampled with replacement within each task, the tasks fixed, percentile, seeded:
  rliable's ``StratifiedBootstrap`` scheme), drawn by
  :func:`baselines.stats.group_bootstrap` with every cell a group and the task its
  stratum.
* :func:`probability_of_improvement`: per task, the Mann-Whitney form
  ``P(X better than Y) + P(X = Y) / 2`` over all pairs of a run of A and a run of B
  (:func:`scipy.stats.mannwhitneyu`'s U over ``n_a * n_b``; 0.5 where the two columns are
  identical, as rliable), averaged over tasks. Our criteria are errors: with
  ``lower_is_better`` (the default) *better* means *lower*.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["iqm", "iqm_intervals", "probability_of_improvement"]


def _matrix(scores: ArrayLike, name: str) -> NDArray[np.float64]:
    m = np.asarray(scores, dtype=np.float64)
    if m.ndim == 1:
        m = m[:, None]
    if m.ndim != 2 or m.size == 0 or not np.all(np.isfinite(m)):
        raise ValueError(f"{name} must be a finite (n_runs, n_tasks) array; got {m.shape}")
    return m


def iqm(scores: ArrayLike) -> float:
    """Interquartile mean of every score pooled (a quarter of them cut at each end)."""
    from scipy.stats import trim_mean

    flat = np.asarray(scores, dtype=np.float64).ravel()
    if flat.size == 0 or not np.all(np.isfinite(flat)):
        raise ValueError(f"scores must be finite and non-empty; got {flat.size} values")
    return float(trim_mean(flat, 0.25))


def iqm_intervals(
    scores: Mapping[str, ArrayLike], reps: int = 2000, seed: int = 0
) -> dict[str, dict[str, Any]]:
    """Per method: ``{"iqm": value, "ci95": [low, high]}`` of its ``(n_runs, n_tasks)``
    scores (runs resampled within each task; module docstring)."""
    from baselines.stats._intervals import group_bootstrap

    out: dict[str, dict[str, Any]] = {}
    for name, value in scores.items():
        m = _matrix(value, name)
        flat = m.ravel()  # row-major: cell (run, task) -> run * n_tasks + task
        tasks = np.tile(np.arange(m.shape[1]), m.shape[0])

        def of_rows(rows: NDArray[np.int64], f: NDArray[np.float64] = flat) -> float:
            return iqm(f[rows])

        point, lo, hi = group_bootstrap(
            of_rows, np.arange(flat.size), strata=tasks, n_resamples=reps, seed=seed
        )
        out[name] = {"iqm": point, "ci95": [lo, hi]}
    return out


def probability_of_improvement(
    scores_a: ArrayLike, scores_b: ArrayLike, lower_is_better: bool = True
) -> float:
    """P(a run of A scores better than a run of B), averaged over tasks (Mann-Whitney
    form; ties count one half)."""
    from scipy.stats import mannwhitneyu

    a, b = _matrix(scores_a, "scores_a"), _matrix(scores_b, "scores_b")
    if a.shape[1] != b.shape[1]:
        raise ValueError(f"scores_a and scores_b need the same tasks; got {a.shape}, {b.shape}")
    sign = -1.0 if lower_is_better else 1.0
    per_task = []
    for x, y in zip((sign * a).T, (sign * b).T, strict=True):
        if np.array_equal(x, y):
            per_task.append(0.5)
            continue
        u = mannwhitneyu(x, y, alternative="greater").statistic
        per_task.append(float(u) / (x.size * y.size))
    return float(np.mean(per_task))
