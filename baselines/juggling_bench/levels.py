"""``motion-bench juggling --levels``: Juggling-v1's levels and its reference controllers.

For each level (``easy``, ``medium``, ``hard``; :data:`motion_envs.models.juggling.LEVELS`)
and each controller (the analytic juggler, the same made latency-aware, a fixed catch
point, minimum jerk to the intercept predicted from the commanded release velocity;
:data:`~motion_envs.models.juggling.CONTROLLERS`), plays ``episodes`` zero-action episodes
of ``MotionEnvs/Juggling-v1`` (the controller alone) reset with the TEST seeds
``SPLIT_SEEDS["test"] + i`` of :mod:`motion_envs.datasets.juggling` (the level values
were chosen on training seeds), with :func:`~baselines.agents.juggling_score.juggling_episodes`,
the function ``motion-bench agent`` scores agents with. With ``agent`` (a run folder of
``motion-bench train`` on Juggling-v1) the trained agent is played on the same seeds of
every level as one more method (its residual on the analytic juggler). An episode ends
at the first drop or after ``max_catches`` catches. At a zero latency (``easy``) the
latency-aware juggler is the juggler step for step: its entry is the juggler's episodes,
not played twice. Reported per method:

* ``catch_rate``: catches per toss pooled over the episodes, with a 95 % bootstrap
  interval resampling episodes (:func:`~baselines.agents.juggling_score.catch_rate_interval`);
* ``consecutive_catches_median``: the median over episodes of the catches before the
  first drop (at most ``max_catches``);
* ``deviation_m``: closed-loop human-likeness, the hand's deviation (m) from the nearest
  HELD-OUT demonstration of the same phase (median over phase segments,
  :class:`~baselines.agents.juggling_score.JugglingEpisodes`), with its interval;
* for the agent, ``catch_rate_difference`` over the analytic juggler on the same seeds,
  with a paired interval.

The demonstrations are SIMULATED. :func:`run` is pure (a frozen :class:`LevelsConfig`),
:func:`report` the printed text, :func:`write` writes ``results.json``.
"""

from __future__ import annotations

import copy
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from baselines import options
from baselines.agents.juggling_score import (
    JugglingEpisodes,
    Policy,
    catch_rate_difference,
    catch_rate_interval,
    deviation_interval,
    juggling_episodes,
)
from motion_envs.datasets.juggling import SIMULATED_LABEL, SPLIT_SEEDS, JugglingTask
from motion_envs.models.juggling import CONTROLLERS, LEVELS

__all__ = [
    "ENV_ID",
    "LevelsConfig",
    "check_levels_config",
    "level_episodes",
    "report_levels",
    "run_levels",
    "summary",
    "write_levels",
]

#: The environment the levels are played in.
ENV_ID = "MotionEnvs/Juggling-v1"


@dataclass(frozen=True)
class LevelsConfig:
    """What ``motion-bench juggling --levels`` runs (``agent``: a run folder or None)."""

    levels: tuple[str, ...] = ("easy", "medium", "hard")
    methods: tuple[str, ...] = CONTROLLERS
    episodes: int = 200
    max_catches: int = 3
    gravity: float = 9.81
    split: str = "test"
    agent: str | None = None


def check_levels_config(config: LevelsConfig) -> None:
    """Raise :class:`baselines.options.ConfigError` naming the first bad field."""
    if not config.levels:
        raise options.ConfigError("levels", "must name at least one level")
    for level in config.levels:
        if level not in LEVELS:
            raise options.ConfigError("levels", f"must be among {list(LEVELS)}; got {level!r}")
    for m in config.methods:
        if m not in CONTROLLERS:
            raise options.ConfigError("methods", f"must be among {list(CONTROLLERS)}; got {m!r}")
    if config.episodes < 2:
        raise options.ConfigError("episodes", f"must be >= 2; got {config.episodes}")
    if config.max_catches < 1:
        raise options.ConfigError("max_catches", f"must be >= 1; got {config.max_catches}")
    if not config.gravity > 0:
        raise options.ConfigError("gravity", f"must be > 0; got {config.gravity}")
    if config.split not in SPLIT_SEEDS:
        raise options.ConfigError("split", f"must be one of {sorted(SPLIT_SEEDS)}")


def level_episodes(
    level: str,
    config: LevelsConfig,
    controller: str = "juggler",
    policy: Policy | None = None,
    env_kwargs: dict[str, Any] | None = None,
) -> JugglingEpisodes:
    """The episodes of ``controller`` (plus ``policy``'s residual; None: the zero action)
    on ``level``, seeds of ``config.split``; ``env_kwargs`` (an agent's) under the level's."""
    kwargs = {
        **(env_kwargs or {}),
        "level": level,
        "controller": controller,
        "max_catches": config.max_catches,
        "gravity": config.gravity,
    }
    return juggling_episodes(policy, ENV_ID, kwargs, config.split, config.episodes)


def summary(eps: JugglingEpisodes) -> dict[str, Any]:
    """One method's entry of ``results.json`` (see the module docstring)."""
    rate, lo, hi = catch_rate_interval(eps)
    dev, dlo, dhi = deviation_interval(eps)
    return {
        "catch_rate": rate,
        "catch_rate_ci": [lo, hi],
        "consecutive_catches_median": float(np.median(eps.catches)),
        "tosses": int(eps.tosses.sum()),
        "catches": int(eps.catches.sum()),
        "drops": int(eps.dropped.sum()),
        "deviation_m": dev,
        "deviation_ci": [dlo, dhi],
    }


