"""Agents trained per level and seed, scored against a bench's reference rows on the
same TEST seeds: what ``experiments/juggling_v2_agents.py`` (Juggling-v2) and
``experiments/cascade_v1_agents.py`` (Cascade-v1) share.

* :func:`add_arguments`: the command line both take (levels, seeds, algorithm, budget,
  test episodes, the run folders' root, the results file);
* :func:`train_all` / :func:`train_or_reuse`: one run folder ``ROOT/{level}-seed{seed}``
  per level and seed, reused when complete (its ``run.json`` exists), trained otherwise by
  ``motion-bench train`` (:func:`baselines.agents.train.run`), or refused in one line
  with ``--reuse-only``;
* :func:`check_run` and :func:`run_fields`: a reused folder is the run asked for (its
  environment, algorithm, level and seed), and what its manifest says about its training
  and its checkpoint chosen on the VALIDATION seeds;
* :func:`check_same_seeds`: an agent's and a row's episodes are paired only on the same
  seeds;
* :func:`median_run` and :func:`validation_pick`: the run of a level the issue's
  verdict is on (the median over the seeds of a difference) and the run validation would
  pick (the lowest validation criterion);
* :func:`margin_met`: the issue's target ``agent - best non-oracle row >=`` :data:`MARGIN`
  with its 95 % interval above 0; :func:`likeness_met`: its likeness target, the agent's
  hand deviation from held-out demonstrations at most the juggler's plus
  :data:`DEVIATION_SLACK_MM`;
* :func:`rows_not_beaten`: the issue's last target, every simple hand-written row below
  the agent, checked row by row (not only against the best row validation chose).
"""

from __future__ import annotations

import argparse
import json
import math
import warnings
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

__all__ = [
    "DEVIATION_SLACK_MM",
    "MARGIN",
    "add_arguments",
    "check_run",
    "check_same_seeds",
    "format_difference",
    "likeness_met",
    "margin_met",
    "median_run",
    "room_for_target",
    "rows_not_beaten",
    "run_fields",
    "save_plot",
    "train_all",
    "train_or_reuse",
    "validation_pick",
    "write_results",
]

#: The catch-rate margin an agent must have over the best non-oracle row (the issue's).
MARGIN = 0.05
#: mm of hand deviation the agent may add to the juggler's (the issue's likeness target).
DEVIATION_SLACK_MM = 5.0


def add_arguments(
    parser: argparse.ArgumentParser,
    levels: Sequence[str],
    runs: str,
    timesteps_help: str,
    controller_help: str,
) -> None:
    """The options both scripts take; ``levels`` and ``runs`` are the defaults of
    ``--levels`` and ``--runs``."""
    from baselines.agents.config import ALGOS

    parser.add_argument("--levels", nargs="+", default=list(levels))
    parser.add_argument("--seeds", nargs="+", type=int, default=[0, 1, 2])
    parser.add_argument("--algo", choices=ALGOS, default="ppo", help="default: ppo")
    parser.add_argument("--timesteps", type=int, default=None, help=timesteps_help)
    parser.add_argument("--test-episodes", type=int, default=100)
    parser.add_argument("--controller", default=None, help=controller_help)
    parser.add_argument("--runs", default=runs, help="run folders' root")
    parser.add_argument(
        "--reuse-only",
        action="store_true",
        help="score complete run folders only: a missing one is an error, nothing is trained",
    )
    parser.add_argument("--out", default=None, help="results JSON (default: RUNS/results.json)")


