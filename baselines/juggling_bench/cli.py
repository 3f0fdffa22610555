"""The ``motion-bench juggling`` sub-command: argparse checkers, :func:`register` and
:func:`main` (build the config, run, print, write)."""

from __future__ import annotations

import argparse
import math
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from baselines import options
from baselines.agents.checks import run_folder
from baselines.juggling_bench.analyse import (
    AnalyseConfig,
    report_analysis,
    run_analysis,
    write_analysis,
)
from baselines.juggling_bench.cascade import (
    CascadeConfig,
    report_cascade,
    run_cascade,
    write_cascade,
)
from baselines.juggling_bench.cascade_v1 import (
    CascadeV1Config,
    report_cascade_v1,
    run_cascade_v1,
    write_cascade_v1,
)
from baselines.juggling_bench.config import JugglingConfig
from baselines.juggling_bench.levels import LevelsConfig, report_levels, run_levels, write_levels
from baselines.juggling_bench.media import write
from baselines.juggling_bench.runner import run
from baselines.juggling_bench.text import report
from baselines.juggling_bench.v2 import V2Config, report_v2, run_v2, write_v2
from motion_envs.datasets.juggling import (
    JugglingTask,
    format_siteswap,
    parse_siteswap,
    siteswap_balls,
)
from motion_envs.datasets.registry import describe_names
from motion_envs.models.juggling import LEVELS, PATTERNS, V2_LEVELS

#: A benchmark's run, report and write functions.
Bench = tuple[Callable[[Any], Any], Callable[[Any], str], Callable[[Any, Path], Any]]


def _levels_benchmark(
    args: argparse.Namespace, config_class: Any, bench: Bench, folder: str, **fields: Any
) -> int:
    """A levels benchmark (``--levels``, ``--version v2``, ``--pattern``): its config from
    ``--levels``, ``--episodes`` and ``--max-catches`` (the config's defaults where not
    given) and ``fields``; ``bench`` = (run, report, write): run, print, write to
    ``folder`` (under results/ unless ``--out``)."""
    run_bench, report_bench, write_bench = bench
    config = config_class(
        levels=args.levels or config_class.levels,
        episodes=args.episodes or config_class.episodes,
        max_catches=args.max_catches or config_class.max_catches,
        **fields,
    )
    doc = run_bench(config)
    print(report_bench(doc))
    print(options.wrote(write_bench(doc, options.results_folder(args.out, folder))))
    return 0


def main(args: argparse.Namespace) -> int:
    """``motion-bench juggling`` with parsed arguments: run, print, write (the levels of
    Juggling-v1 with ``--levels``, a recording's ball flights with ``--analyse``, the
    three-ball cascade with ``--pattern``)."""
    if args.analyse is not None:
        if args.levels is not None:
            return options.fail("motion-bench juggling", "--analyse: not with --levels")
        out = options.results_folder(args.out, "juggling-analyse")
        analysis = run_analysis(AnalyseConfig(source=args.analyse, balls=args.n_balls))
        print(report_analysis(analysis))
        print(options.wrote(write_analysis(analysis, out)))
        return 0
    if args.n_balls is not None:
        return options.fail("motion-bench juggling", "--n-balls: needs --analyse")
    if args.pick_episodes is not None and args.version != "v2":
        return options.fail("motion-bench juggling", "--pick-episodes: needs --version v2")
    # --version v2's pick of the best non-oracle row (the config's default when not given)
    pick = {} if args.pick_episodes is None else {"pick_episodes": args.pick_episodes}
    if args.pattern is not None:
        if args.agent is not None:
            return options.fail("motion-bench juggling", "--agent: not with --pattern")
        if args.version == "v2":  # Cascade-v1's reference rows
            config_class: Any = CascadeV1Config
            bench: Bench = (run_cascade_v1, report_cascade_v1, write_cascade_v1)
            folder = f"juggling-v2-pattern-{args.pattern}"
        else:
            config_class, bench = CascadeConfig, (run_cascade, report_cascade, write_cascade)
            folder = f"juggling-pattern-{args.pattern}"
        fields = {"pattern": args.pattern, **(pick if args.version == "v2" else {})}
        return _levels_benchmark(args, config_class, bench, folder, **fields)
    if args.version == "v2":
        if args.agent is not None:
            return options.fail("motion-bench juggling", "--agent: not with --version v2")
        bench = (run_v2, report_v2, write_v2)
        return _levels_benchmark(args, V2Config, bench, "juggling-v2", **pick)
    if args.levels is None:
        if args.agent is not None:
            return options.fail("motion-bench juggling", "--agent: needs --levels")
    else:
        agent = None if args.agent is None else str(args.agent)
        return _levels_benchmark(
            args, LevelsConfig, (run_levels, report_levels, write_levels), "juggling-levels",
            agent=agent,
        )  # fmt: skip
    out = options.results_folder(args.out, "juggling")
    config = JugglingConfig(
        cycles=args.cycles,
        noise=args.noise,
        tracking=args.tracking,
        seed=args.seed,
        data=args.data,
        progress=not args.no_progress,
        use_dmp=not args.no_dmp,
        world=args.world,
        demo_cycles=args.demo_cycles,
        demo_persons=args.demo_persons,
        mujoco_cycles=args.mujoco_cycles,
        mujoco_noise_cycles=args.mujoco_cycles // 4,
        task=args.gravity,
    )
    t0 = time.perf_counter()
    doc = run(config)
    doc["timing"]["total_s"] = time.perf_counter() - t0
    print(report(doc))
    paths = write(doc, out, video=not args.no_video)
    print(options.wrote(paths))
    print(f"total {doc['timing']['total_s']:.1f} s")
    return 0


