"""The files of ``motion-bench orientation``: :func:`write` (results.json, results.csv, the
residual plot, ``learned_ratio.png``) and the Figure-5-style residual plot."""

from __future__ import annotations

import json
from pathlib import Path

from baselines.orientation_bench.config import OrientationResults
from baselines.orientation_bench.text import document, results_csv
from motion_envs._io import atomic_write_text, save_figure
from motion_envs.datasets import OrientationDataset
from motion_envs.models.criteria import Table1Result


def plot_residuals(
    result: Table1Result, dataset: OrientationDataset, path: Path, task: str | None = None
) -> Path:
    """Figure 5 style residual plot with the fitted models (see :mod:`baselines.plots`).

    Written atomically to ``path``; returns it.
    """
    from baselines.plots import residual_figure

    fig = residual_figure(
        result.residuals, dataset.tasks, task, dataset=dataset.name, simulated=dataset.simulated
    )
    return save_figure(fig, path, dpi=110)


def write(results: OrientationResults, out: str | Path) -> list[Path]:
    """Write ``results.json``, ``results.csv``, ``residuals.png`` and, with the learned
    rows, ``learned_ratio.png`` into ``out`` (atomic)."""
    folder = Path(out)
    written = [
        atomic_write_text(folder / "results.json", json.dumps(document(results), indent=2) + "\n"),
        atomic_write_text(folder / "results.csv", results_csv(results.table)),
        plot_residuals(
            results.table, results.dataset, folder / "residuals.png", task=results.config.plot_task
        ),
    ]
    if results.comparisons:
        from baselines.learned.reading import plot_ratios

        dataset = results.dataset
        written.append(
            plot_ratios(
                results.comparisons,
                folder / "learned_ratio.png",
                f"per-subject ratio of learned to the best analytic row, {dataset.name}"
                f"{' (SIMULATED)' if dataset.simulated else ''}, leave one subject out",
            )
        )
    return written
