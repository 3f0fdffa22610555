"""``MotionEnvs/PositionCoefficients-v0``: a whole position trajectory in one step.

The environment and its vector form; the shared core (scoring, line frames, episode
mechanics) is :mod:`motion_envs.envs._coefficients`.
"""


# ruff: noqa: E501  (the class docstrings hold Gymnasium-style Markdown tables)

from __future__ import annotations

import os
from collections.abc import Sequence

import gymnasium as gym
import numpy as np
from numpy.typing import NDArray

from motion_envs.envs._coefficients import (
    CoefficientEnv,
    CoefficientVectorEnv,
    FloatArray,
    line_frames,
)
from motion_envs.envs.position_reach import load_position_task, position_max_errors

__all__ = ["PositionCoefficientsEnv", "PositionCoefficientsVectorEnv"]


class PositionCoefficientsEnv(CoefficientEnv):
    r"""Predict a whole position trajectory in one step: residual coefficients on the nominal.

    ## Description
    The episodic (black-box) form of ``MotionEnvs/PositionReach-v1``, as in fancy_gym's
    black-box environments: one step per demonstration. The agent sees its pre-movement
    context (start and goal position, duration, task) and answers with the sine
    coefficients of a residual curve in the movement's line frame (first axis from
    start to goal), added to the nominal; the demonstration is scored with the maximum
    over time of the distance to the human's. Splits, the nominal (fitted per task on
    its training demonstrations) and the error are those of the step environment: the
    zero action scores exactly the ``info["max_error"]`` of a zero-action
    ``PositionReach-v1`` episode (tested to 1e-12).

    ## Action Space
    `Box(-1, 1, (D K,), float32)`, ``K = n_sines``, ``D`` the data's dimension (16
    values for LASA by default): the coefficients ``c = residual_scale * a`` of ``p(tau)
    = sum_k c_k sin(k pi tau)``, ordered ``(k, axis)``; the predicted positions are
    ``yhat + s F p`` (``F`` the line frame, ``s`` the start-to-goal distance). Actions
    outside ``[-1, 1]`` are clipped; a wrong shape or a NaN or infinite entry raises
    `ValueError`.

    | Num       | Action                                               | Control Min | Control Max | Type (Unit) |
    |-----------|------------------------------------------------------|-------------|-------------|-------------|
    | D(k-1)+j  | coefficient of ``sin(k pi tau)`` on line axis ``j``  | -1          | 1           | residual_scale (start-to-goal distances) |

    ## Observation Space
    `Box(low, high, (2 D + 1 + T,), float32)`, ``T`` the number of tasks (LASA's 30
    shapes: 35 values):

    | Num          | Observation                                       | Min          | Max          | Type (Unit)   |
    |--------------|---------------------------------------------------|--------------|--------------|---------------|
    | 0..D-1       | start position                                    | data extent  | data extent  | data's unit   |
    | D..2D-1      | goal position                                     | data extent  | data extent  | data's unit   |
    | 2D           | the demonstration's duration ``T``                | 0            | ``T_max``    | time (s)      |
    | 2D+1-...     | one-hot task over the dataset's sorted task names | 0            | 1            | unitless      |

    ## Rewards
    ``-max_k |yhat_k + s F p(tau_k) - y_k|``: minus the per-demonstration criterion of
    ``motion-bench position`` (the data's unit). `info` holds ``max_error`` (the same,
    positive) and ``nominal_max_error`` (the zero action's).

    ## Starting State
    `reset` draws one demonstration of the split uniformly with the environment's
    generator (``options={"trajectory": i}`` picks demonstration ``i``). `info` names it
    (``trajectory_index``, ``trajectory_id``, ``task``).

    ## Episode End
    ### Termination
    Every episode terminates after its single step.

    ### Truncation
    The registration's ``max_episode_steps`` is 1, so that step is also truncated.

    ## Arguments
    ```python
    import gymnasium as gym
    import motion_envs
    env = gym.make("MotionEnvs/PositionCoefficients-v0", shapes=["Angle", "CShape"], split="test")
    ```

    | Parameter        | Type      | Default   | Description |
    |------------------|-----------|-----------|-------------|
    | `data`           | **str**   | `"lasa"`  | `"lasa"` or a path to the users' position CSV |
    | `shapes`         | **list**  | `None`    | LASA shapes (tasks) to use (None: all) |
    | `split`          | **str**   | `"train"` | `"train"`, `"val"` or `"test"` (as `PositionReach`) |
    | `nominal`        | **str**   | `"sine"`  | the nominal model (as `PositionReach`) |
    | `nominal_sines`  | **int**   | `"auto"`  | `n_sines` of the sine nominal (as `PositionReach`'s `n_sines`) |
    | `n_sines`        | **int**   | `8`       | sine terms ``K`` of the residual per axis, 1 to 48 |
    | `residual_scale` | **float** | `0.5`     | coefficient of an action entry of 1, > 0 |
    | `test_fraction`  | **float** | `0.25`    | share of each task's demonstrations held out for the test split |
    | `split_seed`     | **int**   | `0`       | seed of the split |
    | `val_fraction`   | **float** | `0.0`     | share of the training demonstrations held out as `split="val"` |
    | `render_mode`    | **str**   | `None`    | `None` or `"rgb_array"` |
    | `width`          | **int**   | `480`     | frame width in pixels |
    | `height`         | **int**   | `480`     | frame height in pixels |

    A bad argument raises `ValueError` naming it (the same in the vector environment).

    ## Version History
    * v0: Initial version.
    """

    def __init__(
        self,
        data: str | os.PathLike[str] = "lasa",
        shapes: Sequence[str] | None = None,
        split: str = "train",
        nominal: str = "sine",
        nominal_sines: int | str = "auto",
        n_sines: int = 8,
        residual_scale: float = 0.5,
        test_fraction: float = 0.25,
        split_seed: int = 0,
        val_fraction: float = 0.0,
        render_mode: str | None = None,
        width: int = 480,
        height: int = 480,
    ) -> None:
        self._check_common(
            n_sines, residual_scale, render_mode, width, height, test_fraction, split_seed
        )
        self.task = task = load_position_task(
            data, shapes, split, nominal, nominal_sines, test_fraction, split_seed,
            5.0, val_fraction, True,
        )  # fmt: skip
        D = self._width = int(task.n_dims)
        obs0 = task.obs[:, 0]
        cols = np.r_[0 : 2 * D, obs0.shape[1] - 2, 4 * D + 1 : obs0.shape[1] - 2]
        self._context = np.ascontiguousarray(obs0[:, cols])
        self.observation_space = gym.spaces.Box(
            task.obs_low[cols], task.obs_high[cols], dtype=np.float32
        )
        g = task.grids
        self._frames, self._scales = line_frames(g.human[:, 0], g.human[:, -1])
        self._base = np.asarray(g.nominal)
        self._finish_setup()

    def _human_curves(self) -> FloatArray:
        return np.asarray(self.task.grids.human)

    def _errors(self, index: NDArray[np.int64], curves: FloatArray) -> FloatArray:
        return position_max_errors(self.task, curves, index=index)

    def _render_frame(self) -> NDArray[np.uint8]:
        from motion_envs.envs.rendering import CurveRenderer

        if self._renderer is None:
            self._renderer = CurveRenderer(self.width, self.height, self.task.low, self.task.high)
        g, i = self.task.grids, self._index
        agent = g.human[i, :1] if self._predicted is None else self._predicted
        frame: NDArray[np.uint8] = self._renderer.render(
            human=g.human[i],
            nominal=g.nominal[i],
            agent=np.asarray(agent),
            title=f"{self.task.tasks[i]}  {'predicted' if self._predicted is not None else 'context'}",
        )
        return frame


class PositionCoefficientsVectorEnv(CoefficientVectorEnv):
    """``num_envs`` copies of :class:`PositionCoefficientsEnv` (see
    :class:`CoefficientVectorEnv`)."""

    single_class = PositionCoefficientsEnv
