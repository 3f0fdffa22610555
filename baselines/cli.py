"""``motion-bench``: the benchmark command line.

Each sub-command lives in its own module exposing ``register(subparsers)`` and a pure
``run(config) -> results``; this file only assembles them and turns errors into one
line on stderr: usage errors (checked before any computation), bad data and a missing
optional dependency (the line names the extra to install, :data:`EXTRA_OF_MODULE`) exit
with status 2, other I/O errors with 1, Ctrl-C with 130. Run ``motion-bench --help`` or
``motion-bench CMD --help``.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import signal
import sys
from collections.abc import Callable, Iterator, Sequence
from typing import Any

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


#: The optional modules sub-commands import, by top-level name: ``(extra of
#: pyproject.toml, distribution)`` (a sub-command that lacks one says which extra to
#: install; tests/test_cli_extras.py checks the table against pyproject.toml).
EXTRA_OF_MODULE: dict[str, tuple[str, str]] = {
    "stable_baselines3": ("rl", "stable-baselines3"),
    "torch": ("rl", "torch"),
    "rich": ("rl", "rich"),
    "tensorboard": ("rl", "tensorboard"),
    "sklearn": ("learned", "scikit-learn"),
    "safetensors": ("learned", "safetensors"),
    "movement_primitives": ("peers", "movement-primitives"),
    "pytransform3d": ("peers", "pytransform3d"),
    "ray": ("sweep", "ray"),
    "optuna": ("sweep", "optuna"),
    "numba": ("fast", "numba"),
    "ezc3d": ("mocap", "ezc3d"),
    "pybvh": ("mocap", "pybvh"),
}


def missing_extra(exc: ModuleNotFoundError) -> str | None:
    """The one-line message for an optional module that is not installed (``None`` for
    any other missing module: a bug, left to its traceback)."""
    top = (exc.name or "").split(".")[0]
    if top not in EXTRA_OF_MODULE:
        return None
    extra, dist = EXTRA_OF_MODULE[top]
    return (
        f"needs {dist} (the {extra!r} extra), which is not installed; from the project's "
        f'folder: pip install -e ".[{extra}]"'
    )


#: s between re-deliveries of a Ctrl-C that the running code has not yet let through.
REDELIVERY_INTERVAL = 0.1


@contextlib.contextmanager
def interrupts_delivered() -> Iterator[dict[str, bool]]:
    """Ctrl-C raises ``KeyboardInterrupt`` until a caller catches it.

    Python raises it wherever the main thread is when the signal arrives; if that is a
    weakref callback or a ``__del__`` run by the garbage collector, Python prints
    "Exception ignored" and the job runs on (seen: ``motion-bench all`` finishing a 13 s
    job after Ctrl-C). Here a SIGINT is remembered and raised again every
    :data:`REDELIVERY_INTERVAL` s (``SIGALRM``) until the ``with`` block's caller sets
    ``state["caught"]``, and the swallowed one is not reported. Where there is no
    ``setitimer`` (Windows) or outside the main thread, Python's own handling is left
    as it is."""
    state = {"pending": False, "caught": False}
    if not hasattr(signal, "setitimer"):
        yield state
        return
    try:
        old_int = signal.getsignal(signal.SIGINT)
        old_alrm = signal.getsignal(signal.SIGALRM)
        if old_int is signal.SIG_IGN:  # an inherited "ignore": keep it
            yield state
            return

        def raise_pending(signum: int, frame: Any) -> None:
            if state["pending"] and not state["caught"]:
                raise KeyboardInterrupt

        def on_sigint(signum: int, frame: Any) -> None:
            state["pending"] = True
            signal.setitimer(signal.ITIMER_REAL, REDELIVERY_INTERVAL, REDELIVERY_INTERVAL)
            raise KeyboardInterrupt

        signal.signal(signal.SIGALRM, raise_pending)
        signal.signal(signal.SIGINT, on_sigint)
    except ValueError:  # not the main thread
        yield state
        return
    old_hook = sys.unraisablehook

    def quiet_swallowed(unraisable: Any) -> None:
        """The swallowed interrupt is raised again: no "Exception ignored" report."""
        if not (state["pending"] and isinstance(unraisable.exc_value, KeyboardInterrupt)):
            old_hook(unraisable)

    sys.unraisablehook = quiet_swallowed
    try:
        yield state
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0.0)
        signal.signal(signal.SIGINT, old_int)
        signal.signal(signal.SIGALRM, old_alrm)
        sys.unraisablehook = old_hook


def run_command(prog: str, func: Callable[[Any], Any], args: Any) -> int:
    """``func(args)`` as an exit status: Ctrl-C (:func:`interrupts_delivered`) 130, usage
    and data errors 2, other I/O errors 1, each with one line on stderr."""
    with interrupts_delivered() as state:
        try:
            return int(func(args) or 0)
        except KeyboardInterrupt:
            state["caught"] = True
            print(f"{prog}: interrupted; files written so far are complete", file=sys.stderr)
            return 130
        except options.ConfigError as exc:
            return options.fail(prog, f"argument {options.option_name(exc.field)}: {exc.message}")
        except ModuleNotFoundError as exc:
            message = missing_extra(exc)
            if message is None:
                raise
            return options.fail(prog, message)
        except (ValueError, FileNotFoundError) as exc:
            return options.fail(prog, str(exc))
        except OSError as exc:
            return options.fail(prog, str(exc), status=1)


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``motion-bench`` console script; returns the exit code."""
    try:  # the imports of every sub-command and the checks of the options
        parser = build_parser()
        args = parser.parse_args(argv)
    except SystemExit as exc:  # --help, --version, usage errors (already printed)
        return exc.code if isinstance(exc.code, int) else 0 if exc.code is None else 2
    except KeyboardInterrupt:
        print("motion-bench: interrupted while starting; nothing was written", file=sys.stderr)
        return 130
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    command = sub.choices[args.command]

    def guarded(args: Any) -> Any:
        with options.guarded_outputs(command, args):
            return args.func(args)

    return run_command(f"motion-bench {args.command}", guarded, args)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
