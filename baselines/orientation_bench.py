"""``motion-bench orientation``: Faraway & Choe's Table 1 on real or the users' data.

Prints every criterion beside the paper's value, writes ``results.json``,
``results.csv`` and a residual plot in the style of the paper's Figure 5. With at least
3 subjects it adds the path-frame, predicted-timing and learned leave-one-subject-out
rows of :mod:`baselines.learned_rows` (``--learned``), a reading of learned against
analytic, and ``learned_ratio.png``.
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
    from baselines.learned_rows import ROW_LABELS

    if name in _ROW_LABELS or name in ROW_LABELS:
        return _ROW_LABELS.get(name) or ROW_LABELS[name]
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
        f"{'criterion':<50} {'name':<40} {'ours':>7} {'paper':>7}",
        "-" * 108,
    ]
    for name, value in result.criteria.items():
        paper = FARAWAY_CHOE_TABLE1.get(name)
        paper_s = f"{paper:7.3f}" if paper is not None else f"{'-':>7}"
        ours = f"{value:7.3f}" if math.isfinite(value) else f"{'n/a':>7}"
        note = FARAWAY_CHOE_TABLE1_NOTES.get(name, "")
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


def plot_residuals(
    result: Table1Result, dataset: OrientationDataset, path: Path, task: str | None = None
) -> Path:
    """Figure 5 style: three orthogonal, equally scaled views of one task's residual curves."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    tasks, counts = np.unique(dataset.tasks, return_counts=True)
    chosen = task if task is not None else str(tasks[np.argmax(counts)])
    if chosen not in tasks:
        raise ValueError(f"task must be one of {tasks.tolist()}; got {chosen!r}")
    R = result.residuals[dataset.tasks == chosen]
    lim = float(np.abs(R).max()) * 1.05 or 1.0
    fig, axes = plt.subplots(1, 3, figsize=(12, 4.2), constrained_layout=True)
    for ax, (i, j) in zip(axes, [(0, 1), (0, 2), (1, 2)], strict=True):
        for curve in R:
            ax.plot(curve[:, i], curve[:, j], lw=0.8, alpha=0.7)
        ax.plot(0, 0, "k+", ms=10)
        ax.set_xlim(-lim, lim)
        ax.set_ylim(-lim, lim)
        ax.set_aspect("equal")
        ax.set_xlabel("xyz"[i] + " (rad)")
        ax.set_ylabel("xyz"[j] + " (rad)")
        ax.grid(alpha=0.3)
    fig.suptitle(
        f"Empirical slerp residuals, {dataset.name}"
        f"{' (SIMULATED)' if dataset.simulated else ''}, task {chosen!r}: {len(R)} trajectories; "
        f"max distance from origin {np.linalg.norm(R, axis=2).max():.2f} rad"
    )
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.stem}.tmp.png")
    fig.savefig(tmp, dpi=110)
    plt.close(fig)
    tmp.replace(path)
    return path


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


def _learned_rows(
    args: argparse.Namespace, dataset: OrientationDataset, result: Table1Result
) -> dict[str, Any] | None:
    """Add the path-frame, predicted-timing and learned rows (docs/learned.md) to ``result``."""
    mode = getattr(args, "learned", "full")
    n_subjects = np.unique(dataset.subjects).size
    if mode == "off" or n_subjects < 3:
        if mode != "off":
            print(f"learned rows skipped: {n_subjects} subjects, at least 3 needed")
        return None
    from baselines.learned import sklearn_missing_reason, torch_missing_reason
    from baselines.learned_rows import compare, format_reading, learned_orientation_rows

    if sklearn_missing_reason():
        print(f"learned rows skipped: {sklearn_missing_reason()}")
        return None

    config = None
    missing = torch_missing_reason()
    if missing is None:
        from baselines.learned import QUICK_MLP
        from baselines.learned.batched_mlp import MLPConfig

        config = MLPConfig() if mode == "full" else QUICK_MLP
    rows = learned_orientation_rows(dataset, mlp_config=config, use_torch=missing is None)
    result.criteria.update(rows.criteria)
    comparisons = compare(rows, dataset.subjects)
    reading = format_reading(rows, comparisons)
    return {
        "reading": reading,
        "comparisons": comparisons,
        "document": {
            "mode": mode,
            "comparisons": comparisons,
            "chosen": rows.chosen,
            "seconds": rows.seconds,
            "skipped": rows.skipped,
        },
    }


def run(args: argparse.Namespace) -> int:
    """Execute ``motion-bench orientation`` with parsed arguments."""
    t0 = time.perf_counter()
    up = getattr(args, "up", None)
    if up is not None:
        try:
            up = tuple(float(v) for v in up.split(","))
        except ValueError:
            raise ValueError(f"--up must be three numbers 'x,y,z'; got {args.up!r}") from None
    dataset = load_orientation_dataset(args.data, min_deg=args.min_deg, up=up)
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
    learned = _learned_rows(args, dataset, result)
    elapsed = time.perf_counter() - t0
    print(format_table1(result, dataset))
    if learned is not None:
        print(learned["reading"])
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
        if learned is not None:
            doc["learned"] = learned["document"]
        atomic_write_text(out / "results.json", json.dumps(doc, indent=2) + "\n")
        atomic_write_text(out / "results.csv", results_csv(result))
        plot_residuals(result, dataset, out / "residuals.png", task=args.plot_task)
        if learned is not None and learned["comparisons"]:
            from baselines.learned_rows import plot_ratios

            plot_ratios(
                learned["comparisons"],
                out / "learned_ratio.png",
                f"per-subject ratio of learned to the best analytic row, {dataset.name}"
                f"{' (SIMULATED)' if dataset.simulated else ''}, leave one subject out",
            )
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
    p.add_argument(
        "--learned",
        choices=("full", "quick", "off"),
        default="full",
        help=(
            "path-frame, predicted-timing and learned (ridge, torch MLP) LOSO rows "
            "(docs/learned.md); quick: one MLP candidate and 30 epochs (baselines.learned."
            "QUICK_MLP); the MLP "
            "rows are skipped with a message when torch is not installed"
        ),
    )
    p.add_argument(
        "--up",
        default=None,
        help="the data's vertical axis 'x,y,z' for the path frame (default: the dataset's; "
        "+z for a CSV, +y for vr-kitchen)",
    )
    p.set_defaults(func=run)
