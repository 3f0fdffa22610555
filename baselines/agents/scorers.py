"""How agents are scored, one :class:`Scorer` per environment family, looked up by id.

A family is an environment id without its version (``MotionEnvs/Juggling-v0`` ->
``MotionEnvs/Juggling``). Each family's scorer is registered once below
(:func:`register_scorer`, as :func:`baselines.report.register_section` does for the
report's sections); ``motion-bench train`` (validation criterion, the training seeds'
check) and ``motion-bench agent`` (the results) ask :func:`scorer_for` instead of
branching on the id:

* the reaching environments (``OrientationReach``, ``PositionReach``) replay the
  trajectories of a data split: the papers' criterion
  (:mod:`baselines.agents.reaching_score`), the zero action and the learned regressor on
  the same episodes; their validation split is carved from the training data
  (``val_fraction > 0``);
* ``Juggling`` plays seeded runs: the drop rate per toss, catch rates and the hand's
  deviation from the demonstrations (:mod:`baselines.agents.juggling_score`); its splits
  are seed ranges that the training seeds must stay below;
* ``Cascade`` plays seeded runs on the same seed ranges: catches before the first drop
  (median, the headline), catch rate and the drop hazard per catch (the criterion), agent
  and juggler on the same seeds (:mod:`baselines.agents.cascade_score`).
"""

from __future__ import annotations

import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from baselines import options
from baselines.agents.cascade_score import (
    CASCADE_ENV_IDS,
    cascade_agent_episodes,
    cascade_agent_results,
)
from baselines.agents.juggling_score import (
    JUGGLING_ENV_IDS,
    catch_rate_difference,
    catch_rate_interval,
    juggling_episodes,
)
from baselines.agents.reaching_score import EpisodeErrors, Policy, episode_max_errors
from motion_envs.datasets.juggling import SPLIT_SEEDS

__all__ = [
    "SCORERS",
    "Scorer",
    "check_validation_split",
    "env_family",
    "register_scorer",
    "scorer_for",
]


@dataclass(frozen=True)
class Scorer:
    """How one family of environments is scored.

    ``episodes(policy, env_id, env_kwargs, split, episodes)``: the policy's episodes of a
    split (``policy`` None is the zero action), with a ``criterion`` attribute: the one
    checkpoints are chosen by (lower is better).
    ``agent_results(loaded, split, episodes)``: the entries of ``motion-bench agent``'s
    results.json after the run's own (``loaded``: :class:`~baselines.agents.rundir.LoadedRun`).
    ``first_val_seed``: None when the splits are carved from data, else the first reset
    seed of the validation split (training seeds ``seed .. seed + n_envs - 1`` must stay
    below it).
    """

    family: str
    episodes: Callable[[Policy | None, str, Mapping[str, Any], str, int | None], Any]
    agent_results: Callable[[Any, str, int | None], dict[str, Any]]
    first_val_seed: int | None = None


#: Family -> scorer (:func:`register_scorer`).
SCORERS: dict[str, Scorer] = {}


def env_family(env_id: str) -> str:
    """``env_id`` without its ``-vN`` version suffix."""
    return re.sub(r"-v\d+$", "", env_id)


def register_scorer(scorer: Scorer) -> Scorer:
    """Register ``scorer`` for its family (once)."""
    if scorer.family in SCORERS:
        raise ValueError(f"a scorer is already registered for {scorer.family}")
    SCORERS[scorer.family] = scorer
    return scorer


def scorer_for(env_id: str) -> Scorer:
    """The scorer of ``env_id``'s family; ValueError naming the families otherwise."""
    try:
        return SCORERS[env_family(env_id)]
    except KeyError:
        raise ValueError(
            f"no agent scorer for {env_id}; scored families: {sorted(SCORERS)}"
        ) from None


def check_validation_split(
    env_id: str, env_kwargs: Mapping[str, Any], seed: int, n_envs: int
) -> None:
    """A data-split environment needs ``val_fraction > 0`` or ``val_folds`` (its validation
    split is carved from the training data); a seed-range environment (``first_val_seed``) needs the
    training seeds ``seed .. seed + n_envs - 1`` below its validation seeds."""
    from baselines.agents.vec import takes_keyword

    first_val = scorer_for(env_id).first_val_seed
    if first_val is not None:
        if seed + n_envs > first_val:
            raise options.ConfigError(
                "seed",
                f"{seed} with {n_envs} environments would reset on the validation seeds of "
                f"{env_id} (from {first_val}); use a seed below {first_val - n_envs + 1}",
            )
        return
    if not takes_keyword(env_id, "val_fraction"):
        return
    if env_kwargs.get("val_folds"):  # inner folds over people (checked by the environment)
        return
    val_fraction = env_kwargs.get("val_fraction", 0)
    if isinstance(val_fraction, bool) or not isinstance(val_fraction, int | float):
        raise ValueError(f"env_kwargs.val_fraction must be a number; got {val_fraction!r}")
    if not val_fraction > 0:
        raise ValueError(
            "env_kwargs.val_fraction must be > 0: checkpoints are chosen on a validation split "
            "carved from the training data, never on the test split"
        )


