"""``motion-bench orientation``: Faraway & Choe's Table 1 on real or the users' data.

:func:`run` computes (a pure function of an :class:`OrientationConfig`); :func:`report`
is the printed table, every criterion beside the paper's value; :func:`write` writes
``results.json``, ``results.csv`` and a residual plot in the style of the paper's
Figure 5. :func:`register` adds the sub-command to ``motion-bench``.
"""

from __future__ import annotations

import argparse
import csv
import io
import json
import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from baselines import options
from motion_envs._io import atomic_write_text, save_figure
from motion_envs.datasets import ORIENTATION_DATASETS, OrientationDataset, load_orientation_dataset
from motion_envs.datasets.splits import split_by_subject
from motion_envs.datasets.vr_kitchen import DEFAULT_MIN_DEG
from motion_envs.models.criteria import Table1Result, table1
from motion_envs.models.orientation_nominal import ORIENTATION_NOMINALS, orientation_criterion
from motion_envs.models.paper_values import FARAWAY_CHOE_TABLE1, FARAWAY_CHOE_TABLE1_NOTES

__all__ = [
    "OrientationConfig",
    "OrientationResults",
    "format_table1",
    "plot_residuals",
    "register",
    "report",
    "results_csv",
    "results_document",
    "run",
    "write",
]

SPLITS: tuple[str, ...] = ("all", "train", "test")


@dataclass(frozen=True)
class OrientationConfig:
    """What ``motion-bench orientation`` computes (the defaults are the CLI's).

    Attributes
    ----------
    data:
        ``"vr-kitchen"``, ``"cohort"``, ``"cohort:CONFIG"`` or a path to an orientation CSV.
    min_deg:
        Trajectories rotating less than this (degrees, start to end) are dropped.
    split, split_seed, test_fraction:
        Table 1 on ``"all"`` trajectories or one side of the split by subject.
    nominal, degree:
        Also score this nominal model (fitted on the train split) on ``split``.
    plot_task:
        Task whose residuals :func:`write` draws (None: the most frequent).
    """

    data: str = "vr-kitchen"
    min_deg: float = DEFAULT_MIN_DEG
    split: str = "all"
    split_seed: int = 0
    test_fraction: float = 0.25
    nominal: str | None = None
    degree: int = 2
    plot_task: str | None = None


@dataclass(frozen=True)
class OrientationResults:
    """What :func:`run` returns: the scored dataset, Table 1, the nominal's criterion."""

    config: OrientationConfig
    dataset: OrientationDataset
    table: Table1Result
    nominal: dict[str, Any] | None
    seconds: float


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
    """Figure 5 style residual plot with the fitted models (see :mod:`baselines.plots`).

    Written atomically to ``path``; returns it.
    """
    from baselines.plots import residual_figure

    fig = residual_figure(
        result.residuals, dataset.tasks, task, dataset=dataset.name, simulated=dataset.simulated
    )
    return save_figure(fig, path, dpi=110)


def _split(
    config: OrientationConfig, dataset: OrientationDataset
) -> tuple[OrientationDataset, OrientationDataset]:
    return split_by_subject(dataset, test_fraction=config.test_fraction, seed=config.split_seed)


def _nominal_criterion(config: OrientationConfig, dataset: OrientationDataset) -> dict[str, Any]:
    """Offline criterion of ``config.nominal`` fitted on the train split, scored on ``split``.

    The same :mod:`motion_envs.models.orientation_nominal` code builds the environments'
    nominal, so the zero-action policy of ``MotionEnvs/OrientationReach-v0`` reproduces
    this value.
    """
    assert config.nominal is not None
    train, test = _split(config, dataset)
    scored = {"train": train, "test": test, "all": dataset}[config.split]
    res = orientation_criterion(train, scored, nominal=config.nominal, degree=config.degree)
    return {
        "nominal": config.nominal,
        "degree": config.degree,
        "scored_on": config.split,
        "criterion": res["criterion"],
        "n_train": res["n_train"],
        "n_scored": res["n_test"],
        "n_unseen": res["n_unseen"],
    }


def run(config: OrientationConfig) -> OrientationResults:
    """Table 1 (and the nominal's criterion) for ``config``; no printing, no files.

    Raises ``ValueError`` for unusable data and :class:`~baselines.options.ConfigError`
    (naming the field) for a ``plot_task`` the data does not have, before computing.
    """
    t0 = time.perf_counter()
    dataset = load_orientation_dataset(config.data, min_deg=config.min_deg)
    if len(dataset) < 2:
        raise options.ConfigError(
            "min_deg",
            f"only {len(dataset)} trajectories left after dropping those under "
            f"{config.min_deg} degrees; lower --min-deg",
        )
    full = dataset
    if config.split != "all":
        dataset = _split(config, full)[config.split == "test"]
    if config.plot_task is not None and config.plot_task not in set(dataset.tasks.tolist()):
        raise options.ConfigError(
            "plot_task",
            f"task {config.plot_task!r} is not in the data; choose one of "
            f"{sorted(set(dataset.tasks.tolist()))}",
        )
    table = table1(dataset.ragged, dataset.subjects, dataset.tasks)
    elapsed = time.perf_counter() - t0
    nominal = _nominal_criterion(config, full) if config.nominal is not None else None
    return OrientationResults(config, dataset, table, nominal, elapsed)


