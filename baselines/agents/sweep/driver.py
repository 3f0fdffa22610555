"""The driver of ``motion-bench sweep``: Ray (local or a cluster), the ``Tuner`` (grid,
random or Optuna), ``Tuner.restore`` on ``--resume``, the ``--out`` claim, and the
trials collected into the results (:func:`run`)."""

from __future__ import annotations

import json
import logging
import os
import time
from pathlib import Path
from typing import Any

from baselines import options
from baselines.agents.sweep.space import SweepConfig
from baselines.agents.sweep.summary import summarize
from baselines.agents.sweep.trainable import TRIAL_KEYS, TrialSettings, grid_trial, optuna_trial
from motion_envs._io import atomic_write_text


class SweepInterrupted(RuntimeError):
    """The sweep stopped (Ctrl-C) before every trial finished; ``--resume`` continues it."""


def trial_settings(sweep: SweepConfig) -> TrialSettings:
    """What the sweep's trainable needs of it."""
    return TrialSettings(
        out=sweep.out,
        configurations=sweep.configurations,
        seeds=sweep.seeds,
        test_split=sweep.test_split,
        timesteps=sweep.timesteps,
        n_envs=sweep.n_envs,
        path=sweep.path,
        inner_folds=sweep.inner_folds,
    )


def _tune_domain(value: Any) -> Any:
    """A Ray Tune domain of a (validated) random-search value, for Optuna's sampler."""
    from ray import tune

    if isinstance(value, list):
        return tune.choice(value)
    ((kind, (lo, hi)),) = value.items()
    if kind == "uniform":
        return tune.uniform(lo, hi)
    if kind == "loguniform":
        return tune.loguniform(lo, hi)
    return tune.randint(int(lo), int(hi) + 1)


def _settings(sweep: SweepConfig) -> dict[str, Any]:
    """What a sweep trains (not where or how it runs), as JSON: ``OUT/sweep.json``."""
    keys = "configurations seeds timesteps n_envs test_split search num_samples random_seed space"
    keys += " inner_folds"
    settings: dict[str, Any] = json.loads(json.dumps({k: getattr(sweep, k) for k in keys.split()}))
    return settings


def _claim_out(sweep: SweepConfig, out: Path) -> None:
    """Refuse an ``out`` that holds a sweep unless resuming it with the same settings
    (its finished run folders would be reused as they are); record them in sweep.json."""
    stored = out / "sweep.json"
    settings = _settings(sweep)
    if not sweep.resume and ((out / "tune").exists() or (out / "runs").exists()):
        raise options.ConfigError(
            "out",
            f"{out} already holds a sweep; continue it with --resume or choose another folder",
        )
    if sweep.resume and stored.is_file() and json.loads(stored.read_text()) != settings:
        raise options.ConfigError(
            "config",
            f"{sweep.path} is not the sweep in --out {out} (its settings differ from "
            f"{stored.name}'s); resume with the same sweep file or choose another --out",
        )
    atomic_write_text(stored, json.dumps(settings, indent=2) + "\n")


