"""``MotionEnvs/OrientationReach-v0``/``-v1``: act on top of an analytic orientation trajectory."""

# ruff: noqa: E501  (the class docstring holds Gymnasium-style Markdown tables)

from __future__ import annotations

import math
import os
from collections.abc import Mapping
from typing import Any

import gymnasium as gym
import numpy as np
from numpy.typing import NDArray

from motion_envs.envs import _kernels as K
from motion_envs.envs._calibration import orientation_calibration_features
from motion_envs.envs._common import (
    N_STEPS,
    timing_bounds,
)
from motion_envs.envs._kernels import orientation_reward, orientation_step_scalar
from motion_envs.envs._orientation_task import (
    LAYOUT,
    MAX_DEGREE,
    ROW,
    OrientationTask,
    load_orientation_task,
    orientation_split_parts,
)
from motion_envs.envs._reach import (
    ReachEnv,
    ReachKind,
    checked_prediction,
    zero_action_errors,
)
from motion_envs.envs._reach_vector import ReachVectorEnv

__all__ = [
    "DEFAULT_REWARD_WEIGHTS",
    "LAYOUT",
    "MAX_DEGREE",
    "N_STEPS",
    "ORIENTATION",
    "ROW",
    "OrientationKind",
    "OrientationReachEnv",
    "OrientationReachVectorEnv",
    "OrientationTask",
    "load_orientation_task",
    "orientation_max_errors",
    "orientation_split_parts",
]

#: Largest ``residual_scale`` in radians (a half turn).
MAX_RESIDUAL_SCALE = math.pi

#: Default reward weights (see the class docstring, section Rewards).
DEFAULT_REWARD_WEIGHTS: Mapping[str, float] = {"residual": 1.0, "geodesic": 0.0, "action": 0.0}


def _observation_space(task: OrientationTask, observe_timing: bool) -> gym.spaces.Box:
    low = np.full(task.obs_dim, -1.0, dtype=np.float32)
    high = np.ones(task.obs_dim, dtype=np.float32)
    low[LAYOUT.tau] = 0.0
    low[LAYOUT.task] = 0.0
    if observe_timing:
        low[-2:], high[-2:] = timing_bounds(task.max_duration)
    return gym.spaces.Box(low, high, dtype=np.float32)


def orientation_max_errors(
    task: Any, predicted_residuals: NDArray[np.float64], index: Any = None
) -> NDArray[np.float64]:
    """``(L,)`` ``max_k |logmap(expmap(rhat_lk)) - r_lk|`` of an orientation task's episodes.

    ``predicted_residuals`` ``(L, n, 3)`` is a residual curve ``rhat`` per episode of
    ``task`` (:class:`~motion_envs.envs.orientation_reach.OrientationTask`); the
    trajectory ``e_k expmap(rhat_k)`` is scored by the environment's step kernel with a
    zero action (the human residual ``r`` and orientation ``h`` from ``task.steps``).
    With ``index`` (integer array), only those episodes: ``predicted_residuals`` is then
    ``(len(index), n, 3)``.
    """
    from motion_envs.geometry import quaternion as quat

    steps = task.steps if index is None else task.steps[index]
    base = task.grids.base if index is None else task.grids.base[index]
    rhat = checked_prediction(predicted_residuals, steps, 3, "predicted_residuals")
    chart = quat.expmap(rhat)
    predicted = np.array(steps)
    predicted[..., ROW["chart"]] = chart
    predicted[..., ROW["nominal"]] = quat.multiply(base, chart)
    return zero_action_errors(ORIENTATION, task, predicted)


