"""The precomputed episodes of ``OrientationReach``: the observation and step-row layouts,
:class:`OrientationTask`, the subject splits (:func:`orientation_split_parts`) and the
cached task building (:func:`load_orientation_task`); re-exported by
:mod:`motion_envs.envs.orientation_reach`.
"""

from __future__ import annotations

import functools
import os
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from motion_envs.envs._common import (
    N_STEPS,
    check_choice,
    check_data,
    check_integer,
    check_number,
    check_val_fraction,
)
from motion_envs.envs._reach import (
    ObsLayout,
    ReachTask,
    observation_table,
    step_table,
    with_timing,
)

__all__ = [
    "LAYOUT",
    "MAX_DEGREE",
    "ROW",
    "SPLIT_BY",
    "OrientationTask",
    "load_orientation_task",
    "orientation_split_parts",
    "validation_groups",
]

#: Largest Bézier degree of the ``bezier-*`` nominals (the paper uses 2 to 4).
MAX_DEGREE = 12


_SPLITS = ("train", "val", "test")
#: What the splits hold out (``split_by``): people, or trials of one person.
SPLIT_BY = ("subject", "replicate")


#: The observation's parts (a quaternion state): start 0-3, goal 4-7, current 8-11,
#: tau 12, nominal 13-16, one-hot task from 17.
LAYOUT = ObsLayout.for_dim(4)
#: A ``task.steps`` row: ``expmap(rhat_k)`` (the nominal in the residual chart), the
#: nominal ``n_k``, the human ``h_k`` and the human residual ``r_k`` (the layout that
#: :func:`~motion_envs.envs._kernels.orientation_step_scalar` reads).
ROW: dict[str, slice] = {
    "chart": slice(0, 4),
    "nominal": slice(4, 8),
    "human": slice(8, 12),
    "residual": slice(12, 15),
}


@dataclass(frozen=True)
class OrientationTask(ReachTask):
    """Precomputed episodes of one split (read-only arrays shared between environments).

    ``steps[l, k]`` holds, for trajectory ``l`` and grid point ``k``, the 15 values the
    step kernel needs: ``expmap(rhat_k)`` (4), the nominal ``n_k`` (4), the human ``h_k``
    (4) and the human residual ``r_k`` (3). ``obs[l, j]`` is the observation before the
    step that sets grid point ``j`` (``j = 50``: after the last step), with the current
    orientation left at 0.
    """

    name: str
    nominal: str
    degree: int
    split: str
    steps: NDArray[np.float64]  # (L, n, 15)
    obs: NDArray[np.float32]  # (L, n + 1, obs_dim)
    trajectory_ids: NDArray[np.str_]
    subjects: NDArray[np.str_]
    tasks: NDArray[np.str_]
    task_names: tuple[str, ...]
    criterion: float
    grids: Any  # motion_envs.models.orientation_nominal.OrientationGrids
    max_duration: float = 0.0  # longest movement of the dataset (s): bound of the timing
    up: tuple[float, ...] = (0.0, 0.0, 1.0)  # the dataset's vertical axis (path frames)


