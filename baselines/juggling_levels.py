"""``motion-bench juggling-levels``: Juggling-v1's levels, four reference controllers.

For each level (``easy``, ``medium``, ``hard``; ``motion_envs.models.juggling_levels.LEVELS``)
and each controller (the analytic juggler, the same made latency-aware, a fixed catch
point, minimum jerk to the intercept predicted from the commanded release velocity), runs
``episodes`` zero-action episodes of ``MotionEnvs/Juggling-v1`` (the controller alone)
reset with the TEST seeds ``SPLIT_SEEDS["test"] + i`` of ``baselines.agents.juggling_score``
(the level values were chosen on training seeds). An episode ends at the first drop or at
``max_catches`` catches. Reported per method:

* ``catch_rate``: catches / (catches + drops) pooled over the episodes, with a 95 %
  bootstrap interval over episodes (``scipy.stats.bootstrap``, BCa, paired resampling of
  each episode's catches and drop);
* ``consecutive_catches_median``: the median over episodes of the catches before the
  first drop (capped at ``max_catches``);
* ``likeness``: closed-loop human-likeness, the mean over the episode's steps of the
  hand state's distance (m) to the nearest HELD-OUT demonstration state of the same phase
  (``HumanLikeness`` on the test cycles), median over episodes with its 95 % interval.

The demonstrations are SIMULATED. The pure :func:`run` takes a frozen
:class:`LevelsConfig`; :func:`register` adds the sub-command (the lead may instead call
:func:`run` from ``motion-bench juggling --levels``).
"""

from __future__ import annotations

import argparse
import json
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np
from scipy import stats

from baselines import options
from baselines.agents.juggling_score import SPLIT_SEEDS
from motion_envs._io import atomic_write_text
from motion_envs.datasets.juggling_demos import SIMULATED_LABEL
from motion_envs.models.juggling_levels import CONTROLLERS, LEVELS

__all__ = ["LevelsConfig", "check_config", "main", "register", "report", "run", "run_method"]


@dataclass(frozen=True)
class LevelsConfig:
    """What ``motion-bench juggling-levels`` runs."""

    levels: tuple[str, ...] = ("easy", "medium", "hard")
    methods: tuple[str, ...] = CONTROLLERS
    episodes: int = 200
    max_catches: int = 3
    gravity: float = 9.81
    split: str = "test"
    bootstrap_resamples: int = 2000


def check_config(config: LevelsConfig) -> None:
    """Raise :class:`baselines.options.ConfigError` naming the first bad field."""
    for level in config.levels:
        if level not in LEVELS:
            raise options.ConfigError("levels", f"must be among {list(LEVELS)}; got {level!r}")
    if not config.levels:
        raise options.ConfigError("levels", "must name at least one level")
    for m in config.methods:
        if m not in CONTROLLERS:
            raise options.ConfigError("methods", f"must be among {list(CONTROLLERS)}; got {m!r}")
    if config.episodes < 2:
        raise options.ConfigError("episodes", f"must be >= 2; got {config.episodes}")
    if config.max_catches < 1:
        raise options.ConfigError("max_catches", f"must be >= 1; got {config.max_catches}")
    if config.split not in SPLIT_SEEDS:
        raise options.ConfigError("split", f"must be one of {sorted(SPLIT_SEEDS)}")


