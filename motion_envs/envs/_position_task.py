"""The precomputed episodes of ``PositionReach``: the step-row layout (:func:`row_layout`),
:class:`PositionTask`, the data-dependent observation bounds, the split source
(:func:`position_split_source`) and the cached task building
(:func:`load_position_task`); re-exported by :mod:`motion_envs.envs.position_reach`.
"""

from __future__ import annotations

import functools
import os
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from motion_envs.envs._common import (
    N_STEPS,
    check_data,
    check_integer,
    check_val_fraction,
    timing_bounds,
)
from motion_envs.envs._reach import (
    ObsLayout,
    ReachTask,
    observation_table,
    step_table,
    with_timing,
)

__all__ = [
    "MAX_N_SINES",
    "PositionTask",
    "load_position_task",
    "position_split_source",
    "row_layout",
]

#: Largest ``n_sines``: the interior points of the 50-point grid.
MAX_N_SINES = N_STEPS - 2


def row_layout(D: int) -> dict[str, slice]:
    """A ``task.steps`` row of ``D``-dimensional data: the nominal ``n_k``, then the human
    ``y_k`` (the layout that :func:`~motion_envs.envs._kernels.position_step_scalar`
    reads)."""
    return {"nominal": slice(0, D), "human": slice(D, 2 * D)}


@dataclass(frozen=True)
class PositionTask(ReachTask):
    """Precomputed episodes of one split (read-only arrays shared between environments).

    ``steps[l, k]`` holds the nominal ``n_k`` (D values) then the human ``y_k`` (D) of
    trajectory ``l`` at grid point ``k``; ``obs[l, j]`` the observation before the step
    that sets grid point ``j`` with the current position left at 0.
    """

    name: str
    unit: str
    nominal: str
    split: str
    n_dims: int
    steps: NDArray[np.float64]  # (L, n, 2 D)
    obs: NDArray[np.float32]  # (L, n + 1, obs_dim)
    starts: NDArray[np.float64]  # (L, D)
    low: NDArray[np.float32]  # (D,) plot extents of this split (rendering)
    high: NDArray[np.float32]
    obs_low: NDArray[np.float32]  # (obs_dim,) observation space: independent of the split
    obs_high: NDArray[np.float32]
    cur_low: NDArray[np.float64]  # (D,) float64 bounds of the current position (clipped)
    cur_high: NDArray[np.float64]
    trajectory_ids: NDArray[np.str_]
    tasks: NDArray[np.str_]
    task_names: tuple[str, ...]
    criterion: float
    grids: Any  # motion_envs.models.position_nominal.PositionGrids


