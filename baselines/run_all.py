"""``motion-bench all``: every benchmark on the built-in data, in one run.

Runs, one after the other, with each sub-command's defaults:

1. ``motion-bench orientation --data vr-kitchen``: Faraway & Choe's Table 1 on real
   hand-held controller orientations (8 people);
2. ``motion-bench orientation --data cohort``: the same table on the calibrated virtual
   cohort of the paper's design (simulated data);
3. ``motion-bench position --data lasa``: Lippi et al.'s sine-series regression against
   the line, the mean residual, DMP and ProMP on the real LASA handwriting set.

Each writes its tables, CSV/JSON and plot into a sub-folder of ``--out``; an index of
what was written goes to ``OUT/index.json`` and one self-contained page with every
table, the papers' values, the plots and a reading of each benchmark to
``OUT/report.html``.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

from motion_envs.models.serialization import atomic_write_text

__all__ = ["JOBS", "register", "run"]

#: ``(folder, title, argv)`` of each job, in order.
JOBS: tuple[tuple[str, str, tuple[str, ...]], ...] = (
    (
        "orientation-vr-kitchen",
        "Orientation trajectories on vr-kitchen (real data)",
        ("orientation", "--data", "vr-kitchen"),
    ),
    (
        "orientation-cohort",
        "Orientation trajectories on the virtual cohort (SIMULATED data, calibrated to the paper)",
        ("orientation", "--data", "cohort"),
    ),
    (
        "position-lasa",
        "Position trajectories on LASA handwriting (real data)",
        ("position", "--data", "lasa"),
    ),
)


def run(args: argparse.Namespace) -> int:
    """Run every job of :data:`JOBS`; returns the first non-zero exit code, else 0."""
    from baselines.cli import main

    out = Path(args.out)
    index = {"jobs": []}
    status = 0
    for folder, title, argv in JOBS:
        if args.only and folder not in args.only:
            continue
        print(f"\n{'=' * 100}\n{title}\n{'=' * 100}", flush=True)
        extra = ["--no-progress"] if args.no_progress and argv[0] == "position" else []
        t0 = time.perf_counter()
        rc = main([*argv, *extra, "--out", str(out / folder)])
        index["jobs"].append(
            {
                "folder": folder,
                "title": title,
                "command": "motion-bench " + " ".join([*argv, "--out", str(out / folder)]),
                "exit_code": rc,
                "seconds": round(time.perf_counter() - t0, 2),
            }
        )
        status = status or rc
    atomic_write_text(out / "index.json", json.dumps(index, indent=2) + "\n")
    from baselines.report import write_report

    report = write_report(out)
    print(f"\nall results are in {out}/ (index: {out / 'index.json'}; one page: {report})")
    return status


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``all`` sub-command."""
    p = subparsers.add_parser(
        "all",
        help="every benchmark on the built-in data (orientation: vr-kitchen and cohort; "
        "position: LASA)",
        description=__doc__.split("\n\n", 1)[1] if __doc__ else None,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("--out", default="results", help="folder for every job's results")
    p.add_argument(
        "--only",
        nargs="+",
        choices=[job[0] for job in JOBS],
        help="run only these jobs",
    )
    p.add_argument("--no-progress", action="store_true", help="no progress bars")
    p.set_defaults(func=run)
