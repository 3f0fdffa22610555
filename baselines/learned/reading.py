"""What the learned rows of ``motion-bench orientation`` and the learned columns of
``motion-bench position`` share in their readings: the ratio of medians with a bootstrap
interval over groups (subjects, shapes), its printed line, and the per-group bar plot."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from motion_envs._io import save_figure
from motion_envs._typing import FloatArray

__all__ = [
    "bootstrap_ratio",
    "bootstrap_ratio_power",
    "format_comparison",
    "natural_key",
    "plot_ratios",
    "ratio_figure",
    "row_words",
]


def bootstrap_ratio(
    errors_a: FloatArray,
    errors_b: FloatArray,
    groups: NDArray[Any],
    n_boot: int = 2000,
    seed: int = 0,
) -> tuple[float, float, float]:
    """``(ratio, low, high)`` of :func:`bootstrap_ratio_power`."""
    return bootstrap_ratio_power(errors_a, errors_b, groups, n_boot, seed)[:3]


def bootstrap_ratio_power(
    errors_a: FloatArray,
    errors_b: FloatArray,
    groups: NDArray[Any],
    n_boot: int = 2000,
    seed: int = 0,
) -> tuple[float, float, float, tuple[float, float]]:
    """Ratio ``median(a) / median(b)``, its 95% percentile interval over groups and the
    ratios below and above 1 it detects 80 % of the time
    (:func:`baselines.stats.detectable_ratios`, from the same replicates).

    Groups (subjects, shapes) are resampled with replacement (``numpy`` generator
    seeded with ``seed``); each replicate pools the trajectories of the drawn groups.
    """
    from baselines.stats import detectable_ratios

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
    return point, float(lo), float(hi), detectable_ratios(point, float(lo), float(hi), ratios)


def format_comparison(c: dict[str, Any], group: str, widths: tuple[int, int]) -> str:
    """One line of a reading: ``learned / best analytic = ratio (CI); better on k/n``,
    with the target's verdict where the comparison has one; ``group`` names what the
    ratio is taken over (``"subjects"``, ``"shapes"``)."""
    target = (
        f"; target <= {c['target_ratio']:.2f}: {'MET' if c['met'] else 'MISSED'}"
        if c["target_ratio"] is not None
        else ""
    )
    power = ""
    if c.get("detectable_ratios") is not None:
        below, above = c["detectable_ratios"]
        power = f"; 80 % power for ratios <= {below:.3f} or >= {above:.3f}"
    return (
        f"  {c['learned']:<{widths[0]}} / {c['best_analytic']:<{widths[1]}} = {c['ratio']:.3f} "
        f"(95% CI over {group} {c['ratio_ci95'][0]:.3f}-{c['ratio_ci95'][1]:.3f}); "
        f"better on {c['subjects_better']}/{c['n_subjects']} {group}{target}{power}"
    )


def natural_key(name: str) -> tuple[Any, ...]:
    """Sort key ordering ``"9" < "10"`` and ``"Leaf_2" < "Leaf_10"`` (digits as numbers)."""
    return tuple(
        (0, int(t), "") if t.isdigit() else (1, 0, t.lower()) for t in re.split(r"(\d+)", name) if t
    )


_TOKENS = {"mlp": "MLP", "null": "null model", "path": "in the path frame"}


def row_words(row: str) -> str:
    """A row id in words: ``mlp_loso`` -> ``MLP (leave one subject out)``,
    ``null_d2_path_loso`` -> ``null model, d = 2, in the path frame (leave one subject
    out)``."""
    text = row.replace("task_predictor", "task predictor")
    text = text.replace("predicted_timing", "with predicted timing")
    loso = False
    words: list[str] = []
    for token in text.split("_"):
        if token == "loso":
            loso = True
        elif re.fullmatch(r"d\d+", token):
            words.append(f"d = {token[1:]}")
        else:
            words.append(_TOKENS.get(token, token))
    return ", ".join(words) + (" (leave one subject out)" if loso else "")


def ratio_figure(comparisons: list[dict[str, Any]], title: str, group: str = "subject") -> Any:
    """The figure of :func:`plot_ratios`: one panel per comparison, a horizontal bar per
    group (sorted naturally, labels upright at 8 pt or more), coloured by which side is
    better (legend), the parity line and the target; titles in words."""
    from matplotlib.figure import Figure
    from matplotlib.patches import Patch

    n = len(comparisons)
    cols = min(2, n)
    rows = -(-n // cols)
    n_groups = max((len(c["per_group_ratio"]) for c in comparisons), default=1)
    height = max(3.0, 0.24 * n_groups + 1.6)
    fig = Figure(figsize=(6.0 * cols, height * rows), constrained_layout=True)
    axes = fig.subplots(rows, cols, squeeze=False)
    for ax in axes.ravel()[n:]:
        ax.axis("off")
    legend: list[Any] = []
    for ax, c in zip(axes.ravel(), comparisons, strict=False):
        names = sorted(c["per_group_ratio"], key=natural_key)
        vals = np.array([c["per_group_ratio"][k] for k in names])
        ax.barh(range(len(names)), vals, color=np.where(vals < 1, "C2", "C3"))
        ax.axvline(1.0, color="k", lw=0.8)
        handles = [
            Patch(color="C2", label="learned better (< 1)"),
            Patch(color="C3", label="analytic better (>= 1)"),
        ]
        if c.get("target_ratio"):
            handles.append(
                ax.axvline(c["target_ratio"], color="C0", lw=1.0, ls="--", label="target")
            )
        legend = max(legend, handles, key=len)
        ax.set_yticks(range(len(names)))
        ax.set_yticklabels(names, fontsize=8)
        ax.invert_yaxis()  # first group at the top
        ax.tick_params(axis="x", labelsize=8)
        ax.set_ylabel(group, fontsize=9)
        ax.set_xlabel("ratio of median max errors, learned / analytic", fontsize=9)
        lo, hi = (c.get("ratio_ci95") or [float("nan")] * 2)[:2]
        ax.set_title(
            f"{row_words(c['learned'])}\nvs {row_words(c['best_analytic'])}:\n"
            f"ratio {c['ratio']:.3f} (95 % CI {lo:.3f} to {hi:.3f})",
            fontsize=9,
        )
    # one legend below the panels: inside one, it covered the bars of the last groups
    fig.legend(handles=legend, loc="outside lower center", ncols=3, fontsize=8, frameon=False)
    fig.suptitle(title, fontsize=10)
    return fig


def plot_ratios(
    comparisons: list[dict[str, Any]], path: str | Path, title: str, group: str = "subject"
) -> Path:
    """Bar plot of the per-group ratio learned / best analytic (one panel per comparison,
    :func:`ratio_figure`). Written atomically to ``path``
    (:func:`motion_envs._io.save_figure`); returns it.
    """
    return save_figure(ratio_figure(comparisons, title, group), path, dpi=100)
