"""The ``motion-bench position`` sub-command: argparse checkers, :func:`register` and
:func:`main` (build the config, run, print, write)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from baselines import options
from baselines.learned import add_learned_option
from baselines.peers import peers_missing_reason
from baselines.position_bench.config import PositionConfig
from baselines.position_bench.media import write
from baselines.position_bench.runner import run
from baselines.position_bench.text import report
from motion_envs.datasets.registry import describe_names
from motion_envs.datasets.splits import POSITION_SPLITS
from motion_envs.models.position_nominal import (
    CONDITION_KINDS,
)


def warn_missing_peers(use_peers: bool) -> None:
    """Say on stderr when the DMP and ProMP columns will be skipped."""
    missing = peers_missing_reason() if use_peers else None
    if missing:
        print(
            f"motion-bench position: movement_primitives cannot be used ({missing}); "
            "the DMP and ProMP columns are skipped",
            file=sys.stderr,
        )


def main(args: argparse.Namespace) -> int:
    """``motion-bench position`` with parsed arguments: run, print, write."""
    out = options.results_folder(args.out, f"position-{Path(args.data).stem}")
    warn_missing_peers(not args.no_peers)
    config = PositionConfig(
        data=args.data,
        shapes=tuple(args.shapes) if args.shapes else None,
        n_points=args.n_points,
        conditions=args.conditions,
        n_sines=args.n_sines,
        n_weights=args.n_weights,
        split=args.split,
        test_fraction=args.test_fraction,
        split_seed=args.split_seed,
        use_peers=not args.no_peers,
        progress=not args.no_progress,
        learned=args.learned,
    )
    doc = run(config)
    print(report(doc))
    written = write(doc, out)
    print(f"wrote {', '.join(map(str, written[:-1]))} and {written[-1]}")
    return 0


@options.reads_files
def position_data(text: str) -> str:
    """``--data``: a built-in position dataset (``lasa``), a recording or a position CSV."""
    return options.data_file(text, "position")


def n_sines_option(text: str) -> int | None:
    """``--n-sines``: ``auto`` (None, chosen by cross-validation) or an integer >= 0."""
    if text == "auto":
        return None
    try:
        return options.non_negative_int(text)
    except argparse.ArgumentTypeError:
        raise argparse.ArgumentTypeError(
            f"expected 'auto' or an integer >= 0; got {text!r}"
        ) from None


def conditions_option(text: str) -> tuple[str, ...]:
    """``--conditions``: a comma list of ``start``, ``end``, ``duration``."""
    kinds = tuple(k.strip() for k in text.split(",") if k.strip())
    bad = [k for k in kinds if k not in CONDITION_KINDS]
    if bad or not kinds:
        raise argparse.ArgumentTypeError(
            f"expected a comma list of {', '.join(CONDITION_KINDS)}; got {text!r}"
        )
    return kinds


def register(subparsers: argparse._SubParsersAction[options.Parser]) -> None:
    """Add the ``position`` sub-command."""
    p = options.add_subcommand(
        subparsers,
        "position",
        help="sine-series model (Lippi et al.) vs line, null, DMP, ProMP on LASA or a CSV",
        description=(
            "Leave one demonstration out per shape (task): every method is fitted on the\n"
            "other demonstrations of the shape and predicts the held-out one from its start,\n"
            "end and duration, on an --n-points grid of normalised time tau = t / T.\n"
            "Methods: line (start to end), null (line + mean residual), lippi (sine-series\n"
            "regression on --conditions, N by leave-one-out cross-validation), dmp and promp\n"
            "(movement_primitives, same start and goal). Criteria: max error (the papers'),\n"
            "RMSE, DTW, swept error area; median over a shape's demonstrations, then across\n"
            "shapes. ridge and mlp: learned residuals (ridge, torch MLP) of the conditions,\n"
            "every hyper-parameter chosen on the training demonstrations only (--learned).\n"
            "\n"
            "Position CSV (--data PATH): one row per sample, header required, extra\n"
            "columns ignored; columns trajectory,subject,task,t,x,y[,z]:\n"
            "- trajectory: an identifier; the rows of one trajectory are contiguous\n"
            "- subject, task: labels; a task is one shape, its trajectories the\n"
            "  demonstrations\n"
            "- t: seconds, strictly increasing within a trajectory\n"
            "- x, y[, z]: positions (any unit, the same for every row)\n"
            "\n"
            "Each trajectory needs at least 5 samples. Leave-one-out scores a shape with at\n"
            "least 3 demonstrations; with --n-sines auto or --learned (the default) it\n"
            "needs at least 4 (3 left to cross-validate on in every fold)."
        ),
    )
    p.add_argument(
        "--data",
        default="lasa",
        type=position_data,
        help=f"a built-in dataset ({describe_names('position')}), a position CSV path "
        "(format above), or a recording "
        "'FILE.c3d|.bvh|.tsv?option=value&...' with motion-bench import's options "
        "(docs/recordings.md)",
    )
    p.add_argument(
        "--shapes", nargs="+", default=None, help="shapes (LASA) or tasks (CSV); default: all"
    )
    p.add_argument(
        "--out",
        default=None,
        type=options.output_folder,
        help="folder for results.json/.csv and shapes.png (default: results/position-DATA, "
        "the folder of motion-bench all)",
    )
    p.add_argument(
        "--n-points", type=options.int_at_least(5), default=200, help="normalised-time grid size"
    )
    p.add_argument(
        "--n-sines", type=n_sines_option, default="auto", help="N, or 'auto' for cross-validation"
    )
    p.add_argument(
        "--conditions",
        type=conditions_option,
        default="start,end",
        help="comma list of start, end, duration",
    )
    p.add_argument(
        "--n-weights", type=options.positive_int, default=10, help="DMP/ProMP weights per dimension"
    )
    p.add_argument(
        "--split",
        choices=POSITION_SPLITS,
        default="loo",
        help="loo: leave one demonstration out per shape; test/train: fit on each shape's "
        "training demonstrations (split_by_replicate) and score the test/train ones, as "
        "PositionReach-v0's split",
    )
    p.add_argument(
        "--test-fraction",
        type=options.fraction,
        default=0.25,
        help="held-out share per shape (test/train)",
    )
    p.add_argument(
        "--split-seed", type=options.non_negative_int, default=0, help="seed of the per-shape split"
    )
    p.add_argument("--no-peers", action="store_true", help="skip DMP and ProMP")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    add_learned_option(
        p,
        "budget of the learned ridge and torch-MLP columns",
        "the mlp column is skipped with a message when torch is not installed",
    )
    p.set_defaults(func=main)
