"""``motion-bench orientation``: Faraway & Choe's Table 1 on real or the users' data.

Prints every criterion beside the paper's value, writes ``results.json``,
``results.csv`` and a residual plot in the style of the paper's Figure 5.
"""

from __future__ import annotations

import argparse
import csv
import io
import json
import math
import time
from pathlib import Path
from typing import Any

import numpy as np

from motion_envs.datasets import ORIENTATION_DATASETS, OrientationDataset, load_orientation_dataset
from motion_envs.datasets.vr_kitchen import DEFAULT_MIN_DEG
from motion_envs.models.criteria import Table1Result, table1
from motion_envs.models.paper_values import FARAWAY_CHOE_TABLE1, FARAWAY_CHOE_TABLE1_NOTES
from motion_envs.models.serialization import atomic_write_text

__all__ = ["format_table1", "register", "results_csv", "results_document", "run"]

_ROW_LABELS = {
    "within_subject": "Within subject",
    "between_subject": "Between subject",
    "slerp_empirical": "Slerp, empirical",
    "slerp_average": "Slerp, average",
    "null_average": "Null average",
}


def _label(name: str) -> str:
    if name in _ROW_LABELS:
        return _ROW_LABELS[name]
    base, _, rest = name.partition("_d")
    degree, _, split = rest.partition("_")
    pretty = base.replace("_", " ").capitalize()
    suffix = {"loso": ", leave one subject out", "loro": ", leave one replicate out"}.get(split, "")
    return f"{pretty} (d={degree}){suffix}"


def format_table1(result: Table1Result, dataset: OrientationDataset) -> str:
    """Table 1 as text: one row per criterion, ours beside the paper's value (radians)."""
    lines = [
        f"Faraway & Choe Table 1 on {dataset.name!r}: {len(dataset)} trajectories "
        f"({'simulated' if dataset.simulated else 'real'} data), {dataset.n_dropped} dropped, "
        f"{np.unique(dataset.subjects).size} subjects, {np.unique(dataset.tasks).size} tasks",
        "median over trajectories of the max over time of the tangent-space error, radians",
        "",
        f"{'criterion':<50} {'name':<28} {'ours':>7} {'paper':>7}",
        "-" * 96,
    ]
    for name, value in result.criteria.items():
        paper = FARAWAY_CHOE_TABLE1.get(name)
        paper_s = f"{paper:7.3f}" if paper is not None else f"{'-':>7}"
        ours = f"{value:7.3f}" if math.isfinite(value) else f"{'n/a':>7}"
        note = FARAWAY_CHOE_TABLE1_NOTES.get(name, "")
        lines.append(f"{_label(name):<50} {name:<28} {ours} {paper_s}  {note}".rstrip())
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


def plot_residuals(
    result: Table1Result, dataset: OrientationDataset, path: Path, task: str | None = None
) -> Path:
    """Figure 5 style residual plot with the fitted models (see :mod:`baselines.plots`)."""
    from baselines.plots import residual_figure, save_figure

    fig = residual_figure(
        result.residuals, dataset.tasks, task, dataset=dataset.name, simulated=dataset.simulated
    )
    return save_figure(fig, path)


def _split_dataset(
    args: argparse.Namespace, dataset: OrientationDataset
) -> tuple[OrientationDataset, OrientationDataset]:
    from motion_envs.datasets.splits import split_by_subject

    return split_by_subject(dataset, test_fraction=args.test_fraction, seed=args.split_seed)


def _nominal_report(
    args: argparse.Namespace, dataset: OrientationDataset, split: str
) -> dict[str, Any]:
    """Offline criterion of ``--nominal`` fitted on the train split, scored on ``--split``.

    The same :mod:`motion_envs.models.nominal` code builds the environments' nominal, so
    the zero-action policy of ``MotionEnvs/OrientationReach-v0`` reproduces this value.
    """
    from motion_envs.models.nominal import orientation_criterion

    train, test = _split_dataset(args, dataset)
    scored = {"train": train, "test": test, "all": dataset}[split]
    res = orientation_criterion(train, scored, nominal=args.nominal, degree=args.degree)
    degree = f", d={args.degree}" if args.nominal != "slerp" else ""
    print(
        f"\nnominal {args.nominal!r}{degree} fitted on the train split ({res['n_train']} "
        f"trajectories; split by subject, seed {args.split_seed}, test fraction "
        f"{args.test_fraction:g}); criterion on the {split} split ({res['n_test']} "
        f"trajectories): {res['criterion']!r} rad"
        + (
            f" ({res['n_unseen']} with an unseen label use the null model)"
            if res["n_unseen"]
            else ""
        )
    )
    return {
        "nominal": args.nominal,
        "degree": args.degree,
        "scored_on": split,
        "criterion": res["criterion"],
        "n_train": res["n_train"],
        "n_scored": res["n_test"],
        "n_unseen": res["n_unseen"],
    }


