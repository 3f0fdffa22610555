"""``MotionEnvs/PositionReach-v0``/``-v1``: act on top of an analytic position trajectory."""

# ruff: noqa: E501  (the class docstring holds Gymnasium-style Markdown tables)

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from typing import Any

import gymnasium as gym
import numpy as np
from numpy.typing import NDArray

from motion_envs.envs import _kernels as K
from motion_envs.envs._calibration import check_calibration
from motion_envs.envs._common import N_STEPS
from motion_envs.envs._kernels import position_reward, position_step_scalar
from motion_envs.envs._position_task import (
    MAX_N_SINES,
    PositionTask,
    load_position_task,
    position_split_source,
    row_layout,
)
from motion_envs.envs._reach import (
    ReachEnv,
    ReachKind,
    checked_prediction,
    zero_action_errors,
)
from motion_envs.envs._reach_vector import ReachVectorEnv

__all__ = [
    "DEFAULT_POSITION_REWARD_WEIGHTS",
    "MAX_N_SINES",
    "POSITION",
    "PositionKind",
    "PositionReachEnv",
    "PositionReachVectorEnv",
    "PositionTask",
    "load_position_task",
    "position_max_errors",
    "position_split_source",
    "row_layout",
]

#: Largest ``residual_scale`` (the data's unit): the CSV loader's largest position, so
#: the observation bounds stay finite in float32.
MAX_POSITION_RESIDUAL_SCALE = 1e9

#: Default reward weights (see the class docstring, section Rewards).
DEFAULT_POSITION_REWARD_WEIGHTS: Mapping[str, float] = {"distance": 1.0, "action": 0.0}


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
    (:mod:`motion_envs.models.position_nominal`).

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
    | `calibration`    | **int**      | `0`       | only 0: person calibration (as `OrientationReach`'s) needs a dataset with persons, and the position data holds demonstrations of shapes; any other value raises `ValueError` |

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
        calibration: int = 0,
    ) -> None:
        self._check_arguments(
            render_mode, width, height, residual_scale, reward_weights, test_fraction, split_seed
        )
        if check_calibration(calibration):
            raise ValueError(
                "calibration needs a dataset with persons; the position data holds "
                "demonstrations of shapes, not people (use calibration=0)"
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