def orientation_split_parts(
    data: str | os.PathLike[str],
    split: str,
    test_fraction: float,
    split_seed: int,
    min_deg: float,
    val_fraction: float = 0.0,
    fold: int | None = None,
    val_folds: int = 0,
    val_fold: int = 0,
    split_by: str = "subject",
) -> tuple[Any, Any, Any]:
    """``(dataset, fit, part)``: the whole dataset, the subjects the environment's nominal
    is fitted on, and the trajectories of ``split`` (in episode order).

    ``fit`` is the training split (by subject); with ``val_fraction > 0`` and a
    ``"train"``/``"val"`` split, the training subjects minus the validation ones.
    Anything else fitted "on the environment's training data" (the learned regressor
    of ``motion-bench agent``) uses this same ``fit``.

    ``fold = i`` (leave one person out): the test split is the ``i``-th person in sorted
    order of the subject labels, the training split every other person
    (``test_fraction`` and ``split_seed`` then only seed the validation carve).

    ``val_folds = K`` (instead of ``val_fraction``): the training people are permuted
    with ``split_seed`` and cut into ``K`` groups of near-equal size
    (:func:`validation_groups`); group ``val_fold`` is ``"val"``, the other people
    ``"train"`` (and ``fit``): the inner folds over people of a nested evaluation.

    ``split_by="replicate"`` (a one-person recording): the splits hold out trials instead
    of people, each task's trajectories permuted with ``split_seed``
    (:func:`~motion_envs.datasets.splits.split_by_replicate`, ``test_fraction``, then
    ``val_fraction`` of the training trials); not with ``fold`` or ``val_folds``.
    """
    from motion_envs.datasets import load_orientation_dataset
    from motion_envs.datasets.splits import split_by_replicate, split_by_subject

    dataset = load_orientation_dataset(data, min_deg=min_deg)
    if len(dataset) < 2:
        raise ValueError(f"data {data!r} has {len(dataset)} trajectories; at least 2 needed")
    if split_by == "replicate":
        if fold is not None or val_folds:
            raise ValueError(
                "split_by='replicate' holds out trials; fold and val_folds hold out people "
                "(use split_by='subject' with them)"
            )
        train, test = split_by_replicate(dataset, test_fraction=test_fraction, seed=split_seed)
        if len(test) == 0:
            raise ValueError(
                f"split_by='replicate': no task of {data!r} has the 3 trajectories a test "
                "trial needs (2 stay in training)"
            )
        fit, part = train, (train if split == "train" else test)
        if val_fraction > 0 and split != "test":
            fit, val = split_by_replicate(train, test_fraction=val_fraction, seed=split_seed)
            part = fit if split == "train" else val
        return dataset, fit, part
    if fold is None:
        train, test = split_by_subject(dataset, test_fraction=test_fraction, seed=split_seed)
        part = train if split == "train" else test
    else:
        people = np.unique(np.asarray(dataset.subjects).astype(str))
        check_integer(fold, "fold", 0, people.size - 1)
        is_test = np.asarray(dataset.subjects).astype(str) == people[fold]
        train = dataset.subset(~is_test)
        # the held-out person's reaches are copied for the test split only (a "val" split
        # is always carved below): the inner folds never touch them (test_contextual_cem)
        part = dataset.subset(is_test) if split == "test" else train
    fit = train
    if val_folds and split != "test":  # inner K-fold over the training people
        groups = validation_groups(train.subjects, val_folds, split_seed)
        is_val = np.isin(np.asarray(train.subjects).astype(str), groups[val_fold])
        fit, val = train.subset(~is_val), train.subset(is_val)
        part = fit if split == "train" else val
    elif val_fraction > 0 and split != "test":  # validation subjects carved from training
        fit, val = split_by_subject(train, test_fraction=val_fraction, seed=split_seed)
        part = fit if split == "train" else val
    return dataset, fit, part


def validation_groups(subjects: Any, n_groups: int, seed: int) -> list[NDArray[np.str_]]:
    """The ``n_groups`` validation groups of ``val_folds``: the distinct ``subjects``
    (sorted labels) permuted with ``numpy.random.default_rng(seed)`` and cut into
    ``n_groups`` groups of near-equal size (each sorted); ``ValueError`` naming
    ``val_folds`` unless ``2 <= n_groups <= `` the number of people."""
    people = np.unique(np.asarray(subjects).astype(str))
    if not 2 <= n_groups <= people.size:
        raise ValueError(
            f"val_folds must be 0 or in [2, {people.size}] (the training people); got {n_groups}"
        )
    order = np.random.default_rng(seed).permutation(people.size)
    return [np.sort(people[g]) for g in np.array_split(order, n_groups)]