def train_or_reuse(
    env_id: str,
    level: str,
    seed: int,
    root: Path,
    *,
    algo: str = "ppo",
    timesteps: int | None = None,
    env_kwargs: Mapping[str, Any] | None = None,
    overrides: Mapping[str, Any] | None = None,
    reuse_only: bool = False,
    progress: bool = True,
) -> Path:
    """The run folder ``root/{level}-seed{seed}``: reused when complete (``run.json``
    exists), else trained with the config file's block for ``algo`` and ``env_id``
    (``level`` and ``env_kwargs`` over its env keywords, ``overrides`` over its
    hyper-parameters, ``timesteps`` over its budget; None: the config's), else with
    ``reuse_only`` a one-line ``FileNotFoundError`` naming the folder."""
    from baselines.agents.train import TrainConfig
    from baselines.agents.train import run as train

    out = root / f"{level}-seed{seed}"
    if (out / "run.json").exists():
        return out
    if reuse_only:
        raise FileNotFoundError(f"--reuse-only: run folder {out} is not complete (no run.json)")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        train(
            TrainConfig(
                algo=algo,
                env_id=env_id,
                out=str(out),
                seed=seed,
                timesteps=timesteps,
                env_kwargs={"level": level, **(env_kwargs or {})},
                overrides=dict(overrides or {}),
                progress=progress,
                tensorboard=False,
            )
        )
    return out


def train_all(
    env_id: str,
    args: argparse.Namespace,
    env_kwargs: Mapping[str, Any] | None = None,
    overrides: Mapping[str, Any] | None = None,
) -> dict[tuple[str, int], Path]:
    """:func:`train_or_reuse` for every level and seed of ``args`` (:func:`add_arguments`'s
    options; ``env_kwargs`` and ``--controller`` over the config's env keywords)."""
    from tqdm import tqdm

    root = Path(args.runs)
    extra = {**(env_kwargs or {}), **({"controller": args.controller} if args.controller else {})}
    jobs = [(lv, s) for lv in args.levels for s in args.seeds]
    out = {}
    for lv, s in tqdm(jobs, desc="train"):
        out[lv, s] = train_or_reuse(
            env_id, lv, s, root, algo=args.algo, timesteps=args.timesteps, env_kwargs=extra,
            overrides=overrides, reuse_only=args.reuse_only,
        )  # fmt: skip
    return out


def check_run(loaded: Any, env_id: str, algo: str, level: str, seed: int) -> None:
    """A one-line ``ValueError`` naming the folder when the loaded run (a
    :class:`baselines.agents.rundir.LoadedRun`) is not of ``env_id``, ``algo``, ``level``
    and ``seed`` (a reused folder that is not the run its name says)."""
    got = {
        "env_id": loaded.env_id,
        "algo": loaded.config.get("algo"),
        "level": loaded.env_kwargs.get("level"),
        "seed": loaded.config.get("seed"),
    }
    want = {"env_id": env_id, "algo": algo, "level": level, "seed": seed}
    for key, value in want.items():
        if got[key] != value:
            raise ValueError(
                f"run folder {loaded.run_dir}: {key} is {got[key]!r}, expected {value!r}"
            )


def run_fields(loaded: Any, criterion: str) -> dict[str, Any]:
    """What a run's manifest says: its folder, seed, budget, CPU, the step of the kept
    checkpoint, and the validation ``criterion`` (lower is better) of the kept policy and
    of the zero action (``val_{criterion}``, ``val_nominal_{criterion}``)."""
    return {
        "run_dir": str(loaded.run_dir),
        "seed": int(loaded.config["seed"]),
        "timesteps": int(loaded.manifest["timesteps"]),
        "train_seconds": float(loaded.manifest["train_seconds"]),
        "best_timesteps": int(loaded.manifest["best_timesteps"]),
        f"val_{criterion}": float(loaded.manifest["best_val_criterion"]),
        f"val_nominal_{criterion}": float(loaded.manifest["val_nominal_criterion"]),
    }


def check_same_seeds(a: ArrayLike, b: ArrayLike) -> None:
    """``RuntimeError`` unless the two seed arrays are equal (paired episodes)."""
    if not np.array_equal(np.asarray(a), np.asarray(b)):
        raise RuntimeError("the agent and the rows were played on different seeds")


