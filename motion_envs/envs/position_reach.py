"""``MotionEnvs/PositionReach-v0``/``-v1``: act on top of an analytic position trajectory."""

# ruff: noqa: E501  (the class docstring holds Gymnasium-style Markdown tables)

from __future__ import annotations

import functools
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import gymnasium as gym
import numpy as np
from numpy.typing import NDArray

from motion_envs.envs import _kernels as K
from motion_envs.envs._common import (
    N_STEPS,
    check_integer,
    check_val_fraction,
    timing_bounds,
)
from motion_envs.envs._kernels import position_reward, position_step_scalar
from motion_envs.envs._reach import (
    ObsLayout,
    ReachEnv,
    ReachKind,
    ReachTask,
    checked_prediction,
    observation_table,
    step_table,
    with_timing,
    zero_action_errors,
)
from motion_envs.envs._reach_vector import ReachVectorEnv

__all__ = [
    "DEFAULT_POSITION_REWARD_WEIGHTS",
    "POSITION",
    "PositionKind",
    "PositionReachEnv",
    "PositionReachVectorEnv",
    "PositionTask",
    "load_position_task",
    "position_max_errors",
    "position_split_source",
]

#: Largest ``residual_scale`` (the data's unit): the CSV loader's largest position, so
#: the observation bounds stay finite in float32.
MAX_POSITION_RESIDUAL_SCALE = 1e9
#: Largest ``n_sines``: the interior points of the 50-point grid.
MAX_N_SINES = N_STEPS - 2

#: Default reward weights (see the class docstring, section Rewards).
DEFAULT_POSITION_REWARD_WEIGHTS: Mapping[str, float] = {"distance": 1.0, "action": 0.0}


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
    grids: Any  # motion_envs.models.nominal.PositionGrids


