"""The contextual CEM learner (:mod:`baselines.agents.contextual_cem`) on
OrientationCoefficients-v0, leave one person out, against the nominal and the ridge.

The protocol of the PPO headline (``configs/sweeps/orientation_lopo.yaml``,
docs/protocol.md): fold ``i`` holds the ``i``-th person out (the env's ``fold``); the
nominal (``bezier-null``) is fitted on the fold's training people; per seed, the step
(generation) at which the policy is kept is chosen by 3 inner folds over the training
people (the env's ``val_folds = 3``: a learner trained on two groups, validated on the
third; the mean over the three of the validation criterion over the nominal's), then one
learner is trained on all training people with the same seed and budget and kept at that
step; the held-out person's episodes score it. The ridge is the regressor of
``motion-bench agent`` fitted on the same training people
(:func:`baselines.agents.learned_criterion.learned_episode_errors`). The summary is
:func:`baselines.agents.sweep.lopo.lopo_summary`'s: per person the ratio of every seed,
the IQM over (seeds, people) with its 95 % interval over people, its power, the verdict,
against the nominal and against the ridge.

    python experiments/contextual_cem_lopo.py --seeds 0,1,2 --out results/cem_lopo.json
    python experiments/contextual_cem_lopo.py --folds 0 --seeds 0   # the cost of one fold
"""

from __future__ import annotations

import argparse
import json
import time
from typing import Any

import gymnasium as gym
import numpy as np

import motion_envs  # noqa: F401  (registers the ids)
from baselines.agents.contextual_cem import CEMConfig, CEMResult, train_cem
from baselines.agents.learned_criterion import learned_episode_errors
from baselines.agents.sweep.lopo import format_lopo, lopo_summary
from motion_envs._io import atomic_write_text

ENV_ID = "MotionEnvs/OrientationCoefficients-v0"
INNER_FOLDS = 3


def _env(fold: int, split: str, data: str, **kwargs: Any) -> Any:
    return gym.make(ENV_ID, data=data, nominal="bezier-null", fold=fold, split=split,
                    **kwargs).unwrapped  # fmt: skip


def _ratio(env: Any, result: CEMResult, generation: int) -> tuple[float, float]:
    """(criterion, criterion over the nominal's) of the policy kept at ``generation`` on
    every episode of ``env``."""
    policy = result.at(generation)
    n = env._context.shape[0]
    errors = env.score(np.arange(n), policy.act(env._context))
    crit = float(np.median(errors))
    return crit, crit / float(np.median(env._nominal_errors))


def run_fold(fold: int, seeds: list[int], config: CEMConfig, data: str) -> list[dict[str, Any]]:
    """One trial per seed of fold ``fold`` (the keys :func:`lopo_summary` reads)."""
    steps = list(range(0, config.generations + 1))
    inner = [
        (_env(fold, "train", data, val_folds=INNER_FOLDS, val_fold=j),
         _env(fold, "val", data, val_folds=INNER_FOLDS, val_fold=j))
        for j in range(INNER_FOLDS)
    ]  # fmt: skip
    train, test = _env(fold, "train", data), _env(fold, "test", data)
    ridge = learned_episode_errors(ENV_ID, {"data": data, "nominal": "bezier-null",
                                            "fold": fold}, "test").errors  # fmt: skip
    if not np.array_equal(ridge.trajectory_ids, np.asarray(test.task.trajectory_ids)):
        raise RuntimeError(f"fold {fold}: the ridge's episodes are not the test episodes")
    nominal = float(np.median(test._nominal_errors))
    trials = []
    for seed in seeds:
        scores = np.zeros(len(steps))
        for tr, va in inner:
            res = train_cem(tr, config, seed)
            scores += np.array([_ratio(va, res, g)[1] for g in steps]) / len(inner)
        best = steps[int(np.argmin(scores))]  # first on ties
        res = train_cem(train, config, seed)
        crit, ratio = _ratio(test, res, best)
        trials.append(
            {
                "config_index": fold,
                "seed": seed,
                "test_ratio": ratio,
                "test_criterion": crit,
                "test_nominal_criterion": nominal,
                "test_learned_criterion": ridge.criterion,
                "test_learned_ratio": crit / ridge.criterion,
                "inner_val_ratio": float(scores[steps.index(best)]),
                "chosen_generation": best,
                "kept_initial_policy": best == 0,
                "episodes_trained": best * res.episodes_per_generation,
            }
        )
    return trials


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--folds", default="0,1,2,3,4,5,6,7")
    p.add_argument("--seeds", default="0,1,2")
    p.add_argument("--data", default="vr-kitchen")
    p.add_argument("--budget", type=int, default=30_000)
    p.add_argument("--out", default=None)
    args = p.parse_args(argv)
    folds = [int(v) for v in args.folds.split(",")]
    seeds = [int(v) for v in args.seeds.split(",")]
    config = CEMConfig(budget=args.budget)
    t0, c0 = time.perf_counter(), time.process_time()
    trials: list[dict[str, Any]] = []
    for fold in folds:
        f0 = time.process_time()
        trials += run_fold(fold, seeds, config, args.data)
        print(f"fold {fold}: {time.process_time() - f0:.1f} s CPU", flush=True)
    configs = [{"overrides": {"env_kwargs": {"fold": f}}} for f in range(max(folds) + 1)]
    summary = lopo_summary(trials, configs)
    doc = {
        "env_id": ENV_ID,
        "data": args.data,
        "learner": "linear policy from the context, CEM (baselines.agents.contextual_cem)",
        "config": vars(config) | {"generations": config.generations},
        "seeds": seeds,
        "folds": folds,
        "trials": trials,
        "lopo": summary,
        "seconds": time.perf_counter() - t0,
        "cpu_seconds": time.process_time() - c0,
    }
    if summary is not None:
        print(format_lopo(summary))
    kept = sum(t["kept_initial_policy"] for t in trials)
    print(f"kept the initial policy (the nominal) in {kept}/{len(trials)} trials")
    print(f"{doc['cpu_seconds']:.1f} s CPU, {doc['seconds']:.1f} s wall")
    if args.out:
        atomic_write_text(args.out, json.dumps(doc, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
