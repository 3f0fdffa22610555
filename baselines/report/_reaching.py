"""The ``report.html`` sections of the reaching benchmarks: ``orientation`` (Faraway &
Choe, Table 1) and ``position`` (Lippi, Avizzano & Ruffaldi, on LASA)."""

from __future__ import annotations

import csv
import html
import json
import math
from pathlib import Path
from typing import Any

from baselines.report._html import (
    LEARNED_RATIO_CAPTION,
    MODELS_DOC,
    Section,
    fmt,
    html_table,
    images,
    learned_table,
    validation_table,
)

__all__ = ["orientation_section", "position_section"]


# -- orientation (Faraway & Choe, Table 1) ----------------------------------------------


def orientation_section(folder: Path, job: dict[str, Any]) -> Section:
    from motion_envs.models.paper_values import FARAWAY_CHOE_TABLE1, FARAWAY_CHOE_TABLE1_NOTES

    doc = json.loads((folder / "results.json").read_text())
    labels: dict[str, str] = {}
    if (folder / "results.csv").exists():
        with open(folder / "results.csv", newline="", encoding="utf-8") as fh:
            labels = {row["name"]: row["label"] for row in csv.DictReader(fh)}
    c = doc["criteria"]
    paper = doc.get("paper") or FARAWAY_CHOE_TABLE1
    rows = [
        [
            html.escape(labels.get(name, name)),
            f"<code>{html.escape(name)}</code>",
            fmt(value),
            fmt(paper.get(name)),
            html.escape(FARAWAY_CHOE_TABLE1_NOTES.get(name, "")),
        ]
        for name, value in c.items()
    ]
    kind = "SIMULATED" if doc.get("simulated") else "real"
    table = html_table(
        ["criterion", "name", "ours (rad)", "paper (rad)", "note"],
        rows,
        f"Faraway & Choe Table 1 on {doc['dataset']} ({kind} data): median over "
        "trajectories of the max over time of the tangent-space error",
    )

    def get(name: str) -> float:
        v = c.get(name)
        return float("nan") if v is None else float(v)

    def cmp(a: str, b: str) -> str:
        return "below" if get(a) < get(b) else "not below"

    approx = [get(f"approximation_d{d}") for d in (2, 3, 4)]
    gain_in = get("null_d2") - get("task_predictor_d2")
    gain_out = get("null_d2_loso") - get("task_predictor_d2_loso")
    reading = (
        f"{doc['n_trajectories']} trajectories of {doc['n_subjects']} subjects and "
        f"{doc['n_tasks']} tasks ({kind} data; {doc['n_dropped']} dropped for rotating "
        "less than the minimum angle). The disagreement between replicates of one subject "
        f"({fmt(get('within_subject'))} rad) is {cmp('within_subject', 'between_subject')} "
        "that between subjects ("
        f"{fmt(get('between_subject'))} rad); that row is in sample (each reach inside the "
        "mean it is scored against). Predicted from the other replicates of its person and "
        f"task, a reach is missed by {fmt(get('within_subject_loo'))} rad; corrected for the "
        "noise of their mean, the predictive floor is "
        f"{fmt(get('predictive_floor'))} rad in the body frame and "
        f"{fmt(get('predictive_floor_path'))} rad in the path frame. The slerp with the "
        "observed speed profile "
        f"({fmt(get('slerp_empirical'))}) is {cmp('slerp_empirical', 'slerp_average')} the "
        f"slerp with the mean speed profile of the data ({fmt(get('slerp_average'))}), the "
        "timing a prediction must assume. Approximating each curve by its own Bézier "
        f"fit gives {', '.join(fmt(a) for a in approx)} rad for d = 2, 3, 4"
        f"{' (decreasing, as least squares must)' if approx[0] >= approx[1] >= approx[2] else ''}. "
        f"In sample the task model improves on the null model by {fmt(gain_in)} rad (d = 2); "
        f"with each subject left out the gain is {fmt(gain_out)} rad"
        + (
            ", so most of the in-sample gain does not carry to new people. "
            if math.isfinite(gain_out) and gain_out < 0.5 * gain_in
            else ". "
        )
        + "The paper's d = 3 null (0.371, worse than d = 2) cannot follow from its "
        f"procedure; see {MODELS_DOC}."
    )
    return Section(
        title=job.get("title", folder.name),
        command=job.get("command", ""),
        reading=reading,
        tables=[table, *learned_table(doc, "subjects")],
        images=images(
            folder,
            [
                ("residuals.png", "Slerp residual curves of one task with the fitted models"),
                ("learned_ratio.png", LEARNED_RATIO_CAPTION),
            ],
        ),
    )


