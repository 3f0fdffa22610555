"""``motion-bench orientation``: Faraway & Choe's Table 1 on real or the users' data.

:func:`run` computes (a pure function of an :class:`OrientationConfig`); :func:`report`
is the printed table, every criterion beside the paper's value; :func:`write` writes
``results.json``, ``results.csv`` and a residual plot in the style of the paper's
Figure 5. With at least 3 subjects, ``run`` adds the path-frame, predicted-timing and
learned leave-one-subject-out rows of :mod:`baselines.learned_rows` (``--learned``,
docs/learned.md); ``report`` prints a reading of learned against analytic and ``write``
adds ``learned_ratio.png``. :func:`register` adds the sub-command to ``motion-bench``.
"""

from __future__ import annotations

import argparse
import csv
import io
import json
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from baselines import options
from baselines.learned import LEARNED_MODES
from baselines.learned_rows import ROW_LABELS, LearnedRows
from motion_envs._io import atomic_write_text, save_figure
from motion_envs.datasets import ORIENTATION_DATASETS, OrientationDataset, load_orientation_dataset
from motion_envs.datasets.orientation import check_up
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
    learned:
        Budget of the path-frame, predicted-timing and learned rows, one of
        :data:`LEARNED_MODES`.
    up:
        The data's vertical axis for the path frame (None: the dataset's own, ``+y`` for
        vr-kitchen, ``+z`` for a CSV and the cohort).
    """

    data: str = "vr-kitchen"
    min_deg: float = DEFAULT_MIN_DEG
    split: str = "all"
    split_seed: int = 0
    test_fraction: float = 0.25
    nominal: str | None = None
    degree: int = 2
    plot_task: str | None = None
    learned: str = "full"
    up: tuple[float, float, float] | None = None


@dataclass(frozen=True)
class OrientationResults:
    """What :func:`run` returns: the scored dataset, Table 1 (with the learned rows
    appended to ``table.criteria``), the nominal's criterion and the learned rows.

    ``learned`` is None when the rows were not computed, ``learned_note`` then says why
    (None for ``--learned off``); ``comparisons`` are
    :func:`baselines.learned_rows.compare`'s readings.
    """

    config: OrientationConfig
    dataset: OrientationDataset
    table: Table1Result
    nominal: dict[str, Any] | None
    seconds: float
    learned: LearnedRows | None = None
    comparisons: list[dict[str, Any]] = field(default_factory=list)
    learned_note: str | None = None


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
    if name in ROW_LABELS:
        return ROW_LABELS[name]
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


def _learned_rows(
    config: OrientationConfig, dataset: OrientationDataset
) -> tuple[LearnedRows | None, str | None]:
    """The rows of :mod:`baselines.learned_rows` at ``config.learned``'s budget, or None
    and the reason they are skipped (too few subjects, scikit-learn missing)."""
    if config.learned == "off":
        return None, None
    n_subjects = np.unique(dataset.subjects).size
    if n_subjects < 3:
        return None, f"{n_subjects} subjects, at least 3 needed"
    from baselines.learned import mlp_config, sklearn_missing_reason, torch_missing_reason
    from baselines.learned_rows import learned_orientation_rows

    missing_sklearn = sklearn_missing_reason()
    if missing_sklearn:
        return None, missing_sklearn
    use_torch = torch_missing_reason() is None
    budget = mlp_config(config.learned) if use_torch else None
    return learned_orientation_rows(dataset, mlp_config=budget, use_torch=use_torch), None


def run(config: OrientationConfig) -> OrientationResults:
    """Table 1, the learned rows (and the nominal's criterion) for ``config``; no
    printing, no files.

    Raises ``ValueError`` for unusable data and :class:`~baselines.options.ConfigError`
    (naming the field) for a ``plot_task`` the data does not have or an ``up`` or
    ``learned`` that is not valid, before computing.
    """
    if config.learned not in LEARNED_MODES:
        raise options.ConfigError(
            "learned", f"expected one of {list(LEARNED_MODES)}; got {config.learned!r}"
        )
    if config.up is not None:
        try:
            check_up(config.up)
        except ValueError as exc:
            raise options.ConfigError("up", str(exc)) from None
    t0 = time.perf_counter()
    dataset = load_orientation_dataset(config.data, min_deg=config.min_deg, up=config.up)
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
    learned, note = _learned_rows(config, dataset)
    comparisons: list[dict[str, Any]] = []
    if learned is not None:
        from baselines.learned_rows import compare

        table.criteria.update(learned.criteria)
        comparisons = compare(learned, dataset.subjects)
    elapsed = time.perf_counter() - t0
    nominal = _nominal_criterion(config, full) if config.nominal is not None else None
    return OrientationResults(config, dataset, table, nominal, elapsed, learned, comparisons, note)


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
    if results.learned is not None:
        from baselines.learned_rows import format_reading

        parts.append(format_reading(results.learned, results.comparisons))
    elif results.learned_note is not None:
        parts.append(f"\nlearned rows skipped: {results.learned_note}")
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
    if results.learned is not None:
        doc["learned"] = {
            "mode": config.learned,
            "up": list(results.dataset.up),
            "comparisons": results.comparisons,
            "chosen": results.learned.chosen,
            "seconds": results.learned.seconds,
            "skipped": results.learned.skipped,
        }
    return doc


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
        from baselines.learned_rows import plot_ratios

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
        learned=args.learned,
        up=args.up,
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
    if (recording := options.mocap_data(text, "orientation")) is not None:  # FILE.c3d?opt=...
        return recording
    if not Path(text).exists():
        raise argparse.ArgumentTypeError(
            f"expected one of {list(ORIENTATION_DATASETS)}, 'cohort:CONFIG' or a CSV file; "
            f"{text} does not exist"
        )
    return str(options.input_file(text))


def up_option(text: str) -> tuple[float, float, float]:
    """``--up``: three finite numbers ``x,y,z``, not all zero (the data's vertical axis)."""
    parts = text.split(",")
    try:
        values = tuple(float(v) for v in parts)
    except ValueError:
        values = ()
    if len(values) != 3 or not all(math.isfinite(v) for v in values):
        raise argparse.ArgumentTypeError(f"expected three finite numbers 'x,y,z'; got {text!r}")
    if not any(values):
        raise argparse.ArgumentTypeError(f"expected a non-zero vector 'x,y,z'; got {text!r}")
    return (values[0], values[1], values[2])


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
            "configs/cohorts/ or a YAML path), a path to a CSV with "
            "columns trajectory,subject,task,t,qw,qx,qy,qz[,numeric predictors], or a "
            "recording 'FILE.c3d|.bvh|.tsv?option=value&...' with motion-bench import's "
            "options (docs/recordings.md)"
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
    p.add_argument(
        "--learned",
        choices=LEARNED_MODES,
        default="full",
        help=(
            "path-frame, predicted-timing and learned (ridge, torch MLP) leave-one-subject-"
            "out rows (docs/learned.md); quick: one MLP candidate, 30 epochs, 2 inner folds; "
            "off: none; the MLP rows are skipped with a message when torch is not installed"
        ),
    )
    p.add_argument(
        "--up",
        type=up_option,
        default=None,
        metavar="X,Y,Z",
        help="the data's vertical axis for the path frame (default: the dataset's; "
        "+z for a CSV and the cohort, +y for vr-kitchen); write --up=-1,0,0 when the first "
        "value is negative",
    )
    p.set_defaults(func=main)
