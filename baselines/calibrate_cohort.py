"""``motion-bench calibrate-cohort``: fit the virtual cohort's scales to Table 1.

The generator's calibrated parameters (``CALIBRATED_PARAMETERS`` of
:mod:`motion_envs.datasets.cohort_config`: the five residual-component scales, the
spectral decay and the speed-profile spread) are chosen so that the criteria computed by
the real pipeline (:func:`motion_envs.models.criteria.table1`) on the generated
quaternions match target values, by default the paper's Table 1.

Optimiser: ``scipy.optimize.least_squares`` (trust region reflective, finite-difference
Jacobian with relative step ``diff_step``) on ``x = (log scales..., decay,
log spread)`` within bounds, minimising ``sum_c rho_c(x)^2`` with the relative miss
``rho_c = log(value_c / hi_c)`` above a target interval ``[lo_c, hi_c]``,
``log(value_c / lo_c)`` below it and 0 inside (a point target has ``lo = hi``). The
cohort's seed is held fixed (common random numbers), so the objective is a
deterministic, piecewise smooth function of ``x``. The targets are the paper's rows
that the issue asks to match; the d = 3 and d = 4 rows are not targets (docs/models.md
explains why the paper's d = 3 null cannot follow from its procedure).

:func:`run` fits (a pure function of a :class:`CalibrateConfig`), :func:`report` is the
printed text and :func:`write` saves the calibrated YAML: to ``--out``, or over the
shipped configuration only with ``--replace-shipped``.
"""

from __future__ import annotations

import argparse
import datetime as _dt
import math
import os
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy import optimize
from tqdm.auto import tqdm

from baselines import options
from motion_envs._io import UserFileError, read_regular_file, strict_json_loads
from motion_envs.datasets.cohort import CohortGenerator
from motion_envs.datasets.cohort_config import (
    CALIBRATED_PARAMETERS,
    DEFAULT_COHORT,
    CohortConfig,
    load_cohort_config,
    resolve_cohort_config,
)
from motion_envs.models.criteria import table1
from motion_envs.models.paper_values import FARAWAY_CHOE_TABLE1

__all__ = [
    "PAPER_TARGETS",
    "CalibrateConfig",
    "CalibrationResult",
    "CalibrationRun",
    "calibrate",
    "cohort_criteria",
    "format_report",
    "register",
    "report",
    "run",
    "write",
]

#: The paper's Table 1 rows the cohort is calibrated to, as [lo, hi] intervals (radians).
#: Between subject: 0.242 in the paper's text, 0.265 in its table.
PAPER_TARGETS: dict[str, tuple[float, float]] = {
    name: (FARAWAY_CHOE_TABLE1[name], FARAWAY_CHOE_TABLE1[name])
    for name in (
        "within_subject",
        "slerp_empirical",
        "slerp_average",
        "approximation_d2",
        "null_d2",
        "null_average",
        "subject_predictor_d2",
        "task_predictor_d2",
    )
}
PAPER_TARGETS["between_subject"] = (0.242, 0.265)

_LOG_PARAMS = {key for key in CALIBRATED_PARAMETERS if key != "residual.decay"}
_BOUNDS = {"residual.decay": (0.0, 8.0)}
_LOG_BOUNDS = (math.log(1e-4), math.log(2.0))


def cohort_criteria(config: CohortConfig, degrees: tuple[int, ...] = (2,)) -> dict[str, float]:
    """Table 1 criteria (via :func:`table1`) of the cohort a configuration generates."""
    ds = CohortGenerator(config).generate()
    return table1(ds.ragged, ds.subjects, ds.tasks, degrees=degrees).criteria


def relative_miss(value: float, target: tuple[float, float]) -> float:
    """``log(value / hi)`` above ``[lo, hi]``, ``log(value / lo)`` below, 0 inside."""
    lo, hi = target
    if value > hi:
        return math.log(value / hi)
    if value < lo:
        return math.log(value / lo)
    return 0.0


def _to_x(config: CohortConfig) -> np.ndarray:
    vals = config.calibrated_values()
    return np.array(
        [
            math.log(max(vals[k], 1e-4)) if k in _LOG_PARAMS else vals[k]
            for k in CALIBRATED_PARAMETERS
        ]
    )


def _from_x(config: CohortConfig, x: np.ndarray) -> CohortConfig:
    values = {
        key: float(math.exp(v)) if key in _LOG_PARAMS else float(v)
        for key, v in zip(CALIBRATED_PARAMETERS, x, strict=True)
    }
    return config.with_values(**values)