# -- the reaching environments -----------------------------------------------------------
def reaching_agent_results(loaded: Any, split: str, episodes: int | None) -> dict[str, Any]:
    """The agent, the zero action and the learned regressor on the same episodes."""
    kwargs = loaded.env_kwargs
    agent = episode_max_errors(loaded.policy(), loaded.env_id, kwargs, split, episodes)
    nominal = episode_max_errors(None, loaded.env_id, kwargs, split, episodes)
    learned_entries, learned = _learned(loaded.env_id, kwargs, split, episodes)
    results: dict[str, Any] = {
        "n_episodes": int(agent.max_errors.size),
        "criterion": agent.criterion,
        "nominal_criterion": nominal.criterion,
        "ratio": agent.criterion / nominal.criterion,
        "median_of_task_medians": agent.median_of_task_medians,
        "nominal_median_of_task_medians": nominal.median_of_task_medians,
        "best_val_criterion": loaded.manifest.get("best_val_criterion"),
        **learned_entries,
        "episodes": {
            "trajectory_id": agent.trajectory_ids.tolist(),
            "task": agent.tasks.tolist(),
            "agent_max_error": agent.max_errors.tolist(),
            "nominal_max_error": nominal.max_errors.tolist(),
        },
    }
    if learned is not None:
        if not np.array_equal(learned.trajectory_ids, agent.trajectory_ids):
            raise RuntimeError("the learned regressor was scored on other episodes")
        results["learned_ratio"] = agent.criterion / learned.criterion
        results["episodes"]["learned_max_error"] = learned.max_errors.tolist()
    from baselines.verdicts import agent_verdicts

    results.update(agent_verdicts(loaded.env_id, agent, nominal, learned))
    return results


def _learned(
    env_id: str, kwargs: Mapping[str, Any], split: str, episodes: int | None
) -> tuple[dict[str, Any], EpisodeErrors | None]:
    """``learned_*`` entries of results.json (null with ``learned_skipped`` when there is
    no regressor) and the regressor's per-episode errors."""
    from baselines.agents.learned_criterion import learned_episode_errors, learned_skip_reason

    reason = learned_skip_reason(env_id)
    if reason is not None:
        entries: dict[str, Any] = {
            "learned_criterion": None,
            "learned_ratio": None,
            "learned_skipped": reason,
        }
        return entries, None
    got = learned_episode_errors(env_id, kwargs, split, episodes)
    entries = {
        "learned_criterion": got.errors.criterion,
        "learned_model": got.model,
        "learned_chosen": got.chosen,
    }
    return entries, got.errors


# -- the juggling environment ------------------------------------------------------------
def juggling_agent_results(loaded: Any, split: str, episodes: int | None) -> dict[str, Any]:
    """Catch rate and the hand's deviation from the demonstrations (held-out ones on
    ``test``), agent and zero action on the same seeds."""
    kwargs = loaded.env_kwargs
    agent = juggling_episodes(loaded.policy(), loaded.env_id, kwargs, split, episodes)
    nominal = juggling_episodes(None, loaded.env_id, kwargs, split, episodes)
    from motion_envs.datasets.juggling import PHASES

    both = set(agent.segment_phase.tolist()) & set(nominal.segment_phase.tolist())
    phases = [p for p in PHASES if p in both]  # in the task's order
    from baselines.verdicts import juggling_verdicts

    _, lo, hi = catch_rate_interval(agent)
    _, nlo, nhi = catch_rate_interval(nominal)
    diff, dlo, dhi = catch_rate_difference(agent, nominal)
    results = {
        "n_episodes": int(agent.seeds.size),
        "criterion": agent.criterion,
        "nominal_criterion": nominal.criterion,
        "ratio": agent.criterion / nominal.criterion if nominal.criterion > 0 else None,
        "catch_rate": agent.catch_rate,
        "nominal_catch_rate": nominal.catch_rate,
        "catch_rate_ci": [lo, hi],
        "nominal_catch_rate_ci": [nlo, nhi],
        "catch_rate_difference": diff,
        "catch_rate_difference_ci": [dlo, dhi],
        "tosses": int(agent.tosses.sum()),
        "nominal_tosses": int(nominal.tosses.sum()),
        "deviation": agent.deviation,
        "nominal_deviation": nominal.deviation,
        "deviation_ratio": agent.deviation / nominal.deviation,
        "phase_deviation": {p: agent.phase_deviation(p) for p in phases},
        "nominal_phase_deviation": {p: nominal.phase_deviation(p) for p in phases},
        # segments per phase: the pooled deviation weighs the phases by these counts
        "phase_segments": {p: int(np.sum(agent.segment_phase == p)) for p in phases},
        "nominal_phase_segments": {p: int(np.sum(nominal.segment_phase == p)) for p in phases},
        "deviation_reference": (
            "held-out demonstrations" if split == "test" else "training demonstrations"
        ),
        "best_val_criterion": loaded.manifest.get("best_val_criterion"),
        "learned_criterion": None,
        "learned_ratio": None,
        "learned_skipped": f"{loaded.env_id} has no learned regressor",
        "episodes": {
            "seed": agent.seeds.tolist(),
            "agent_tosses": agent.tosses.tolist(),
            "agent_catches": agent.catches.tolist(),
            "agent_dropped": agent.dropped.tolist(),
            "agent_deviation": agent.episode_deviation().tolist(),
            "nominal_tosses": nominal.tosses.tolist(),
            "nominal_catches": nominal.catches.tolist(),
            "nominal_dropped": nominal.dropped.tolist(),
            "nominal_deviation": nominal.episode_deviation().tolist(),
        },
    }
    return results | juggling_verdicts(agent, nominal)


for _family in (
    "MotionEnvs/OrientationReach",
    "MotionEnvs/PositionReach",
    "MotionEnvs/OrientationCoefficients",
    "MotionEnvs/PositionCoefficients",
):
    register_scorer(Scorer(_family, episode_max_errors, reaching_agent_results))
for _family in sorted({env_family(i) for i in JUGGLING_ENV_IDS}):
    register_scorer(Scorer(_family, juggling_episodes, juggling_agent_results, SPLIT_SEEDS["val"]))
for _family in sorted({env_family(i) for i in CASCADE_ENV_IDS}):
    register_scorer(
        Scorer(_family, cascade_agent_episodes, cascade_agent_results, SPLIT_SEEDS["val"])
    )
