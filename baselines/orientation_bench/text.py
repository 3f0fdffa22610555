"""The text outputs of ``motion-bench orientation``: Table 1 beside the paper's values
(:func:`report`), ``results.csv`` and the results document."""

from __future__ import annotations

import csv
import io
import math
from typing import Any

import numpy as np

from baselines.learned.rows import ROW_LABELS
from baselines.orientation_bench.config import OrientationConfig, OrientationResults
from baselines.verdicts import FLOOR_ROWS, IN_SAMPLE_ROW, calibration_label
from motion_envs.datasets import OrientationDataset
from motion_envs.models.criteria import Table1Result
from motion_envs.models.paper_values import FARAWAY_CHOE_TABLE1, FARAWAY_CHOE_TABLE1_NOTES

_ROW_LABELS = {
    "within_subject": "Within subject",
    "within_subject_loo": "Within subject, leave one out",
    "within_subject_path_loo": "Within subject, path frame, leave one out",
    "predictive_floor": "Predictive floor",
    "predictive_floor_path": "Predictive floor, path frame",
    "between_subject": "Between subject",
    "slerp_empirical": "Slerp, empirical",
    "slerp_average": "Slerp, average",
    "null_average": "Null average",
}


def _label(name: str) -> str:
    if name in _ROW_LABELS:
        return _ROW_LABELS[name]
    if name in ROW_LABELS:
        return ROW_LABELS[name]
    if (label := calibration_label(name)) is not None:
        return label
    base, _, rest = name.partition("_d")
    degree, _, split = rest.partition("_")
    pretty = base.replace("_", " ").capitalize()
    suffix = {"loso": ", leave one subject out", "loro": ", leave one replicate out"}.get(split, "")
    return f"{pretty} (d={degree}){suffix}"


def format_table1(
    result: Table1Result, dataset: OrientationDataset, min_deg: float | None = None
) -> str:
    """Table 1 as text: one row per criterion, ours beside the paper's value (radians);
    ``min_deg``: the ``--min-deg`` the dropped trajectories were under."""
    why = "" if min_deg is None else f" for rotating less than {min_deg:g} degrees (--min-deg)"
    lines = [
        f"Faraway & Choe Table 1 on {dataset.name!r}: {len(dataset)} trajectories "
        f"({'simulated' if dataset.simulated else 'real'} data), {dataset.n_dropped} "
        f"dropped{why}, {np.unique(dataset.subjects).size} subjects, "
        f"{np.unique(dataset.tasks).size} tasks",
        "median over trajectories of the max over time of the tangent-space error, radians",
        "",
        f"{'criterion':<50} {'name':<40} {'ours':>7} {'paper':>7}",
        "-" * 108,
    ]
    floors = {row: frame for frame, (row, _, _) in FLOOR_ROWS.items()}
    for name, value in result.criteria.items():
        paper = FARAWAY_CHOE_TABLE1.get(name)
        paper_s = f"{paper:7.3f}" if paper is not None else f"{'-':>7}"
        ours = f"{value:7.3f}" if math.isfinite(value) else f"{'n/a':>7}"
        note = FARAWAY_CHOE_TABLE1_NOTES.get(name, "")
        if name in floors:
            note = f"noise floor, {floors[name]} frame"
        elif name == IN_SAMPLE_ROW:
            note = f"in sample (not a floor for predictors){'; ' + note if note else ''}"
        lines.append(f"{_label(name):<50} {name:<40} {ours} {paper_s}  {note}".rstrip())
    lines.append("")
    lines.append(
        "paper: 1,088 reaches of 20 subjects (hand relative to forearm); rows ending in "
        "_loso/_loro are ours only (out of sample)."
    )
    return "\n".join(lines)


def results_document(result: Table1Result, dataset: OrientationDataset) -> dict[str, Any]:
    """The ``results.json`` document."""
    return {
        "dataset": dataset.name,
        "simulated": dataset.simulated,
        "n_trajectories": len(dataset),
        "n_dropped": dataset.n_dropped,
        "n_subjects": int(np.unique(dataset.subjects).size),
        "n_tasks": int(np.unique(dataset.tasks).size),
        "criteria": {k: (v if math.isfinite(v) else None) for k, v in result.criteria.items()},
        "paper": dict(FARAWAY_CHOE_TABLE1),
        "fallbacks": dict(result.fallbacks),
    }


def results_csv(result: Table1Result) -> str:
    """``results.csv``: one row per criterion, ``name,label,ours,paper`` (radians)."""
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(["name", "label", "ours", "paper"])
    for name, value in result.criteria.items():
        paper = FARAWAY_CHOE_TABLE1.get(name)
        writer.writerow(
            [name, _label(name), repr(value) if math.isfinite(value) else "", paper or ""]
        )
    return buf.getvalue()


