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
    # the folds in two processes, then one summary:
    python experiments/contextual_cem_lopo.py --folds 0,1,2,3 --out a.json
    python experiments/contextual_cem_lopo.py --folds 4,5,6,7 --out b.json
    python experiments/contextual_cem_lopo.py --combine a.json b.json --out cem_lopo.json
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


def _report(doc: dict[str, Any]) -> dict[str, Any]:
    """``doc`` with the LOPO summary of its trials (``lopo``), printed in words."""
    configs = [{"overrides": {"env_kwargs": {"fold": f}}} for f in range(max(doc["folds"]) + 1)]
    doc["lopo"] = summary = lopo_summary(doc["trials"], configs)
    if summary is not None:
        print(format_lopo(summary))
    trials, choices = doc["trials"], doc["choices"]
    kept = sum(t["kept_initial_policy"] for t in trials)
    chosen = np.bincount(
        [v["chosen_setting"] for v in choices.values()], minlength=len(doc["grid"])
    )
    print(f"kept the initial policy (the nominal) in {kept}/{len(trials)} trials")
    print(f"settings chosen per fold (grid index: folds): {dict(enumerate(chosen.tolist()))}")
    print(f"{doc['cpu_seconds']:.1f} s CPU, {doc['seconds']:.1f} s wall")
    return doc


def combine(paths: list[str]) -> dict[str, Any]:
    """One document from runs on disjoint folds with the same seeds and grid (the folds
    run in separate processes); the times are their sums."""
    docs = [json.loads(open(p).read()) for p in paths]
    first = docs[0]
    for p, d in zip(paths, docs, strict=True):
        if (d["seeds"], d["grid"], d["data"]) != (first["seeds"], first["grid"], first["data"]):
            raise ValueError(f"{p}: other seeds, grid or data than {paths[0]}")
    folds = [f for d in docs for f in d["folds"]]
    if len(set(folds)) != len(folds):
        raise ValueError(f"the runs share folds: {sorted(folds)}")
    return first | {
        "folds": sorted(folds),
        "trials": [t for d in docs for t in d["trials"]],
        "choices": {k: v for d in docs for k, v in d["choices"].items()},
        "seconds": sum(d["seconds"] for d in docs),
        "cpu_seconds": sum(d["cpu_seconds"] for d in docs),
        "combined_from": paths,
    }


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--folds", default="0,1,2,3,4,5,6,7")
    p.add_argument("--seeds", default="0,1,2")
    p.add_argument("--data", default="vr-kitchen")
    p.add_argument("--budget", type=int, default=30_000)
    p.add_argument("--out", default=None)
    p.add_argument("--combine", nargs="+", metavar="JSON",
                   help="summarise runs on disjoint folds (their --out files) instead")  # fmt: skip
    args = p.parse_args(argv)
    if args.combine:
        try:
            doc = _report(combine(args.combine))
        except (OSError, ValueError, KeyError) as e:
            p.error(f"--combine: {e}")
        if args.out:
            atomic_write_text(args.out, json.dumps(doc, indent=2))
        return 0
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
        "seconds": time.perf_counter() - t0,
        "cpu_seconds": time.process_time() - c0,
    }
    _report(doc)
    if args.out:
        atomic_write_text(args.out, json.dumps(doc, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