def noise_levels(text: str) -> tuple[float, ...]:
    """``--noise``: a comma list of finite numbers in [0, 1) (relative std)."""
    what = f"a comma list of numbers in [0, 1) (e.g. 0.05,0.1); got {text!r}"
    try:
        levels = tuple(float(v) for v in text.split(",") if v.strip())
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected {what}") from None
    if not levels or not all(math.isfinite(v) and 0 <= v < 1 for v in levels):
        raise argparse.ArgumentTypeError(f"expected {what}")
    return levels


#: ``--gravity``'s range (m/s^2): the default 1.0 (the paper's phase sizes) to beyond
#: Jupiter's 24.8; outside it the phase timings under- or overflow.
GRAVITY_RANGE = (0.1, 100.0)
#: ``--tracking``'s range (m): tracking noise std up to 10 cm.
TRACKING_RANGE = (0.0, 0.1)


def level_names(text: str) -> tuple[str, ...]:
    """``--levels``: a comma list of Juggling-v1's levels (easy, medium, hard) or
    Juggling-v2's (also ``drift``; which version's is checked by its config)."""
    names = tuple(v.strip() for v in text.split(",") if v.strip())
    known = list(dict.fromkeys([*LEVELS, *V2_LEVELS]))
    bad = [n for n in names if n not in known]
    if not names or bad or len(set(names)) != len(names):
        raise argparse.ArgumentTypeError(
            f"expected a comma list of distinct levels among {known}; got {text!r}"
        )
    return names


def siteswap_pattern(text: str) -> str:
    """``--pattern``: a registered pattern's name
    (:data:`motion_envs.models.juggling.PATTERNS`) or a valid vanilla siteswap (lower
    case; whether the cascade juggler can play it is
    :func:`.cascade.check_cascade_config`'s)."""
    if text in PATTERNS:
        return text
    try:
        throws = parse_siteswap(text)
        siteswap_balls(throws)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    return format_siteswap(throws)


def gravity_task(text: str) -> JugglingTask:
    """``--gravity``: a finite number in :data:`GRAVITY_RANGE` (m/s^2), as the task it
    defines."""
    value = options.float_in(*GRAVITY_RANGE, "(m/s^2)")(text)
    try:
        return JugglingTask(gravity=value)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


@options.reads_files
def juggling_data(text: str) -> str:
    """``--data``: a built-in juggling dataset (``simulated``), a recording or an existing,
    readable juggling CSV with ``t,x,z``.

    Only the header line is read here (the rows are checked when the run loads them).
    """
    if options.builtin_data(text, "juggling"):
        return text
    if (recording := options.mocap_data(text, "juggling")) is not None:  # FILE.c3d?opt=...
        return recording
    return options.csv_with_columns(
        text, ("t", "x", "z"), "t,x,z[,ball_x,ball_z][,phase][,recording]"
    )


@options.reads_files
def analyse_source(text: str) -> str:
    """``--analyse``: a juggling CSV with ``ball_x, ball_z``, or a C3D/BVH/TSV file with
    ``?ball=NAME[,NAME...]`` or ``?balls=unlabelled`` (and the import's other options).

    Only the name, the options and a CSV's header line are checked here."""
    from motion_envs.datasets.mocap import is_mocap_source, parse_source

    if is_mocap_source(text):
        try:
            path, opts = parse_source(text)
        except (ValueError, FileNotFoundError) as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None
        options.input_file(str(path))
        if opts.ball is None and opts.balls != "unlabelled":
            raise argparse.ArgumentTypeError(
                f"{path}: give the ball markers (FILE?ball=NAME[,NAME...]) or FILE?balls=unlabelled"
            )
        return text
    return options.csv_with_columns(
        text,
        ("t", "ball_x", "ball_z"),
        "t,x,z,ball_x,ball_z[,recording] (or give a .c3d/.bvh/.tsv recording)",
    )