@dataclass
class _Best:
    """The best point the optimiser has evaluated so far."""

    cost: float = math.inf
    x: np.ndarray | None = None
    crit: dict[str, float] = field(default_factory=dict)


class _BudgetExhausted(Exception):
    """Raised inside the objective when the evaluation budget is used up."""


@dataclass(frozen=True)
class CalibrationResult:
    """Outcome of :func:`calibrate`."""

    config: CohortConfig
    targets: dict[str, tuple[float, float]]
    achieved: dict[str, float]
    initial: dict[str, float]
    n_evaluations: int
    cost: float
    seconds: float
    message: str

    def deviations(self) -> dict[str, float]:
        """Relative miss of each target (0 inside an interval), in percent."""
        return {
            k: 100.0 * (math.exp(relative_miss(self.achieved[k], t)) - 1.0)
            for k, t in self.targets.items()
        }


def calibrate(
    config: CohortConfig,
    targets: Mapping[str, tuple[float, float]] = PAPER_TARGETS,
    max_evaluations: int = 150,
    diff_step: float = 0.02,
    progress: bool = True,
    criteria_fn: Callable[[CohortConfig], Mapping[str, float]] | None = None,
) -> CalibrationResult:
    """Fit the calibrated parameters of ``config`` so its criteria meet ``targets``.

    Parameters
    ----------
    config:
        Starting configuration (its seed is kept fixed throughout).
    targets:
        criterion name -> ``(lo, hi)`` interval in radians (``lo == hi`` for a point).
    max_evaluations:
        Budget of cohort generations + Table 1 evaluations (finite-difference Jacobian
        evaluations included); the best point seen is returned when it runs out.
    diff_step:
        Relative finite-difference step of ``least_squares``.
    progress:
        Show a tqdm bar (stderr) with the current cost.
    criteria_fn:
        ``config -> criteria`` (default :func:`cohort_criteria` with ``degrees=(2,)``).
    """
    if not targets:
        raise ValueError("targets must name at least one criterion")
    for name, (lo, hi) in targets.items():
        if not (0 < lo <= hi):
            raise ValueError(f"target {name!r} must be an interval 0 < lo <= hi; got {(lo, hi)}")
    if max_evaluations < 2:
        raise ValueError(f"max_evaluations must be >= 2; got {max_evaluations}")
    fn = criteria_fn or cohort_criteria
    names = list(targets)
    t0 = time.perf_counter()
    cache: dict[bytes, np.ndarray] = {}
    bar = tqdm(total=max_evaluations, desc="calibrate-cohort", disable=not progress, unit="eval")
    best = _Best()

    def residuals(x: np.ndarray) -> np.ndarray:
        key = x.tobytes()
        if key in cache:
            return cache[key]
        if len(cache) >= max_evaluations:
            raise _BudgetExhausted
        crit = fn(_from_x(config, x))
        missing = [n for n in names if n not in crit]
        if missing:
            raise ValueError(f"criteria {missing} are not computed; cannot calibrate to them")
        res = np.array([relative_miss(float(crit[n]), targets[n]) for n in names])
        cost = 0.5 * float(res @ res)
        if cost < best.cost:
            best.cost, best.x, best.crit = cost, x.copy(), dict(crit)
        cache[key] = res
        bar.update(1)
        bar.set_postfix(cost=f"{cost:.2e}", best=f"{best.cost:.2e}")
        return res

    x0 = _to_x(config)
    lower = np.array(
        [_LOG_BOUNDS[0] if k in _LOG_PARAMS else _BOUNDS[k][0] for k in CALIBRATED_PARAMETERS]
    )
    upper = np.array(
        [_LOG_BOUNDS[1] if k in _LOG_PARAMS else _BOUNDS[k][1] for k in CALIBRATED_PARAMETERS]
    )
    x0 = np.clip(x0, lower, upper)
    initial_res = residuals(x0)
    initial = dict(best.crit)
    message = "targets met at the start"
    if float(initial_res @ initial_res) > 0:
        try:
            sol = optimize.least_squares(
                residuals,
                x0,
                bounds=(lower, upper),
                method="trf",
                diff_step=diff_step,
                x_scale=1.0,
                xtol=1e-6,
                ftol=1e-6,
            )
            message = str(sol.message)
        except _BudgetExhausted:
            message = f"stopped after the budget of {max_evaluations} evaluations"
    bar.close()
    assert best.x is not None  # the first evaluation always improves on inf
    final = _from_x(config, best.x)
    achieved = dict(best.crit)
    return CalibrationResult(
        config=final,
        targets=dict(targets),
        achieved=achieved,
        initial=initial,
        n_evaluations=len(cache),
        cost=best.cost,
        seconds=time.perf_counter() - t0,
        message=message,
    )


