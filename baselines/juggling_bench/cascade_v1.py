"""``motion-bench juggling --version v2 --pattern P``: Cascade-v1's reference rows (a
pattern at Juggling-v2's human levels), scored by catches before the first drop.

For each level (``easy``, ``medium``, ``hard``;
:data:`motion_envs.models.juggling.CASCADE_V1_LEVELS`) the rows (:data:`ROWS`) are played
in ``MotionEnvs/Cascade-v1`` with ``pattern=P`` (the residual, where a row acts, in the
env's own action space, :data:`RESIDUAL_SCALE` m per unit action):

* ``juggler``: the analytic juggler told each ball through the flight fitted to its
  frames taken as the present (the zero action);
* ``oracle``: the juggler given the episode's true delay and each ball's true drag
  (``juggler_oracle``): a reference, never a competitor and never chosen;
* ``oracle_catch``: the oracle with Juggling-v2's catch planned for the capture rule
  (``juggler_oracle_catch``: each flying ball told ``lead`` s ahead, so the hand ends its
  reach early at the meeting point and waits; the lead chosen per juggler on TRAINING
  seeds, :data:`motion_envs.models.juggling.CASCADE_CATCH_PLANS`): the reference the
  room is measured against (:data:`UPPER_REFERENCE`), called the UPPER reference only
  where measured at or above every row (``upper_is_upper``: its paired difference from
  every other row, in mean catches, is >= 0; the report names the rows with an interval
  wholly above it);
* ``juggler_mean_delay``: the frames shifted by the level's mean delay;
* ``late_meeting``: the same told the mean delay plus an offset from
  :data:`LATE_OFFSETS` (declared here before any run), the offset with the most mean
  catches before the first drop on VALIDATION episodes;
* ``mean_delay_catch``: the same catch plan on the level's mean delay
  (``juggler_mean_delay_catch``, its lead chosen on TRAINING seeds; no hidden
  information: a competitor). Without drag in its estimate, telling a ball ``lead``
  ahead is what ``late_meeting``'s offset does (a later placed fit, predicted further);
  the rows differ in the seeds the number is chosen on (one lead for all levels) and in
  the flight told before a ball's first three frames (advanced by the lead only);
* ``fixed_point``: the juggler that catches at the nominal point and time, never
  looking (trivial);
* ``random``: uniform random actions on the juggler (trivial; each episode's generator
  seeded by its seed).

Every choice (the late offset; the best non-oracle row, by mean catches before the first
drop) is made on ``val_episodes`` VALIDATION episodes (``SPLIT_SEEDS["val"]``) before
any test seed is played; the rows are then played on ``episodes`` TEST episodes. An
episode ends at the first drop or after ``max_catches`` catches (censored). Reported per
row (:func:`baselines.juggling_bench.cascade.summary`, 95 % bootstrap intervals resampling
episodes): the median and the mean catches before the first drop, the catch rate, the
median time to the first drop; per level the ROOM, the paired difference of mean catches
of ``oracle_catch`` and of the best non-oracle row, ``oracle_catch`` minus every other
row (paired), and the old ``oracle`` minus the best row. The demonstrations (the
likeness reward, the siteswap juggler's style) are SIMULATED.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from baselines import options
from baselines.juggling_bench.cascade import CascadeEpisodes, summary
from motion_envs.datasets.juggling import SIMULATED_LABEL, SPLIT_SEEDS, episode_seeds
from motion_envs.models.juggling import CASCADE_V1_LEVELS, V2_LEVELS, pattern_spec

__all__ = [
    "CASCADE_V1_ENV_ID",
    "LATE_OFFSETS",
    "REFERENCES",
    "RESIDUAL_SCALE",
    "ROWS",
    "UPPER_REFERENCE",
    "CascadeV1Config",
    "cascade_v1_episodes",
    "check_cascade_v1_config",
    "choose_late_offset",
    "report_cascade_v1",
    "row_play",
    "row_summary",
    "run_cascade_v1",
    "write_cascade_v1",
]

CASCADE_V1_ENV_ID = "MotionEnvs/Cascade-v1"
#: m of residual per unit action (the random row's; the agent block's scale).
RESIDUAL_SCALE = 0.1
#: s added to the level's mean delay by ``late_meeting`` (the env's ``delay_offset``);
#: Juggling-v2's grid (0-80 ms, its best at the largest on medium and hard) widened to
#: 120 ms before any Cascade-v1 run.
LATE_OFFSETS: tuple[float, ...] = (0.0, 0.02, 0.04, 0.06, 0.08, 0.10, 0.12)
#: The rows, in the report's order.
ROWS = (
    "juggler",
    "oracle",
    "oracle_catch",
    "juggler_mean_delay",
    "late_meeting",
    "mean_delay_catch",
    "fixed_point",
    "random",
)
#: The references (given what the world hides): never a competitor, never chosen.
REFERENCES = ("oracle", "oracle_catch")
#: The reference the room is measured against.
UPPER_REFERENCE = "oracle_catch"
_LABELS = {"oracle": "oracle (true delay, drag)", "oracle_catch": "oracle+catch plan"}
#: A row's policy: None (the zero action) or ``"random"``.
Policy = str | None
Play = Callable[[Policy, dict[str, Any], str, int], CascadeEpisodes]


@dataclass(frozen=True)
class CascadeV1Config:
    """What ``motion-bench juggling --version v2 --pattern P`` runs."""

    pattern: str = "3"
    levels: tuple[str, ...] = CASCADE_V1_LEVELS
    episodes: int = 100
    val_episodes: int = 30
    max_catches: int = 30


def check_cascade_v1_config(config: CascadeV1Config) -> None:
    """Raise :class:`baselines.options.ConfigError` naming the first bad field."""
    try:
        pattern_spec(config.pattern)
    except ValueError as exc:
        raise options.ConfigError("pattern", str(exc)) from None
    if not config.levels or any(lv not in CASCADE_V1_LEVELS for lv in config.levels):
        raise options.ConfigError(
            "levels", f"must be among {list(CASCADE_V1_LEVELS)}; got {list(config.levels)}"
        )
    for name in ("episodes", "val_episodes"):
        if getattr(config, name) < 2:
            raise options.ConfigError(name, f"must be >= 2; got {getattr(config, name)}")
    if config.max_catches < 1:
        raise options.ConfigError("max_catches", f"must be >= 1; got {config.max_catches}")


def cascade_v1_episodes(
    policy: Policy, kwargs: dict[str, Any], split: str, n: int
) -> CascadeEpisodes:
    """``n`` episodes of Cascade-v1 made with ``kwargs``, reset with the seeds of
    ``split``: the zero action (``policy`` None; the env's :meth:`play`) or uniform
    random actions (``"random"``, a generator per episode seeded with its seed)."""
    from motion_envs.envs.juggling import CascadeV1Env

    env = CascadeV1Env(**kwargs)
    seeds = episode_seeds(split, n)
    rows = []
    for seed in seeds.tolist():
        if policy is None:
            rows.append(env.play(seed))
            continue
        rng = np.random.default_rng(seed)
        env.reset(seed=seed)
        terminated = truncated = False
        while not (terminated or truncated):
            _, _, terminated, truncated, info = env.step(rng.uniform(-1.0, 1.0, 4))
        rows.append((info["catches"], info["tosses"], terminated, info["time"]))
    return CascadeEpisodes(
        seeds=seeds,
        catches=np.array([r[0] for r in rows], dtype=np.int64),
        tosses=np.array([r[1] for r in rows], dtype=np.int64),
        dropped=np.array([r[2] for r in rows], dtype=bool),
        time=np.array([r[3] for r in rows], dtype=np.float64),
    )


def _kwargs(
    level: str, config: CascadeV1Config, controller: str, offset: float = 0.0
) -> dict[str, Any]:
    out: dict[str, Any] = {
        "level": level,
        "pattern": config.pattern,
        "controller": controller,
        "max_catches": config.max_catches,
        "residual_scale": RESIDUAL_SCALE,
    }
    if offset:
        out["delay_offset"] = offset
    return out


def _offset_key(offset: float) -> str:
    return f"{offset * 1000:.0f} ms"


def choose_late_offset(
    level: str, config: CascadeV1Config, play: Play = cascade_v1_episodes
) -> tuple[float, dict[str, float]]:
    """The offset of :data:`LATE_OFFSETS` with the most mean catches before the first
    drop on ``config.val_episodes`` VALIDATION episodes (ties: the smallest), and every
    candidate's validation mean."""
    means: dict[str, float] = {}
    best, best_mean = LATE_OFFSETS[0], -1.0
    for offset in LATE_OFFSETS:
        eps = play(None, _kwargs(level, config, "juggler_mean_delay", offset), "val",
                   config.val_episodes)  # fmt: skip
        means[_offset_key(offset)] = float(eps.catches.mean())
        if means[_offset_key(offset)] > best_mean:
            best, best_mean = offset, means[_offset_key(offset)]
    return best, means


def _players(offset: float) -> dict[str, tuple[str, Policy, float]]:
    """Each row's controller, policy and delay offset."""
    return {
        "juggler": ("juggler", None, 0.0),
        "oracle": ("juggler_oracle", None, 0.0),
        "oracle_catch": ("juggler_oracle_catch", None, 0.0),
        "juggler_mean_delay": ("juggler_mean_delay", None, 0.0),
        "late_meeting": ("juggler_mean_delay", None, offset),
        "mean_delay_catch": ("juggler_mean_delay_catch", None, 0.0),
        "fixed_point": ("fixed_point", None, 0.0),
        "random": ("juggler", "random", 0.0),
    }


def row_play(
    level: str, config: CascadeV1Config, name: str, offset: float
) -> tuple[Policy, dict[str, Any]]:
    """Row ``name``'s policy and env keywords on ``level`` (``offset``: the late offset
    :func:`choose_late_offset` chose), as :func:`run_cascade_v1` plays it."""
    ctl, policy, off = _players(offset)[name]
    return policy, _kwargs(level, config, ctl, off)


def row_summary(eps: Any) -> dict[str, Any]:
    """A row's entry of the results (:func:`~baselines.juggling_bench.cascade.summary`
    and the 95 % interval of the mean catches before the first drop); any episodes with
    seeds, catches, tosses, dropped and time (an agent's too)."""
    return {**summary(eps), "catches_mean_ci": _mean_ci(eps)}


def _paired(a: CascadeEpisodes, b: CascadeEpisodes) -> dict[str, Any]:
    """Mean catches of ``a`` minus ``b`` over the same seeds, with its 95 % interval."""
    from baselines.stats import group_bootstrap

    if not np.array_equal(a.seeds, b.seeds):
        raise ValueError("paired episodes must share their seeds")
    d = (a.catches - b.catches).astype(np.float64)
    value, lo, hi = group_bootstrap(lambda rows: float(d[rows].mean()), np.arange(d.size))
    return {"value": value, "ci": [lo, hi]}


def _mean_ci(eps: CascadeEpisodes) -> list[float]:
    from baselines.stats import group_bootstrap

    c = eps.catches.astype(np.float64)
    _, lo, hi = group_bootstrap(lambda rows: float(c[rows].mean()), np.arange(c.size))
    return [lo, hi]


def run_cascade_v1(
    config: CascadeV1Config,
    play: Play = cascade_v1_episodes,
    offset_chooser: Any = choose_late_offset,
) -> dict[str, Any]:
    """Every level's rows (module docstring); JSON-ready. ``play`` and ``offset_chooser``
    are for tests (the spy that proves the choices read no test seed)."""
    check_cascade_v1_config(config)
    t0 = time.process_time()
    levels = []
    for level in config.levels:
        offset, offset_means = offset_chooser(level, config, play)
        players = _players(offset)
        reuse = {
            "juggler_mean_delay": _offset_key(0.0),
            "late_meeting": _offset_key(offset),
        }
        val_means: dict[str, float] = {}
        for name, (ctl, policy, off) in players.items():
            if name in REFERENCES:
                continue
            key = reuse.get(name)
            if key is not None and key in offset_means:
                val_means[name] = offset_means[key]
            else:
                eps = play(policy, _kwargs(level, config, ctl, off), "val", config.val_episodes)
                val_means[name] = float(eps.catches.mean())
        best = max((r for r in ROWS if r in val_means), key=lambda r: val_means[r])
        played = {
            name: play(policy, _kwargs(level, config, ctl, off), "test", config.episodes)
            for name, (ctl, policy, off) in players.items()
        }
        rows = {name: row_summary(eps) for name, eps in played.items()}
        room = _paired(played[UPPER_REFERENCE], played[best])
        above = {
            name: _paired(played[UPPER_REFERENCE], eps)
            for name, eps in played.items()
            if name != UPPER_REFERENCE
        }
        levels.append(
            {
                "level": level,
                "values": asdict(V2_LEVELS[level]),
                "late_offset_s": offset,
                "late_offset_val_mean_catches": offset_means,
                "val_mean_catches": val_means,
                "best_non_oracle": best,
                "rows": rows,
                "room": room,
                "upper_minus_rows": above,
                "upper_is_upper": all(d["value"] >= 0 for d in above.values()),
                "oracle_minus_best": _paired(played["oracle"], played[best]),
                "best_minus_juggler": _paired(played[best], played["juggler"]),
            }
        )
    spec = pattern_spec(config.pattern)
    return {
        "benchmark": f"juggling v2 rows, pattern {config.pattern} ({CASCADE_V1_ENV_ID})",
        "config": asdict(config),
        "demonstrations": SIMULATED_LABEL,
        "pattern": {
            "name": spec.name,
            "siteswap": spec.siteswap,
            "balls": spec.balls,
            "juggler": "fitted cascade" if spec.fitted else "siteswap",
        },
        "residual_scale_m": RESIDUAL_SCALE,
        "seeds": {
            "choice": {"split": "val", "first": SPLIT_SEEDS["val"], "count": config.val_episodes},
            "test": {"split": "test", "first": SPLIT_SEEDS["test"], "count": config.episodes},
        },
        "levels": levels,
        "timing": {"cpu_s": time.process_time() - t0},
    }


def report_cascade_v1(doc: dict[str, Any]) -> str:
    """The printed table of :func:`run_cascade_v1`'s document."""
    test, pat = doc["seeds"]["test"], doc["pattern"]
    lines = [
        f"Cascade-v1, pattern {pat['siteswap']} ({pat['juggler']} juggler; "
        f"{doc['demonstrations']}); {test['count']} test episodes per level and row (seeds "
        f"from {test['first']}), at most {doc['config']['max_catches']} catches; choices on "
        f"{doc['seeds']['choice']['count']} validation episodes",
        f"{'level':7s} {'row':19s} {'catches median [95% CI]':24s} "
        f"{'mean [95% CI]':22s} {'catch rate [95% CI]':22s} {'censored':>8s}",
    ]
    for lv in doc["levels"]:
        for name, m in lv["rows"].items():
            c, (clo, chi) = m["catches_median"], m["catches_median_ci"]
            mean, (mlo, mhi) = m["catches_mean"], m["catches_mean_ci"]
            r, (rlo, rhi) = m["catch_rate"], m["catch_rate_ci"]
            label = _LABELS.get(name, name)
            lines.append(
                f"{lv['level']:7s} {label[:19]:19s} {c:5.1f} [{clo:5.1f}, {chi:5.1f}]{'':6s} "
                f"{mean:5.2f} [{mlo:5.2f}, {mhi:5.2f}]{'':3s} {r:.3f} [{rlo:.3f}, {rhi:.3f}]"
                f"{'':2s} {m['censored']:8d}"
            )
        room, old = lv["room"], lv["oracle_minus_best"]
        upper = "the upper reference" if lv["upper_is_upper"] else "NOT an upper reference"
        below = [k for k, d in lv["upper_minus_rows"].items() if d["ci"][1] < 0]
        lines.append(
            f"{lv['level']:7s} late offset {lv['late_offset_s'] * 1000:.0f} ms; best non-oracle "
            f"row {lv['best_non_oracle']} (chosen on validation); ROOM oracle_catch - best "
            f"(paired mean catches): {room['value']:+.2f} [{room['ci'][0]:+.2f}, "
            f"{room['ci'][1]:+.2f}]; oracle - best {old['value']:+.2f} [{old['ci'][0]:+.2f}, "
            f"{old['ci'][1]:+.2f}]; oracle_catch is {upper}"
            + (f" (below {', '.join(below)})" if below else "")
        )
    lines.append(f"CPU {doc['timing']['cpu_s']:.1f} s")
    return "\n".join(lines)


def write_cascade_v1(doc: dict[str, Any], out: str | Path) -> list[Path]:
    """``results.json`` in ``out`` (through :mod:`motion_envs._io`)."""
    from motion_envs._io import atomic_write_text

    path = Path(out) / "results.json"
    return [atomic_write_text(path, json.dumps(doc, indent=2) + "\n")]