DESCRIPTION = """\
The analytic juggler of Lippi, Avizzano & Ruffaldi (section III-A). Demonstrations are
SIMULATED by default (a seeded model of a person; the paper's recordings are not public)
or read from a juggling CSV (--data). They are split by demonstration (cycle): the
juggler is fitted on the training cycles only (N per phase by cross-validation inside
them) and scored on the held-out ones.

Reported: the catch rate of --cycles seeded cycles, unperturbed and with release noise
(--noise) plus tracking noise (--tracking), each with and without the eq. 10
correction; per phase, on the held-out demonstrations, the median over demonstrations of
the max over time of the position error (and of the RMSE) for Lippi's regression,
minimum jerk and a DMP, next to the within-person variability; the paper's validation of
the linear hypothesis; a Figure-6-style plot and a GIF of the juggler (with --out).

With --levels easy,medium,hard: Juggling-v1 instead (real gravity, contacts, an actuated
hand, the ball seen 0 / 100 / 110 ms late with measurement and release noise). Per level,
--episodes test-seed episodes of each controller: the analytic juggler (eq. 9 toss, eq. 10
correction from the delayed measurement), the same juggler predicting the flight forward
by the known delay, a fixed catch point, minimum jerk to the intercept predicted from the
commanded release velocity, and with --agent DIR a trained agent's residual on the same
seeds. Reported: catch rate with a 95 % bootstrap interval, consecutive catches before
the first drop (median), the hand's deviation from held-out demonstrations (SIMULATED).

With --analyse FILE: the ball flights and the juggling pattern of a recording (a
juggling CSV with ball_x, ball_z, or a motion capture file with its import options
after ?, e.g. 'session.tsv?balls=unlabelled&up=y'; lengths in metres after the unit):
per flight the fitted gravity, apex and flight time; releases and catches where a ball
leaves and joins a hand (never at a tracking loss or a marker swap); the across-body
axis from the data, the hands, the throw period, dwell ratio, each throw's value and the
siteswap, the balls by the siteswap, Shannon's theorem and the balls in the air and
hands at once; warnings where the recording does not fit (vanilla asynchronous
juggling, reflective balls). results.json, flights.csv and flights.png (heights,
gravity, ladder diagram) in --out; docs/recordings.md.

With --pattern P (a registered pattern: 3 and 3-human, the three-ball cascade of the
fitted cascade juggler; 5, 4, 441, 531, 423, 51, the siteswap juggler's, each throw value
on its own flight): MotionEnvs/Cascade-v0 (two hands, the pattern's balls, Juggling-v1's
physics, sensor and levels, the timing of Shannon's juggling theorem). Per level,
--episodes (50) test-seed episodes of the analytic juggler, its
latency-aware variant and the two trivial catches, each ending at the first drop or after
--max-catches (10) catches. Reported with 95 % bootstrap intervals: catches before the
first drop (median), catch rate, time to the first drop (SIMULATED demonstrations).
Another siteswap (e.g. 5 or 441) is checked at the cascade juggler's tempo and refused
with the reasons it does not fit (ball count, flight, the hand's speed limit).

With --version v2 --pattern P: MotionEnvs/Cascade-v1 instead (the pattern at Juggling-v2's
human levels easy, medium, hard: a hidden per-episode delay, a position-only camera per
ball, drag per ball, the capture at impact). Per level, the late-meeting offset and the
best non-oracle row are chosen on validation episodes (the grids on 30, the best row
on --pick-episodes, 200), then --episodes (100) test
episodes of each row (the juggler, the oracle given the true delay and drag, the
mean-delay juggler, late meeting, a fixed catch point, random actions), each ending at
the first drop or after --max-catches (30) catches. Reported with 95 % bootstrap
intervals: catches before the first drop (median and mean), catch rate, and the paired
oracle minus best row (SIMULATED demonstrations)."""