class OrientationKind(ReachKind):
    """The orientation kind: a unit quaternion state set by a rotation-vector action."""

    name = "orientation"
    instance_name = "ORIENTATION"
    step_keys = ("error", "geodesic_error", "reward_residual", "reward_geodesic", "reward_action")
    end_keys = (("max_error", "error"), ("max_geodesic_error", "geodesic_error"))
    weight_keys = ("residual", "geodesic", "action")
    default_weights = DEFAULT_REWARD_WEIGHTS
    max_residual_scale = MAX_RESIDUAL_SCALE
    load_task = staticmethod(load_orientation_task)
    max_errors = staticmethod(orientation_max_errors)

    def state_dim(self, task: Any) -> int:
        return 4

    def action_dim(self, task: Any) -> int:
        return 3

    def row_layout(self, dim: int) -> dict[str, slice]:
        return ROW

    def scalar_step(
        self, row: list[float], a: list[float], scale: float, w: tuple[float, ...]
    ) -> tuple[tuple[float, ...], float, dict[str, float]]:
        ax, ay, az = a
        q, err, geo = orientation_step_scalar(row, ax, ay, az, scale)
        r_res, r_geo, r_act, reward = orientation_reward(err, geo, ax, ay, az, w[0], w[1], w[2])
        info = {
            "error": err,
            "geodesic_error": geo,
            "reward_residual": r_res,
            "reward_geodesic": r_geo,
            "reward_action": r_act,
        }
        return q, reward, info

    def batch_step(
        self, rows: NDArray[np.float64], a: NDArray[np.float64], scale: float, w: tuple[float, ...]
    ) -> tuple[NDArray[np.float64], Any, list[Any]]:
        ax, ay, az = a[:, 0], a[:, 1], a[:, 2]
        e, n, h, r = (rows[ROW[name]] for name in ("chart", "nominal", "human", "residual"))
        q, err, geo = K.orientation_step(
            K.BATCH,
            (e[0], e[1], e[2], e[3]),
            (n[0], n[1], n[2], n[3]),
            (h[0], h[1], h[2], h[3]),
            r[0],
            r[1],
            r[2],
            ax,
            ay,
            az,
            scale,
        )
        r_res, r_geo, r_act, reward = orientation_reward(err, geo, ax, ay, az, *w)
        return np.stack(q, axis=1), reward, [err, geo, r_res, r_geo, r_act]

    @staticmethod
    def fused_physics(
        row: Any, a: Any, scale: float, w: Any, q: Any
    ) -> tuple[float, tuple[float, ...]]:
        qo, err, geo = orientation_step_scalar(row, a[0], a[1], a[2], scale)
        r_res, r_geo, r_act, reward = orientation_reward(
            err, geo, a[0], a[1], a[2], w[0], w[1], w[2]
        )
        q[0] = qo[0]
        q[1] = qo[1]
        q[2] = qo[2]
        q[3] = qo[3]
        return reward, (err, geo, r_res, r_geo, r_act)


#: The orientation kind (one instance serves every orientation environment).
ORIENTATION = OrientationKind()