def _same_controller(level: str, method: str, gravity: float) -> str:
    """The controller ``method`` is on ``level``: the latency-aware juggler predicts the
    ball forward by the delay, which rounds to no control period at a zero latency
    (``easy``): there it is the juggler, step for step."""
    dt = JugglingTask(gravity=gravity).dt
    if method == "juggler_latency_aware" and round(LEVELS[level].latency / dt) == 0:
        return "juggler"
    return method


def run_levels(config: LevelsConfig) -> dict[str, Any]:
    """Every level x method, and the agent when given (module docstring); JSON-ready."""
    check_levels_config(config)
    loaded = None
    if config.agent is not None:
        from baselines.agents.rundir import load_run

        loaded = load_run(config.agent)
        if loaded.env_id != ENV_ID:
            raise options.ConfigError("agent", f"was trained on {loaded.env_id}, not {ENV_ID}")
    t0 = time.process_time()
    levels = []
    for level in config.levels:
        methods: dict[str, Any] = {}
        played: dict[str, JugglingEpisodes] = {}
        for method in config.methods:
            same = _same_controller(level, method, config.gravity)
            if same in played:  # the same controller on the same seeds: not played twice
                played[method] = played[same]
                methods[method] = copy.deepcopy(methods[same])
                continue
            played[method] = level_episodes(level, config, method)
            methods[method] = summary(played[method])
        if loaded is not None:
            kwargs = {k: v for k, v in loaded.env_kwargs.items() if k != "controller"}
            eps = level_episodes(level, config, "juggler", loaded.policy(), kwargs)
            entry = summary(eps)
            juggler = played.get("juggler") or level_episodes(level, config)
            diff, lo, hi = catch_rate_difference(eps, juggler)
            entry |= {"catch_rate_difference": diff, "catch_rate_difference_ci": [lo, hi]}
            methods["agent"] = entry
        levels.append({"level": level, "values": asdict(LEVELS[level]), "methods": methods})
    return {
        "benchmark": f"juggling levels ({ENV_ID})",
        "config": asdict(config),
        "demonstrations": SIMULATED_LABEL,
        "seeds": {
            "split": config.split,
            "first": SPLIT_SEEDS[config.split],
            "count": config.episodes,
        },
        "levels": levels,
        "targets": _targets(levels),
        "timing": {"cpu_s": time.process_time() - t0},
    }


def _targets(levels: list[dict[str, Any]]) -> dict[str, Any]:
    by = {lv["level"]: lv["methods"] for lv in levels}

    def rate(level: str, method: str) -> float | None:
        value = by.get(level, {}).get(method, {}).get("catch_rate")
        return None if value is None else float(value)

    # (value, bound, at least): the benchmark's acceptance targets
    checks: dict[str, tuple[float | None, float, bool]] = {
        "juggler_easy>=0.95": (rate("easy", "juggler"), 0.95, True),
        "juggler_medium<=0.80": (rate("medium", "juggler"), 0.80, False),
        "juggler_hard<=0.50": (rate("hard", "juggler"), 0.50, False),
        "latency_aware_medium>=0.95": (rate("medium", "juggler_latency_aware"), 0.95, True),
    }
    out: dict[str, Any] = {}
    for key, (value, bound, at_least) in checks.items():
        met = None if value is None else (value >= bound if at_least else value <= bound)
        out[key] = {"value": value, "met": met}
    for level, methods in by.items():
        j = rate(level, "juggler")
        for trivial in ("fixed_point", "commanded_intercept"):
            t = rate(level, trivial)
            if j is not None and t is not None:
                out[f"{trivial}<juggler_{level}"] = {"value": t, "juggler": j, "met": t < j}
        agent = methods.get("agent")
        if level == "medium" and agent is not None:
            diff, (lo, _) = agent["catch_rate_difference"], agent["catch_rate_difference_ci"]
            out["agent_medium>=juggler+0.10"] = {
                "value": diff,
                "ci_low": lo,
                "met": bool(diff >= 0.10 and lo > 0),
            }
    return out


def report_levels(doc: dict[str, Any]) -> str:
    """The printed table of :func:`run_levels`'s document."""
    seeds = doc["seeds"]
    lines = [
        f"Juggling-v1 levels ({doc['demonstrations']}); {seeds['count']} {seeds['split']} "
        f"episodes per level and method (seeds from {seeds['first']})",
        f"{'level':8s} {'method':24s} {'catch rate [95% CI]':24s} {'consec.':>7s} "
        f"{'deviation m':>11s}",
    ]
    for lv in doc["levels"]:
        for name, m in lv["methods"].items():
            lo, hi = m["catch_rate_ci"]
            extra = ""
            if "catch_rate_difference" in m:
                dlo, dhi = m["catch_rate_difference_ci"]
                extra = f"  vs juggler {m['catch_rate_difference']:+.3f} [{dlo:+.3f}, {dhi:+.3f}]"
            lines.append(
                f"{lv['level']:8s} {name:24s} {m['catch_rate']:.3f} [{lo:.3f}, {hi:.3f}]{'':4s} "
                f"{m['consecutive_catches_median']:7.1f} {m['deviation_m']:11.4f}{extra}"
            )
    for key, t in doc["targets"].items():
        met = "met" if t["met"] else ("n/a" if t["met"] is None else "NOT met")
        value = "-" if t["value"] is None else f"{t['value']:.3f}"
        lines.append(f"target {key}: {value} ({met})")
    lines.append(f"CPU {doc['timing']['cpu_s']:.1f} s")
    return "\n".join(lines)


def write_levels(doc: dict[str, Any], out: str | Path) -> list[Path]:
    """``results.json`` of the levels in ``out`` (through :mod:`motion_envs._io`)."""
    import json

    from motion_envs._io import atomic_write_text

    path = Path(out) / "results.json"
    return [atomic_write_text(path, json.dumps(doc, indent=2) + "\n")]
