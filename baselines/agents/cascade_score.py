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
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from baselines.agents.juggling_score import (
    catch_rate_comparison,
    catch_rate_difference,
    catch_rate_interval,
    play_until_ended,
    pooled_catch_rate,
    split_episode_count,
)
from motion_envs.datasets.juggling import episode_seeds

if TYPE_CHECKING:
    from baselines.stats import Difference

__all__ = [
    "CASCADE_ENV_IDS",
    "CascadeAgentEpisodes",
    "cascade_agent_episodes",
    "cascade_agent_results",
    "catch_rate_comparison",
    "catch_rate_difference",
    "catches_median_comparison",
    "catches_median_difference",
    "is_cascade",
]

Policy = Callable[[NDArray[np.float32]], NDArray[np.floating]]

#: Environment ids scored by this module.
CASCADE_ENV_IDS: tuple[str, ...] = ("MotionEnvs/Cascade-v0", "MotionEnvs/Cascade-v1")


def is_cascade(env_id: str) -> bool:
    """True for the environments this module scores."""
    return env_id in CASCADE_ENV_IDS


@dataclass(frozen=True)
class CascadeAgentEpisodes:
    """Per episode: ``catches`` before the first drop, ``tosses``, ``dropped``, ``time``
    (s, at the drop or at the end), as in
    :class:`baselines.juggling_bench.cascade.CascadeEpisodes`; ``max_catches``: the
    environment's truncation."""

    seeds: NDArray[np.int64]
    catches: NDArray[np.int64]
    tosses: NDArray[np.int64]
    dropped: NDArray[np.bool_]
    time: NDArray[np.float64]
    max_catches: int

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
) -> CascadeAgentEpisodes:
    """Play ``episodes`` (default :data:`~baselines.agents.juggling_score.DEFAULT_EPISODES`)
    deterministic episodes of ``split`` (seeds ``SPLIT_SEEDS[split] + i``), all at once;
    ``policy`` maps raw observations ``(N, obs_dim)`` to actions, None is the zero action
    (the analytic cascade juggler). Each episode is stepped until it ends and no further
    (a finished episode's row keeps its last observation; the policy's action for it is
    unused)."""
    import gymnasium as gym

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

    envs = [gym.make(env_id, **kwargs) for _ in range(n)]
    max_catches = int(envs[0].unwrapped.max_catches)  # type: ignore[attr-defined]
    play_until_ended(envs, seeds, policy, record)
    return CascadeAgentEpisodes(seeds, catches, tosses, dropped, times, max_catches)


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