def run_method(
    level: str, method: str, episodes: int, max_catches: int, gravity: float, first_seed: int
) -> dict[str, np.ndarray]:
    """Per-episode ``catches``, ``drops`` (0/1) and mean ``likeness`` (held-out) of
    ``method`` on ``level``, zero action, seeds ``first_seed + i``."""
    from motion_envs.envs.juggling_v1 import JugglingV1Env, held_out_likeness

    env = JugglingV1Env(level=level, controller=method, max_catches=max_catches, gravity=gravity)
    likeness = held_out_likeness(gravity)
    zero = np.zeros(2)
    catches, drops, like = [], [], []
    for i in range(episodes):
        env.reset(seed=first_seed + i)
        total, n = 0.0, 0
        world = env.world
        while True:
            _, _, terminated, truncated, info = env.step(zero)
            st = world.state
            assert st is not None
            total += likeness.distance(info["phase"], st.hand_pos, st.hand_vel)
            n += 1
            if terminated or truncated:
                break
        catches.append(info["catches"])
        drops.append(int(terminated))
        like.append(total / n)
    return {
        "catches": np.asarray(catches, dtype=np.float64),
        "drops": np.asarray(drops, dtype=np.float64),
        "likeness": np.asarray(like),
    }


def _summary(res: dict[str, np.ndarray], resamples: int, seed: int) -> dict[str, Any]:
    c, d = res["catches"], res["drops"]

    def rate(cc: np.ndarray, dd: np.ndarray, axis: int = -1) -> np.ndarray:
        tot = np.sum(cc + dd, axis=axis)
        out: np.ndarray = np.sum(cc, axis=axis) / np.where(tot > 0, tot, 1)
        return out

    value = float(rate(c, d))
    if np.ptp(c) == 0 and np.ptp(d) == 0:
        lo = hi = value
    else:
        ci = stats.bootstrap(
            (c, d),
            rate,
            paired=True,
            vectorized=True,
            n_resamples=resamples,
            confidence_level=0.95,
            method="percentile",
            random_state=seed,
        ).confidence_interval
        lo, hi = float(ci.low), float(ci.high)
    like = res["likeness"]
    lci = stats.bootstrap(
        (like,),
        np.median,
        vectorized=True,
        n_resamples=resamples,
        method="percentile",
        random_state=seed,
    ).confidence_interval
    return {
        "catch_rate": value,
        "catch_rate_ci": [lo, hi],
        "catches": int(c.sum()),
        "drops": int(d.sum()),
        "consecutive_catches_median": float(np.median(c)),
        "likeness_m": float(np.median(like)),
        "likeness_ci": [float(lci.low), float(lci.high)],
    }


def run(config: LevelsConfig) -> dict[str, Any]:
    """Every level x method (see the module docstring); a JSON-ready document."""
    check_config(config)
    first = SPLIT_SEEDS[config.split]
    t0 = time.process_time()
    levels = []
    for level in config.levels:
        methods = {}
        for method in config.methods:
            res = run_method(
                level, method, config.episodes, config.max_catches, config.gravity, first
            )
            methods[method] = _summary(res, config.bootstrap_resamples, seed=0)
        values = asdict(LEVELS[level])
        levels.append({"level": level, "values": values, "methods": methods})
    return {
        "config": asdict(config),
        "demonstrations": SIMULATED_LABEL,
        "seeds": {"split": config.split, "first": first, "count": config.episodes},
        "levels": levels,
        "targets": _targets(levels),
        "cpu_s": time.process_time() - t0,
    }


def _targets(levels: list[dict[str, Any]]) -> dict[str, Any]:
    by = {lv["level"]: lv["methods"] for lv in levels}
    out: dict[str, Any] = {}

    def rate(level: str, method: str) -> float | None:
        value = by.get(level, {}).get(method, {}).get("catch_rate")
        return None if value is None else float(value)

    # (value, bound, at least): the targets
    checks: dict[str, tuple[float | None, float, bool]] = {
        "juggler_easy_ge_0.95": (rate("easy", "juggler"), 0.95, True),
        "juggler_medium_le_0.80": (rate("medium", "juggler"), 0.80, False),
        "juggler_hard_le_0.50": (rate("hard", "juggler"), 0.50, False),
        "latency_aware_medium_ge_0.95": (rate("medium", "juggler_latency_aware"), 0.95, True),
    }
    for key, (value, bound, at_least) in checks.items():
        met = None if value is None else (value >= bound if at_least else value <= bound)
        out[key] = {"value": value, "met": met}
    for level, methods in by.items():
        j = methods.get("juggler", {}).get("catch_rate")
        for trivial in ("fixed_point", "commanded_intercept"):
            t = methods.get(trivial, {}).get("catch_rate")
            if j is not None and t is not None:
                out[f"{trivial}_below_juggler_{level}"] = {"value": t, "juggler": j, "met": t < j}
    return out


