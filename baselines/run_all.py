"""``motion-bench all``: every benchmark on the built-in data, in one run.

Runs, one after the other, with each sub-command's defaults:

1. ``motion-bench orientation --data vr-kitchen``: Faraway & Choe's Table 1 on real
   hand-held controller orientations (8 people);
2. ``motion-bench orientation --data cohort --learned off``: the same table on the
   calibrated virtual cohort of the paper's design (simulated data; without the learned
   rows, which would train 20 x nested folds on 1,000+ trajectories: run
   ``motion-bench orientation --data cohort`` for them);
3. ``motion-bench position --data lasa``: Lippi et al.'s sine-series regression against
   the line, the mean residual, DMP and ProMP on the real LASA handwriting set;
4. ``motion-bench juggling``: the analytic juggler of Lippi et al.'s section III-A on
   SIMULATED demonstrations (catch rates, per-phase errors, validation statistics);
5. ``motion-bench juggling --levels easy,medium,hard``: Juggling-v1's levels, the
   analytic juggler seeing the ball late against its latency-aware variant and two
   trivial policies (200 test episodes per level and method).

The orientation and position jobs include the learned rows and columns
(docs/learned.md) at the full budget; ``--learned quick`` or ``off`` lowers the budget of
every job.

Before each long job a line gives its cost measured beforehand (the CPU time of the
job at the default settings, with how and where it was measured; the wall time depends
on the machine and its load). Each writes its tables, CSV/JSON and plot into a
sub-folder of ``--out``; an index of what was written goes to ``OUT/index.json``,
rewritten after every job (``"complete": false`` until the last one is done), so an
interrupted run leaves an index that lists exactly the jobs whose files are new. Every
file is written atomically: a previous result is never left half-written. After the
last job, one self-contained page with every table, the papers' values, the plots and a
reading of each benchmark goes to ``OUT/report.html``.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from baselines import juggling_bench, options, orientation_bench, position_bench
from baselines.learned import LEARNED_MODES, add_learned_option
from baselines.report import write_report
from motion_envs._io import atomic_write_text
from motion_envs.models.person_calibration import DEFAULT_CALIBRATION

__all__ = ["JOBS", "AllConfig", "Job", "register", "run"]


#: How the jobs' ``cpu_seconds`` were measured: the command, the machine, the date.
MEASURED = (
    "user + sys of `motion-bench all --no-progress` per job, 2026-12-06, a 2-core AMD EPYC "
    "VM shared with other jobs (170 s in all; the vr-kitchen job re-measured with both "
    "response modes)"
)
#: A job whose measured cost is at least this many CPU seconds gets an estimate line.
LONG_JOB_CPU_SECONDS = 10.0


@dataclass(frozen=True)
class Job:
    """One benchmark of ``motion-bench all``: its folder, title and sub-command config;
    ``cpu_seconds`` its CPU time at the default settings (:data:`MEASURED`)."""

    folder: str
    title: str
    config: (
        orientation_bench.OrientationConfig
        | position_bench.PositionConfig
        | juggling_bench.JugglingConfig
        | juggling_bench.LevelsConfig
    )
    cpu_seconds: float = 0.0

    def estimate(self, learned: str) -> str | None:
        """The line printed before a long job: its measured CPU time (``None`` for a
        short job)."""
        if self.cpu_seconds < LONG_JOB_CPU_SECONDS:
            return None
        budget = "" if learned == "full" else f" at --learned full (less at {learned})"
        return (
            f"estimate: about {self.cpu_seconds:.0f} s of CPU time{budget}, measured as "
            f"{MEASURED}; the wall time depends on the machine's load"
        )

    def command(self, out: Path) -> str:
        """The equivalent ``motion-bench`` command line (recorded in the index)."""
        if isinstance(self.config, orientation_bench.OrientationConfig):
            head = f"orientation --data {self.config.data}"
        elif isinstance(self.config, juggling_bench.JugglingConfig):
            head = "juggling"
        elif isinstance(self.config, juggling_bench.LevelsConfig):
            head = f"juggling --levels {','.join(self.config.levels)}"
        else:
            head = f"position --data {self.config.data}"
        if isinstance(
            self.config, orientation_bench.OrientationConfig | position_bench.PositionConfig
        ):
            if self.config.learned != "full":
                head += f" --learned {self.config.learned}"
        return f"motion-bench {head} --out {out / self.folder}"

    def with_learned(self, learned: str) -> Job:
        """This job with the learned budget lowered to ``learned`` (``full`` leaves it;
        a job already at ``off`` stays off; the juggling job has no learned rows)."""
        config = self.config
        if learned == "full" or not isinstance(
            config, orientation_bench.OrientationConfig | position_bench.PositionConfig
        ):
            return self
        if config.learned == "off":
            return self
        return dataclasses.replace(self, config=dataclasses.replace(config, learned=learned))


#: The jobs, in order.
JOBS: tuple[Job, ...] = (
    Job(
        "orientation-vr-kitchen",
        "Orientation trajectories on vr-kitchen (real data)",
        orientation_bench.OrientationConfig(data="vr-kitchen", calibration=DEFAULT_CALIBRATION),
        cpu_seconds=43.0,  # both response modes (648 reaches); measured idle on 2026-12-06
    ),
    Job(
        "orientation-cohort",
        "Orientation trajectories on the virtual cohort (SIMULATED data, calibrated to the paper)",
        orientation_bench.OrientationConfig(data="cohort", learned="off"),
        cpu_seconds=0.5,
    ),
    Job(
        "position-lasa",
        "Position trajectories on LASA handwriting (real data)",
        position_bench.PositionConfig(data="lasa"),
        cpu_seconds=37.0,
    ),
    Job(
        "juggling",
        "Juggling: the analytic juggler (SIMULATED demonstrations, MuJoCo scene)",
        juggling_bench.JugglingConfig(),
        cpu_seconds=10.0,
    ),
    Job(
        "juggling_v1-levels",
        "Juggling-v1 levels: the analytic juggler with a delayed view of the ball, "
        "its latency-aware variant and two trivial policies (SIMULATED demonstrations)",
        juggling_bench.LevelsConfig(),
        cpu_seconds=34.0,
    ),
)


@dataclass(frozen=True)
class AllConfig:
    """``out``: the results folder; ``only``: job folders to run (None: all);
    ``progress``: progress bars of the position job; ``learned``: the budget of the
    learned rows and columns of every job (``full``, ``quick`` or ``off``)."""

    out: Path = Path("results")
    only: tuple[str, ...] | None = None
    progress: bool = True
    learned: str = "full"


def _run_job(job: Job, out: Path, progress: bool, echo: Callable[[str], Any]) -> None:
    config = job.config
    if isinstance(config, orientation_bench.OrientationConfig):
        results = orientation_bench.run(config)
        echo(orientation_bench.report(results))
        written = orientation_bench.write(results, out / job.folder)
    elif isinstance(config, juggling_bench.JugglingConfig):
        doc = juggling_bench.run(dataclasses.replace(config, progress=progress))
        echo(juggling_bench.report(doc))
        written = juggling_bench.write(doc, out / job.folder)
    elif isinstance(config, juggling_bench.LevelsConfig):
        doc = juggling_bench.run_levels(config)
        echo(juggling_bench.report_levels(doc))
        written = juggling_bench.write_levels(doc, out / job.folder)
    else:
        position_bench.warn_missing_peers(config.use_peers)
        doc = position_bench.run(
            position_bench.PositionConfig(**{**config.__dict__, "progress": progress})
        )
        echo(position_bench.report(doc))
        written = position_bench.write(doc, out / job.folder)
    echo(options.wrote(written))


def run(config: AllConfig, echo: Callable[[str], Any] = lambda text: None) -> dict[str, Any]:
    """Run the jobs of ``config``; returns the index (also written to ``OUT/index.json``).

    Unlike the other sub-commands' ``run``, this one writes: its results are the jobs'
    files. ``echo`` receives the text the CLI prints. A job failing on bad data is
    recorded with ``exit_code`` 2 and its message, and the next job runs.
    """
    if config.learned not in LEARNED_MODES:
        raise options.ConfigError(
            "learned",
            f"expected one of {list(LEARNED_MODES)}; got {config.learned!r}",
        )
    out = Path(config.out)
    index: dict[str, Any] = {"jobs": [], "complete": False}
    for job in (job.with_learned(config.learned) for job in JOBS):
        if config.only and job.folder not in config.only:
            continue
        echo(f"\n{'=' * 100}\n{job.title}\n{'=' * 100}")
        if (line := job.estimate(config.learned)) is not None:
            echo(line)
        t0, cpu0 = time.perf_counter(), time.process_time()
        entry: dict[str, Any] = {
            "folder": job.folder,
            "title": job.title,
            "command": job.command(out),
            "exit_code": 0,
        }
        try:
            _run_job(job, out, config.progress, echo)
        except (ValueError, OSError) as exc:
            print(f"motion-bench all: {job.folder}: error: {exc}", file=sys.stderr)
            entry["exit_code"] = 2
            entry["error"] = str(exc)
        entry["seconds"] = round(time.perf_counter() - t0, 2)
        entry["cpu_seconds"] = round(time.process_time() - cpu0, 2)
        index["jobs"].append(entry)
        atomic_write_text(out / "index.json", json.dumps(index, indent=2) + "\n")
    index["complete"] = True
    atomic_write_text(out / "index.json", json.dumps(index, indent=2) + "\n")
    report = write_report(out)
    echo(f"\nall results are in {out}/ (index: {out / 'index.json'}; one page: {report})")
    return index


def main(args: argparse.Namespace) -> int:
    """``motion-bench all`` with parsed arguments; the first failing job's code, else 0."""
    config = AllConfig(
        out=args.out,
        only=tuple(args.only) if args.only else None,
        progress=not args.no_progress,
        learned=args.learned,
    )
    index = run(config, echo=lambda text: print(text, flush=True))
    return next((job["exit_code"] for job in index["jobs"] if job["exit_code"]), 0)


def register(subparsers: argparse._SubParsersAction[options.Parser]) -> None:
    """Add the ``all`` sub-command."""
    p = options.add_subcommand(
        subparsers,
        "all",
        help="every benchmark on the built-in data (orientation: vr-kitchen and cohort; "
        "position: LASA; juggling: SIMULATED)",
        description=__doc__.split("\n\n", 1)[1].replace("``", "") if __doc__ else "",
    )
    p.add_argument(
        "--out",
        default="results",
        type=options.output_folder,
        help="folder for every job's results",
    )
    p.add_argument(
        "--only",
        nargs="+",
        choices=[job.folder for job in JOBS],
        metavar="JOB",
        help=f"run only these jobs, among {', '.join(job.folder for job in JOBS)} (default: all)",
    )
    p.add_argument("--no-progress", action="store_true", help="no progress bars")
    add_learned_option(
        p,
        "budget of the learned rows and columns of every job",
        "the cohort job runs with the learned rows off",
    )
    p.set_defaults(func=main)
