"""The Ray Tune trainables of ``motion-bench sweep``: one trial trains and scores with the
code path of ``motion-bench train`` and ``motion-bench agent``, and reports to Tune.

As in Ray Tune's examples, the trainable knows nothing of the sweep's driver: it gets a
:class:`TrialSettings` (what every trial trains with) through ``tune.with_parameters``
and its configuration index and seed (grid, random) or the proposed point (Optuna)
through the trial's parameters.
"""

from __future__ import annotations

import json
import time
import warnings
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from baselines.agents.rundir import read_run_json
from baselines.agents.sweep.space import configuration


@dataclass(frozen=True)
class TrialSettings:
    """What every trial of a sweep shares: the run folders' root ``out``, the
    configurations (grid, random), the seeds, the agent-config overrides and the scored
    split; ``path`` (the sweep file) names errors."""

    out: str
    configurations: tuple[dict[str, Any], ...]
    seeds: tuple[int, ...]
    test_split: str = "test"
    timesteps: int | None = None
    n_envs: int | None = None
    path: str = "sweep"
    #: ``K``: checkpoints chosen by ``K`` inner folds over the training people, then a
    #: refit (:mod:`baselines.agents.sweep.nested`); None: on the validation split.
    inner_folds: int | None = None


#: The metrics of one (configuration, seed) trial, in ``trials.csv`` order.
TRIAL_KEYS = (
    "config_index",
    "seed",
    "timesteps",
    "best_val_criterion",
    "val_nominal_criterion",
    "test_criterion",
    "test_nominal_criterion",
    "test_ratio",
    "test_catch_rate",
    "test_nominal_catch_rate",
    "test_deviation_ratio",
    "test_learned_criterion",
    "test_learned_ratio",
    "kept_timesteps",
    "inner_val_ratio",
    "train_seconds",
    "trial_seconds",
    "run_dir",
    "resumed",
)


def train_and_score(
    cfg: Mapping[str, Any], seed: int, run_dir: Path, settings: TrialSettings, intermediate: bool
) -> dict[str, Any]:
    """``train.run`` for one configuration and seed (unless ``run_dir`` already holds a
    finished run), then the test split; the trial's metrics. With
    ``settings.inner_folds`` the run is the refit of a nested trial
    (:func:`~baselines.agents.sweep.nested.nested_train`)."""
    from ray import tune

    import motion_envs  # noqa: F401  (registers the environments inside the worker)
    from baselines.agents.evaluate import AgentConfig
    from baselines.agents.evaluate import run as evaluate
    from baselines.agents.train import TrainConfig
    from baselines.agents.train import run as train

    warnings.filterwarnings("ignore", message=".*is out of date", category=DeprecationWarning)
    t0 = time.perf_counter()
    resumed = (run_dir / "run.json").exists()  # finished before an interruption: rescore it
    if not resumed and settings.inner_folds:
        from baselines.agents.sweep.nested import nested_train

        nested_train(cfg, seed, run_dir, settings.inner_folds, settings.timesteps, settings.n_envs)
    elif not resumed:
        import shutil

        if run_dir.exists():  # an interrupted trial: start it over
            shutil.rmtree(run_dir)
        # the staging folder of a trial whose worker was stopped before train could remove it
        for leftover in run_dir.parent.glob(f".{run_dir.name}.partial-*"):
            shutil.rmtree(leftover, ignore_errors=True)

        def report(ev: dict[str, Any]) -> None:
            keys = ("timesteps", "val_criterion", "best_val_criterion")
            tune.report({k: ev[k] for k in keys})

        train(
            TrainConfig(
                algo=cfg["algo"],
                env_id=cfg["env_id"],
                out=str(run_dir),
                seed=seed,
                timesteps=settings.timesteps,
                n_envs=settings.n_envs,
                overrides=cfg["overrides"],
                progress=False,
                tensorboard=True,
            ),
            on_evaluation=report if intermediate else None,
        )
    test = evaluate(AgentConfig(str(run_dir), settings.test_split))
    manifest = read_run_json(run_dir / "run.json", run_dir)
    selection = manifest.get("selection") or {}
    return {
        "seed": seed,
        "timesteps": manifest["timesteps"],
        "best_val_criterion": manifest["best_val_criterion"],
        "val_nominal_criterion": manifest["val_nominal_criterion"],
        "test_criterion": test["criterion"],
        "test_nominal_criterion": test["nominal_criterion"],
        "test_ratio": test["ratio"],  # None where the nominal's criterion is 0
        # Juggling-v0 (None for the reaching environments)
        "test_catch_rate": test.get("catch_rate"),
        "test_nominal_catch_rate": test.get("nominal_catch_rate"),
        "test_deviation_ratio": test.get("deviation_ratio"),
        # the learned ridge regressor fitted on the same training people (reaching envs)
        "test_learned_criterion": test.get("learned_criterion"),
        "test_learned_ratio": test.get("learned_ratio"),
        "kept_timesteps": manifest["best_timesteps"],
        "inner_val_ratio": selection.get("val_ratio"),
        "train_seconds": manifest["train_seconds"],
        "trial_seconds": time.perf_counter() - t0,
        "run_dir": str(run_dir),
        "resumed": resumed,
    }


def grid_trial(params: dict[str, Any], settings: TrialSettings) -> None:
    """One Ray Tune trial of a grid or random sweep: one configuration, one seed."""
    from ray import tune

    index, seed = int(params["config_index"]), int(params["seed"])
    run_dir = Path(settings.out) / "runs" / f"config{index:03d}-seed{seed}"
    metrics = train_and_score(settings.configurations[index], seed, run_dir, settings, True)
    tune.report(
        {"config_index": index, **metrics},
        checkpoint=tune.Checkpoint.from_directory(str(run_dir)),
    )


def optuna_trial(params: dict[str, Any], settings: TrialSettings) -> None:
    """One Ray Tune trial of an Optuna sweep: the proposed configuration on every seed
    (in turn); the objective is the median over seeds of the validation criterion."""
    from ray import tune

    point = {tuple(k.split(".", 1)): v for k, v in params.items()}
    cfg = configuration(point, settings.path)
    trial_id = tune.get_context().get_trial_id()
    per_seed = [
        train_and_score(
            cfg, seed, Path(settings.out) / "runs" / f"{trial_id}-seed{seed}", settings, False
        )
        for seed in settings.seeds
    ]
    tune.report(
        {
            "val_criterion_median": float(np.median([m["best_val_criterion"] for m in per_seed])),
            "configuration": json.dumps(cfg),
            "per_seed": json.dumps(per_seed),
        }
    )
