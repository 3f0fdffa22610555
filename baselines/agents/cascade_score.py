"""The cascades' criteria for agents: catches before the first drop, and the drop hazard.

An episode of ``MotionEnvs/Cascade-v0`` or ``-v1`` ends at the first drop (or after ``max_catches``
catches: censored). Its splits are Juggling's seed ranges
(:data:`motion_envs.datasets.juggling.SPLIT_SEEDS`: training seeds < validation seeds
``1e9 + i`` < test seeds ``2e9 + i``), so validation and test episodes are never trained
on. For each episode :func:`cascade_agent_episodes` records the ``catches`` before the
first drop, the ``tosses`` (releases), whether it ``dropped`` and its simulated ``time``,
the same four numbers ``motion-bench juggling --pattern 3`` records for the analytic
juggler (:func:`baselines.juggling_bench.cascade.cascade_episode`); the zero action's
episodes ARE the juggler's (tested).

* the **headline** is the median over episodes of the catches before the first drop,
  with its 95 % bootstrap interval resampling episodes, computed as ``motion-bench
  juggling --pattern 3`` computes it (tested equal);
  agent and juggler are compared by the difference of their medians on the SAME seeds,
  with a paired bootstrap interval (an episode of both resampled together;
  :func:`catches_median_comparison`); the catch rate (catches per toss, pooled) likewise;
  each difference carries its power line (:class:`baselines.stats.Difference`: the
  differences its interval detects 80 % of the time at this many episodes, and "cannot
  decide at this size" where the claimed one is below);
* the **criterion** checkpoints are chosen by (lower is better) is the drop hazard per
  catch, ``drops / catches`` pooled over the episodes: under a constant chance of a drop
  per catch it is the maximum-likelihood estimate of that chance with censored episodes
  counted correctly (``1 / hazard`` is then the expected catches before a drop). The
  median of a few validation episodes' integer counts moves in steps and ties often; the
  pooled hazard uses every episode's count. ``motion-bench train`` evaluates it on the
  validation seeds only.

The **hand deviation from held-out demonstrations** (the likeness criterion of
:mod:`baselines.agents.juggling_score`, per hand): :class:`RecordHandPaths` keeps each
episode's hand positions ``info["hands"]`` and phase labels ``info["phases"]`` at the
reset and after every step; each hand's path is taken into its OWN frame (the left
hand's mirrored ``x -> -x``, as the cascade demonstrations record it and the env's
likeness reward reads it: :func:`~motion_envs.datasets.juggling.mirror_x`) and cut into
phase segments, each compared with the SIMULATED two-hand cascade demonstrations of the
same ball count (:func:`~motion_envs.models.juggling.cascade_fit`, the cycles held out of
the juggler's fit for the ``"test"`` split, the training ones otherwise;
:func:`cascade_demonstration_paths`) by
:func:`~baselines.agents.juggling_score.segment_deviations`: the distance, after the
departure from the straight line between the segment's ends, to the nearest
demonstration segment of the same phase (``min_j max_k``), in metres. A policy's
deviation is the median over the complete segments of both hands and all episodes,
with a 95 % bootstrap interval resampling episodes
(:func:`~baselines.agents.juggling_score.deviation_interval`). Only the odd cascades
with demonstrations of their ball count (:func:`deviation_balls`: ``"3"``,
``"3-human"``, ``"5"``) are scored; the other patterns have none.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import gymnasium as gym
import numpy as np
from numpy.typing import NDArray

from baselines.agents.juggling_score import (
    catch_rate_comparison,
    catch_rate_difference,
    catch_rate_interval,
    deviation_interval,
    phase_departures,
    play_until_ended,
    pooled_catch_rate,
    segment_deviations,
    split_episode_count,
)
from motion_envs._typing import FloatArray
from motion_envs.datasets.juggling import (
    CASCADE_HANDS,
    CASCADE_STYLES,
    PHASES,
    SPLIT_SEEDS,
    episode_seeds,
    mirror_x,
)

if TYPE_CHECKING:
    from baselines.stats import Difference

__all__ = [
    "CASCADE_ENV_IDS",
    "CascadeAgentEpisodes",
    "CascadeDeviations",
    "HandPaths",
    "RecordHandPaths",
    "cascade_agent_episodes",
    "cascade_agent_results",
    "cascade_demonstration_paths",
    "catch_rate_comparison",
    "catch_rate_difference",
    "catches_median_comparison",
    "catches_median_difference",
    "deviation_balls",
    "hand_segment_deviations",
    "is_cascade",
    "record_hand_paths",
]

Policy = Callable[[NDArray[np.float32]], NDArray[np.floating]]

#: Environment ids scored by this module.
CASCADE_ENV_IDS: tuple[str, ...] = ("MotionEnvs/Cascade-v0", "MotionEnvs/Cascade-v1")


def is_cascade(env_id: str) -> bool:
    """True for the environments this module scores."""
    return env_id in CASCADE_ENV_IDS


def deviation_balls(pattern: str) -> int | None:
    """The ball count of the held-out demonstrations the hands of ``pattern`` (a
    registered pattern's name) are compared with: its balls when it is an odd cascade
    (its siteswap the one throw value equal to its ball count) with SIMULATED
    demonstrations of that count (:data:`~motion_envs.datasets.juggling.CASCADE_STYLES`:
    3 and 5), else None (no demonstrations of it: not measured)."""
    from motion_envs.models.juggling import pattern_spec

    spec = pattern_spec(str(pattern))
    if spec.siteswap == str(spec.balls) and spec.balls in CASCADE_STYLES:
        return int(spec.balls)
    return None


@functools.lru_cache(maxsize=8)
def cascade_demonstration_paths(
    balls: int, split: str, gravity: float = 9.81
) -> dict[str, FloatArray]:
    """Per phase, the departures from their lines of the ``balls``-ball cascade
    demonstration segments ``(m, N_POINTS, 2)`` (each hand in its own frame; SIMULATED,
    :func:`~motion_envs.models.juggling.cascade_fit` at ``gravity``): the cycles held
    out of the juggler's fit for ``"test"``, its training cycles otherwise."""
    from motion_envs.models.juggling import cascade_fit

    if split not in SPLIT_SEEDS:
        raise ValueError(f"split must be one of {sorted(SPLIT_SEEDS)}; got {split!r}")
    fit = cascade_fit(float(gravity), int(balls))
    return phase_departures(fit.demos, fit.test if split == "test" else fit.train)


def hand_segment_deviations(
    times: FloatArray,
    hands: FloatArray,
    phases: Sequence[Sequence[str]],
    demos: Mapping[str, FloatArray],
) -> list[tuple[int, str, float]]:
    """``(hand, phase, deviation)`` of every complete phase segment of each hand (0
    right, 1 left) of one episode: ``times (n,)``, ``hands (n, 2, 2)`` (world frame, as
    ``info["hands"]``) and ``phases`` (n pairs of labels, as ``info["phases"]``), the
    reset's sample first. Each hand's path is taken into its own frame (the left hand's
    mirrored ``x -> -x``) and scored by
    :func:`~baselines.agents.juggling_score.segment_deviations` against ``demos``
    (:func:`cascade_demonstration_paths`)."""
    t = np.asarray(times, dtype=np.float64)
    y = np.asarray(hands, dtype=np.float64)
    if y.shape != (t.size, CASCADE_HANDS, 2) or len(phases) != t.size:
        raise ValueError(
            f"hands must be (n, {CASCADE_HANDS}, 2) and phases n pairs for n = {t.size} times; "
            f"got hands {y.shape} and {len(phases)} phases"
        )
    out: list[tuple[int, str, float]] = []
    for h in range(CASCADE_HANDS):
        own = y[:, h] if h == 0 else mirror_x(y[:, h])
        labels = [str(p[h]) for p in phases]
        out += [(h, phase, d) for phase, d in segment_deviations(t, own, labels, demos)]
    return out


class HandPaths:
    """One episode's ``time``, ``hands (2, 2)`` and ``phases`` (a label per hand), as its
    infos give them, at the reset and after every step."""

    def __init__(self) -> None:
        self.time: list[float] = []
        self.hands: list[FloatArray] = []
        self.phases: list[tuple[str, ...]] = []

    def add(self, info: Mapping[str, Any]) -> None:
        """Append one info's sample."""
        self.time.append(float(info["time"]))
        self.hands.append(np.array(info["hands"], dtype=np.float64))
        self.phases.append(tuple(str(p) for p in info["phases"]))


@dataclass(frozen=True)
class CascadeDeviations:
    """Per complete phase segment of each hand of a policy's episodes (module
    docstring): its episode's index, hand (0 right, 1 left), phase and deviation (m)
    from the ``balls``-ball cascade demonstrations of ``split`` (``"test"``: held out)."""

    balls: int
    split: str
    segment_episode: NDArray[np.int64]
    segment_hand: NDArray[np.int64]
    segment_phase: NDArray[np.str_]
    segment_deviation: FloatArray

    @classmethod
    def of_paths(
        cls, paths: Sequence[HandPaths], balls: int, split: str, gravity: float = 9.81
    ) -> CascadeDeviations:
        """The segments of the episodes ``paths`` (in episode order) against the
        demonstrations of ``split`` (:func:`cascade_demonstration_paths`)."""
        demos = cascade_demonstration_paths(balls, split, gravity)
        rows = [
            (i, *seg)
            for i, p in enumerate(paths)
            for seg in hand_segment_deviations(
                np.asarray(p.time), np.asarray(p.hands).reshape(-1, CASCADE_HANDS, 2),
                p.phases, demos,
            )
        ]  # fmt: skip
        return cls(
            balls=int(balls),
            split=split,
            segment_episode=np.array([r[0] for r in rows], dtype=np.int64),
            segment_hand=np.array([r[1] for r in rows], dtype=np.int64),
            segment_phase=np.array([r[2] for r in rows], dtype=str),
            segment_deviation=np.array([r[3] for r in rows], dtype=np.float64),
        )

    @property
    def deviation(self) -> float:
        """The median over the segments of both hands (m; NaN without segments)."""
        d = self.segment_deviation
        return float(np.median(d)) if d.size else math.nan

    def hand_deviation(self, hand: int) -> float:
        """:attr:`deviation` over one hand's segments (0 right, 1 left)."""
        d = self.segment_deviation[self.segment_hand == hand]
        return float(np.median(d)) if d.size else math.nan

    def summary(self) -> dict[str, Any]:
        """The results' entry: ``deviation_m`` and its 95 % interval resampling episodes
        ``deviation_ci`` (seed 0), per hand ``deviation_hand_m`` (right, left), per
        phase ``deviation_phase_m`` (medians; None for a phase without segments), the
        segments scored and the demonstrations they were compared with."""
        dev, lo, hi = deviation_interval(self)
        phases: dict[str, float | None] = {}
        for phase in PHASES:
            d = self.segment_deviation[self.segment_phase == phase]
            phases[phase] = float(np.median(d)) if d.size else None
        return {
            "deviation_m": dev,
            "deviation_ci": [lo, hi],
            "deviation_hand_m": [self.hand_deviation(h) for h in range(CASCADE_HANDS)],
            "deviation_phase_m": phases,
            "deviation_segments": int(self.segment_deviation.size),
            "deviation_demonstrations": demonstrations_label(self.balls, self.split),
        }


def demonstrations_label(balls: int, split: str) -> str:
    """What a deviation was measured against, in words."""
    which = "held-out" if split == "test" else "training"
    return f"{which} SIMULATED {balls}-ball cascade demonstrations (cascade_fit, {split} split)"


class RecordHandPaths(gym.Wrapper):
    """``env`` (a Cascade-v0 or -v1 env), recording each episode's :class:`HandPaths`
    from its infos (a reset starts the next one); :meth:`deviations` scores them."""

    def __init__(self, env: gym.Env, balls: int) -> None:
        super().__init__(env)
        self.balls = int(balls)
        self.gravity = float(getattr(env.unwrapped, "gravity", 9.81))
        #: The episodes' paths, in the order they were reset.
        self.paths: list[HandPaths] = []

    def reset(self, **kwargs: Any) -> tuple[Any, dict[str, Any]]:
        obs, info = self.env.reset(**kwargs)
        self.paths.append(HandPaths())
        self.paths[-1].add(info)
        return obs, info

    def step(self, action: Any) -> tuple[Any, Any, bool, bool, dict[str, Any]]:
        obs, reward, terminated, truncated, info = self.env.step(action)
        self.paths[-1].add(info)
        return obs, reward, terminated, truncated, info

    def deviations(self, split: str) -> CascadeDeviations:
        """The recorded episodes' :class:`CascadeDeviations` against ``split``'s
        demonstrations."""
        return CascadeDeviations.of_paths(self.paths, self.balls, split, self.gravity)


def record_hand_paths(env: gym.Env, pattern: str) -> RecordHandPaths | None:
    """``env`` wrapped in :class:`RecordHandPaths`, or None when ``pattern`` has no
    demonstrations to compare with (:func:`deviation_balls`)."""
    balls = deviation_balls(pattern)
    return None if balls is None else RecordHandPaths(env, balls)


@dataclass(frozen=True)
class CascadeAgentEpisodes:
    """Per episode: ``catches`` before the first drop, ``tosses``, ``dropped``, ``time``
    (s, at the drop or at the end), as in
    :class:`baselines.juggling_bench.cascade.CascadeEpisodes`; ``max_catches``: the
    environment's truncation; ``deviations``: the hands' segments scored against the
    demonstrations (:class:`CascadeDeviations`), when asked for."""

    seeds: NDArray[np.int64]
    catches: NDArray[np.int64]
    tosses: NDArray[np.int64]
    dropped: NDArray[np.bool_]
    time: NDArray[np.float64]
    max_catches: int
    deviations: CascadeDeviations | None = None

    @property
    def catches_median(self) -> float:
        """Median over episodes of the catches before the first drop."""
        return float(np.median(self.catches))

    @property
    def catch_rate(self) -> float:
        """Catches per toss over all episodes."""
        return pooled_catch_rate(self, np.arange(self.seeds.size))

    @property
    def drop_hazard(self) -> float:
        """Drops per catch over all episodes (module docstring)."""
        return _hazard(self, np.arange(self.seeds.size))

    @property
    def criterion(self) -> float:
        """:attr:`drop_hazard` (lower is better)."""
        return self.drop_hazard

    def episode_hazard(self) -> NDArray[np.float64]:
        """Per episode, drops per catch (0 when censored, inf for a drop before any
        catch)."""
        with np.errstate(divide="ignore", invalid="ignore"):
            h = self.dropped.astype(np.float64) / self.catches.astype(np.float64)
        return np.where(self.dropped, h, 0.0)


def _hazard(eps: CascadeAgentEpisodes, rows: NDArray[np.int64]) -> float:
    return float(eps.dropped[rows].sum() / max(int(eps.catches[rows].sum()), 1))


def cascade_agent_episodes(
    policy: Policy | None,
    env_id: str,
    env_kwargs: Mapping[str, Any],
    split: str,
    episodes: int | None = None,
    deviation: bool = False,
) -> CascadeAgentEpisodes:
    """Play ``episodes`` (default :data:`~baselines.agents.juggling_score.DEFAULT_EPISODES`)
    deterministic episodes of ``split`` (seeds ``SPLIT_SEEDS[split] + i``), all at once;
    ``policy`` maps raw observations ``(N, obs_dim)`` to actions, None is the zero action
    (the analytic cascade juggler). Each episode is stepped until it ends and no further
    (a finished episode's row keeps its last observation; the policy's action for it is
    unused). With ``deviation`` the hands' paths are recorded and scored against the
    demonstrations of ``split`` (module docstring; None for a pattern without them)."""
    import motion_envs  # noqa: F401  (registers the ids, also inside Ray workers)

    if not is_cascade(env_id):
        raise ValueError(f"{env_id} is not a cascade environment")
    n = split_episode_count(split, episodes)
    kwargs = {k: v for k, v in env_kwargs.items() if k != "split"}
    seeds = episode_seeds(split, n)
    catches = np.zeros(n, dtype=np.int64)
    tosses = np.zeros(n, dtype=np.int64)
    dropped = np.zeros(n, dtype=bool)
    times = np.zeros(n, dtype=np.float64)

    def record(i: int, info: dict[str, Any], ended: bool, terminated: bool) -> None:
        if ended:
            catches[i] = int(info["catches"])
            tosses[i] = int(info["tosses"])
            dropped[i] = terminated
            times[i] = float(info["time"])

    envs: list[Any] = [gym.make(env_id, **kwargs) for _ in range(n)]
    max_catches = int(envs[0].unwrapped.max_catches)
    if deviation:
        pattern = str(kwargs.get("pattern", "3"))
        envs = [record_hand_paths(env, pattern) or env for env in envs]
    play_until_ended(envs, seeds, policy, record)
    devs = None
    if isinstance(envs[0], RecordHandPaths):
        paths = [p for env in envs for p in env.paths]
        devs = CascadeDeviations.of_paths(paths, envs[0].balls, split, envs[0].gravity)
    return CascadeAgentEpisodes(seeds, catches, tosses, dropped, times, max_catches, devs)


def _check_same_seeds(a: CascadeAgentEpisodes, b: CascadeAgentEpisodes) -> None:
    if not np.array_equal(a.seeds, b.seeds):
        raise ValueError("the two policies were played on different seeds")


def catches_median_difference(
    a: CascadeAgentEpisodes, b: CascadeAgentEpisodes, seed: int = 0
) -> tuple[float, float, float]:
    """``(difference, low, high)``: ``a``'s median catches before the first drop minus
    ``b``'s on the same seeds and its 95 % paired bootstrap interval (an episode of both
    is resampled together; :func:`catches_median_comparison`)."""
    c = catches_median_comparison(a, b, seed)
    return c.difference, *c.ci95


def catches_median_comparison(
    a: CascadeAgentEpisodes,
    b: CascadeAgentEpisodes,
    seed: int = 0,
    names: tuple[str, str] = ("agent", "nominal"),
) -> Difference:
    """:func:`catches_median_difference` as a :class:`baselines.stats.Difference`: with
    the power line (the differences its interval detects 80 % of the time at this many
    episodes) and the verdict in words; ``names``: what ``a`` and ``b`` are called."""
    from baselines.stats import compare_difference

    _check_same_seeds(a, b)
    ca, cb = a.catches.astype(np.float64), b.catches.astype(np.float64)
    return compare_difference(
        lambda rows: float(np.median(ca[rows]) - np.median(cb[rows])),
        np.arange(a.seeds.size), *names, "median catches before the first drop", seed=seed,
    )  # fmt: skip


def _hazard_comparison(agent: CascadeAgentEpisodes, nominal: CascadeAgentEpisodes) -> Any:
    """The agent's drop hazard over the juggler's (lower is better), episodes resampled;
    wins: episodes where the agent's drops per catch are below the juggler's."""
    from baselines.stats import Comparison, detectable_ratios, group_bootstrap_replicates

    def ratio(rows: NDArray[np.int64]) -> float:
        b = _hazard(nominal, rows)
        return _hazard(agent, rows) / b if b > 0 else float("nan")

    point, lo, hi, reps = group_bootstrap_replicates(ratio, np.arange(agent.seeds.size))
    wins = int(np.sum(agent.episode_hazard() < nominal.episode_hazard()))
    return Comparison(
        "agent drop hazard", "nominal drop hazard", point, (lo, hi), wins,
        int(agent.seeds.size), "episodes", "drops per catch (episodes end at the first drop)",
        "1", detectable_ratios(point, lo, hi, reps),
    )  # fmt: skip


def _summary(eps: CascadeAgentEpisodes) -> dict[str, Any]:
    """Median catches before the first drop and catch rate with their 95 % intervals
    (episodes resampled, seed 0), the mean and the censored count: what ``motion-bench
    juggling --pattern 3`` reports per method (tested equal)."""
    from baselines.stats import group_bootstrap

    idx = np.arange(eps.seeds.size)
    v = eps.catches.astype(np.float64)
    c, clo, chi = group_bootstrap(lambda rows: float(np.median(v[rows])), idx)
    r, rlo, rhi = catch_rate_interval(eps)
    return {
        "catches_median": c,
        "catches_median_ci": [clo, chi],
        "catches_mean": float(v.mean()),
        "catch_rate": r,
        "catch_rate_ci": [rlo, rhi],
        "censored": int((~eps.dropped).sum()),
    }


def cascade_agent_results(loaded: Any, split: str, episodes: int | None) -> dict[str, Any]:
    """Catches before the first drop and catch rate, agent and zero action (the analytic
    cascade juggler) on the same seeds, with their intervals and paired differences."""
    from baselines.verdicts import verdicts_document

    kwargs = loaded.env_kwargs
    agent = cascade_agent_episodes(loaded.policy(), loaded.env_id, kwargs, split, episodes)
    nominal = cascade_agent_episodes(None, loaded.env_id, kwargs, split, episodes)
    a, b = _summary(agent), _summary(nominal)
    median_diff = catches_median_comparison(agent, nominal)
    rate_diff = catch_rate_comparison(agent, nominal)
    diff, (dlo, dhi) = median_diff.difference, median_diff.ci95
    rdiff, (rlo, rhi) = rate_diff.difference, rate_diff.ci95
    comparisons = []
    if nominal.drop_hazard > 0:
        comparisons.append(_hazard_comparison(agent, nominal))
    doc = verdicts_document(comparisons)
    by = {c.a: c for c in comparisons}
    hazard = by.get("agent drop hazard")
    return {
        "n_episodes": int(agent.seeds.size),
        "max_catches": agent.max_catches,
        "criterion": agent.criterion,
        "nominal_criterion": nominal.criterion,
        "criterion_name": "drops per catch",
        "ratio": agent.criterion / nominal.criterion if nominal.criterion > 0 else None,
        "ratio_ci": None if hazard is None else list(hazard.ci95),
        "catches_median": a["catches_median"],
        "catches_median_ci": a["catches_median_ci"],
        "nominal_catches_median": b["catches_median"],
        "nominal_catches_median_ci": b["catches_median_ci"],
        "catches_median_difference": diff,
        "catches_median_difference_ci": [dlo, dhi],
        "beats_nominal_median": bool(dlo > 0),
        "catches_mean": a["catches_mean"],
        "nominal_catches_mean": b["catches_mean"],
        "censored": a["censored"],
        "nominal_censored": b["censored"],
        "catch_rate": a["catch_rate"],
        "nominal_catch_rate": b["catch_rate"],
        "catch_rate_ci": a["catch_rate_ci"],
        "nominal_catch_rate_ci": b["catch_rate_ci"],
        "catch_rate_difference": rdiff,
        "catch_rate_difference_ci": [rlo, rhi],
        "differences": [median_diff.to_dict(), rate_diff.to_dict()],
        "tosses": int(agent.tosses.sum()),
        "nominal_tosses": int(nominal.tosses.sum()),
        "best_val_criterion": loaded.manifest.get("best_val_criterion"),
        "learned_criterion": None,
        "learned_ratio": None,
        "learned_skipped": f"{loaded.env_id} has no learned regressor",
        **doc,
        "verdict": "; ".join(c.sentence() for c in comparisons) or None,
        "episodes": {
            "seed": agent.seeds.tolist(),
            "agent_catches": agent.catches.tolist(),
            "agent_tosses": agent.tosses.tolist(),
            "agent_dropped": agent.dropped.tolist(),
            "agent_time": agent.time.tolist(),
            "nominal_catches": nominal.catches.tolist(),
            "nominal_tosses": nominal.tosses.tolist(),
            "nominal_dropped": nominal.dropped.tolist(),
            "nominal_time": nominal.time.tolist(),
        },
    }