def run(sweep: SweepConfig) -> dict[str, Any]:
    """Run (or resume) the sweep on Ray Tune; the summary and every trial's metrics."""
    import ray
    from ray import tune

    out = Path(sweep.out).resolve()
    out.mkdir(parents=True, exist_ok=True)
    sweep = SweepConfig(**{**sweep.__dict__, "out": str(out)})
    _claim_out(sweep, out)
    started_here = False
    # --address, else Ray's own RAY_ADDRESS (a cluster), else a local Ray with --num-cpus
    address = sweep.address if sweep.address is not None else os.environ.get("RAY_ADDRESS")
    if not ray.is_initialized():
        # quiet unless --verbose: Ray's start-up log lines go to its log files only
        level = logging.INFO if sweep.progress else logging.ERROR
        if address:
            ray.init(address=address, log_to_driver=False, logging_level=level)
        else:
            ray.init(
                num_cpus=sweep.num_cpus or os.cpu_count(),
                log_to_driver=False,
                include_dashboard=False,
                logging_level=level,
            )
        started_here = True
    t0 = time.perf_counter()
    try:
        optuna = sweep.search == "optuna"
        fn = optuna_trial if optuna else grid_trial
        trainable = tune.with_resources(
            tune.with_parameters(fn, settings=trial_settings(sweep)), {"cpu": 1}
        )
        name = "tune"
        run_config = tune.RunConfig(
            name=name, storage_path=str(out), verbose=1 if sweep.progress else 0
        )
        if sweep.resume and tune.Tuner.can_restore(str(out / name)):
            tuner = tune.Tuner.restore(str(out / name), trainable, resume_errored=True)
        elif optuna:
            from ray.tune.search.optuna import OptunaSearch

            assert sweep.space is not None
            metric = "val_criterion_median"
            tuner = tune.Tuner(
                trainable,
                param_space={k: _tune_domain(v) for k, v in sweep.space.items()},
                tune_config=tune.TuneConfig(
                    search_alg=OptunaSearch(metric=metric, mode="min", seed=sweep.random_seed),
                    num_samples=sweep.num_samples,
                    metric=metric,
                    mode="min",
                ),
                run_config=run_config,
            )
        else:
            tuner = tune.Tuner(
                trainable,
                param_space={
                    "config_index": tune.grid_search(list(range(len(sweep.configurations)))),
                    "seed": tune.grid_search(list(sweep.seeds)),
                },
                tune_config=tune.TuneConfig(metric="best_val_criterion", mode="min"),
                run_config=run_config,
            )
        # quiet unless --verbose (RunConfig's verbose=0); Ray Tune's newer console output
        # still prints its configuration box: the library does not change the process's
        # environment to hide it (export RAY_AIR_NEW_OUTPUT=0 for the classic reporter)
        grid = tuner.fit()
    finally:
        wall = time.perf_counter() - t0
        if started_here:
            ray.shutdown()
    if grid.errors:
        raise RuntimeError(
            f"a sweep trial failed: {grid.errors[0]}; once fixed, --resume --out {out} "
            "runs the failed trials again"
        )
    # Ctrl-C: Ray Tune saves its state, stops the running trials and returns; a trial
    # finished if it made its last report (Ray marks the stopped ones terminated too)
    expected = sweep.num_samples if optuna else len(sweep.configurations) * len(sweep.seeds)
    last = "per_seed" if optuna else "config_index"
    finished = sum(last in (grid[i].metrics or {}) for i in range(len(grid)))
    if finished != expected:
        raise SweepInterrupted(
            f"the sweep was interrupted with {finished} of {expected} trials finished; "
            f"continue it with --resume --out {out}"
        )
    trials = []
    # optuna: the configurations are the ones the sampler proposed, one per trial
    configurations = [] if sweep.search == "optuna" else list(sweep.configurations)
    for i in range(len(grid)):
        m: dict[str, Any] = grid[i].metrics or {}
        if sweep.search == "optuna":  # one configuration per trial, every seed inside
            configurations.append(json.loads(m["configuration"]))
            for t in json.loads(m["per_seed"]):
                trials.append({"config_index": len(configurations) - 1, **t})
        else:
            trials.append({k: m[k] for k in TRIAL_KEYS})
    sweep = SweepConfig(**{**sweep.__dict__, "configurations": tuple(configurations)})
    trials.sort(key=lambda t: (t["config_index"], t["seed"]))
    summary = summarize(trials, sweep)
    return {
        "sweep": sweep.path,
        "seeds": list(sweep.seeds),
        "test_split": sweep.test_split,
        "n_trials": len(trials),
        "wall_seconds": wall,
        "num_cpus": None if address else sweep.num_cpus or os.cpu_count(),
        "address": address or None,
        **summary,
        "trials": trials,
    }