def _observation_bounds(
    dataset: Any, D: int, n_tasks: int, residual_scale: float
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Observation bounds (float64) that depend on the data (and ``residual_scale``), never on the split.

    With ``lo_d``, ``hi_d`` the extent of coordinate ``d`` over every demonstration of
    the whole dataset (all splits) on the grid and ``m_d = (hi_d - lo_d) +
    residual_scale``: start and goal lie in ``[lo_d, hi_d]``; current and nominal
    position in ``[lo_d - m_d, hi_d + m_d]`` (the observation clips them there); ``tau``
    and the one-hot task in ``[0, 1]``.
    """
    from motion_envs.models.nominal import resample_positions

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
    :func:`~motion_envs.models.nominal.position_folds` on these arguments give every
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
    val_fraction: float = 0.0,
    observe_timing: bool = False,
) -> PositionTask:
    from motion_envs.models.nominal import position_grids

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
    """Build (or reuse) the precomputed episodes of a split; LASA is cached."""
    from motion_envs.models.nominal import POSITION_NOMINALS, POSITION_SPLITS, PositionNominal

    splits = (*POSITION_SPLITS, "val")
    if split not in splits:
        raise ValueError(f"split must be one of {list(splits)}; got {split!r}")
    val_fraction = check_val_fraction(val_fraction, split)
    if n_sines != "auto":
        check_integer(n_sines, "n_sines", 0, MAX_N_SINES)
    PositionNominal(nominal, n_sines)  # validates nominal and n_sines
    assert nominal in POSITION_NOMINALS
    if shapes is not None:
        if isinstance(shapes, str) or not all(isinstance(s, str) for s in shapes):
            raise ValueError(f"shapes must be a list of shape names or None; got {shapes!r}")
        shapes = tuple(shapes)
    args: tuple[Any, ...] = (data, shapes, split, nominal, n_sines, float(test_fraction))
    args += (split_seed, residual_scale, val_fraction, bool(observe_timing))
    if isinstance(data, str) and data == "lasa":
        return _build_task_cached(*args)
    return _build_task(*args)


def position_max_errors(
    task: Any, predicted_positions: NDArray[np.float64], index: Any = None
) -> NDArray[np.float64]:
    """``(L,)`` ``max_k |yhat_lk - y_lk|`` of a position task's episodes.

    ``predicted_positions`` ``(L, n, D)``; scored by the environment's step kernel with a
    zero action (the demonstration ``y`` from ``task.steps``). With ``index`` (integer
    array), only those episodes: ``predicted_positions`` is ``(len(index), n, D)``.
    """
    D = task.n_dims
    steps = task.steps if index is None else task.steps[index]
    yhat = checked_prediction(predicted_positions, steps, D, "predicted_positions")
    predicted = np.array(steps)
    predicted[..., row_layout(D)["nominal"]] = yhat
    return zero_action_errors(POSITION, task, predicted)


class PositionKind(ReachKind):
    """The position kind: a ``D``-dimensional position set by an offset action."""

    name = "position"
    instance_name = "POSITION"
    step_keys = ("error", "reward_distance", "reward_action")
    end_keys = (("max_error", "error"),)
    weight_keys = ("distance", "action")
    default_weights = DEFAULT_POSITION_REWARD_WEIGHTS
    max_residual_scale = MAX_POSITION_RESIDUAL_SCALE
    load_task = staticmethod(load_position_task)
    max_errors = staticmethod(position_max_errors)

    def state_dim(self, task: Any) -> int:
        return int(task.n_dims)

    def action_dim(self, task: Any) -> int:
        return int(task.n_dims)

    def row_layout(self, dim: int) -> dict[str, slice]:
        return row_layout(dim)

    def scalar_step(
        self, row: list[float], a: list[float], scale: float, w: tuple[float, ...]
    ) -> tuple[tuple[float, ...], float, dict[str, float]]:
        q = [0.0] * len(a)
        err = position_step_scalar(row, a, scale, q)
        sq = 0.0
        for v in a:
            sq = sq + v * v
        r_dist, r_act, reward = position_reward(err, sq, w[0], w[1])
        return tuple(q), reward, {"error": err, "reward_distance": r_dist, "reward_action": r_act}

    def batch_step(
        self, rows: NDArray[np.float64], a: NDArray[np.float64], scale: float, w: tuple[float, ...]
    ) -> tuple[NDArray[np.float64], Any, list[Any]]:
        D = a.shape[1]
        layout = row_layout(D)
        cols = [a[:, i] for i in range(D)]
        q, err = K.position_step(
            K.BATCH, rows[layout["nominal"]], rows[layout["human"]], cols, scale
        )
        sq: Any = 0.0
        for c in cols:
            sq = sq + c * c
        r_dist, r_act, reward = position_reward(err, sq, *w)
        return np.stack(q, axis=1), reward, [err, r_dist, r_act]

    @staticmethod
    def fused_physics(
        row: Any, a: Any, scale: float, w: Any, q: Any
    ) -> tuple[float, tuple[float, ...]]:
        err = position_step_scalar(row, a, scale, q)
        sq = 0.0
        for j in range(a.shape[0]):
            sq = sq + a[j] * a[j]
        r_dist, r_act, reward = position_reward(err, sq, w[0], w[1])
        return reward, (err, r_dist, r_act)


#: The position kind (one instance serves every position environment).
POSITION = PositionKind()


class PositionReachEnv(ReachEnv):
    r"""Replay a human demonstration's positions; the agent corrects an analytic nominal.

    ## Description
    Lippi, Avizzano & Ruffaldi (2011) write a movement as a line from its start to its
    end plus a sine series on normalised time, and regress the coefficients on the
    movement's boundary conditions. Each episode replays the *task* of one recorded
    demonstration (its start and end point and its shape/task label) on the 50-point
    normalised-time grid: at every step the agent moves the nominal model's position
    by a small offset and is scored by its distance to the demonstration at that time.
    Nominals are fitted per task on the training demonstrations only
    (:mod:`motion_envs.models.nominal`).

    The zero action reproduces the nominal exactly: on a split (``"test"``, ``"train"``,
    or ``"loo"``: every demonstration, its nominal fitted on the other demonstrations of
    its shape) the median over shapes of the median over their episodes of
    ``info["max_error"]`` equals ``motion-bench position --split SPLIT --n-points 50``'s
    max-error criterion of the same model (``line``, ``null``, ``lippi`` for ``"sine"``),
    tested to 1e-9 for ``"test"`` and ``"loo"``.

    ## Action Space
    The action space is a `Box(-1, 1, (D,), float32)`, ``D`` the data's dimension (2 for
    LASA): the offset from the nominal position in units of `residual_scale`,
    ``y_k = n_k + residual_scale * a_k``. Actions outside ``[-1, 1]`` are clipped; a
    wrong shape or a NaN or infinite entry raises `ValueError` and leaves the
    environment unchanged.

    | Num | Action                                 | Control Min | Control Max | Type (Unit)                   |
    |-----|----------------------------------------|-------------|-------------|-------------------------------|
    | 0   | x offset from the nominal              | -1          | 1           | position (residual_scale)     |
    | 1   | y offset from the nominal              | -1          | 1           | position (residual_scale)     |
    | 2   | z offset (3-D data only)               | -1          | 1           | position (residual_scale)     |

    ## Observation Space
    The observation space is a `Box(low, high, (4 D + 1 + T,), float32)`, ``T`` the number
    of tasks (30 LASA shapes: 39 values). It depends on `data`, `shapes` and
    `residual_scale` only, never on `split`, `split_seed` or `test_fraction`, so a policy
    trained on one split loads and runs on another (SB3's ``PPO.load(path, env=...)``,
    ``set_env``). With ``lo_d``, ``hi_d`` the extent of coordinate ``d`` over every
    demonstration of the dataset (all splits) and the margin ``m_d = (hi_d - lo_d) +
    residual_scale``, start and goal lie in ``[lo_d, hi_d]``, current and nominal position
    in ``[lo_d - m_d, hi_d + m_d]``. A nominal fitted on very few demonstrations can
    diverge beyond that margin (LASA, ``nominal="sine"``, ``test_fraction=0.5``: up to
    3 data extents on some test splits; never on the default splits); the observation
    clips such positions to the bounds, while the error and reward use the true ones.

    | Num             | Observation                                                  | Min       | Max       | Type (Unit)     |
    |-----------------|--------------------------------------------------------------|-----------|-----------|-----------------|
    | 0 .. D-1        | start position ``y_0``                                       | lo_d      | hi_d      | position        |
    | D .. 2D-1       | goal position ``y_1``                                        | lo_d      | hi_d      | position        |
    | 2D .. 3D-1      | current position (the last one set; ``y_0`` at reset)        | lo_d - m_d | hi_d + m_d | position        |
    | 3D              | ``tau`` of the grid point the next action sets (1 after the last) | 0         | 1         | normalised time |
    | 3D+1 .. 4D      | the nominal's position at that grid point ``n_k``            | lo_d - m_d | hi_d + m_d | position        |
    | 4D+1 ..         | one-hot task (shape) over the sorted task names              | 0         | 1         | unitless        |
    | -2 (v1)         | the movement's duration ``T`` (a pre-movement condition)     | 0         | ``T_max`` | time (s)        |
    | -1 (v1)         | elapsed time ``tau T`` at that grid point                     | 0         | ``T_max`` | time (s)        |

    ``-v1`` (``observe_timing=True``) appends the last two entries (41 values for LASA);
    ``T_max`` is the longest demonstration of the data (padded by 0.1 %).

    ## Rewards
    The reward is ``-(w_distance |y_k - h_k| + w_action |a_k|^2)`` with ``h_k`` the
    demonstration at grid point ``k`` and the weights of `reward_weights` (default
    ``distance: 1, action: 0``). `info` holds ``error`` (the distance, in the data's
    unit), ``reward_distance``, ``reward_action`` and ``tau`` every step and, at the end
    of an episode, ``max_error`` (the paper's per-trajectory criterion).

    ## Starting State
    `reset` draws one trajectory of the split uniformly with the environment's
    generator (``options={"trajectory": i}`` picks trajectory ``i``); the current
    position is its start ``y_0``.

    ## Episode End
    ### Termination
    The episode terminates after 50 steps, when every point of the grid is set.

    ### Truncation
    The default duration of an episode is 50 steps (``max_episode_steps`` of the
    registration), so the last step is both terminated and truncated.

    ## Arguments
    ```python
    import gymnasium as gym
    import motion_envs
    env = gym.make("MotionEnvs/PositionReach-v0", shapes=["GShape"], nominal="sine")
    ```

    | Parameter        | Type         | Default   | Description |
    |------------------|--------------|-----------|-------------|
    | `data`           | **str**      | `"lasa"`  | `"lasa"` or a path to the users' position CSV |
    | `shapes`         | **list**     | `None`    | shapes (LASA) or tasks (CSV) to use; None: all |
    | `split`          | **str**      | `"train"` | `"train"`, `"val"`, `"test"` (held-out demonstrations of each task, `split_by_replicate`) or `"loo"` (every demonstration, nominal fitted on the others) |
    | `nominal`        | **str**      | `"sine"`  | `"line"`, `"null"` (line + mean residual) or `"sine"` (Lippi's regression) |
    | `n_sines`        | **int/str**  | `"auto"`  | number of sines of `"sine"` (0 to 48), or `"auto"` (leave-one-out CV, 0..15) |
    | `residual_scale` | **float**    | `5.0`     | offset of an action of 1, in the data's unit (mm for LASA), in (0, 1e9] |
    | `reward_weights` | **dict**     | `None`    | weights of the reward terms, keys `distance`, `action` (None: 1, 0) |
    | `test_fraction`  | **float**    | `0.25`    | share of each task's demonstrations held out for the test split, in (0, 1) |
    | `split_seed`     | **int**      | `0`       | seed of the split (`split_by_replicate`), >= 0 |
    | `render_mode`    | **str**      | `None`    | `None` or `"rgb_array"` |
    | `width`          | **int**      | `480`     | frame width in pixels |
    | `height`         | **int**      | `480`     | frame height in pixels |
    | `val_fraction`   | **float**    | `0.0`     | share of each task's *training* demonstrations held out as `split="val"`; with it `"train"` holds the others and the nominals are fitted on them only (`"test"`, `"loo"` unchanged) |
    | `observe_timing` | **bool**     | `False`   | append the duration and the elapsed time to the observation (`True` in `-v1`) |

    A bad argument raises `ValueError` naming it (the same in the vector environment);
    reward weights must lie in [0, 1e6]. `step` raises `ValueError` for an action that
    is not an array of real numbers (a dict, a string, complex numbers).

    ## Version History
    * v1: the observation also holds the movement's duration and the elapsed time
      (``observe_timing=True``); the zero-action invariant and everything else as in v0.
    * v0: Initial version.
    """

    kind = POSITION

    def __init__(
        self,
        data: str | os.PathLike[str] = "lasa",
        shapes: Sequence[str] | None = None,
        split: str = "train",
        nominal: str = "sine",
        n_sines: int | str = "auto",
        residual_scale: float = 5.0,
        reward_weights: Mapping[str, float] | None = None,
        test_fraction: float = 0.25,
        split_seed: int = 0,
        render_mode: str | None = None,
        width: int = 480,
        height: int = 480,
        val_fraction: float = 0.0,
        observe_timing: bool = False,
    ) -> None:
        self._check_arguments(
            render_mode, width, height, residual_scale, reward_weights, test_fraction, split_seed
        )
        self.task = load_position_task(
            data, shapes, split, nominal, n_sines, test_fraction, split_seed, self.residual_scale,
            val_fraction, observe_timing,
        )  # fmt: skip
        self.observation_space = gym.spaces.Box(
            self.task.obs_low, self.task.obs_high, dtype=np.float32
        )
        # the current position clipped to the observation bounds as float64 (float32
        # rounding is monotonic: the float32 observation stays inside the bounds)
        bounds = (tuple(self.task.cur_low.tolist()), tuple(self.task.cur_high.tolist()))
        self._setup(self.task.starts, bounds)

    def _render_frame(self) -> NDArray[np.uint8]:
        if self._renderer is None:
            from motion_envs.envs.rendering import CurveRenderer

            self._renderer = CurveRenderer(self.width, self.height, self.task.low, self.task.high)
        g = self.task.grids
        frame: NDArray[np.uint8] = self._renderer.render(
            human=g.human[self._index],
            nominal=g.nominal[self._index],
            agent=np.asarray(self._history),
            title=f"{self.task.tasks[self._index]}  step {len(self._history) - 1}/{N_STEPS}",
        )
        return frame


class PositionReachVectorEnv(ReachVectorEnv):
    """``num_envs`` copies of :class:`PositionReachEnv`, bit-identical to
    ``SyncVectorEnv`` (arguments: :class:`~motion_envs.envs._reach_vector.ReachVectorEnv`,
    contract: :mod:`motion_envs.envs.vector`)."""

    single_class = PositionReachEnv
