"""``motion-bench``: the benchmark command line.

Each sub-command lives in its own module exposing ``register(subparsers)``; this file
only assembles them. Run ``motion-bench --help`` or ``motion-bench CMD --help``.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence

# Modules providing sub-commands, in the order they are listed by --help.
SUBCOMMAND_MODULES: tuple[str, ...] = (
    "baselines.run_all",
    "baselines.orientation_bench",
    "baselines.position_bench",
    "baselines.calibrate_cohort",
    "baselines.agents.train",
    "baselines.agents.evaluate",
    "baselines.agents.sweep",
)


def build_parser() -> argparse.ArgumentParser:
    """Return the ``motion-bench`` argument parser with every sub-command registered."""
    parser = argparse.ArgumentParser(
        prog="motion-bench",
        description=(
            "Benchmark human-motion models against the papers' error criteria "
            "(Faraway & Choe 2008; Lippi, Avizzano & Ruffaldi 2011)."
        ),
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for name in SUBCOMMAND_MODULES:
        importlib.import_module(name).register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``motion-bench`` console script; returns the exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except (ValueError, FileNotFoundError) as exc:
        print(f"motion-bench {args.command}: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
