"""The contextual CEM learner (:mod:`baselines.agents.contextual_cem`) on
OrientationCoefficients-v0, leave one person out, against the nominal and the ridge.

The protocol of the PPO headline (``configs/sweeps/orientation_lopo.yaml``,
docs/protocol.md): fold ``i`` holds the ``i``-th person out (the env's ``fold``); the
nominal (``bezier-null``) is fitted on the fold's training people. Every choice is made
by inner folds over the fold's training people only
(:func:`baselines.agents.contextual_cem.lopo_fold`): each setting of the declared grid
(:func:`~baselines.agents.contextual_cem.settings_grid`, 12 settings) is trained per seed
on the training people minus one and scored on that one, every generation, for each of
the 7 training people (the env's ``val_folds = 7``); the setting with the lowest mean
inner criterion over the inner nominal's (each seed at its best generation) is the
fold's, each seed keeps its best generation; one learner per seed is then trained on all
training people with that setting and kept at that generation, and only then are the
held-out person's episodes read, once. Every learner, inner or final, has the PPO
agents' budget (30,000 episodes; a PPO step is one episode). The ridge is the regressor
of ``motion-bench agent`` fitted on the same training people
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

import numpy as np
from tqdm import tqdm

from baselines.agents.contextual_cem import ENV_ID, lopo_fold, settings_grid
from baselines.agents.sweep.lopo import format_lopo, lopo_summary
from motion_envs._io import atomic_write_text
from motion_envs.datasets import load_orientation_dataset


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
    grid = settings_grid(args.budget)
    t0, c0 = time.perf_counter(), time.process_time()
    trials: list[dict[str, Any]] = []
    choices = {}
    # the bar's length: each fold's training people are its inner folds (labels only)
    inner = np.unique(load_orientation_dataset(args.data).subjects).size - 1
    per_fold = len(seeds) * (len(grid) * inner + 1)
    with tqdm(total=len(folds) * per_fold, desc="CEM learners", unit="learner") as bar:
        for fold in folds:
            f0 = time.process_time()
            fold_trials, choice = lopo_fold(fold, seeds, grid, args.data, bar)
            trials += fold_trials
            choices[str(fold)] = {
                "inner_people": list(choice.inner_people),
                "setting_scores": choice.setting_scores().tolist(),
                "chosen_setting": choice.config_index,
                "chosen_config": vars(choice.config),
                "generation_per_seed": {str(s): choice.generation(s) for s in seeds},
                "cpu_seconds": time.process_time() - f0,
            }
            c = choice.config
            bar.write(
                f"fold {fold}: setting {choice.config_index} (sigma {c.sigma}, policy_sines "
                f"{c.policy_sines}, population {c.population}, elite {c.elite}), generations "
                f"{[choice.generation(s) for s in seeds]}, inner score "
                f"{choice.setting_scores()[choice.config_index]:.4f}; "
                f"{time.process_time() - f0:.1f} s CPU"
            )
    configs = [{"overrides": {"env_kwargs": {"fold": f}}} for f in range(max(folds) + 1)]
    summary = lopo_summary(trials, configs)
    doc = {
        "env_id": ENV_ID,
        "data": args.data,
        "learner": "linear policy from the context, CEM (baselines.agents.contextual_cem)",
        "grid": [vars(c) | {"generations": c.generations} for c in grid],
        "selection": "leave one person out over the fold's training people (inner folds)",
        "seeds": seeds,
        "folds": folds,
        "choices": choices,
        "trials": trials,
        "lopo": summary,
        "seconds": time.perf_counter() - t0,
        "cpu_seconds": time.process_time() - c0,
    }
    if summary is not None:
        print(format_lopo(summary))
    kept = sum(t["kept_initial_policy"] for t in trials)
    chosen = np.bincount([v["chosen_setting"] for v in choices.values()], minlength=len(grid))
    print(f"kept the initial policy (the nominal) in {kept}/{len(trials)} trials")
    print(f"settings chosen per fold (grid index: folds): {dict(enumerate(chosen.tolist()))}")
    print(f"{doc['cpu_seconds']:.1f} s CPU, {doc['seconds']:.1f} s wall")
    if args.out:
        atomic_write_text(args.out, json.dumps(doc, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