def median_run(runs: Sequence[dict[str, Any]], key: str) -> dict[str, Any]:
    """The run whose ``key`` is the median over the runs (the upper one of an even count)."""
    if not runs:
        raise ValueError("no runs to take the median of")
    return sorted(runs, key=lambda r: r[key])[len(runs) // 2]


def validation_pick(runs: Sequence[dict[str, Any]], key: str) -> dict[str, Any]:
    """The run with the lowest validation criterion ``key`` (the first of ties)."""
    if not runs:
        raise ValueError("no runs to pick from")
    return min(runs, key=lambda r: r[key])


def margin_met(difference: float, ci: Sequence[float], margin: float = MARGIN) -> bool:
    """The issue's target: ``difference >= margin`` and the interval's low end above 0."""
    return bool(difference >= margin and ci[0] > 0)


def room_for_target(
    best: str, upper: str, value: float, ci: Sequence[float], margin: float = MARGIN
) -> dict[str, Any]:
    """Whether a level can show an agent meeting the target ``agent - best >= margin``:
    the room the upper reference leaves above the best non-oracle row (``upper - best``,
    paired, ``value`` and ``ci``). When even the interval's high end is below ``margin``
    an agent would have to beat the upper reference itself (given the hidden values) by
    ``margin - high``: the level cannot decide for a learner that only reaches the
    reference. Returns ``{"margin", "room", "room_ci", "open", "sentence"}``."""
    hi = float(ci[1])
    open_ = bool(hi >= margin)
    room = format_difference(value, ci)
    if open_:
        sentence = (
            f"room for the target: {upper} - {best} = {room}, its interval reaches "
            f"+{margin:.2f}: an agent could meet the target without beating {upper}"
        )
    else:
        sentence = (
            f"NO room for the target: {upper} - {best} = {room}, below +{margin:.2f} even "
            f"at the interval's high end: an agent would have to beat the upper reference "
            f"({upper}, given the hidden values) by at least {margin - hi:+.3f}"
        )
    return {"margin": margin, "room": float(value), "room_ci": [float(c) for c in ci],
            "open": open_, "sentence": sentence}  # fmt: skip


def rows_not_beaten(
    differences: Mapping[str, tuple[float, Sequence[float]]], unit: str = "catch rate"
) -> dict[str, Any]:
    """Whether the agent stays above EVERY row it is compared with, not only the best
    row validation chose: ``differences`` maps each row to ``agent - row`` (paired,
    ``(value, ci)``). A row is beaten when the interval's low end is above 0. Returns
    ``{"beaten", "not_beaten", "every_row_beaten", "sentence"}``; the rows not beaten in
    the sentence come lowest difference first."""
    if not differences:
        raise ValueError("differences: no rows to compare the agent with")
    beaten = [r for r, (_, ci) in differences.items() if float(ci[0]) > 0]
    missed = sorted((r for r in differences if r not in beaten), key=lambda r: differences[r][0])
    if not missed:
        sentence = f"the agent is above every one of the {len(differences)} rows ({unit})"
    else:
        shown = "; ".join(f"{r} {format_difference(*differences[r])}" for r in missed)
        sentence = (
            f"the agent is NOT above {len(missed)} of the {len(differences)} rows "
            f"(agent - row, {unit}): {shown}"
        )
    return {"beaten": beaten, "not_beaten": missed, "every_row_beaten": not missed,
            "sentence": sentence}  # fmt: skip


def likeness_met(
    deviation_mm: float, juggler_mm: float, slack_mm: float = DEVIATION_SLACK_MM
) -> bool | None:
    """The issue's likeness target: the agent's hand deviation (mm) at most the juggler's
    plus ``slack_mm``; None when either is not measured (NaN)."""
    if math.isnan(deviation_mm) or math.isnan(juggler_mm):
        return None
    return bool(deviation_mm <= juggler_mm + slack_mm)


def format_difference(value: float, ci: Sequence[float], digits: int = 3) -> str:
    """``+0.012 [-0.004, +0.031]``."""
    return f"{value:+.{digits}f} [{ci[0]:+.{digits}f}, {ci[1]:+.{digits}f}]"


def write_results(doc: Mapping[str, Any], path: Path) -> Path:
    """``doc`` as indented JSON at ``path``, atomically (:mod:`motion_envs._io`)."""
    from motion_envs._io import atomic_write_text

    return atomic_write_text(path, json.dumps(doc, indent=2) + "\n")


def save_plot(fig: Any, path: Path) -> Path:
    """``fig`` saved atomically at 150 dpi, then closed."""
    import matplotlib.pyplot as plt

    from motion_envs._io import save_figure

    try:
        return save_figure(fig, path, dpi=150)
    finally:
        plt.close(fig)
