"""The summary of a sweep: one row per configuration (median and spread over seeds,
best by median validation criterion), its Markdown table and the result files."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from baselines.agents.sweep.plot import plot_sweep
from baselines.agents.sweep.space import SweepConfig
from motion_envs._io import atomic_write_text


def _spread(values: Sequence[float | None]) -> tuple[float | None, float | None, float | None]:
    """Median, min and max over seeds; None when any seed has no value (a ratio to a
    nominal criterion of 0, or a juggling-only metric of a reaching run)."""
    if not values or any(v is None for v in values):
        return None, None, None
    a = np.asarray(values, dtype=float)
    return float(np.median(a)), float(a.min()), float(a.max())


def summarize(trials: Sequence[Mapping[str, Any]], sweep: SweepConfig) -> dict[str, Any]:
    """One row per configuration: median and spread over seeds; best by median validation."""
    rows = []
    for index, cfg in enumerate(sweep.configurations):
        mine = sorted((t for t in trials if t["config_index"] == index), key=lambda t: t["seed"])
        if not mine:
            continue
        test = np.array([t["test_criterion"] for t in mine])
        val = np.array([t["best_val_criterion"] for t in mine])
        ratio = _spread([t["test_ratio"] for t in mine])
        rows.append(
            {
                "config_index": index,
                "label": cfg["label"],
                "algo": cfg["algo"],
                "env_id": cfg["env_id"],
                "overrides": cfg["overrides"],
                "n_seeds": len(mine),
                "seeds": [int(t["seed"]) for t in mine],
                "val_criterion_median": float(np.median(val)),
                "test_criterion_median": float(np.median(test)),
                "test_criterion_min": float(test.min()),
                "test_criterion_max": float(test.max()),
                "test_criterion_iqr": float(np.subtract(*np.percentile(test, [75, 25]))),
                "test_nominal_criterion": float(mine[0]["test_nominal_criterion"]),
                "test_ratio_median": ratio[0],
                "test_ratio_min": ratio[1],
                "test_ratio_max": ratio[2],
                "test_criteria": test.tolist(),
            }
        )
        for key in ("test_catch_rate", "test_nominal_catch_rate", "test_deviation_ratio"):
            median, lo, hi = _spread([t.get(key) for t in mine])
            rows[-1].update({f"{key}_median": median, f"{key}_min": lo, f"{key}_max": hi})
    best = min(rows, key=lambda r: r["val_criterion_median"]) if rows else None
    for r in rows:
        r["best_on_validation"] = best is not None and r["config_index"] == best["config_index"]
    from baselines.agents.sweep.lopo import lopo_summary

    out: dict[str, Any] = {
        "configurations": rows,
        "best_config_index": None if best is None else best["config_index"],
    }
    lopo = lopo_summary(trials, sweep.configurations)
    if lopo is not None:  # agents judged by people (leave one person out)
        out["lopo"] = lopo
    return out


def format_table(results: Mapping[str, Any]) -> str:
    """The summary as a Markdown table (the README's agent table)."""
    rows = results["configurations"]
    juggling = any(r.get("test_catch_rate_median") is not None for r in rows)
    head = (
        "| configuration | seeds | val median | test median | test min-max | nominal (test) | "
        "x nominal (median, min-max) |"
    )
    rule = "|---|--:|--:|--:|--:|--:|--:|"
    if juggling:
        head += " catch rate (median, min-max) | nominal catch rate | deviation x nominal |"
        rule += "--:|--:|--:|"
    lines = [head, rule]

    def spread(r: Mapping[str, Any], key: str) -> str:
        if r.get(f"{key}_median") is None:
            return "n/a"
        return f"{r[f'{key}_median']:.3f} ({r[f'{key}_min']:.3f}-{r[f'{key}_max']:.3f})"

    for r in rows:
        mark = " **(best on val)**" if r["best_on_validation"] else ""
        line = (
            f"| {r['label']}{mark} | {r['n_seeds']} | {r['val_criterion_median']:.4f} | "
            f"{r['test_criterion_median']:.4f} | {r['test_criterion_min']:.4f}-"
            f"{r['test_criterion_max']:.4f} | {r['test_nominal_criterion']:.4f} | "
            f"{spread(r, 'test_ratio')} |"
        )
        if juggling:
            nominal = r.get("test_nominal_catch_rate_median")
            line += (
                f" {spread(r, 'test_catch_rate')} | "
                f"{'n/a' if nominal is None else f'{nominal:.3f}'} | "
                f"{spread(r, 'test_deviation_ratio')} |"
            )
        lines.append(line)
    return "\n".join(lines)


def relative_to_out(path: str, out: Path) -> str:
    """``path`` relative to ``out`` when it lies inside it (POSIX separators), else as is."""
    try:
        return Path(path).resolve().relative_to(Path(out).resolve()).as_posix()
    except ValueError:
        return str(path)


def write_results(results: Mapping[str, Any], out: Path) -> None:
    """results.json, trials.csv (run folders relative to ``out``), table.csv, table.md and
    sweep.png in ``out``."""
    import pandas as pd

    from baselines.agents.rundir import write_json

    write_json(out / "results.json", dict(results))
    frame = pd.DataFrame(results["trials"])
    if "run_dir" in frame:  # relative to --out, so that the folder can be moved or shared
        frame["run_dir"] = [relative_to_out(p, out) for p in frame["run_dir"]]
    trials = frame.to_csv(index=False, float_format="%.17g")
    atomic_write_text(out / "trials.csv", trials)
    table = pd.DataFrame(results["configurations"]).drop(
        columns=["overrides", "test_criteria", "seeds"]
    )
    atomic_write_text(out / "table.csv", table.to_csv(index=False, float_format="%.17g"))
    atomic_write_text(out / "table.md", format_table(results) + "\n")
    plot_sweep(results, out / "sweep.png")