# -- position (Lippi, Avizzano & Ruffaldi, on LASA) --------------------------------------


def position_section(folder: Path, job: dict[str, Any]) -> Section:
    doc = json.loads((folder / "results.json").read_text())
    methods = doc["methods"]
    summary = doc["summary_median_across_shapes"]
    unit = doc.get("unit") or "data unit"
    rows = [
        [html.escape(f"{name}: {text}")] + [fmt(summary[m][name]) for m in methods] + ["&ndash;"]
        for name, text in doc["criteria"].items()
    ]
    table = html_table(
        ["criterion", *methods, "paper"],
        rows,
        f"{doc['dataset']}: median across shapes of the per-shape median ({unit}); "
        "Lippi et al. report no figures on this data set",
    )
    per_shape = doc["per_shape"]
    wins: dict[str, int] = {}
    for m in methods:
        if m == "lippi":
            continue
        wins[m] = sum(
            1
            for s in per_shape.values()
            if s["criteria"]["lippi"]["max_error"] < s["criteria"][m]["max_error"]
        )
    win_rows = [[html.escape(m), f"{n} of {len(per_shape)}"] for m, n in wins.items()]
    win_table = html_table(
        ["opponent", "shapes where lippi has the lower max error"],
        win_rows,
        "Per-shape comparison of Lippi et al.'s regression with each other method",
    )
    tables = [table, win_table]
    timing = doc.get("timing") or {}
    if "lippi" in timing:
        t_rows = [
            [
                html.escape(m),
                fmt(v["fit_s_per_call"] * 1e3, 2),
                fmt(v["predict_s_per_call"] * 1e3, 2),
            ]
            for m, v in timing.items()
            if "fit_s_per_call" in v
        ]
        tables.append(
            html_table(
                ["method", "fit (ms)", "generate one (ms)"], t_rows, "Timing on this machine"
            )
        )
    best = min(methods, key=lambda m: summary[m]["max_error"])
    reading = (
        f"{len(per_shape)} shapes; every method predicts each held-out demonstration from "
        f"its start, end and duration. The lowest median max error is {best}'s "
        f"({fmt(summary[best]['max_error'])} {unit}); the straight line's is "
        f"{fmt(summary['line']['max_error'])} {unit}"
        + (
            ", so every method that learns the shape helps by a wide margin. "
            if all(
                summary[m]["max_error"] < 0.5 * summary["line"]["max_error"]
                for m in methods
                if m != "line"
            )
            else ". "
        )
        + (
            f"Lippi et al.'s regression beats the mean residual (null) on "
            f"{wins['null']} of {len(per_shape)} shapes"
            if "null" in wins
            else ""
        )
        + (
            ": with few demonstrations per shape the boundary conditions explain little of "
            "the shape, and the regression adds variance the plain mean does not have"
            + (" (every LASA demonstration ends at the origin)" if doc["dataset"] == "lasa" else "")
            + ". "
            if "null" in wins and wins["null"] < len(per_shape) / 2
            else (". " if "null" in wins else "")
        )
        + (
            "Lippi et al. published no figures on this data set (their data was a juggling "
            f"task), so the 'paper' column is empty; see {MODELS_DOC}."
        )
    )
    return Section(
        title=job.get("title", folder.name),
        command=job.get("command", ""),
        reading=reading,
        tables=[
            *tables,
            *learned_table(doc, "shapes"),
            *validation_table(
                {k: v.get("validation") for k, v in doc.get("per_shape", {}).items()},
                "shape",
                "Validation of the linear hypothesis per shape (all its demonstrations)",
            ),
        ],
        images=images(
            folder,
            [
                ("shapes.png", "Held-out demonstrations and each method's prediction"),
                ("learned_ratio.png", LEARNED_RATIO_CAPTION),
            ],
        ),
    )
