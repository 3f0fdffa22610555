"""``MotionEnvs/OrientationCoefficients-v0``: a whole hand-orientation reach in one step.

The environment and its vector form; the shared core (scoring, calibration, episode
mechanics) is :mod:`motion_envs.envs._coefficients`.
"""


# ruff: noqa: E501  (the class docstrings hold Gymnasium-style Markdown tables)

from __future__ import annotations

import os

import gymnasium as gym
import numpy as np
from numpy.typing import NDArray

from motion_envs.envs._calibration import orientation_calibration_features
from motion_envs.envs._coefficients import (
    CoefficientEnv,
    CoefficientVectorEnv,
    FloatArray,
)
from motion_envs.envs._common import (
    N_STEPS,
    timing_bounds,
)
from motion_envs.envs.orientation_reach import (
    LAYOUT,
    load_orientation_task,
    orientation_max_errors,
)

__all__ = ["OrientationCoefficientsEnv", "OrientationCoefficientsVectorEnv"]


class OrientationCoefficientsEnv(CoefficientEnv):
    r"""Predict a whole hand-orientation reach in one step: residual coefficients on the nominal.

    ## Description
    The episodic (black-box) form of ``MotionEnvs/OrientationReach-v1``, as in fancy_gym's
    black-box environments: one step per movement. The agent sees the pre-movement
    context of one recorded reach (start and goal orientation, duration, task) and
    answers with the sine coefficients of a residual curve in the movement's path frame
    (:mod:`motion_envs.models.path_frame`), added to the nominal's residual; the whole
    movement is scored with Faraway & Choe's criterion. Splits (by subject), the
    nominal (fitted on the training subjects only) and the error are those of the step
    environment: the zero action scores exactly the ``info["max_error"]`` of a
    zero-action ``OrientationReach-v1`` episode of the same trajectory (tested to 1e-12).

    ## Action Space
    `Box(-1, 1, (3 K,), float32)`, ``K = n_sines`` (24 values by default): the
    coefficients ``c = residual_scale * a`` of ``p(tau) = sum_k c_k sin(k pi tau)``,
    ordered ``(k, axis)`` (``a[3 (k - 1) + j]``, axes ``j``: rotation axis, up, side of
    the path frame). The predicted residual is ``rhat + s F p`` (``F`` the path frame,
    ``s`` the rotation angle, radians); ``p`` vanishes at both ends. Actions outside
    ``[-1, 1]`` are clipped; a wrong shape or a NaN or infinite entry raises
    `ValueError`.

    | Num       | Action                                               | Control Min | Control Max | Type (Unit) |
    |-----------|------------------------------------------------------|-------------|-------------|-------------|
    | 3(k-1)+j  | coefficient of ``sin(k pi tau)`` on path axis ``j``  | -1          | 1           | residual_scale (rad per rad of rotation) |

    ## Observation Space
    `Box(low, high, (9 + T,), float32)`, ``T`` the number of tasks (20 for
    ``"vr-kitchen"``, 10 targets in 2 response modes: 29 values; 39 with
    ``calibration > 0``; 19 and 29 for ``"vr-kitchen:laser"``):

    | Num    | Observation                                           | Min | Max       | Type (Unit)     |
    |--------|-------------------------------------------------------|-----|-----------|-----------------|
    | 0-3    | start orientation ``q_0`` (w, x, y, z)                | -1  | 1         | unit quaternion |
    | 4-7    | goal orientation ``q_n`` (w, x, y, z)                 | -1  | 1         | unit quaternion |
    | 8      | the movement's duration ``T``                         | 0   | ``T_max`` | time (s)        |
    | 9-...  | one-hot task over the dataset's sorted task names     | 0   | 1         | unitless        |

    The subject is not observed (a split by subject holds whole people out). With
    ``calibration=K > 0`` the observation gains 10 entries: the mean over ``K`` other
    reaches of the episode's person (drawn at `reset` with the environment's generator
    among the person's trajectories *of the same split*, without replacement, never the
    episode's own; all of them if the person has fewer) of their own human residual's
    first 3 sine coefficients per path axis (path frame, as the action; clipped to
    ``[-3, 3]``), then the share drawn ``m / K`` in ``[0, 1]`` (0: no other reach,
    summary 0). `info["calibration_trajectories"]` lists the drawn trajectories
    (sorted, padded with -1 to ``K`` entries). The summary is
    :func:`motion_envs.models.person_calibration.calibration_summaries`, the one the
    ``ridge_person_k{K}_loso`` rows of ``motion-bench orientation`` are given.

    ## Rewards
    ``-max_k |logmap(conj(e_k) q_k) - r_k|``: minus the paper's per-trajectory error of
    the predicted orientation curve ``q_k = e_k expmap(rhat_k + s F p(tau_k))`` against
    the human's residual ``r_k`` (``e_k`` the base slerp with the training subjects'
    average speed profile; radians). `info` holds ``max_error`` (the same, positive)
    and ``nominal_max_error`` (the zero action's).

    ## Starting State
    `reset` draws one trajectory of the split uniformly with the environment's
    generator (``options={"trajectory": i}`` picks trajectory ``i``). `info` names it
    (``trajectory_index``, ``trajectory_id``, ``task``, ``subject``).

    ## Episode End
    ### Termination
    Every episode terminates after its single step.

    ### Truncation
    The registration's ``max_episode_steps`` is 1, so that step is also truncated.

    ## Arguments
    ```python
    import gymnasium as gym
    import motion_envs
    env = gym.make("MotionEnvs/OrientationCoefficients-v0", split="test", nominal="bezier-null")
    ```

    | Parameter        | Type      | Default        | Description |
    |------------------|-----------|----------------|-------------|
    | `data`           | **str**   | `"vr-kitchen"` | built-in dataset name or a path to the users' orientation CSV |
    | `split`          | **str**   | `"train"`      | `"train"`, `"val"` or `"test"` (as `OrientationReach`) |
    | `nominal`        | **str**   | `"slerp"`      | the nominal model (as `OrientationReach`) |
    | `degree`         | **int**   | `2`            | Bézier degree of the `"bezier-*"` nominals |
    | `n_sines`        | **int**   | `8`            | sine terms ``K`` per path axis, 1 to 48 |
    | `residual_scale` | **float** | `0.5`          | coefficient of an action entry of 1, > 0 |
    | `test_fraction`  | **float** | `0.25`         | share of subjects held out for the test split |
    | `split_seed`     | **int**   | `0`            | seed of the subject permutation |
    | `min_deg`        | **float** | `10.0`         | drop trajectories rotating less than this (degrees) |
    | `val_fraction`   | **float** | `0.0`          | share of the training subjects held out as `split="val"` |
    | `fold`           | **int**   | `None`         | leave one person out: the `fold`-th person (sorted labels) is `"test"` (as `OrientationReach`) |
    | `val_folds`      | **int**   | `0`            | `K >= 2`: group `val_fold` of `K` groups of the training people is `"val"` (inner folds over people; as `OrientationReach`) |
    | `val_fold`       | **int**   | `0`            | the validation group of `val_folds`, 0 to `K - 1` |
    | `calibration`    | **int**   | `0`            | ``K``: observe the summary of ``K`` other reaches of the person (0: none) |
    | `render_mode`    | **str**   | `None`         | `None` or `"rgb_array"` |
    | `width`          | **int**   | `480`          | frame width in pixels |
    | `height`         | **int**   | `480`          | frame height in pixels |

    A bad argument raises `ValueError` naming it (the same in the vector environment).

    ## Version History
    * v0: Initial version.
    """

    _width = 3

    def __init__(
        self,
        data: str | os.PathLike[str] = "vr-kitchen",
        split: str = "train",
        nominal: str = "slerp",
        degree: int = 2,
        n_sines: int = 8,
        residual_scale: float = 0.5,
        test_fraction: float = 0.25,
        split_seed: int = 0,
        min_deg: float = 10.0,
        val_fraction: float = 0.0,
        fold: int | None = None,
        val_folds: int = 0,
        val_fold: int = 0,
        calibration: int = 0,
        render_mode: str | None = None,
        width: int = 480,
        height: int = 480,
    ) -> None:
        from motion_envs.models.path_frame import path_frames

        self._check_common(
            n_sines, residual_scale, render_mode, width, height, test_fraction, split_seed
        )
        self.task = load_orientation_task(
            data, split, nominal, degree, test_fraction, split_seed, min_deg, val_fraction, True,
            fold, val_folds, val_fold,
        )  # fmt: skip
        obs0 = self.task.obs[:, 0]
        task_part = slice(LAYOUT.task.start, obs0.shape[1] - 2)  # before the v1 timing
        self._context = np.ascontiguousarray(
            np.concatenate(
                [obs0[:, LAYOUT.start], obs0[:, LAYOUT.goal], obs0[:, -2:-1], obs0[:, task_part]],
                axis=1,
            )
        )
        n_tasks = task_part.stop - task_part.start
        low = np.concatenate([-np.ones(8), [0.0], np.zeros(n_tasks)]).astype(np.float32)
        high = np.ones(9 + n_tasks, dtype=np.float32)
        high[8] = timing_bounds(self.task.max_duration)[1]
        self.observation_space = gym.spaces.Box(low, high, dtype=np.float32)
        g = self.task.grids
        self._frames, self._scales = path_frames(g.starts, g.goals, self.task.up)
        self._base = np.asarray(g.predicted_residuals)
        self._setup_calibration(
            calibration, self.task.subjects, orientation_calibration_features(self.task)
        )
        self._finish_setup()

    def _human_curves(self) -> FloatArray:
        return np.asarray(self.task.grids.residuals)

    def _errors(self, index: NDArray[np.int64], curves: FloatArray) -> FloatArray:
        return orientation_max_errors(self.task, curves, index=index)

    def _render_frame(self) -> NDArray[np.uint8]:
        from motion_envs.envs.rendering import HandFrameRenderer
        from motion_envs.geometry import quaternion as quat

        if self._renderer is None:
            self._renderer = HandFrameRenderer(self.width, self.height)
        g, i = self.task.grids, self._index
        if self._predicted is None:
            agent, step = g.starts[i : i + 1], 0
        else:
            agent, step = quat.multiply(g.base[i], quat.expmap(self._predicted)), N_STEPS - 1
        frame: NDArray[np.uint8] = self._renderer.render(
            human=g.human[i], nominal=g.nominal[i], agent=np.asarray(agent), step=step
        )
        return frame


class OrientationCoefficientsVectorEnv(CoefficientVectorEnv):
    """``num_envs`` copies of :class:`OrientationCoefficientsEnv` (see
    :class:`CoefficientVectorEnv`)."""

    single_class = OrientationCoefficientsEnv