def _nominal_text(config: OrientationConfig, nominal: dict[str, Any]) -> str:
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
    parts = [format_table1(results.table, results.dataset)]
    if results.nominal is not None:
        parts.append(_nominal_text(results.config, results.nominal))
    parts.append(f"\ncomputed in {results.seconds:.2f} s")
    return "\n".join(parts)


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
    return doc


def write(results: OrientationResults, out: str | Path) -> list[Path]:
    """Write ``results.json``, ``results.csv`` and ``residuals.png`` into ``out`` (atomic)."""
    folder = Path(out)
    return [
        atomic_write_text(folder / "results.json", json.dumps(document(results), indent=2) + "\n"),
        atomic_write_text(folder / "results.csv", results_csv(results.table)),
        plot_residuals(
            results.table, results.dataset, folder / "residuals.png", task=results.config.plot_task
        ),
    ]


def main(args: argparse.Namespace) -> int:
    """``motion-bench orientation`` with parsed arguments: run, print, write."""
    config = OrientationConfig(
        data=args.data,
        min_deg=args.min_deg,
        split=args.split,
        split_seed=args.split_seed,
        test_fraction=args.test_fraction,
        nominal=args.nominal,
        degree=args.degree,
        plot_task=args.plot_task,
    )
    results = run(config)
    print(report(results))
    if args.out is not None:
        written = write(results, args.out)
        print(f"wrote {', '.join(map(str, written[:-1]))} and {written[-1]}")
    return 0


def orientation_data(text: str) -> str:
    """``--data``: a built-in name, ``cohort:CONFIG`` or an existing CSV file."""
    if text in ORIENTATION_DATASETS or text.startswith("cohort:"):
        return text
    if not Path(text).exists():
        raise argparse.ArgumentTypeError(
            f"expected one of {list(ORIENTATION_DATASETS)}, 'cohort:CONFIG' or a CSV file; "
            f"{text} does not exist"
        )
    return str(options.input_file(text))


def register(subparsers: argparse._SubParsersAction[options.Parser]) -> None:
    """Add the ``orientation`` sub-command."""
    p = options.add_subcommand(
        subparsers,
        "orientation",
        help="Faraway & Choe Table 1 (orientation trajectories)",
        description=(
            "Compute Faraway & Choe's Table 1 (median over trajectories of the max over "
            "time of the slerp-residual error, radians) with the paper's value beside "
            "ours, plus leave-one-subject-out and leave-one-replicate-out rows."
        ),
    )
    p.add_argument(
        "--data",
        default="vr-kitchen",
        type=orientation_data,
        help=(
            f"built-in dataset ({', '.join(ORIENTATION_DATASETS)}; 'cohort' is the simulated "
            "cohort calibrated to the paper, 'cohort:CONFIG' another one, CONFIG a name under "
            "configs/cohorts/ or a YAML path) or a path to a CSV with "
            "columns trajectory,subject,task,t,qw,qx,qy,qz[,numeric predictors]"
        ),
    )
    p.add_argument(
        "--min-deg",
        type=options.non_negative_float,
        default=DEFAULT_MIN_DEG,
        help="drop trajectories rotating less than this many degrees from start to end",
    )
    p.add_argument(
        "--out",
        default=None,
        type=options.output_folder,
        help="folder for results.json, results.csv and residuals.png (nothing written without it)",
    )
    p.add_argument(
        "--plot-task",
        default=None,
        help="task whose residuals residuals.png shows (default: the most frequent task)",
    )
    p.add_argument(
        "--split",
        choices=SPLITS,
        default="all",
        help="compute Table 1 on all trajectories or on one side of a split by subject",
    )
    p.add_argument(
        "--split-seed",
        type=options.non_negative_int,
        default=0,
        help="seed of the split by subject",
    )
    p.add_argument(
        "--test-fraction",
        type=options.fraction,
        default=0.25,
        help="share of subjects held out for test",
    )
    p.add_argument(
        "--nominal",
        choices=ORIENTATION_NOMINALS,
        default=None,
        help=(
            "also report the criterion of this nominal model (as in the Gymnasium "
            "environments), fitted on the train split and scored on --split"
        ),
    )
    p.add_argument(
        "--degree", type=options.positive_int, default=2, help="Bezier degree of --nominal"
    )
    p.set_defaults(func=main)
