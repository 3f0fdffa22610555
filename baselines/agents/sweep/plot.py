"""``sweep.png``: the test criterion (or its ratio to the zero-action nominal's) per seed
and configuration."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from motion_envs._io import save_figure


def plot_sweep(results: Mapping[str, Any], path: Path) -> None:
    """Test criterion / nominal per seed (points) and median (bar) for each configuration."""
    import textwrap

    from baselines.plots import new_figure

    rows = results["configurations"]
    fig = new_figure(max(6.0, 2.2 * len(rows) + 1.5), 4.5)
    ax = fig.subplots()
    if any(r["test_ratio_median"] is None for r in rows):
        _plot_criteria(ax, rows, results["test_split"])
        save_figure(fig, path, dpi=120)
        return
    for i, r in enumerate(rows):
        ratios = np.asarray(r["test_criteria"]) / r["test_nominal_criterion"]
        color = "C1" if r["best_on_validation"] else "C0"
        ax.bar(i, r["test_ratio_median"], color=color, alpha=0.5, width=0.6)
        ax.scatter(np.full(ratios.size, i), ratios, color="k", s=14, zorder=3)
    ax.axhline(1.0, color="k", ls="--", lw=1, label="zero-action nominal")
    ax.set_xticks(range(len(rows)))
    ax.set_xticklabels([textwrap.fill(r["label"], 24) for r in rows], fontsize=8)
    ax.set_ylabel(f"{results['test_split']} criterion / nominal's")
    ax.set_title("median over seeds (bar), each seed (dot); orange: best on validation", fontsize=9)
    all_ratios = np.concatenate(
        [np.asarray(r["test_criteria"]) / r["test_nominal_criterion"] for r in rows]
    )
    lo, hi = float(all_ratios.min()), float(all_ratios.max())
    pad = max(0.02, 0.1 * (max(hi, 1.0) - min(lo, 1.0)))
    ax.set_ylim(min(lo, 1.0) - pad, max(hi, 1.0) + pad)
    ax.legend(loc="upper right", fontsize=8)
    save_figure(fig, path, dpi=120)


def _plot_criteria(ax: Any, rows: Sequence[Mapping[str, Any]], split: str) -> None:
    """The test criterion itself per seed and configuration, with the nominal's: where a
    nominal's criterion is 0 (the analytic juggler drops nothing) there is no ratio."""
    import textwrap

    for i, r in enumerate(rows):
        crit = np.asarray(r["test_criteria"], dtype=float)
        color = "C1" if r["best_on_validation"] else "C0"
        ax.bar(i, r["test_criterion_median"], color=color, alpha=0.5, width=0.6)
        ax.scatter(np.full(crit.size, i), crit, color="k", s=14, zorder=3)
        label = "zero-action nominal" if i == 0 else None
        ax.plot([i - 0.4, i + 0.4], [r["test_nominal_criterion"]] * 2, "k--", lw=1, label=label)
    ax.set_xticks(range(len(rows)))
    ax.set_xticklabels([textwrap.fill(r["label"], 24) for r in rows], fontsize=8)
    ax.set_ylabel(f"{split} criterion (lower is better; Juggling-v0: drop rate per toss)")
    ax.set_title("median over seeds (bar), each seed (dot); orange: best on validation", fontsize=9)
    ax.set_ylim(bottom=0.0, top=max(0.05, 1.1 * max(max(r["test_criteria"]) for r in rows)))
    ax.legend(loc="upper right", fontsize=8)