def _observation_bounds(
    dataset: Any, D: int, n_tasks: int, residual_scale: float
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Observation bounds (float64) that depend on the data (and ``residual_scale``),
    never on the split.

    With ``lo_d``, ``hi_d`` the extent of coordinate ``d`` over every demonstration of
    the whole dataset (all splits) on the grid and ``m_d = (hi_d - lo_d) +
    residual_scale``: start and goal lie in ``[lo_d, hi_d]``; current and nominal
    position in ``[lo_d - m_d, hi_d + m_d]`` (the observation clips them there); ``tau``
    and the one-hot task in ``[0, 1]``.
    """
    from motion_envs.datasets.resampling import resample_positions

    y, _ = resample_positions(dataset, N_STEPS)
    lo, hi = y.min(axis=(0, 1)), y.max(axis=(0, 1))
    margin = (hi - lo) + residual_scale
    layout = ObsLayout.for_dim(D)
    low = np.zeros(layout.size(n_tasks))
    high = np.ones(layout.size(n_tasks))
    low[layout.start] = low[layout.goal] = lo
    high[layout.start] = high[layout.goal] = hi
    low[layout.current] = low[layout.nominal] = lo - margin
    high[layout.current] = high[layout.nominal] = hi + margin
    return low, high


def position_split_source(
    data: str | os.PathLike[str],
    shapes: Sequence[str] | None,
    split: str,
    test_fraction: float,
    split_seed: int,
    val_fraction: float = 0.0,
) -> tuple[Any, Any, str, float]:
    """``(full, dataset, inner_split, fraction)``: the environment's episodes of ``split``
    are ``position_grids(dataset, inner_split, ..., fraction, split_seed)``.

    ``full`` is the whole dataset (observation bounds and task names); ``dataset`` the
    demonstrations the split is drawn from (with ``val_fraction > 0`` and a
    ``"train"``/``"val"`` split, the training demonstrations, split again). The folds of
    :func:`~motion_envs.datasets.splits.position_folds` on these arguments give every
    task's training demonstrations, which anything else fitted "on the environment's
    training data" (the learned regressor of ``motion-bench agent``) uses too.
    """
    from motion_envs.datasets import load_position_dataset
    from motion_envs.datasets.splits import split_by_replicate

    full = load_position_dataset(data, None if shapes is None else tuple(shapes))
    if val_fraction > 0 and split in ("train", "val"):  # validation carved from training
        dataset, _ = split_by_replicate(full, test_fraction=test_fraction, seed=split_seed)
        return full, dataset, ("train" if split == "train" else "test"), val_fraction
    return full, full, split, test_fraction


def _build_task(
    data: str | os.PathLike[str],
    shapes: tuple[str, ...] | None,
    split: str,
    nominal: str,
    n_sines: int | str,
    test_fraction: float,
    split_seed: int,
    residual_scale: float,
    val_fraction: float,
    observe_timing: bool,
) -> PositionTask:
    """The episodes of a split; every argument checked and given by
    :func:`load_position_task` (the defaults live there)."""
    from motion_envs.models.position_nominal import position_grids

    full, dataset, inner, fraction = position_split_source(
        data, shapes, split, test_fraction, split_seed, val_fraction
    )
    all_durations = np.array([t[-1] - t[0] for t in full.times])
    g = position_grids(dataset, inner, nominal, n_sines, fraction, split_seed, N_STEPS)
    D = g.human.shape[2]
    layout = ObsLayout.for_dim(D)
    steps = step_table(row_layout(D), {"nominal": g.nominal, "human": g.human})
    task_names = tuple(sorted(set(np.asarray(full.tasks).astype(str).tolist())))
    starts, goals = g.human[:, 0], g.human[:, -1]
    # plot extents of this split (rendering): an agent's position is a nominal + residual
    lo = min(g.nominal.min(), g.human.min()) - residual_scale
    hi = max(g.nominal.max(), g.human.max()) + residual_scale
    pad = 1e-3 * max(1.0, abs(lo), abs(hi))
    low = np.full(D, lo - pad, dtype=np.float32)
    high = np.full(D, hi + pad, dtype=np.float32)
    low64, high64 = _observation_bounds(full, D, len(task_names), residual_scale)
    obs_low, obs_high = low64.astype(np.float32), high64.astype(np.float32)
    task_index = np.searchsorted(np.asarray(task_names), g.tasks)
    # clipped: a diverged nominal (see the class docstring)
    obs = observation_table(
        layout, starts, goals, g.tau, g.nominal, task_index, len(task_names), obs_low, obs_high
    )
    if observe_timing:  # v1: the movement's duration T and the elapsed time tau T (s)
        obs = with_timing(obs, layout, np.array([t[-1] - t[0] for t in dataset.times])[g.index])
        t_low, t_high = timing_bounds(float(all_durations.max()))
        obs_low = np.concatenate([obs_low, np.full(2, t_low, dtype=np.float32)])
        obs_high = np.concatenate([obs_high, np.full(2, t_high, dtype=np.float32)])
    for arr in (steps, obs, starts, *vars(g).values()):
        arr.flags.writeable = False  # shared by every environment built from the cache
    return PositionTask(
        name=dataset.name,
        unit=getattr(dataset, "unit", ""),
        nominal=nominal,
        split=split,
        n_dims=D,
        steps=steps,
        obs=obs,
        starts=starts,
        low=low,
        high=high,
        obs_low=obs_low,
        obs_high=obs_high,
        cur_low=low64[layout.current],
        cur_high=high64[layout.current],
        trajectory_ids=np.asarray(dataset.trajectory_ids)[g.index],
        tasks=g.tasks,
        task_names=task_names,
        criterion=g.criterion(),
        grids=g,
    )


_build_task_cached = functools.lru_cache(maxsize=32)(_build_task)


def load_position_task(
    data: str | os.PathLike[str] = "lasa",
    shapes: Sequence[str] | None = None,
    split: str = "train",
    nominal: str = "sine",
    n_sines: int | str = "auto",
    test_fraction: float = 0.25,
    split_seed: int = 0,
    residual_scale: float = 5.0,
    val_fraction: float = 0.0,
    observe_timing: bool = False,
) -> PositionTask:
    """Build (or reuse) the precomputed episodes of a split; built-in data is cached."""
    from motion_envs.datasets.registry import lookup
    from motion_envs.datasets.splits import POSITION_SPLITS
    from motion_envs.models.position_nominal import POSITION_NOMINALS, PositionNominal

    data = check_data(data)
    splits = (*POSITION_SPLITS, "val")
    if split not in splits:
        raise ValueError(f"split must be one of {list(splits)}; got {split!r}")
    val_fraction = check_val_fraction(val_fraction, split)
    if n_sines != "auto":
        check_integer(n_sines, "n_sines", 0, MAX_N_SINES)
    PositionNominal(nominal, n_sines)  # validates nominal and n_sines
    assert nominal in POSITION_NOMINALS
    if shapes is not None:
        if not isinstance(shapes, (list, tuple)) or not all(isinstance(s, str) for s in shapes):
            raise ValueError(f"shapes must be a list of shape names or None; got {shapes!r}")
        shapes = tuple(shapes)
    args: tuple[Any, ...] = (data, shapes, split, nominal, n_sines, float(test_fraction))
    args += (split_seed, residual_scale, val_fraction, bool(observe_timing))
    if lookup(data, "position") is not None:  # built-in data: cached
        return _build_task_cached(*args)
    return _build_task(*args)
