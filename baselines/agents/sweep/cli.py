"""The ``motion-bench sweep`` sub-command: :func:`register` and its handler."""

from __future__ import annotations

import argparse
import os
import warnings
from pathlib import Path
from typing import Any

from baselines import options
from baselines.agents import checks
from baselines.agents.config import SWEEP_CONFIG_DIR
from baselines.agents.sweep.driver import SweepInterrupted, run
from baselines.agents.sweep.space import load_sweep
from baselines.agents.sweep.summary import format_table, write_results

DESCRIPTION = "motion-bench sweep: many configurations x seeds of motion-bench train on Ray Tune."


@options.reads_files
def sweep_file(text: str) -> Path:
    """``--config``: a sweep YAML file, or the name of a shipped one (``NAME`` for
    ``configs/sweeps/NAME.yaml``, packaged with ``baselines``) where no such file exists."""
    packaged = SWEEP_CONFIG_DIR / f"{text}.yaml"
    if "/" not in text and not Path(text).exists() and packaged.is_file():
        return checks.yaml_file(str(packaged))
    return checks.yaml_file(text)


def _cli(args: argparse.Namespace) -> int:
    warnings.filterwarnings("ignore", message=".*is out of date", category=DeprecationWarning)
    if args.num_cpus is not None and (args.address is not None or os.environ.get("RAY_ADDRESS")):
        raise options.ConfigError(
            "num_cpus", "applies to a local Ray only; omit it with --address or RAY_ADDRESS"
        )
    name = Path(args.config).stem
    sweep = load_sweep(
        args.config,
        out=str(args.out) if args.out is not None else f"sweeps/{name}",
        address=args.address,
        num_cpus=args.num_cpus,
        resume=args.resume,
        progress=args.verbose and not args.no_progress,
    )
    try:
        results = run(sweep)
    except SweepInterrupted as exc:
        return options.fail("motion-bench sweep", str(exc), status=130)
    out = Path(sweep.out)
    write_results(results, out)
    print(format_table(results))
    if results.get("lopo"):
        from baselines.agents.sweep.lopo import format_lopo

        print(format_lopo(results["lopo"]))
    print(
        f"{results['n_trials']} trials in {results['wall_seconds']:.0f} s; wrote "
        f"{out / 'results.json'}, trials.csv, table.csv, table.md, sweep.png"
    )
    return 0


def register(subparsers: Any) -> None:
    """Add ``motion-bench sweep``."""
    p = options.add_subcommand(
        subparsers,
        "sweep",
        help="configurations x seeds of motion-bench train on Ray Tune (local or a cluster)",
        description=DESCRIPTION,
    )
    p.add_argument(
        "--config", required=True, type=sweep_file, metavar="PATH",
        help="sweep file, e.g. configs/sweeps/orientation_ppo.yaml (or the name of a shipped "
        "one: orientation_ppo)",
    )  # fmt: skip
    p.add_argument("--address", default=None, help="existing Ray cluster (e.g. auto)")
    p.add_argument(
        "--num-cpus", type=options.positive_int, default=None,
        help="local Ray's CPUs (default: all)",
    )  # fmt: skip
    p.add_argument(
        "--out", default=None, type=options.output_folder, metavar="DIR",
        help="results folder (default: sweeps/NAME)",
    )  # fmt: skip
    p.add_argument(
        "--resume", action="store_true",
        help="continue the interrupted sweep in --out (or start it if --out holds none)",
    )  # fmt: skip
    p.add_argument(
        "--verbose", action="store_true",
        help="Ray's log lines and Ray Tune's status table (default: quiet; the results table "
        "is printed either way)",
    )  # fmt: skip
    p.add_argument(
        "--no-progress", action="store_true",
        help="no Ray Tune status table (the default; kept for scripts, overrides --verbose)",
    )  # fmt: skip
    p.set_defaults(func=_cli)
