"""The files of ``motion-bench position``: :func:`write` (results.json, results.csv,
``shapes.png``, ``learned_ratio.png``) and the shapes figure."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from baselines.position_bench.text import clean_json, results_csv
from motion_envs._io import atomic_write_text, save_figure


def plot_grid(doc: dict[str, Any], path: Path) -> Path:
    """Held-out demonstrations and each method's predictions (see :mod:`baselines.plots`),
    written atomically to ``path``."""
    from baselines.plots import shapes_figure

    return save_figure(shapes_figure(doc), path, dpi=100)


def write(doc: dict[str, Any], out: str | Path) -> list[Path]:
    """Write ``results.json``, ``results.csv``, ``shapes.png`` and, with learned columns,
    ``learned_ratio.png`` into ``out`` (atomic)."""
    folder = Path(out)
    written = [
        atomic_write_text(folder / "results.json", json.dumps(clean_json(doc), indent=2) + "\n"),
        atomic_write_text(folder / "results.csv", results_csv(doc)),
    ]
    plot_grid(doc, folder / "shapes.png")
    written.append(folder / "shapes.png")
    comparisons = doc["learned"]["comparisons"]
    if comparisons:
        from baselines.learned.reading import plot_ratios

        written.append(
            plot_ratios(
                comparisons,
                folder / "learned_ratio.png",
                f"per-shape ratio of learned to the best analytic column, {doc['dataset']}",
                group="shape",
            )
        )
    return written
