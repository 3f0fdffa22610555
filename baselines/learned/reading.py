"""What the learned rows of ``motion-bench orientation`` and the learned columns of
``motion-bench position`` share in their readings: the ratio of medians with a bootstrap
interval over groups (subjects, shapes), its printed line, and the per-group bar plot."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from motion_envs._io import save_figure

__all__ = ["bootstrap_ratio", "format_comparison", "plot_ratios"]

FloatArray = NDArray[np.float64]


def bootstrap_ratio(
    errors_a: FloatArray,
    errors_b: FloatArray,
    groups: NDArray[Any],
    n_boot: int = 2000,
    seed: int = 0,
) -> tuple[float, float, float]:
    """Ratio ``median(a) / median(b)`` and its 95% percentile interval over groups.

    Groups (subjects, shapes) are resampled with replacement (``numpy`` generator
    seeded with ``seed``); each replicate pools the trajectories of the drawn groups.
    """
    groups = np.asarray(groups).astype(str)
    levels = np.unique(groups)
    members = [np.flatnonzero(groups == g) for g in levels]
    rng = np.random.default_rng(seed)
    ratios = np.empty(n_boot)
    for i in range(n_boot):
        idx = np.concatenate([members[j] for j in rng.integers(0, levels.size, levels.size)])
        ratios[i] = np.median(errors_a[idx]) / np.median(errors_b[idx])
    point = float(np.median(errors_a) / np.median(errors_b))
    lo, hi = np.percentile(ratios, [2.5, 97.5])
    return point, float(lo), float(hi)


def format_comparison(c: dict[str, Any], group: str, widths: tuple[int, int]) -> str:
    """One line of a reading: ``learned / best analytic = ratio (CI); better on k/n``,
    with the target's verdict where the comparison has one; ``group`` names what the
    ratio is taken over (``"subjects"``, ``"shapes"``)."""
    target = (
        f"; target <= {c['target_ratio']:.2f}: {'MET' if c['met'] else 'MISSED'}"
        if c["target_ratio"] is not None
        else ""
    )
    return (
        f"  {c['learned']:<{widths[0]}} / {c['best_analytic']:<{widths[1]}} = {c['ratio']:.3f} "
        f"(95% CI over {group} {c['ratio_ci95'][0]:.3f}-{c['ratio_ci95'][1]:.3f}); "
        f"better on {c['subjects_better']}/{c['n_subjects']} {group}{target}"
    )


def plot_ratios(
    comparisons: list[dict[str, Any]], path: str | Path, title: str, group: str = "subject"
) -> Path:
    """Bar plot of the per-group ratio learned / best analytic (one panel per comparison).

    Written atomically to ``path`` (:func:`motion_envs._io.save_figure`); returns it.
    """
    from matplotlib.figure import Figure

    n = len(comparisons)
    cols = min(2, n)
    rows = -(-n // cols)
    fig = Figure(figsize=(5.5 * cols, 3.4 * rows), constrained_layout=True)
    axes = fig.subplots(rows, cols, squeeze=False)
    for ax in axes.ravel()[n:]:
        ax.axis("off")
    for ax, c in zip(axes.ravel(), comparisons, strict=False):
        names = list(c["per_group_ratio"])
        vals = np.array([c["per_group_ratio"][k] for k in names])
        ax.bar(range(len(names)), vals, color=np.where(vals < 1, "C2", "C3"))
        ax.axhline(1.0, color="k", lw=0.8)
        if c.get("target_ratio"):
            ax.axhline(c["target_ratio"], color="C0", lw=0.8, ls="--", label="target")
            ax.legend(fontsize=7)
        ax.set_xticks(range(len(names)))
        ax.set_xticklabels(names, rotation=90, fontsize=6)
        ax.set_xlabel(group)
        ax.set_ylabel("median max error ratio")
        ax.set_title(f"{c['learned']} /\n{c['best_analytic']}: {c['ratio']:.3f}", fontsize=8)
    fig.suptitle(title, fontsize=9)
    return save_figure(fig, path, dpi=100)