def register(subparsers: argparse._SubParsersAction[options.Parser]) -> None:
    """Add the ``juggling`` sub-command."""
    p = options.add_subcommand(
        subparsers,
        "juggling",
        help="the analytic juggler (Lippi et al. III-A): catch rates, per-phase errors vs "
        "minimum jerk and DMP, validation statistics (SIMULATED demonstrations by default)",
        description=DESCRIPTION,
    )
    p.add_argument(
        "--cycles", type=options.positive_int, default=1000, help="seeded juggling cycles per run"
    )
    p.add_argument(
        "--noise",
        type=noise_levels,
        default="0.05,0.10",
        help="release-velocity noise levels (relative std), comma-separated",
    )
    p.add_argument(
        "--tracking",
        type=options.float_in(*TRACKING_RANGE, "(m)"),
        default=0.0005,
        help="tracking noise std (m), in [0, 0.1]",
    )
    p.add_argument(
        "--seed",
        type=options.non_negative_int,
        default=0,
        help="seed of data, split and cycles (default: 0)",
    )
    p.add_argument(
        "--data",
        type=juggling_data,
        default=None,
        help=(
            f"a juggling CSV, a recording, or a built-in dataset ({describe_names('juggling')}; "
            "default: the SIMULATED demonstrations)"
        ),
    )
    p.add_argument(
        "--demo-cycles",
        type=options.positive_int,
        default=50,
        help="SIMULATED cycles per person (examples)",
    )
    p.add_argument("--demo-persons", type=options.positive_int, default=1, help="SIMULATED persons")
    p.add_argument(
        "--gravity",
        type=gravity_task,
        default="1.0",
        help="m/s^2, in [0.1, 100] (1.0: the paper's phase sizes; 9.81: real gravity)",
    )
    p.add_argument(
        "--out",
        type=options.output_folder,
        default=None,
        help="folder for results.json/.csv, plot, GIF (default: results/juggling, the folder "
        "of motion-bench all)",
    )
    p.add_argument(
        "--world",
        choices=("mujoco", "model"),
        default="mujoco",
        help="mujoco: the figure, the video and the first --mujoco-cycles cycles of each run "
        "in the MuJoCo scene (checked equal to the pure model, which runs all cycles); "
        "model: pure model only (fast)",
    )
    p.add_argument(
        "--mujoco-cycles",
        type=options.non_negative_int,
        default=100,
        help="unperturbed cycles stepped in MuJoCo (a quarter of it per perturbed run)",
    )
    p.add_argument(
        "--levels",
        type=level_names,
        default=None,
        help="levels, comma-separated (e.g. easy,medium,hard): run the levels benchmark "
        "instead of the paper's; with --version v2 also drift (Juggling-v2's level whose "
        "delay and drag change at every catch)",
    )
    p.add_argument(
        "--pattern",
        type=siteswap_pattern,
        default=None,
        help="a juggling pattern (a registered name or siteswap): run its levels benchmark "
        "on MotionEnvs/Cascade-v0 (with --version v2: Cascade-v1's rows; every level unless "
        "--levels); the registered patterns "
        "(3, 3-human, 5, 4, 441, 531, 423, 51) are played, another siteswap is refused "
        "with the reason",
    )
    p.add_argument(
        "--episodes",
        type=options.int_at_least(2),
        default=None,
        help="test episodes per level and method (--levels: default 200; --pattern: 50; "
        "--version v2 --pattern: 100)",
    )
    p.add_argument(
        "--version",
        choices=("v1", "v2"),
        default="v1",
        help="with --levels: v1 (Juggling-v1's levels and controllers, default) or v2 "
        "(Juggling-v2's reference rows, on medium,hard unless --levels names others; "
        "catch rate against deviation plotted); with --pattern: v2 runs Cascade-v1's rows",
    )
    p.add_argument(
        "--max-catches",
        type=options.positive_int,
        default=None,
        help="catches after which an episode ends (--levels: default 3; --pattern: 10; "
        "--version v2 --pattern: 30)",
    )
    p.add_argument(
        "--pick-episodes",
        type=options.int_at_least(2),
        default=None,
        help="--version v2: the validation episodes the best non-oracle row is picked on "
        "(default 200; at least the grids' 30)",
    )
    p.add_argument(
        "--agent",
        type=run_folder,
        default=None,
        metavar="DIR",
        help="a motion-bench train run folder on Juggling-v1, played as one more method (--levels)",
    )
    p.add_argument(
        "--analyse",
        type=analyse_source,
        default=None,
        metavar="FILE",
        help="analyse the ball flights and pattern (hands, beat, dwell ratio, siteswap, "
        "balls) of a recording (juggling CSV, or FILE.c3d|.bvh|.tsv?ball=NAME or "
        "?balls=unlabelled, with up=y, unit=..., lateral=x|y to force the across-body "
        "axis) instead of running the juggler",
    )
    p.add_argument(
        "--n-balls",
        type=options.positive_int,
        default=None,
        help="balls in the analysed pattern (--analyse; default: the siteswap's, else "
        "Shannon's theorem's count; a warning when the measured counts disagree)",
    )
    p.add_argument("--no-dmp", action="store_true", help="skip the DMP competitor")
    p.add_argument("--no-video", action="store_true", help="skip the GIF")
    p.add_argument("--no-progress", action="store_true", help="no progress bars")
    p.set_defaults(func=main)
