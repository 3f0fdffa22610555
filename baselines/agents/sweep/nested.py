"""Checkpoints chosen by inner folds over people: the nested trial of a LOPO sweep.

With ``inner_folds: K`` in the sweep file, one (configuration, seed) trial of an outer
leave-one-person-out fold (``fold = i``: person ``i`` is the test split) trains:

1. ``K`` *inner* agents: the fold's training people are cut into ``K`` groups
   (``val_folds = K``, ``val_fold = j``: :func:`~motion_envs.envs.orientation_reach.
   orientation_split_parts`); agent ``j`` trains on the other groups, with the nominal
   fitted on them, and is validated on group ``j`` at every point of the evaluation
   schedule (start, every ``eval_freq`` steps, end);
2. the *choice*: at each point of the schedule, the mean over the ``K`` groups of the
   validation criterion over the group's nominal criterion; the kept step is the
   lowest (the earliest of ties; step 0 is the initial policy, the nominal);
3. the *refit*: one agent on all the fold's training people (nominal fitted on them,
   for training and for the test's scoring), same seed and hyper-parameters, kept at the
   chosen step (:class:`~baselines.agents.callbacks.KeepAtCallback`). It is the trial's
   run folder, scored on the held-out person as any run.

The held-out person is in none of these (the test split is built only to score the
refit). Hyper-parameters searched by the sweep are chosen per outer fold on the same
inner score (:func:`baselines.agents.sweep.lopo.lopo_summary`). Inner run folders:
``OUT/runs/inner/NAME-inner{j}``; a finished one is reused on ``--resume``.
"""

from __future__ import annotations

import shutil
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from baselines.agents.rundir import read_run_json

__all__ = ["choose_step", "inner_overrides", "nested_train", "refit_overrides"]


def inner_overrides(overrides: Mapping[str, Any], k: int, j: int) -> dict[str, Any]:
    """The overrides of inner agent ``j`` of ``k``: validation on group ``j`` of the
    training people (``val_folds``, ``val_fold``; ``val_fraction`` 0)."""
    env_kwargs = {**overrides.get("env_kwargs", {}), "val_fraction": 0.0}
    return {**overrides, "env_kwargs": {**env_kwargs, "val_folds": int(k), "val_fold": int(j)}}


def refit_overrides(overrides: Mapping[str, Any]) -> dict[str, Any]:
    """The overrides of the refit: every training person (``val_fraction`` 0, no folds)."""
    env_kwargs = {
        k: v
        for k, v in overrides.get("env_kwargs", {}).items()
        if k not in ("val_folds", "val_fold")
    }
    return {**overrides, "env_kwargs": {**env_kwargs, "val_fraction": 0.0}}


def choose_step(
    timesteps: Sequence[Sequence[int]],
    criteria: Sequence[Sequence[float]],
    nominals: Sequence[float],
) -> dict[str, Any]:
    """The kept step of the inner folds' evaluations: ``timesteps[j]`` and
    ``criteria[j]`` (validation criterion at each point) and ``nominals[j]`` (the
    nominal's criterion on group ``j``); the points must agree across folds. Returns the
    step, the mean ratio there (``val_ratio``), the mean criterion and nominal there, and
    the mean ratio curve."""
    steps = [list(map(int, t)) for t in timesteps]
    if not steps or any(t != steps[0] for t in steps):
        raise ValueError(f"the inner folds were evaluated at different steps: {steps}")
    crit = np.asarray(criteria, dtype=float)
    nom = np.asarray(nominals, dtype=float)
    if crit.shape != (len(steps), len(steps[0])) or nom.shape != (len(steps),):
        raise ValueError(f"criteria {crit.shape} and nominals {nom.shape} do not match the folds")
    if not (np.isfinite(crit).all() and (nom > 0).all()):
        raise ValueError("inner validation criteria must be finite and the nominals' > 0")
    ratio = (crit / nom[:, None]).mean(axis=0)
    best = int(np.argmin(ratio))  # the first of ties
    return {
        "timesteps": steps[0][best],
        "val_ratio": float(ratio[best]),
        "val_criterion": float(crit[:, best].mean()),
        "val_nominal_criterion": float(nom.mean()),
        "inner_folds": len(steps),
        "curve": {"timesteps": steps[0], "val_ratio": ratio.tolist()},
        "per_fold_val_ratio": (crit[:, best] / nom).tolist(),
    }


def _evaluations(run_dir: Path) -> tuple[list[int], list[float], float]:
    """A finished run's evaluation points, criteria and validation nominal criterion."""
    rows = (run_dir / "evaluations.csv").read_text().split("\n")[1:]
    pairs = [r.split(",") for r in rows if r]
    manifest = read_run_json(run_dir / "run.json", run_dir)
    steps = [int(p[0]) for p in pairs]
    return steps, [float(p[1]) for p in pairs], float(manifest["val_nominal_criterion"])


def _fresh(run_dir: Path) -> bool:
    """Whether ``run_dir`` must be trained: False when it holds a finished run; an
    unfinished one (and its staging folders) is removed."""
    if (run_dir / "run.json").exists():
        return False
    if run_dir.exists():
        shutil.rmtree(run_dir)
    for leftover in run_dir.parent.glob(f".{run_dir.name}.partial-*"):
        shutil.rmtree(leftover, ignore_errors=True)
    return True


def nested_train(
    cfg: Mapping[str, Any],
    seed: int,
    run_dir: Path,
    inner_folds: int,
    timesteps: int | None,
    n_envs: int | None,
    train: Callable[[Any], Any] | None = None,
) -> dict[str, Any]:
    """Inner agents, the choice and the refit into ``run_dir`` (module docstring); the
    selection (:func:`choose_step`, with the inner run folders). ``train`` is
    :func:`baselines.agents.train.run` (a test may wrap it)."""
    from baselines.agents.train import TrainConfig
    from baselines.agents.train import run as train_run

    train = train or train_run
    inner_root = run_dir.parent / "inner"
    inner_dirs = [inner_root / f"{run_dir.name}-inner{j}" for j in range(inner_folds)]

    def config(out: Path, overrides: Mapping[str, Any], **extra: Any) -> TrainConfig:
        return TrainConfig(
            algo=cfg["algo"],
            env_id=cfg["env_id"],
            out=str(out),
            seed=seed,
            timesteps=timesteps,
            n_envs=n_envs,
            overrides=overrides,
            progress=False,
            tensorboard=False,
            **extra,
        )

    for j, inner in enumerate(inner_dirs):
        if _fresh(inner):
            train(config(inner, inner_overrides(cfg["overrides"], inner_folds, j)))
    evaluations = [_evaluations(d) for d in inner_dirs]
    selection = choose_step(
        [e[0] for e in evaluations], [e[1] for e in evaluations], [e[2] for e in evaluations]
    )
    selection["inner_run_dirs"] = [str(d) for d in inner_dirs]
    selection["rule"] = "mean over inner folds over people of val criterion / nominal's"
    _fresh(run_dir)
    train(
        config(
            run_dir,
            refit_overrides(cfg["overrides"]),
            # an on-policy agent ends on a whole rollout, so the inner agents' last
            # evaluation may come after `timesteps` (30,208 of 30,000); the refit keeps the
            # first evaluation at or after keep_timesteps: that same one
            keep_timesteps=int(selection["timesteps"])
            if timesteps is None
            else min(int(selection["timesteps"]), int(timesteps)),
            selection=selection,
        )
    )
    return selection