def _build_task(
    data: str | os.PathLike[str],
    split: str,
    nominal: str,
    degree: int,
    test_fraction: float,
    split_seed: int,
    min_deg: float,
    val_fraction: float,
    observe_timing: bool,
    fold: int | None,
    val_folds: int,
    val_fold: int,
    split_by: str,
) -> OrientationTask:
    """The episodes of a split; every argument checked and given by
    :func:`load_orientation_task` (the defaults live there)."""
    from motion_envs.geometry import quaternion as quat
    from motion_envs.models.orientation_nominal import OrientationNominal

    dataset, fit, part = orientation_split_parts(
        data, split, test_fraction, split_seed, min_deg, val_fraction, fold, val_folds, val_fold,
        split_by,
    )  # fmt: skip
    model = OrientationNominal(nominal, degree, N_STEPS).fit(fit)
    g = model.grids(part)
    parts = {
        "chart": quat.expmap(g.predicted_residuals),
        "nominal": g.nominal,
        "human": g.human,
        "residual": g.residuals,
    }
    steps = step_table(ROW, parts)
    task_names = tuple(np.unique(dataset.tasks).tolist())
    task_index = np.searchsorted(np.asarray(task_names), part.tasks)
    obs = observation_table(
        LAYOUT, g.starts, g.goals, g.tau, g.nominal, task_index, len(task_names), -1.0, 1.0
    )
    max_duration = float(max(t[-1] - t[0] for t in dataset.times))
    if observe_timing:  # v1: the movement's duration T and the elapsed time tau T (s)
        obs = with_timing(obs, LAYOUT, np.array([t[-1] - t[0] for t in part.times]))
    for arr in (steps, obs, *vars(g).values()):
        arr.flags.writeable = False  # shared by every environment built from the cache
    return OrientationTask(
        name=dataset.name,
        nominal=nominal,
        degree=int(degree),
        split=split,
        steps=steps,
        obs=obs,
        trajectory_ids=part.trajectory_ids,
        subjects=part.subjects,
        tasks=part.tasks,
        task_names=task_names,
        criterion=g.criterion(),
        grids=g,
        max_duration=max_duration,
        up=tuple(float(v) for v in dataset.up),
    )


_build_task_cached = functools.lru_cache(maxsize=32)(_build_task)


def load_orientation_task(
    data: str | os.PathLike[str] = "vr-kitchen",
    split: str = "train",
    nominal: str = "slerp",
    degree: int = 2,
    test_fraction: float = 0.25,
    split_seed: int = 0,
    min_deg: float = 10.0,
    val_fraction: float = 0.0,
    observe_timing: bool = False,
    fold: int | None = None,
    val_folds: int = 0,
    val_fold: int = 0,
    split_by: str = "subject",
) -> OrientationTask:
    """Build (or reuse) the precomputed episodes of a split; built-in data is cached.

    ``fold`` (None or an integer >= 0): leave one person out, the ``fold``-th person
    (sorted labels) is the test split (:func:`orientation_split_parts`); ``val_folds = K``
    and ``val_fold = j`` (0 <= j < K): the ``j``-th of ``K`` groups of the training people
    is the validation split (instead of ``val_fraction``); ``split_by="replicate"``: the
    splits hold out trials, not people (a one-person recording)."""
    from motion_envs.datasets.registry import lookup
    from motion_envs.models.orientation_nominal import ORIENTATION_NOMINALS

    data = check_data(data)
    check_choice(split, "split", _SPLITS)
    check_choice(split_by, "split_by", SPLIT_BY)
    check_choice(nominal, "nominal", ORIENTATION_NOMINALS)
    check_integer(degree, "degree", 1, MAX_DEGREE)
    check_number(min_deg, "min_deg", 0.0, 180.0)
    val_folds = check_integer(val_folds, "val_folds", 0, 2**31)
    if val_folds == 1:
        raise ValueError("val_folds must be 0 (off) or at least 2; got 1")
    val_fold = check_integer(val_fold, "val_fold", 0, max(val_folds - 1, 0))
    val_fraction = check_val_fraction(val_fraction, "train" if val_folds else split)
    if val_folds and val_fraction:
        raise ValueError("val_fraction must be 0 with val_folds (the folds choose the validation)")
    args: tuple[Any, ...] = (data, split, nominal, int(degree), float(test_fraction))
    if fold is not None:
        fold = check_integer(fold, "fold", 0, 2**31)
    args += (int(split_seed), min_deg, val_fraction, bool(observe_timing), fold)
    args += (val_folds, val_fold, split_by)
    builtin = lookup(data, "orientation")
    if builtin is not None and builtin[1] is None:  # a built-in name, not cohort:CONFIG
        return _build_task_cached(*args)
    return _build_task(*args)
