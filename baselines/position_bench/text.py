"""The text outputs of ``motion-bench position``: the printed table, validation and
timing (:func:`report`), ``results.csv`` and the JSON-ready results document."""

from __future__ import annotations

import csv
import io
import math
from typing import Any

from motion_envs.models.position_criteria import CRITERIA


def _split_text(split: dict[str, Any]) -> str:
    if split["split"] == "loo":
        return "leave one demonstration out"
    return (
        f"{split['split']} split (test fraction {split['test_fraction']:g} per shape, "
        f"seed {split['split_seed']})"
    )


def format_table(doc: dict[str, Any]) -> str:
    """The printed table: median across shapes of each per-shape criterion."""
    methods = doc["methods"]
    unit = f" ({doc['unit']})" if doc["unit"] else ""
    lines = [
        f"position benchmark on {doc['dataset']!r}: {len(doc['per_shape'])} shapes, "
        f"{_split_text(doc['split'])}, {doc['n_points']}-point normalised-time grid{unit}",
        "per shape: median over held-out demos; below: median across shapes",
        "",
        f"{'criterion':<56}" + "".join(f"{m:>10}" for m in methods),
        "-" * (56 + 10 * len(methods)),
    ]
    for c, text in doc["criteria"].items():
        vals = "".join(f"{doc['summary_median_across_shapes'][m][c]:10.3f}" for m in methods)
        lines.append(f"{c + ': ' + text:<56}{vals}")
    if not doc["peers_available"]:
        lines.append("dmp, promp: skipped (movement_primitives not installed or not requested)")
    return "\n".join(lines)


def format_validation(doc: dict[str, Any]) -> str:
    """Per shape (phase) and coordinate: the paper's checks of the linear hypothesis."""
    lines = [
        "validation of the linear hypothesis (Lippi et al.), all demos of each shape, "
        "non-exact sine coefficients:",
        "  normal: share with Lilliefors p > 0.05; F-test: share with p < 0.05; "
        "CI/|F|: median 95% CI half-width over |F|; jack/|F|: median jackknife sd over |F|",
        f"{'shape':<18}{'coord':>6}{'n':>4}{'normal':>8}{'F-test':>8}{'CI/|F|':>9}{'jack/|F|':>10}",
    ]
    for shape, res in doc["per_shape"].items():
        if not res["validation"]:
            lines.append(f"{shape:<18}  (too few demonstrations for the tests)")
        for row in res["validation"]:
            lines.append(
                f"{shape:<18}{row['coordinate']:>6}{row['n_coefficients']:>4}"
                f"{row['normal_frac']:8.2f}{row['ftest_frac']:8.2f}"
                f"{row['ci_rel']:9.2f}{row['jack_rel']:10.2f}"
            )
    return "\n".join(lines)


def clean_json(value: Any) -> Any:
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: clean_json(v) for k, v in value.items() if not str(k).startswith("_")}
    if isinstance(value, list):
        return [clean_json(v) for v in value]
    return value


def results_csv(doc: dict[str, Any]) -> str:
    buf = io.StringIO()
    writer = csv.writer(buf)
    writer.writerow(["shape", "method", *CRITERIA])
    for shape, res in doc["per_shape"].items():
        for m, vals in res["criteria"].items():
            writer.writerow([shape, m, *(f"{vals[c]:.6g}" for c in CRITERIA)])
    return buf.getvalue()


def report(doc: dict[str, Any]) -> str:
    """The text ``motion-bench position`` prints: table, learned reading, validation,
    timing."""
    from baselines.learned.position_reading import format_position_reading

    parts = [format_table(doc)]
    if doc["learned"]["comparisons"] or doc["learned"]["skipped"]:
        parts.append(format_position_reading(doc, doc["learned"]["comparisons"]))
    if doc.get("verdicts"):
        from baselines.verdicts import format_verdict_entries

        parts.append(format_verdict_entries(doc["verdicts"], "verdicts, shapes resampled"))
    parts += ["", format_validation(doc)]
    if doc["timing"]:
        parts += [
            "",
            "timing, seconds per call (fit on the training demos / generate one trajectory):",
        ]
        for m, v in doc["timing"].items():
            if "fit_s_per_call" in v:
                parts.append(
                    f"  {m:<6} fit {v['fit_s_per_call']:.3g}  predict {v['predict_s_per_call']:.3g}"
                )
            else:
                parts.append(f"  {m:<13} fit x{v['fit']:.1f}  predict x{v['predict']:.1f}")
    return "\n".join(parts)