def nominal_text(config: OrientationConfig, nominal: dict[str, Any]) -> str:
    degree = f", d={config.degree}" if config.nominal != "slerp" else ""
    unseen = (
        f" ({nominal['n_unseen']} with an unseen label use the null model)"
        if nominal["n_unseen"]
        else ""
    )
    return (
        f"\nnominal {config.nominal!r}{degree} fitted on the train split ({nominal['n_train']} "
        f"trajectories; split by subject, seed {config.split_seed}, test fraction "
        f"{config.test_fraction:g}); criterion on the {config.split} split "
        f"({nominal['n_scored']} trajectories): {nominal['criterion']!r} rad{unseen}"
    )


def report(results: OrientationResults) -> str:
    """The text ``motion-bench orientation`` prints."""
    parts = [format_table1(results.table, results.dataset, results.config.min_deg)]
    if results.learned is not None:
        from baselines.learned.rows import format_reading

        parts.append(format_reading(results.learned, results.comparisons))
    elif results.learned_note is not None:
        parts.append(f"\nlearned rows skipped: {results.learned_note}")
    parts.append(_floor_and_verdicts(results))
    if results.nominal is not None:
        parts.append(nominal_text(results.config, results.nominal))
    parts.append(f"\ncomputed in {results.seconds:.2f} s")
    return "\n".join(parts)


def _floor_and_verdicts(results: OrientationResults) -> str:
    """The noise-floor block, the calibration note and every ratio's verdict line."""
    from baselines.verdicts import format_floor, format_verdicts, noise_floor

    text = format_floor(noise_floor(results.table.criteria))
    cal = results.calibration
    if cal is not None:
        text += (
            f"\nperson calibration: K of the held-out person's other reaches, {cal.n_draws} "
            f"draws (seed {cal.seed}) averaged per trajectory; k0 chosen on the training "
            "people (docs/protocol.md)"
        )
        lc = results.learned_calibration
        if lc is not None:
            text += (
                "\nridge/mlp_person_k{K}_loso: ridge_loso/mlp_loso given the calibration summary "
                "of the same draws (9 path-frame sine coefficients and the share drawn; "
                f"training people's rows, one per draw; MLP trained on {lc.mlp_train_draws} "
                "draws per reach)"
            )
            for name, why in lc.skipped.items():
                text += f"\n  {name}: skipped ({why})"
    elif results.calibration_note is not None:
        text += f"\nperson-calibration rows skipped: {results.calibration_note}"
    return text + format_verdicts(results.verdicts, "verdicts, leave one person out")


def _new_entries(results: OrientationResults) -> dict[str, Any]:
    """The keys of ``results.json`` added with the intervals: ``noise_floor``,
    ``calibration``, ``intervals``, ``verdicts``."""
    from baselines.verdicts import noise_floor, verdicts_document

    out: dict[str, Any] = {"noise_floor": noise_floor(results.table.criteria)}
    cal = results.calibration
    if cal is not None:
        out["calibration"] = {
            "k": list(results.config.calibration),
            "n_draws": cal.n_draws,
            "seed": cal.seed,
            "chosen_k0": cal.chosen_k0,
            "trajectories_with_fewer_than_k_others": {str(k): n for k, n in cal.short.items()},
        }
        lc = results.learned_calibration
        if lc is not None:
            out["calibration"]["learned"] = {
                "chosen": lc.chosen,
                "seconds": lc.seconds,
                "skipped": lc.skipped,
                "mlp_train_draws": lc.mlp_train_draws,
            }
    elif results.calibration_note is not None:
        out["calibration"] = {"skipped": results.calibration_note}
    return {**out, **verdicts_document(results.verdicts)}


def document(results: OrientationResults) -> dict[str, Any]:
    """The ``results.json`` document of a run."""
    config = results.config
    doc = results_document(results.table, results.dataset)
    if config.split != "all" or results.nominal is not None:
        doc["split"] = {
            "split": config.split,
            "split_seed": config.split_seed,
            "test_fraction": config.test_fraction,
        }
    if results.nominal is not None:
        doc["nominal"] = results.nominal
    if results.learned is not None:
        doc["learned"] = {
            "mode": config.learned,
            "up": list(results.dataset.up),
            "comparisons": results.comparisons,
            "chosen": results.learned.chosen,
            "seconds": results.learned.seconds,
            "skipped": results.learned.skipped,
        }
    doc.update(_new_entries(results))
    return doc
