"""``motion-bench``: the benchmark command line.

Each sub-command lives in its own module exposing ``register(subparsers)`` and a pure
``run(config) -> results``; this file only assembles them and turns errors into one
line on stderr: usage errors (checked before any computation) and bad data exit with
status 2, other I/O errors with 1, Ctrl-C with 130. Run ``motion-bench --help`` or
``motion-bench CMD --help``.
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Sequence

from baselines import options

# Modules providing sub-commands, in the order they are listed by --help.
SUBCOMMAND_MODULES: tuple[str, ...] = (
    "baselines.run_all",
    "baselines.orientation_bench",
    "baselines.position_bench",
    "baselines.juggling_bench",
    "baselines.mocap_import",
    "baselines.calibrate_cohort",
    "baselines.agents.train",
    "baselines.agents.evaluate",
    "baselines.agents.sweep",
)


def build_parser() -> options.Parser:
    """Return the ``motion-bench`` argument parser with every sub-command registered."""
    from motion_envs import __version__  # here, so that Ctrl-C while importing is handled

    parser = options.Parser(
        prog="motion-bench",
        description=(
            "Benchmark human-motion models against the papers' error criteria "
            "(Faraway & Choe 2008; Lippi, Avizzano & Ruffaldi 2011)."
        ),
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for name in SUBCOMMAND_MODULES:
        importlib.import_module(name).register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``motion-bench`` console script; returns the exit code."""
    try:  # the imports of every sub-command and the checks of the options
        args = build_parser().parse_args(argv)
    except SystemExit as exc:  # --help, --version, usage errors (already printed)
        return exc.code if isinstance(exc.code, int) else 0 if exc.code is None else 2
    except KeyboardInterrupt:
        print("motion-bench: interrupted while starting; nothing was written", file=sys.stderr)
        return 130
    prog = f"motion-bench {args.command}"
    try:
        return int(args.func(args) or 0)
    except KeyboardInterrupt:
        print(f"{prog}: interrupted; files written so far are complete", file=sys.stderr)
        return 130
    except options.ConfigError as exc:
        return options.fail(prog, f"argument {options.option_name(exc.field)}: {exc.message}")
    except (ValueError, FileNotFoundError) as exc:
        return options.fail(prog, str(exc))
    except OSError as exc:
        return options.fail(prog, str(exc), status=1)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
