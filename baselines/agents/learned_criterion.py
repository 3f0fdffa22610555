"""The learned regressor on an environment's episodes, scored as the environment scores.

``motion-bench agent`` reports, next to the agent and the zero-action nominal, the
*learned* residual regressor of :mod:`baselines.learned` on the same episodes with the
same criterion: the median over episodes of ``info["max_error"]``.

* **Orientation** (``OrientationReach-v0``/``-v1``, and ``OrientationCoefficients-v0``,
  whose episodes and scoring are the same task's): the ridge regressor of
  :mod:`baselines.learned.orientation` (pre-movement conditions: start and goal
  orientation, their relative rotation and angle, log duration, one-hot task) predicts
  the residual's path-frame sine coefficients. It is fitted on the trajectories the
  environment's nominal is fitted on
  (:func:`~motion_envs.envs.orientation_reach.orientation_split_parts`), with residuals
  taken against the same base slerp as the environment: ``e = slerp(q_0, q_n,
  alpha_bar)`` with ``alpha_bar`` the mean speed profile of those trajectories (the
  "predicted timing" residual of :mod:`baselines.learned.rows`). The ridge penalty is
  chosen by inner folds over the training subjects
  (:func:`~baselines.learned.orientation.ridge_nested`).
* **Position** (``PositionReach-v0``/``-v1``, ``PositionCoefficients-v0``): the ``ridge`` column of
  :mod:`baselines.learned.position` (Lippi's residual ``y - line`` regressed on the
  conditions, start and end, constant columns dropped), fitted per shape on the
  environment's training demonstrations of that shape (the folds of
  :func:`~motion_envs.datasets.splits.position_folds`, as the nominal).

Scoring is the environments' own:
:func:`~motion_envs.envs.orientation_reach.orientation_max_errors` and
:func:`~motion_envs.envs.position_reach.position_max_errors` run their step kernels with a
zero action on top of the learned trajectory (the orientation ``e_k expmap(rhat_k)``
gives ``| logmap(expmap(rhat_k)) - r_k |``, the position ``yhat_k`` gives ``| yhat_k -
y_k |``); each episode's error is the maximum over the grid, as ``info["max_error"]``.
Given the environment's own nominal they reproduce the zero-action episodes (tested).
"""

from __future__ import annotations

import inspect
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from baselines.agents.reaching_score import EpisodeErrors
from motion_envs._typing import FloatArray
from motion_envs.envs.orientation_reach import N_STEPS, orientation_max_errors
from motion_envs.envs.position_reach import position_max_errors

__all__ = [
    "LearnedErrors",
    "learned_episode_errors",
    "learned_skip_reason",
    "orientation_learned_residuals",
    "orientation_max_errors",
    "position_learned_positions",
    "position_max_errors",
]


@dataclass(frozen=True)
class LearnedErrors:
    """Per-episode max errors of the learned regressor and what it chose."""

    errors: EpisodeErrors
    model: str
    chosen: list[dict[str, Any]] = field(default_factory=list)


# -- the regressors, fitted on the environment's training data -------------------------
def orientation_learned_residuals(
    fit: Any, part: Any, n_points: int = N_STEPS
) -> tuple[FloatArray, list[dict[str, Any]]]:
    """Ridge-predicted body-frame residuals ``(len(part), n_points, 3)`` of ``part``.

    Fitted on ``fit`` only (an :class:`~motion_envs.datasets.OrientationDataset`):
    residuals against ``slerp(q_0, q_n, alpha_bar)`` with ``alpha_bar`` the mean speed
    profile of ``fit``, in the path frame, as sine coefficients; the ridge penalty chosen
    by inner folds over ``fit``'s subjects. ``part``'s trajectories are used for their
    pre-movement conditions only (their target rows are NaN, so a fit that touched them
    would fail). Returns the residuals and the chosen penalty.
    """
    from baselines.learned.orientation import (
        orientation_features,
        ridge_nested,
        sine_curves,
        sine_targets,
    )
    from motion_envs.models.orientation_nominal import OrientationNominal
    from motion_envs.models.path_frame import from_path_frame, to_path_frame
    from motion_envs.models.slerp_residual import slerp_residuals

    alpha_bar = OrientationNominal("slerp", n_points=n_points).fit(fit).average_alpha_
    tr, te = fit.ragged, part.ragged
    up = fit.up
    R = slerp_residuals(tr, n_points, average_alpha=alpha_bar)
    Y_fit = sine_targets(to_path_frame(R, tr.starts, tr.ends, up))
    levels = sorted(set(np.asarray(fit.tasks).astype(str).tolist()))
    X = np.concatenate(
        [
            orientation_features(tr.starts, tr.ends, tr.durations, fit.tasks, levels),
            orientation_features(te.starts, te.ends, te.durations, part.tasks, levels),
        ]
    )
    Y = np.concatenate([Y_fit, np.full((len(part), Y_fit.shape[1]), np.nan)])
    groups = np.concatenate([np.asarray(fit.subjects), np.asarray(part.subjects)]).astype(str)
    n_fit = len(fit)
    folds = [(np.arange(n_fit), np.arange(n_fit, n_fit + len(part)))]
    coef, chosen = ridge_nested(X, Y, groups, folds)
    rhat = from_path_frame(sine_curves(coef[n_fit:], n_points), te.starts, te.ends, up)
    return np.asarray(rhat, dtype=np.float64), chosen