class OrientationReachEnv(ReachEnv):
    r"""Replay a human hand-orientation trajectory; the agent corrects an analytic nominal.

    ## Description
    Faraway & Choe (2008) model a reach's hand orientation as a slerp from the start to
    the end orientation along an average speed profile, bent by a Bézier residual
    curve. Each episode replays the *task* of one recorded human trajectory (its start
    and goal orientation and its task label) on the 50-point normalised-time grid. At
    every step the agent adds a small rotation to the nominal model's orientation and is
    scored against what the human actually did, with the paper's criterion. The nominal
    is fitted on the *training* subjects only (:mod:`motion_envs.models.orientation_nominal`), so
    on ``split="test"`` both the nominal and the agent face people they have not seen.

    The zero action reproduces the nominal model exactly: over the test split, the
    median of ``info["max_error"]`` at the end of the episodes equals the offline
    criterion that ``motion-bench orientation --split test --nominal ...`` reports
    (tested to 1e-9).

    ## Action Space
    The action space is a `Box(-1, 1, (3,), float32)`: a rotation vector (tangent space
    at the identity) scaled by `residual_scale`, composed on the right of the nominal
    orientation: ``q_k = n_k * expmap(residual_scale * a_k)`` (scalar-first quaternions
    ``(w, x, y, z)``). Actions outside ``[-1, 1]`` are clipped; a wrong shape or a NaN or
    infinite entry raises `ValueError` and leaves the environment unchanged.

    | Num | Action                                         | Control Min | Control Max | Type (Unit)              |
    |-----|------------------------------------------------|-------------|-------------|--------------------------|
    | 0   | x component of the residual rotation vector    | -1          | 1           | rotation (residual_scale rad) |
    | 1   | y component of the residual rotation vector    | -1          | 1           | rotation (residual_scale rad) |
    | 2   | z component of the residual rotation vector    | -1          | 1           | rotation (residual_scale rad) |

    ## Observation Space
    The observation space is a `Box(low, high, (17 + T,), float32)`, ``T`` the number of
    tasks in the dataset (20 for ``"vr-kitchen"``, 10 targets in 2 response modes: 37
    values; 27 for ``"vr-kitchen:laser"``). Quaternions are scalar
    first and sign-continuous with the start.

    | Num     | Observation                                                   | Min | Max | Type (Unit)      |
    |---------|---------------------------------------------------------------|-----|-----|------------------|
    | 0-3     | start orientation ``q_0`` (w, x, y, z)                        | -1  | 1   | unit quaternion  |
    | 4-7     | goal orientation ``q_n`` (w, x, y, z)                         | -1  | 1   | unit quaternion  |
    | 8-11    | current orientation (the last one the agent set; ``q_0`` at reset) | -1  | 1   | unit quaternion  |
    | 12      | ``tau`` of the grid point the next action sets (1 after the last) | 0   | 1   | normalised time  |
    | 13-16   | the nominal's orientation at that grid point ``n_k``          | -1  | 1   | unit quaternion  |
    | 17-...  | one-hot task over the dataset's sorted task names             | 0   | 1   | unitless         |
    | -2 (v1) | the movement's duration ``T`` (a pre-movement condition)      | 0   | ``T_max`` | time (s)   |
    | -1 (v1) | elapsed time ``tau T`` at that grid point                      | 0   | ``T_max`` | time (s)   |

    ``-v1`` (``observe_timing=True``) appends the last two entries (39 values for
    ``"vr-kitchen"``); ``T_max`` is the longest movement of the whole dataset (padded by
    0.1 %), so the bounds do not depend on the split. Everything else is as in ``-v0``.

    The subject is not observed: a split by subject holds whole people out, so a
    subject encoding would be meaningless on the test split. With ``calibration=K > 0``
    the person is described instead by ``K`` of their other reaches: every observation
    of the episode ends with 10 more entries (49 for ``-v1`` on ``"vr-kitchen"``),
    the same for all its steps:

    | Num      | Observation (``calibration=K > 0``)                              | Min | Max | Type (Unit) |
    |----------|------------------------------------------------------------------|-----|-----|-------------|
    | -10..-2  | mean over the calibration reaches of their own human residual's first 3 sine coefficients per path axis (path frame, ordered (k, axis); clipped) | -3  | 3   | rad per rad of rotation |
    | -1       | share drawn ``m / K`` (0: the person has no other reach, summary 0) | 0   | 1   | unitless    |

    The ``K`` reaches are drawn at `reset` with the environment's generator (after the
    trajectory) among the person's trajectories *of the same split*, without
    replacement, never the episode's own (all of them if the person has fewer);
    `info["calibration_trajectories"]` lists them (sorted, padded with -1 to ``K``).
    The summary is :func:`motion_envs.models.person_calibration.calibration_summaries`,
    the one ``OrientationCoefficients-v0`` observes and ``motion-bench orientation``'s
    ``ridge_person_k{K}_loso`` rows are given.

    ## Rewards
    With ``e_k`` the base slerp ``slerp(q_0, q_n, alpha_bar(tau_k))`` (training split's
    average speed profile), ``r_k = logmap(conj(e_k) h_k)`` the human's residual and
    ``h_k`` the human orientation, the agent's orientation ``q_k`` has

    - *residual error* ``|logmap(conj(e_k) q_k) - r_k|``: the paper's tangent-space
      distance between the agent's and the human's residual (radians);
    - *geodesic error* ``2 atan2(|v|, |w|)`` of ``conj(q_k) h_k``: the plain rotation
      angle between the agent and the human (radians).

    The reward is ``-(w_residual * residual error + w_geodesic * geodesic error +
    w_action * |a|^2)`` with the weights of `reward_weights` (default ``residual: 1,
    geodesic: 0, action: 0``). `info` holds ``error``, ``geodesic_error``,
    ``reward_residual``, ``reward_geodesic``, ``reward_action`` and ``tau`` every step and,
    at the end of an episode, ``max_error`` (the trajectory's ``max_k`` residual error:
    its contribution to the paper's median criterion) and ``max_geodesic_error``.

    ## Starting State
    `reset` draws one trajectory of the split uniformly with the environment's
    generator (``options={"trajectory": i}`` picks trajectory ``i``); the current
    orientation is its start ``q_0``. `info` names the trajectory (``trajectory_index``,
    ``trajectory_id``, ``task``, ``subject``).

    ## Episode End
    ### Termination
    The episode terminates after 50 steps, when every point of the grid is set.

    ### Truncation
    The default duration of an episode is 50 steps (``max_episode_steps`` of the
    registration), equal to the trajectory, so the last step is both terminated and
    truncated; a shorter ``max_episode_steps`` truncates earlier.

    ## Arguments
    ```python
    import gymnasium as gym
    import motion_envs
    env = gym.make("MotionEnvs/OrientationReach-v0", split="test", nominal="bezier-task")
    ```

    | Parameter        | Type         | Default        | Description |
    |------------------|--------------|----------------|-------------|
    | `data`           | **str**      | `"vr-kitchen"` | built-in dataset name or a path to the users' orientation CSV |
    | `split`          | **str**      | `"train"`      | `"train"`, `"val"` or `"test"`: the subjects of a split by subject (the trials with `split_by="replicate"`) |
    | `nominal`        | **str**      | `"slerp"`      | `"slerp"`, `"bezier-null"`, `"bezier-task"` or `"bezier-subject"` (unseen subjects fall back to the null model) |
    | `degree`         | **int**      | `2`            | Bézier degree of the `"bezier-*"` nominals, 1 to 12 |
    | `residual_scale` | **float**    | `0.25`         | rotation angle in radians of an action of norm 1, in (0, pi] |
    | `reward_weights` | **dict**     | `None`         | weights of the reward terms, keys `residual`, `geodesic`, `action` (None: 1, 0, 0) |
    | `test_fraction`  | **float**    | `0.25`         | share of subjects held out for the test split, in (0, 1) |
    | `split_seed`     | **int**      | `0`            | seed of the subject permutation (`split_by_subject`), >= 0 |
    | `min_deg`        | **float**    | `10.0`         | drop trajectories rotating less than this (degrees), in [0, 180] |
    | `render_mode`    | **str**      | `None`         | `None` or `"rgb_array"` |
    | `width`          | **int**      | `480`          | frame width in pixels |
    | `height`         | **int**      | `480`          | frame height in pixels |
    | `val_fraction`   | **float**    | `0.0`          | share of the *training* subjects held out as `split="val"`; with it `"train"` holds the others and its nominal is fitted on them only (`"test"` is unchanged) |
    | `observe_timing` | **bool**     | `False`        | append the duration and the elapsed time to the observation (`True` in `-v1`) |
    | `fold`           | **int**      | `None`         | leave one person out: the `fold`-th person (sorted labels) is `"test"`, the others `"train"` (and `"val"` with `val_fraction`); replaces `test_fraction` |
    | `calibration`    | **int**      | `0`            | ``K``, 0 to 1000: observe the summary of ``K`` other reaches of the episode's person (0: the observation is unchanged); the native vector environment then runs the numpy backend |
    | `val_folds`      | **int**      | `0`            | `K >= 2`: the training people cut into `K` groups (permuted with `split_seed`); group `val_fold` is `"val"`, the others `"train"` with the nominal fitted on them (inner folds over people; needs `val_fraction=0`) |
    | `val_fold`       | **int**      | `0`            | the validation group of `val_folds`, 0 to `K - 1` |
    | `split_by`       | **str**      | `"subject"`    | what the splits hold out: `"subject"` (people) or `"replicate"` (trials: each task's trajectories permuted with `split_seed`, `test_fraction` of them held out and at least 2 kept; for a one-person recording; not with `fold` or `val_folds`) |

    A bad argument raises `ValueError` naming it (the same in the vector environment);
    reward weights must lie in [0, 1e6]. `step` raises `ValueError` for an action that
    is not an array of real numbers (a dict, a string, complex numbers).

    ## Version History
    * v1: the observation also holds the movement's duration and the elapsed time
      (``observe_timing=True``); the zero-action invariant and everything else as in v0.
    * v0: Initial version.
    """

    kind = ORIENTATION

    def __init__(
        self,
        data: str | os.PathLike[str] = "vr-kitchen",
        split: str = "train",
        nominal: str = "slerp",
        degree: int = 2,
        residual_scale: float = 0.25,
        reward_weights: Mapping[str, float] | None = None,
        test_fraction: float = 0.25,
        split_seed: int = 0,
        min_deg: float = 10.0,
        render_mode: str | None = None,
        width: int = 480,
        height: int = 480,
        val_fraction: float = 0.0,
        observe_timing: bool = False,
        fold: int | None = None,
        calibration: int = 0,
        val_folds: int = 0,
        val_fold: int = 0,
        split_by: str = "subject",
    ) -> None:
        self._check_arguments(
            render_mode, width, height, residual_scale, reward_weights, test_fraction, split_seed
        )
        self.task = load_orientation_task(
            data, split, nominal, degree, test_fraction, split_seed, min_deg,
            val_fraction, observe_timing, fold, val_folds, val_fold, split_by,
        )  # fmt: skip
        self.observation_space = _observation_space(self.task, bool(observe_timing))
        self._setup(self.task.grids.starts)
        self._setup_calibration(
            calibration, self.task.subjects, lambda: orientation_calibration_features(self.task)
        )

    # -- rendering ------------------------------------------------------------------
    def _render_frame(self) -> NDArray[np.uint8]:
        if self._renderer is None:
            from motion_envs.envs.rendering import HandFrameRenderer

            self._renderer = HandFrameRenderer(self.width, self.height)
        g = self.task.grids
        k = len(self._history) - 1
        frame: NDArray[np.uint8] = self._renderer.render(
            human=g.human[self._index],
            nominal=g.nominal[self._index],
            agent=np.asarray(self._history),
            step=k,
        )
        return frame


class OrientationReachVectorEnv(ReachVectorEnv):
    """``num_envs`` copies of :class:`OrientationReachEnv`, bit-identical to
    ``SyncVectorEnv`` (arguments: :class:`~motion_envs.envs._reach_vector.ReachVectorEnv`,
    contract: :mod:`motion_envs.envs.vector`)."""

    single_class = OrientationReachEnv