def run(args: argparse.Namespace) -> int:
    """Execute ``motion-bench orientation`` with parsed arguments."""
    t0 = time.perf_counter()
    dataset = load_orientation_dataset(args.data, min_deg=args.min_deg)
    if len(dataset) < 2:
        raise ValueError(
            f"only {len(dataset)} trajectories left after dropping those under "
            f"{args.min_deg} degrees; lower --min-deg"
        )
    full = dataset
    split = getattr(args, "split", "all")
    if split != "all":
        dataset = _split_dataset(args, full)[split == "test"]
    result = table1(dataset.ragged, dataset.subjects, dataset.tasks)
    elapsed = time.perf_counter() - t0
    print(format_table1(result, dataset))
    nominal = None
    if getattr(args, "nominal", None) is not None:
        nominal = _nominal_report(args, full, split)
    print(f"\ncomputed in {elapsed:.2f} s")
    if args.out is not None:
        out = Path(args.out)
        doc = results_document(result, dataset)
        if split != "all" or nominal is not None:
            doc["split"] = {
                "split": split,
                "split_seed": args.split_seed,
                "test_fraction": args.test_fraction,
            }
        if nominal is not None:
            doc["nominal"] = nominal
        atomic_write_text(out / "results.json", json.dumps(doc, indent=2) + "\n")
        atomic_write_text(out / "results.csv", results_csv(result))
        plot_residuals(result, dataset, out / "residuals.png", task=args.plot_task)
        print(f"wrote {out / 'results.json'}, {out / 'results.csv'} and {out / 'residuals.png'}")
    return 0


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``orientation`` sub-command."""
    p = subparsers.add_parser(
        "orientation",
        help="Faraway & Choe Table 1 (orientation trajectories)",
        description=(
            "Compute Faraway & Choe's Table 1 (median over trajectories of the max over "
            "time of the slerp-residual error, radians) with the paper's value beside "
            "ours, plus leave-one-subject-out and leave-one-replicate-out rows."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    p.add_argument(
        "--data",
        default="vr-kitchen",
        help=(
            f"built-in dataset ({', '.join(ORIENTATION_DATASETS)}; 'cohort' is the simulated "
            "cohort calibrated to the paper, 'cohort:CONFIG' another one, CONFIG a name under "
            "configs/cohorts/ or a YAML path) or a path to a CSV with "
            "columns trajectory,subject,task,t,qw,qx,qy,qz[,numeric predictors]"
        ),
    )
    p.add_argument(
        "--min-deg",
        type=float,
        default=DEFAULT_MIN_DEG,
        help="drop trajectories rotating less than this many degrees from start to end",
    )
    p.add_argument(
        "--out",
        default=None,
        help="folder for results.json, results.csv and residuals.png (none written without it)",
    )
    p.add_argument(
        "--plot-task",
        default=None,
        help="task whose residuals residuals.png shows (default: the most frequent task)",
    )
    p.add_argument(
        "--split",
        choices=("all", "train", "test"),
        default="all",
        help="compute Table 1 on all trajectories or on one side of a split by subject",
    )
    p.add_argument("--split-seed", type=int, default=0, help="seed of the split by subject")
    p.add_argument(
        "--test-fraction", type=float, default=0.25, help="share of subjects held out for test"
    )
    p.add_argument(
        "--nominal",
        choices=("slerp", "bezier-null", "bezier-task", "bezier-subject"),
        default=None,
        help=(
            "also report the criterion of this nominal model (as in the Gymnasium "
            "environments), fitted on the train split and scored on --split"
        ),
    )
    p.add_argument("--degree", type=int, default=2, help="Bezier degree of --nominal")
    p.set_defaults(func=run)