def format_report(result: CalibrationResult) -> str:
    """Target vs achieved table (radians; deviation 0 % inside a target interval)."""
    lines = [
        f"{'criterion':<24} {'target':>13} {'start':>7} {'achieved':>9} {'miss':>7}",
        "-" * 64,
    ]
    dev = result.deviations()
    for name, (lo, hi) in result.targets.items():
        tgt = f"{lo:.3f}" if lo == hi else f"{lo:.3f}-{hi:.3f}"
        lines.append(
            f"{name:<24} {tgt:>13} {result.initial.get(name, float('nan')):7.3f} "
            f"{result.achieved[name]:9.3f} {dev[name]:+6.1f}%"
        )
    lines.append("")
    lines.append("calibrated parameters:")
    for key, value in result.config.calibrated_values().items():
        lines.append(f"  {key:<30} {value:.6g}")
    lines.append(
        f"{result.n_evaluations} evaluations in {result.seconds:.1f} s; cost "
        f"{result.cost:.3e}; {result.message}"
    )
    return "\n".join(lines)


def load_targets(spec: str) -> dict[str, tuple[float, float]]:
    """``paper`` (:data:`PAPER_TARGETS`) or a JSON file ``{criterion: value or [lo, hi]}``."""
    if spec == "paper":
        return dict(PAPER_TARGETS)
    path = Path(spec)
    if not os.path.lexists(path):
        raise ValueError(f"--target must be 'paper' or a JSON file of targets; got {spec!r}")
    try:  # a regular file (no FIFO or device), bounded, strict JSON
        raw = strict_json_loads(read_regular_file(path, max_bytes=1 << 20), str(path))
    except UserFileError as exc:
        raise ValueError(str(exc)) from None
    if not isinstance(raw, dict) or not raw:
        raise ValueError(f"{path}: expected a JSON object criterion -> value or [lo, hi]")
    out = {}
    for name, value in raw.items():
        pair = value if isinstance(value, list) else [value, value]
        if len(pair) != 2 or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
            for v in pair
        ):
            raise ValueError(f"{path}: target {name!r} must be a number or [lo, hi]")
        out[name] = (float(pair[0]), float(pair[1]))
    return out


def _record(result: CalibrationResult, target_spec: str) -> dict[str, object]:
    return {
        "target": target_spec,
        "date": _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d"),
        "optimiser": "scipy.optimize.least_squares (trf, finite differences) on log scales",
        "seed_held_fixed": result.config.seed,
        "evaluations": result.n_evaluations,
        "cost": float(f"{result.cost:.6g}"),
        "targets": {k: [lo, hi] if lo != hi else lo for k, (lo, hi) in result.targets.items()},
        "achieved": {k: round(float(v), 4) for k, v in result.achieved.items()},
    }


@dataclass(frozen=True)
class CalibrateConfig:
    """What ``motion-bench calibrate-cohort`` fits (the defaults are the CLI's).

    ``target`` is ``"paper"`` or a JSON file of targets, ``config`` the starting cohort
    (a name under ``configs/cohorts/`` or a YAML path); ``check_seeds`` other seeds are
    generated with the fitted parameters to report the spread of the criteria.
    """

    target: str = "paper"
    config: str = DEFAULT_COHORT
    max_evaluations: int = 150
    check_seeds: int = 3
    progress: bool = True


@dataclass(frozen=True)
class CalibrationRun:
    """What :func:`run` returns: the fit, the config to save and the seeds' spread."""

    source: Path
    result: CalibrationResult
    final: CohortConfig
    seed_spread: dict[str, tuple[float, float]]
    n_seeds: int


def run(config: CalibrateConfig) -> CalibrationRun:
    """Calibrate the cohort of ``config``; no printing (but a progress bar), no files."""
    source = resolve_cohort_config(config.config)
    start = load_cohort_config(source)
    targets = load_targets(config.target)
    result = calibrate(
        start, targets, max_evaluations=config.max_evaluations, progress=config.progress
    )
    data = dict(result.config.data)
    data["calibration"] = _record(result, config.target)
    final = CohortConfig(data, source=str(source))
    spread: dict[str, tuple[float, float]] = {}
    if config.check_seeds > 0:
        rows: dict[str, list[float]] = {name: [] for name in targets}
        for s in range(1, config.check_seeds + 1):
            crit = cohort_criteria(final.with_values(seed=final.seed + s))
            for name in targets:
                rows[name].append(crit[name])
        spread = {name: (min(vals), max(vals)) for name, vals in rows.items()}
    return CalibrationRun(source, result, final, spread, config.check_seeds)