def position_learned_positions(
    dataset: Any, split: str, fraction: float, split_seed: int, n_points: int = N_STEPS
) -> tuple[FloatArray, NDArray[np.int64], list[dict[str, Any]]]:
    """Ridge-predicted positions of the episodes of ``position_grids(dataset, split, ...)``.

    Per shape, fitted on the training demonstrations of
    :func:`~motion_envs.datasets.splits.position_folds` (the nominal's). Returns the
    predictions ``(L, n_points, D)``, the dataset rows they belong to (episode order) and
    the chosen penalties.
    """
    from baselines.learned.position import learned_position_predictions
    from motion_envs.datasets.resampling import resample_positions
    from motion_envs.datasets.splits import position_folds
    from motion_envs.models.position_nominal import POSITION_CONDITIONS

    folds = position_folds(dataset, split, fraction, split_seed)
    y_all, durations = resample_positions(dataset, n_points)
    preds, chosen = learned_position_predictions(
        y_all, durations, folds, POSITION_CONDITIONS, methods=("ridge",)
    )
    index = np.concatenate([s for _, _, s in folds]).astype(np.int64)
    return preds["ridge"], index, chosen["ridge"]


# -- on an environment id -------------------------------------------------------------
def learned_skip_reason(env_id: str) -> str | None:
    """Why ``env_id`` has no learned row (None: it has one)."""
    from baselines.learned import sklearn_missing_reason

    families = (
        "OrientationReach",
        "PositionReach",
        "OrientationCoefficients",
        "PositionCoefficients",
    )
    if not any(name in env_id for name in families):
        return f"no learned regressor for {env_id}"
    return sklearn_missing_reason()


def _arguments(env: Any, env_id: str, env_kwargs: Mapping[str, Any], split: str) -> dict[str, Any]:
    """The environment's constructor arguments (registration and defaults filled in)."""
    import gymnasium as gym

    kwargs = {**gym.spec(env_id).kwargs, **env_kwargs, "split": split}
    bound = inspect.signature(type(env).__init__).bind_partial(None, **kwargs)
    bound.apply_defaults()
    return {k: v for k, v in bound.arguments.items() if k != "self"}


def learned_episode_errors(
    env_id: str,
    env_kwargs: Mapping[str, Any],
    split: str,
    episodes: int | None = None,
) -> LearnedErrors:
    """The learned regressor's per-episode max error on the episodes of
    :func:`~baselines.agents.evaluate.episode_max_errors` (same ids, same order)."""
    import gymnasium as gym

    import motion_envs  # noqa: F401  (registers the ids)
    from motion_envs.envs.orientation_coefficients import OrientationCoefficientsEnv
    from motion_envs.envs.orientation_reach import OrientationReachEnv, orientation_split_parts
    from motion_envs.envs.position_coefficients import PositionCoefficientsEnv
    from motion_envs.envs.position_reach import PositionReachEnv, position_split_source

    reason = learned_skip_reason(env_id)
    if reason is not None:
        raise ValueError(reason)
    kwargs = {k: v for k, v in env_kwargs.items() if k != "split"}
    env: Any = gym.make(env_id, split=split, **kwargs).unwrapped
    task = env.task
    a = _arguments(env, env_id, kwargs, split)
    # the coefficient envs score the same episodes of the same task (one step each)
    if isinstance(env, (OrientationReachEnv, OrientationCoefficientsEnv)):
        _, fit, part = orientation_split_parts(
            a["data"], split, a["test_fraction"], a["split_seed"], a["min_deg"], a["val_fraction"],
            a.get("fold"), a.get("val_folds", 0), a.get("val_fold", 0),
            a.get("split_by", "subject"),
        )  # fmt: skip
        if not np.array_equal(np.asarray(part.trajectory_ids), task.trajectory_ids):
            raise RuntimeError(f"{env_id}: the learned split does not match the environment's")
        rhat, chosen = orientation_learned_residuals(fit, part)
        errors, model = orientation_max_errors(task, rhat), "ridge (path frame, mean profile)"
    elif isinstance(env, (PositionReachEnv, PositionCoefficientsEnv)):
        _, dataset, inner, fraction = position_split_source(
            a["data"], a["shapes"], split, a["test_fraction"], a["split_seed"], a["val_fraction"]
        )
        yhat, index, chosen = position_learned_positions(dataset, inner, fraction, a["split_seed"])
        if not np.array_equal(index, task.grids.index):
            raise RuntimeError(f"{env_id}: the learned split does not match the environment's")
        errors, model = position_max_errors(task, yhat), "ridge (Lippi residual on conditions)"
    else:  # pragma: no cover - learned_skip_reason filters by id
        raise ValueError(f"no learned regressor for {env_id}")
    env.close()
    n = errors.size if episodes is None else min(int(episodes), errors.size)
    return LearnedErrors(
        EpisodeErrors(
            errors[:n],
            np.asarray(task.trajectory_ids[:n]).astype(str),
            np.asarray(task.tasks[:n]).astype(str),
        ),
        model,
        chosen,
    )
