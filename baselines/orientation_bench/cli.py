"""The ``motion-bench orientation`` sub-command: argparse checkers, :func:`register` and
:func:`main` (build the config, run, print, write)."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from baselines import options
from baselines.learned import add_learned_option
from baselines.orientation_bench.config import SPLITS, OrientationConfig
from baselines.orientation_bench.media import write
from baselines.orientation_bench.runner import run
from baselines.orientation_bench.text import report
from baselines.verdicts import calibration_option
from motion_envs.datasets.registry import describe_names
from motion_envs.datasets.vr_kitchen import DEFAULT_MIN_DEG
from motion_envs.models.orientation_nominal import ORIENTATION_NOMINALS


def main(args: argparse.Namespace) -> int:
    """``motion-bench orientation`` with parsed arguments: run, print, write."""
    out = options.results_folder(args.out, f"orientation-{Path(args.data).stem}")
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
        calibration=args.calibration,
    )
    results = run(config)
    print(report(results))
    written = write(results, out)
    print(options.wrote(written))
    return 0


@options.reads_files
def orientation_data(text: str) -> str:
    """``--data``: a built-in name, ``cohort:CONFIG`` or an existing CSV file."""
    return options.data_file(text, "orientation")


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
            f"built-in dataset ({describe_names('orientation')}; 'cohort' is the simulated "
            "cohort calibrated to the paper, 'cohort:CONFIG' another one, CONFIG a name under "
            "configs/cohorts/ or a YAML path), a path to a CSV with "
            "columns trajectory,subject,task,t,qw,qx,qy,qz[,numeric predictors], or a "
            "recording 'FILE.c3d|.bvh|.tsv?option=value&...' with motion-bench import's "
            "options (docs/recordings.md)"
        ),
    )
    p.add_argument(
        "--min-deg",
        type=options.float_in(0.0, 180.0, "(degrees)"),
        default=DEFAULT_MIN_DEG,
        help="drop trajectories rotating less than this many degrees from start to end",
    )
    p.add_argument(
        "--out",
        default=None,
        type=options.output_folder,
        help="folder for results.json, results.csv and residuals.png (default: "
        "results/orientation-DATA, the folder of motion-bench all)",
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
    add_learned_option(
        p,
        "path-frame, predicted-timing and learned (ridge, torch MLP) leave-one-subject-out rows",
        "the MLP rows are skipped with a message when torch is not installed",
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
    p.add_argument(
        "--calibration",
        type=calibration_option,
        default=(),
        metavar="K,K,...",
        help="person-calibration rows for each K (a held-out person's reach predicted from K "
        "of their other reaches; docs/protocol.md), e.g. 1,3,5,10; default: none ('motion-bench "
        "all' uses 1,3,5,10)",
    )
    p.set_defaults(func=main)