def report(outcome: CalibrationRun) -> str:
    """The text ``motion-bench calibrate-cohort`` prints after fitting."""
    lines = [format_report(outcome.result)]
    if outcome.seed_spread:
        lines.append(f"\nsame parameters, {outcome.n_seeds} other seeds (spread of the criteria):")
        for name, (lo, hi) in outcome.seed_spread.items():
            lines.append(f"  {name:<24} {lo:.3f} .. {hi:.3f}")
    return "\n".join(lines)


def write(outcome: CalibrationRun, out: Path | None, replace_shipped: bool = False) -> list[Path]:
    """Save the calibrated YAML to ``out``; with ``replace_shipped`` over the starting
    config instead (the file itself: ``configs/cohorts/`` links to the package's folder,
    so a shipped config has one file). Atomic writes."""
    if replace_shipped:
        return [outcome.final.save(outcome.source.resolve())]
    if out is None:
        raise ValueError("write needs an output path or replace_shipped=True")
    return [outcome.final.save(out)]


def default_out(config_name: str) -> Path:
    """Where the calibrated YAML goes without ``--out``: ``results/calibrate-cohort/NAME.yaml``."""
    return Path("results") / "calibrate-cohort" / f"{Path(config_name).stem}.yaml"


def main(args: argparse.Namespace) -> int:
    """``motion-bench calibrate-cohort`` with parsed arguments: run, print, write."""
    config = CalibrateConfig(
        target=args.target,
        config=args.config,
        max_evaluations=args.max_evaluations,
        check_seeds=args.check_seeds,
        progress=not args.no_progress,
    )
    source = resolve_cohort_config(config.config)
    start = load_cohort_config(source)
    print(f"calibrating cohort {start.name!r} from {source} (seed {start.seed}) to {config.target}")
    outcome = run(config)
    print(report(outcome))
    if args.dry_run:
        print("\n--dry-run: nothing written")
        return 0
    out = args.out if args.out is not None else default_out(config.config)
    written = write(outcome, out, replace_shipped=args.replace_shipped)
    print("\n" + "\n".join(f"wrote {p}" for p in written))
    return 0


@options.reads_files
def target_option(text: str) -> str:
    """``--target``: ``paper`` or a readable JSON file of targets (checked now)."""
    try:
        load_targets(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc).removeprefix("--target must be ")) from None
    return text


@options.reads_files
def config_option(text: str) -> str:
    """``--config``: a cohort name or a YAML path that resolves (checked now)."""
    try:
        resolve_cohort_config(text)
    except (ValueError, FileNotFoundError) as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    return text


def register(subparsers: argparse._SubParsersAction[options.Parser]) -> None:
    """Add the ``calibrate-cohort`` sub-command."""
    p = options.add_subcommand(
        subparsers,
        "calibrate-cohort",
        help="fit the virtual cohort's scales to the paper's Table 1",
        description=(
            "Fit the simulated cohort's residual scales, spectral decay and speed-profile "
            "spread (least squares on log scales, seed held fixed) so that Table 1 computed "
            "on the generated data matches the targets; prints target vs achieved and "
            "writes the calibrated YAML to --out (the shipped config is replaced only with "
            "--replace-shipped)."
        ),
    )
    p.add_argument(
        "--target",
        default="paper",
        type=target_option,
        help="'paper' (Faraway & Choe Table 1) or a JSON file {criterion: value or [lo, hi]}",
    )
    p.add_argument(
        "--config",
        default=DEFAULT_COHORT,
        type=config_option,
        help="starting cohort config: a name under configs/cohorts/ or a YAML path",
    )
    where = p.add_mutually_exclusive_group()
    where.add_argument(
        "--out",
        default=None,
        type=options.output_file,
        help="where to write the calibrated YAML (default: results/calibrate-cohort/NAME.yaml)",
    )
    where.add_argument(
        "--replace-shipped",
        action="store_true",
        help="overwrite the starting config instead (the shipped one: its one file in the "
        "package, which configs/cohorts/ links to)",
    )
    where.add_argument("--dry-run", action="store_true", help="fit and report, write nothing")
    p.add_argument(
        "--max-evaluations",
        type=options.int_at_least(2),
        default=150,
        help="budget of cohort evaluations",
    )
    p.add_argument(
        "--check-seeds",
        type=options.non_negative_int,
        default=3,
        help="after fitting, report the criteria's range over this many other seeds",
    )
    p.add_argument("--no-progress", action="store_true", help="hide the progress bar")
    p.set_defaults(func=main)