def report(doc: dict[str, Any]) -> str:
    """A plain-text table of ``doc``."""
    seeds = doc["seeds"]
    lines = [
        f"Juggling-v1 levels ({doc['demonstrations']}); "
        f"{seeds['count']} {seeds['split']} episodes each",
        f"{'level':8s} {'method':24s} {'catch rate [95% CI]':26s} "
        f"{'consec.':>7s} {'likeness m':>10s}",
    ]
    for lv in doc["levels"]:
        for name, m in lv["methods"].items():
            lo, hi = m["catch_rate_ci"]
            lines.append(
                f"{lv['level']:8s} {name:24s} {m['catch_rate']:.3f} [{lo:.3f}, {hi:.3f}]{'':6s} "
                f"{m['consecutive_catches_median']:7.1f} {m['likeness_m']:10.4f}"
            )
    for key, t in doc["targets"].items():
        met = "met" if t["met"] else ("n/a" if t["met"] is None else "NOT met")
        lines.append(f"target {key}: {t['value']} ({met})")
    lines.append(f"CPU {doc['cpu_s']:.1f} s")
    return "\n".join(lines)


def main(args: argparse.Namespace) -> int:
    """``motion-bench juggling-levels`` with parsed arguments."""
    config = LevelsConfig(
        levels=tuple(args.levels),
        episodes=args.episodes,
        max_catches=args.max_catches,
    )
    check_config(config)
    doc = run(config)
    print(report(doc))
    if args.out:
        path = atomic_write_text(Path(args.out) / "results.json", json.dumps(doc, indent=2) + "\n")
        print(f"wrote {path}")
    return 0


def _levels(text: str) -> list[str]:
    names = [v.strip() for v in text.split(",") if v.strip()]
    bad = [n for n in names if n not in LEVELS]
    if not names or bad:
        raise argparse.ArgumentTypeError(f"expected a comma list of {list(LEVELS)}; got {text!r}")
    return names


DESCRIPTION = """\
Juggling-v1's levels (easy, medium, hard: the ball seen 0 / 100 / 110 ms late, with
measurement and release noise) and four controllers: the analytic juggler (eq. 9 toss,
eq. 10 correction from the delayed measurement), the same juggler predicting the flight
forward by the known delay, a fixed catch point and minimum jerk to the intercept
predicted from the commanded release velocity. Zero-action episodes on the test seeds
(the level values were chosen on training seeds); an episode ends at the first drop or
after --max-catches catches. Reported per level and controller: catch rate with a 95 %
bootstrap interval, consecutive catches before the first drop (median) and closed-loop
human-likeness against held-out demonstrations (SIMULATED)."""


def register(subparsers: argparse._SubParsersAction[options.Parser]) -> None:
    """Add the ``juggling-levels`` sub-command."""
    p = options.add_subcommand(
        subparsers,
        "juggling-levels",
        help="Juggling-v1's levels: catch rates of the analytic juggler, the latency-aware "
        "juggler and two trivial policies (SIMULATED demonstrations)",
        description=DESCRIPTION,
    )
    p.add_argument("--levels", type=_levels, default="easy,medium,hard", help="comma list")
    p.add_argument("--episodes", type=options.positive_int, default=200, help="test episodes")
    p.add_argument(
        "--max-catches", type=options.positive_int, default=3, help="catches per episode at most"
    )
    p.add_argument(
        "--out", type=options.output_folder, default=None, help="folder for results.json"
    )
    p.set_defaults(func=main)
