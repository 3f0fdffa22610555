"""``motion-bench juggling --pattern 3``: the three-ball cascade (``MotionEnvs/Cascade-v0``)
at Juggling-v1's levels, for the analytic cascade juggler, its latency-aware variant and
the two trivial policies.

For each level (:data:`motion_envs.models.juggling.LEVELS`) and each controller
(:data:`~motion_envs.models.juggling.CASCADE_CONTROLLERS`), plays ``episodes`` episodes
reset with the TEST seeds ``SPLIT_SEEDS["test"] + i`` of
:mod:`motion_envs.datasets.juggling` (the cascade juggler's timing and the levels were
chosen on other seeds, its three constants on the training seeds by
``experiments/cascade_constants.py``). An episode is Cascade-v0's zero-action episode (the
controller alone; :func:`cascade_episode` steps the env's world, sensor and controller
directly, the same loop the env runs, tested equal to it): it ends at the first drop or after
``max_catches`` catches. Reported per method, with 95 % bootstrap intervals resampling
episodes (:func:`baselines.stats.group_bootstrap`):

* ``catches_median``: the median over episodes of the catches before the first drop
  (censored at ``max_catches``: ``censored`` episodes reached it without a drop);
* ``catch_rate``: catches per toss, pooled over the episodes;
* ``time_to_drop_median``: the median over episodes of the simulated time (s) to the
  first drop; a censored episode counts with its length (a lower bound).

At a level without latency the latency-aware juggler IS the juggler (it predicts the
measurement forward by zero seconds): its episodes are the juggler's (``"same_as"``).
The demonstrations are SIMULATED. :func:`run_cascade` is pure, :func:`report_cascade`
the printed text, :func:`write_cascade` writes ``results.json``.
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from baselines import options
from motion_envs.datasets.juggling import (
    SIMULATED_LABEL,
    SPLIT_SEEDS,
    JugglingTask,
    episode_seeds,
)
from motion_envs.models.juggling import (
    CASCADE_CONTROLLERS,
    LEVELS,
    CascadeTunables,
    PatternCheck,
    cascade_fit,
    pattern_spec,
    pattern_tempo,
)

if TYPE_CHECKING:
    from baselines.agents.cascade_score import CascadeDeviations

__all__ = [
    "CASCADE_ENV_ID",
    "CascadeConfig",
    "CascadeEpisodes",
    "cascade_episode",
    "cascade_episodes",
    "check_cascade_config",
    "pattern_check",
    "report_cascade",
    "run_cascade",
    "write_cascade",
]

#: The environment the pattern is played in.
CASCADE_ENV_ID = "MotionEnvs/Cascade-v0"
#: Catches before the first drop the analytic juggler should sustain on ``easy`` (median).
TARGET_EASY_CATCHES = 100
#: ... per pattern where the benchmark's target says otherwise (the five-ball cascade:
#: median >= 50 of at most 100, the trivial policies' median <= 2).
PATTERN_EASY_CATCHES = {"5": 50}
#: The trivial policies' easy median at most (the five-ball target).
TARGET_TRIVIAL_CATCHES = 2


@dataclass(frozen=True)
class CascadeConfig:
    """What ``motion-bench juggling --pattern 3`` runs."""

    pattern: str = "3"
    levels: tuple[str, ...] = ("easy", "medium", "hard")
    methods: tuple[str, ...] = CASCADE_CONTROLLERS
    episodes: int = 50
    max_catches: int = 10
    gravity: float = 9.81
    split: str = "test"


def pattern_check(pattern: str, gravity: float) -> PatternCheck:
    """The registered ``pattern`` (its name; :func:`~motion_envs.models.juggling.pattern_spec`)
    at its own juggler's tempo (:func:`~motion_envs.models.juggling.pattern_tempo`: the
    fitted cascade juggler's fit of its ball count at ``gravity`` checked against the
    hand's speed limit, or the siteswap juggler's plan). Raises ``ValueError`` with the
    reason for a pattern that is not registered."""
    return pattern_tempo(pattern_spec(pattern), gravity)


def check_cascade_config(config: CascadeConfig) -> None:
    """Raise :class:`baselines.options.ConfigError` naming the first bad field (a
    ``pattern`` the cascade juggler cannot play gets its reasons)."""
    if not (math.isfinite(config.gravity) and config.gravity > 0):
        raise options.ConfigError("gravity", f"must be > 0; got {config.gravity}")
    try:
        check = pattern_check(config.pattern, config.gravity)
    except ValueError as exc:
        raise options.ConfigError("pattern", str(exc)) from None
    if not check.fits:
        raise options.ConfigError(
            "pattern",
            f"{check.siteswap!r} does not fit the cascade juggler at its tempo (beat "
            f"{check.beat:.3f} s, dwell {check.dwell:.3f} s): " + "; ".join(check.reasons),
        )
    if not config.levels or any(lv not in LEVELS for lv in config.levels):
        raise options.ConfigError("levels", f"must be among {list(LEVELS)}")
    for m in config.methods:
        if m not in CASCADE_CONTROLLERS:
            raise options.ConfigError("methods", f"must be among {list(CASCADE_CONTROLLERS)}")
    if config.episodes < 2:
        raise options.ConfigError("episodes", f"must be >= 2; got {config.episodes}")
    if config.max_catches < 1:
        raise options.ConfigError("max_catches", f"must be >= 1; got {config.max_catches}")
    if config.split not in SPLIT_SEEDS:
        raise options.ConfigError("split", f"must be one of {sorted(SPLIT_SEEDS)}")


@dataclass(frozen=True)
class CascadeEpisodes:
    """Per episode: ``catches`` before the first drop, ``tosses``, ``dropped``, ``time``
    (s, at the drop or at the end); ``deviations``: the hands' phase segments scored
    against demonstrations, when recorded
    (:class:`~baselines.agents.cascade_score.CascadeDeviations`)."""

    seeds: NDArray[np.int64]
    catches: NDArray[np.int64]
    tosses: NDArray[np.int64]
    dropped: NDArray[np.bool_]
    time: NDArray[np.float64]
    deviations: CascadeDeviations | None = None

    @classmethod
    def from_rows(
        cls,
        seeds: NDArray[np.int64],
        rows: Sequence[tuple[int, int, bool, float]],
        deviations: CascadeDeviations | None = None,
    ) -> CascadeEpisodes:
        """The episodes of ``seeds`` from one ``(catches, tosses, dropped, time)`` row
        each (:func:`cascade_episode`'s order)."""
        return cls(
            seeds=seeds,
            catches=np.array([r[0] for r in rows], dtype=np.int64),
            tosses=np.array([r[1] for r in rows], dtype=np.int64),
            dropped=np.array([r[2] for r in rows], dtype=bool),
            time=np.array([r[3] for r in rows], dtype=np.float64),
            deviations=deviations,
        )


def cascade_episode(
    level: str,
    method: str,
    seed: int,
    max_catches: int,
    gravity: float = 9.81,
    pattern: str = "3",
    tunables: CascadeTunables | None = None,
) -> tuple[int, int, bool, float]:
    """One zero-action episode of Cascade-v0 (``level``, ``controller=method``,
    ``pattern``, ``tunables``, reset with ``seed``): ``(catches, tosses, dropped, time)``,
    played by the env itself (:meth:`~motion_envs.envs.juggling.CascadeEnv.play`)."""
    from motion_envs.envs.juggling import CascadeEnv

    env = CascadeEnv(
        level=level,
        controller=method,
        max_catches=max_catches,
        gravity=gravity,
        pattern=pattern,
        tunables=tunables,
    )
    return env.play(seed)


def cascade_episodes(level: str, method: str, config: CascadeConfig) -> CascadeEpisodes:
    """The episodes of ``method`` on ``level``, seeds of ``config.split``."""
    seeds = episode_seeds(config.split, config.episodes)
    rows = [
        cascade_episode(level, method, int(s), config.max_catches, config.gravity, config.pattern)
        for s in seeds
    ]
    return CascadeEpisodes.from_rows(seeds, rows)


def summary(eps: CascadeEpisodes) -> dict[str, Any]:
    """One method's entry of ``results.json`` (module docstring)."""
    from baselines.stats import group_bootstrap

    idx = np.arange(eps.seeds.size)

    def median_of(values: NDArray[Any]) -> tuple[float, float, float]:
        v = values.astype(np.float64)
        return group_bootstrap(lambda rows: float(np.median(v[rows])), idx)

    c, clo, chi = median_of(eps.catches)
    t, tlo, thi = median_of(eps.time)
    rate, rlo, rhi = group_bootstrap(
        lambda rows: float(eps.catches[rows].sum() / max(int(eps.tosses[rows].sum()), 1)), idx
    )
    return {
        "catches_median": c,
        "catches_median_ci": [clo, chi],
        "catches_mean": float(eps.catches.mean()),
        "catch_rate": rate,
        "catch_rate_ci": [rlo, rhi],
        "time_to_drop_median": t,
        "time_to_drop_median_ci": [tlo, thi],
        "drops": int(eps.dropped.sum()),
        "censored": int((~eps.dropped).sum()),
        "tosses": int(eps.tosses.sum()),
        "catches": int(eps.catches.sum()),
    }


def run_cascade(config: CascadeConfig) -> dict[str, Any]:
    """Every level x method (module docstring); JSON-ready."""
    check_cascade_config(config)
    t0 = time.process_time()
    levels = []
    task = JugglingTask(gravity=config.gravity)
    for level in config.levels:
        methods: dict[str, Any] = {}
        played: dict[str, CascadeEpisodes] = {}
        no_delay = round(LEVELS[level].latency / task.dt) == 0
        for method in config.methods:
            if method == "juggler_latency_aware" and no_delay and "juggler" in played:
                methods[method] = {**summary(played["juggler"]), "same_as": "juggler"}
                continue
            played[method] = cascade_episodes(level, method, config)
            methods[method] = summary(played[method])
        levels.append({"level": level, "values": asdict(LEVELS[level]), "methods": methods})
    spec = pattern_spec(config.pattern)
    check = pattern_check(config.pattern, config.gravity)
    if spec.fitted:
        p = cascade_fit(config.gravity, spec.balls).pattern
        r = p.dwell_ratio if spec.dwell_ratio is None else spec.dwell_ratio
        flight, demo_r, demo_period = p.flight, p.dwell_ratio, p.demo_period
    else:  # the siteswap juggler: the flight of the highest throw
        r = float(spec.dwell_ratio or 0.0)
        flight, demo_r, demo_period = check.throws[0].flight, None, None
    return {
        "benchmark": f"juggling pattern {config.pattern} ({CASCADE_ENV_ID})",
        "config": asdict(config),
        "demonstrations": SIMULATED_LABEL,
        "pattern": {
            "name": spec.name,
            "siteswap": spec.siteswap,
            "juggler": "fitted cascade" if spec.fitted else "siteswap",
            "hands": 2,
            "balls": spec.balls,
            "dwell_ratio": r,
            "dwell_ratio_source": spec.note,
            "flight_s": flight,
            "period_s": 2.0 * check.beat,
            "beat_s": check.beat,
            "demonstrations_dwell_ratio": demo_r,
            "demonstrations_period_s": demo_period,
            "throws": [asdict(n) for n in check.throws],
        },
        "seeds": {
            "split": config.split,
            "first": SPLIT_SEEDS[config.split],
            "count": config.episodes,
        },
        "levels": levels,
        "targets": _targets(levels, config),
        "timing": {"cpu_s": time.process_time() - t0},
    }


def _targets(levels: list[dict[str, Any]], config: CascadeConfig) -> dict[str, Any]:
    by = {lv["level"]: lv["methods"] for lv in levels}

    def value(level: str, method: str, key: str) -> float | None:
        v = by.get(level, {}).get(method, {}).get(key)
        return None if v is None else float(v)

    out: dict[str, Any] = {}
    easy = value("easy", "juggler", "catches_median")
    target = PATTERN_EASY_CATCHES.get(config.pattern, TARGET_EASY_CATCHES)
    checkable = config.max_catches >= target
    out[f"juggler_easy_catches_median>={target}"] = {
        "value": easy,
        "met": None if easy is None or not checkable else easy >= target,
        "note": None if checkable else f"needs --max-catches >= {target}",
    }
    if config.pattern in PATTERN_EASY_CATCHES:
        for trivial in ("fixed_point", "commanded_intercept"):
            t = value("easy", trivial, "catches_median")
            if t is not None:
                out[f"{trivial}_easy_catches_median<={TARGET_TRIVIAL_CATCHES}"] = {
                    "value": t,
                    "met": t <= TARGET_TRIVIAL_CATCHES,
                }
    for level in by:
        j = value(level, "juggler", "catches_mean")
        la = value(level, "juggler_latency_aware", "catches_mean")
        if level != "easy" and j is not None and la is not None:
            out[f"juggler<latency_aware_{level}"] = {"value": j, "reference": la, "met": j < la}
        for trivial in ("fixed_point", "commanded_intercept"):
            t = value(level, trivial, "catches_mean")
            if j is not None and t is not None:
                out[f"{trivial}<juggler_{level}"] = {"value": t, "juggler": j, "met": t < j}
    return out


def report_cascade(doc: dict[str, Any]) -> str:
    """The printed table of :func:`run_cascade`'s document."""
    seeds, pat = doc["seeds"], doc["pattern"]
    lines = [
        f"Cascade-v0, pattern {pat['siteswap']} ({doc['demonstrations']}); beat "
        f"{pat['beat_s']:.3f} s, flight {pat['flight_s']:.3f} s, dwell ratio "
        f"{pat['dwell_ratio']:.3f}; {seeds['count']} {seeds['split']} episodes per level and "
        f"method (seeds from {seeds['first']}), at most {doc['config']['max_catches']} catches",
        f"{'level':8s} {'method':22s} {'catches median [95% CI]':26s} {'mean':>6s} "
        f"{'catch rate [95% CI]':24s} {'s to drop [95% CI]':22s} {'censored':>8s}",
    ]
    for lv in doc["levels"]:
        for name, m in lv["methods"].items():
            c, (clo, chi) = m["catches_median"], m["catches_median_ci"]
            r, (rlo, rhi) = m["catch_rate"], m["catch_rate_ci"]
            t, (tlo, thi) = m["time_to_drop_median"], m["time_to_drop_median_ci"]
            same = " (= juggler)" if m.get("same_as") else ""
            lines.append(
                f"{lv['level']:8s} {name:22s} {c:6.1f} [{clo:5.1f}, {chi:5.1f}]{'':7s} "
                f"{m['catches_mean']:6.1f} {r:.3f} [{rlo:.3f}, {rhi:.3f}]{'':4s} "
                f"{t:5.2f} [{tlo:5.2f}, {thi:5.2f}]{'':3s} {m['censored']:8d}{same}"
            )
    for key, t in doc["targets"].items():
        met = "met" if t["met"] else ("n/a" if t["met"] is None else "NOT met")
        v = "-" if t["value"] is None else f"{t['value']:.2f}"
        note = f"; {t['note']}" if t.get("note") else ""
        lines.append(f"target {key}: {v} ({met}{note})")
    lines.append(f"CPU {doc['timing']['cpu_s']:.1f} s")
    return "\n".join(lines)


def write_cascade(doc: dict[str, Any], out: str | Path) -> list[Path]:
    """``results.json`` in ``out`` (through :mod:`motion_envs._io`)."""
    from motion_envs._io import atomic_write_text

    path = Path(out) / "results.json"
    return [atomic_write_text(path, json.dumps(doc, indent=2) + "\n")]
