"""Episodic (black-box) reaching environments: one step per movement.

``MotionEnvs/OrientationCoefficients-v0`` and ``MotionEnvs/PositionCoefficients-v0``
follow fancy_gym's black-box environments: the agent sees the pre-movement context of a
reach (start, goal, duration, task), answers once with the coefficients of a residual
curve added to the nominal, and is scored on the whole movement with the paper's
criterion (the maximum over time of the error). The episodes, splits, nominal and the
error arithmetic are those of the step environments
(:func:`~motion_envs.envs.orientation_reach.load_orientation_task`,
:func:`~motion_envs.envs.orientation_reach.orientation_max_errors`, and their position
counterparts): the zero action scores exactly what a zero-action episode of
``OrientationReach-v1`` / ``PositionReach-v1`` scores (``info["max_error"]``).

The residual curve lives in the movement's start-to-goal frame, as sine series that
vanish at both ends, ``p(tau) = sum_{k=1..K} c_k sin(k pi tau)``:

* orientation: ``p`` is a path-frame residual (:mod:`motion_envs.models.path_frame`:
  axes ``[rotation axis, up, side]``, scaled by the rotation angle); the nominal's
  residual ``rhat`` becomes ``rhat + s F p``;
* position: ``p`` is expressed in the line frame of the movement (first axis from start
  to goal, the others completing an orthonormal basis: a quarter turn in 2-D, a
  Householder reflection otherwise), scaled by the start-to-goal distance; the nominal
  ``yhat`` becomes ``yhat + s F p``.

``c = residual_scale * action``. :class:`CoefficientVectorEnv` steps ``N`` of them with
one batched scoring and the episode mechanics of ``SyncVectorEnv`` (bit-identical).
"""

# ruff: noqa: E501  (the class docstrings hold Gymnasium-style Markdown tables)

from __future__ import annotations

import os
from collections.abc import Sequence
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np
from gymnasium.vector import AutoresetMode
from gymnasium.vector.utils import batch_space
from numpy.typing import NDArray

from motion_envs.envs._common import (
    MAX_FRAME_SIZE,
    N_STEPS,
    JsonSpecMixin,
    LazyRendererMixin,
    as_action,
    check_integer,
    check_max_episode_steps,
    check_num_envs,
    check_scale,
    timing_bounds,
)
from motion_envs.envs._reach import reset_labels
from motion_envs.envs.orientation_reach import (
    LAYOUT,
    load_orientation_task,
    orientation_max_errors,
)
from motion_envs.envs.position_reach import load_position_task, position_max_errors

__all__ = [
    "MAX_COEFFICIENT_SINES",
    "CoefficientEnv",
    "CoefficientVectorEnv",
    "OrientationCoefficientsEnv",
    "OrientationCoefficientsVectorEnv",
    "PositionCoefficientsEnv",
    "PositionCoefficientsVectorEnv",
    "line_frames",
]

#: Largest ``n_sines`` (the interior points of the grid).
MAX_COEFFICIENT_SINES = N_STEPS - 2
#: Largest ``calibration`` (reaches of the person in the summary).
MAX_CALIBRATION = 1000
#: Sine terms per path axis of a calibration summary (9 values).
CALIBRATION_SINES = 3
#: The calibration summary is clipped to ``[-CALIBRATION_BOUND, CALIBRATION_BOUND]``.
CALIBRATION_BOUND = 3.0

FloatArray = NDArray[np.float64]


def line_frames(starts: Any, goals: Any, min_scale: float = 1e-9) -> tuple[FloatArray, FloatArray]:
    """Line frames ``F`` ``(L, D, D)`` (orthonormal columns, the first along ``goal -
    start``) and scales ``s = max(|goal - start|, min_scale)`` ``(L,)``.

    2-D: ``F = [d, rot90(d)]`` (a rotation); other ``D``: the Householder reflection
    mapping ``e_1`` to ``d``; a zero ``goal - start`` takes ``d = e_1``.
    """
    S = np.asarray(starts, dtype=np.float64)
    G = np.asarray(goals, dtype=np.float64)
    delta = G - S
    dist = np.linalg.norm(delta, axis=1)
    L, D = delta.shape
    d = np.zeros_like(delta)
    d[:, 0] = 1.0
    moving = dist > 0
    d[moving] = delta[moving] / dist[moving, None]
    if D == 2:
        F = np.stack([d, np.stack([-d[:, 1], d[:, 0]], axis=1)], axis=2)
    else:
        v = d.copy()
        v[:, 0] -= 1.0
        nv = np.einsum("li,li->l", v, v)
        F = np.broadcast_to(np.eye(D), (L, D, D)).copy()
        reflect = nv > 1e-30
        F[reflect] -= 2.0 * v[reflect, :, None] * v[reflect, None, :] / nv[reflect, None, None]
    return F, np.maximum(dist, min_scale)


class CoefficientEnv(JsonSpecMixin, LazyRendererMixin, gym.Env):
    """One movement per episode: the context in, residual coefficients out.

    A subclass builds ``task`` (the step environments' task), sets ``_context``
    ``(L, obs_dim)`` float32, ``observation_space``, ``_frames``/``_scales`` (the
    start-to-goal frames) and ``_base`` (the nominal curve the residual is added to, in
    the frame's space), and implements :meth:`_errors` and :meth:`_render_frame`.
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 4}  # noqa: RUF012 (gymnasium's)
    task: Any
    _context: NDArray[np.float32]
    _frames: FloatArray
    _scales: FloatArray
    _base: FloatArray
    #: Width of a curve point (3: a rotation vector; D: a position).
    _width: int

    def _check_common(
        self, n_sines: int, residual_scale: float, render_mode: str | None, width: int, height: int
    ) -> None:
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(
                f"render_mode must be None or one of {self.metadata['render_modes']}; "
                f"got {render_mode!r}"
            )
        for name, value in (("width", width), ("height", height)):
            check_integer(value, name, 16, MAX_FRAME_SIZE)
        self.n_sines = check_integer(n_sines, "n_sines", 1, MAX_COEFFICIENT_SINES)
        self.residual_scale = check_scale(residual_scale)
        self.render_mode = render_mode
        self.width, self.height = int(width), int(height)
        self._renderer: Any = None
        self._index = -1
        self._done = True
        self._predicted: FloatArray | None = None

    def _setup_calibration(self, calibration: int, subjects: Any, features: FloatArray) -> None:
        """``calibration = K``: the observation gains the mean of ``features`` ``(L, f)``
        over ``K`` other trajectories of the episode's subject (within the split), drawn
        at reset with the environment's generator, and the share drawn ``m / K``."""
        self.calibration = check_integer(calibration, "calibration", 0, MAX_CALIBRATION)
        self._cal_features = features
        labels = np.asarray(subjects).astype(str)
        self._others = [
            np.flatnonzero((labels == s) & (np.arange(labels.size) != l))
            for l, s in enumerate(labels)
        ]
        self._drawn: NDArray[np.int64] = np.zeros(0, dtype=np.int64)
        if self.calibration:
            box: Any = self.observation_space
            f = features.shape[1]
            low = np.concatenate([box.low, np.full(f, -CALIBRATION_BOUND), [0.0]])
            high = np.concatenate([box.high, np.full(f, CALIBRATION_BOUND), [1.0]])
            self.observation_space = gym.spaces.Box(
                low.astype(np.float32), high.astype(np.float32), dtype=np.float32
            )

    def _observe(self, index: int) -> NDArray[np.float32]:
        """The episode's observation: the context, then (``calibration = K``) the
        calibration summary of ``K`` other reaches of the same person, drawn now."""
        context: NDArray[np.float32] = self._context[index].copy()
        if not getattr(self, "calibration", 0):
            return context
        others = self._others[index]
        m = min(self.calibration, others.size)
        drawn = np.sort(self.np_random.choice(others, size=m, replace=False)) if m else others[:0]
        self._drawn = drawn
        f = self._cal_features.shape[1]
        mean = self._cal_features[drawn].mean(axis=0) if m else np.zeros(f)
        summary = np.clip(mean, -CALIBRATION_BOUND, CALIBRATION_BOUND)
        return np.concatenate([context, summary, [m / self.calibration]]).astype(np.float32)

    def _finish_setup(self) -> None:
        tau = np.linspace(0.0, 1.0, N_STEPS)
        from motion_envs.geometry.sine_series import basis

        self._basis = basis(tau, self.n_sines)[:, 2:]  # (n, K): sin(k pi tau)
        d = self.n_sines * self._width
        self.action_space = gym.spaces.Box(-1.0, 1.0, (d,), dtype=np.float32)
        self._action_shape = (d,)
        self._labels = reset_labels(self.task)
        self._nominal_errors = self._errors(np.arange(self.task.n_trajectories), self._base)

    # -- the arithmetic (batched over episodes) ---------------------------------------
    def curves(self, index: Any, actions: Any) -> FloatArray:
        """Predicted curves ``(N, n, width)`` of episodes ``index`` under ``actions``
        ``(N, action_dim)`` (clipped to ``[-1, 1]``): ``base + s F p`` (module docstring);
        a zero action returns the nominal's curve exactly."""
        idx = np.asarray(index, dtype=np.int64)
        a = np.clip(np.asarray(actions, dtype=np.float64), -1.0, 1.0)
        c = (self.residual_scale * a).reshape(idx.size, self.n_sines, self._width)
        p = np.einsum("tk,lkc->ltc", self._basis, c)
        body = np.einsum("lij,ltj->lti", self._frames[idx], p) * self._scales[idx, None, None]
        out: FloatArray = self._base[idx] + body
        return out

    def target_actions(self) -> FloatArray:
        """``(L, action_dim)`` the least-squares action of every episode: the coefficients
        whose curve is closest (grid least squares) to the human's, unclipped (a
        regression target for the learned comparisons)."""
        gap = self._human_curves() - self._base
        local = np.einsum("lij,lti->ltj", self._frames, gap) / self._scales[:, None, None]
        L, n, w = local.shape
        coef = np.linalg.lstsq(self._basis, local.transpose(1, 0, 2).reshape(n, -1), rcond=None)[0]
        c = coef.reshape(self.n_sines, L, w).transpose(1, 0, 2).reshape(L, -1)
        out: FloatArray = c / self.residual_scale
        return out

    def _human_curves(self) -> FloatArray:
        raise NotImplementedError

    def _errors(self, index: NDArray[np.int64], curves: FloatArray) -> FloatArray:
        raise NotImplementedError

    def score(self, index: Any, actions: Any) -> FloatArray:
        """``(N,)`` the criterion (max over time of the error) of episodes ``index``
        under ``actions``: what :meth:`step` returns as ``-reward``."""
        idx = np.asarray(index, dtype=np.int64)
        return self._errors(idx, self.curves(idx, actions))

    # -- episode ------------------------------------------------------------------------
    def _draw(self, options: dict[str, Any] | None) -> int:
        L = self.task.n_trajectories
        if options is not None and options.get("trajectory") is not None:
            index = options["trajectory"]
            if isinstance(index, bool) or not isinstance(index, (int, np.integer)):
                raise ValueError(f"options['trajectory'] must be an integer; got {index!r}")
            if not 0 <= index < L:
                raise ValueError(f"options['trajectory'] must be in [0, {L}); got {index}")
            return int(index)
        return int(self.np_random.integers(L))

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[NDArray[np.float32], dict[str, Any]]:
        super().reset(seed=seed)
        index = self._draw(options)
        self._index = index
        self._done = False
        self._predicted = None
        self._obs = self._observe(index)
        info: dict[str, Any] = {"trajectory_index": index}
        for key, labels in self._labels.items():
            info[key] = str(labels[index])
        if getattr(self, "calibration", 0):
            info["calibration_trajectories"] = self._drawn.copy()
        return self._obs.copy(), info

    def _check_action(self, action: Any) -> NDArray[np.float64]:
        a = as_action(action, self._action_shape)
        if not np.all(np.isfinite(a)):
            raise ValueError(f"action must be finite; got {a.tolist()}")
        return a

    def _result(
        self, error: float, curve: FloatArray
    ) -> tuple[NDArray[np.float32], float, bool, bool, dict[str, Any]]:
        """The step's return for episode ``_index`` scored ``error`` (curve kept for
        rendering)."""
        self._done = True
        self._predicted = curve
        i = self._index
        info = {"max_error": float(error), "nominal_max_error": float(self._nominal_errors[i])}
        return self._obs.copy(), -float(error), True, False, info

    def step(self, action: Any) -> tuple[NDArray[np.float32], float, bool, bool, dict[str, Any]]:
        if self._done:
            raise RuntimeError("the episode has ended (or never started); call reset() first")
        a = self._check_action(action)
        idx = np.array([self._index])
        curve = self.curves(idx, a[None])
        return self._result(float(self._errors(idx, curve)[0]), curve[0])

    def render(self) -> NDArray[np.uint8] | None:
        if self.render_mode is None:
            gym.logger.warn(
                "render() called without a render_mode; pass render_mode='rgb_array' to "
                "gym.make(...)"
            )
            return None
        if self._index < 0:
            raise RuntimeError("call reset() before render()")
        return self._render_frame()

    def _render_frame(self) -> NDArray[np.uint8]:
        raise NotImplementedError


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
    `Box(low, high, (9 + T,), float32)`, ``T`` the number of tasks (10 for
    ``"vr-kitchen"``: 19 values; 29 with ``calibration > 0``):

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
    summary 0). `info["calibration_trajectories"]` lists the drawn trajectories.

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
        calibration: int = 0,
        render_mode: str | None = None,
        width: int = 480,
        height: int = 480,
    ) -> None:
        from motion_envs.models.path_frame import path_frames

        self._check_common(n_sines, residual_scale, render_mode, width, height)
        self.task = load_orientation_task(
            data, split, nominal, degree, test_fraction, split_seed, min_deg, val_fraction, True,
            fold,
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
        self._setup_calibration(calibration, self.task.subjects, self._path_coefficients())
        self._finish_setup()

    def _path_coefficients(self) -> FloatArray:
        """``(L, 3 CALIBRATION_SINES)`` least-squares sine coefficients of each
        trajectory's own human residual in its path frame (the calibration features:
        each row from that trajectory alone)."""
        from motion_envs.geometry.sine_series import basis

        local = np.einsum("lij,lti->ltj", self._frames, self.task.grids.residuals)
        local = local / self._scales[:, None, None]
        B = basis(np.linspace(0.0, 1.0, N_STEPS), CALIBRATION_SINES)[:, 2:]
        L, n, w = local.shape
        coef = np.linalg.lstsq(B, local.transpose(1, 0, 2).reshape(n, -1), rcond=None)[0]
        out: FloatArray = coef.reshape(CALIBRATION_SINES, L, w).transpose(1, 0, 2).reshape(L, -1)
        return out

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
        self._check_common(n_sines, residual_scale, render_mode, width, height)
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


class CoefficientVectorEnv(JsonSpecMixin, gym.vector.VectorEnv):
    """``num_envs`` copies of a coefficient environment, scored in one batch.

    Sub-environment ``i`` is bit-identical to a single environment made with the same
    arguments and seeded with ``seed + i``, and episodes end and restart as under
    ``SyncVectorEnv`` with the same ``autoreset_mode`` (``NEXT_STEP``, the default, or
    ``SAME_STEP``; ``DISABLED`` needs ``reset(options={"reset_mask": mask})`` before an
    ended sub-environment steps again). The scoring of the stepped sub-environments is
    one batched call (:meth:`CoefficientEnv.score`).

    Parameters
    ----------
    num_envs : int
        Number of sub-environments, 1 to ``MAX_NUM_ENVS``.
    max_episode_steps : int or None
        The registration's (1): every step is then also truncated, as under ``TimeLimit``.
    autoreset_mode : AutoresetMode or str
        ``NEXT_STEP`` (default), ``SAME_STEP`` or ``DISABLED``.
    **kwargs
        The single environment's keyword arguments.
    """

    metadata: dict[str, Any] = {  # noqa: RUF012  (Gymnasium's instance attribute)
        "render_modes": ["rgb_array"],
        "render_fps": 4,
        "autoreset_mode": AutoresetMode.NEXT_STEP,
    }
    single_class: ClassVar[type[CoefficientEnv]]
    _obs: NDArray[np.float32]

    def __init__(
        self,
        num_envs: int = 1,
        max_episode_steps: int | None = None,
        autoreset_mode: AutoresetMode | str = AutoresetMode.NEXT_STEP,
        **kwargs: Any,
    ) -> None:
        from motion_envs.envs._common import check_autoreset_mode

        first = self.single_class(**kwargs)
        self.num_envs = check_num_envs(num_envs)
        self._max_steps = check_max_episode_steps(max_episode_steps, 2**62)
        self.autoreset_mode = check_autoreset_mode(autoreset_mode)
        self.metadata = {**type(self).metadata, "autoreset_mode": self.autoreset_mode}
        self.envs = [first] + [self.single_class(**kwargs) for _ in range(self.num_envs - 1)]
        self.single = first
        self.single_action_space = first.action_space
        self.single_observation_space = first.observation_space
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.render_mode = first.render_mode
        self._autoreset = np.zeros(self.num_envs, dtype=bool)
        self._started = False

    def reset(
        self,
        *,
        seed: int | Sequence[int | None] | None = None,
        options: dict[str, Any] | None = None,
    ) -> tuple[NDArray[np.float32], dict[str, Any]]:
        N = self.num_envs
        if seed is None:
            seeds: list[int | None] = [None] * N
        elif isinstance(seed, (int, np.integer)) and not isinstance(seed, bool):
            seeds = [int(seed) + i for i in range(N)]
        else:
            seeds = list(seed)  # type: ignore[arg-type]
            if len(seeds) != N:
                raise ValueError(f"seed must be an int or a list of {N} seeds; got {len(seeds)}")
        options = dict(options or {})
        mask = options.pop("reset_mask", None)
        if mask is None:
            mask = np.ones(N, dtype=bool)
        else:
            mask = np.asarray(mask)
            if mask.shape != (N,) or mask.dtype != bool:
                raise ValueError(f"options['reset_mask'] must be a bool array ({N},)")
            if not self._started and not mask.all():
                raise ValueError("the first reset must reset every sub-environment")
        traj = options.pop("trajectory", None)
        if traj is not None:  # one trajectory per sub-environment (broadcast)
            traj = np.broadcast_to(np.asarray(traj), (N,))
        obs = np.zeros((N, *self.single_observation_space.shape), dtype=np.float32)  # type: ignore[misc]
        if self._started:
            obs[:] = self._obs
        infos: dict[str, Any] = {}
        for i in np.flatnonzero(mask).tolist():
            sub = dict(options)
            if traj is not None:
                t = traj[i]
                sub["trajectory"] = int(t) if np.asarray(t).dtype.kind in "iu" else t
            obs[i], info = self.envs[i].reset(seed=seeds[i], options=sub or None)
            infos = self._add_info(infos, info, i)
            self._autoreset[i] = False
        self._started = True
        self._obs = obs.copy()
        return obs, infos

    def step(
        self, actions: Any
    ) -> tuple[
        NDArray[np.float32],
        NDArray[np.float64],
        NDArray[np.bool_],
        NDArray[np.bool_],
        dict[str, Any],
    ]:
        N = self.num_envs
        a = as_action(actions, (N, *self.single_action_space.shape), "actions")  # type: ignore[misc]
        if not self._started:
            raise RuntimeError("call reset() before step()")
        bad = ~np.isfinite(a).all(axis=1)
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            raise ValueError(f"actions must be finite; got {a[i].tolist()} at index {i}")
        resetting = self._autoreset.copy()
        if self.autoreset_mode == AutoresetMode.DISABLED and resetting.any():
            i = int(np.flatnonzero(resetting)[0])
            raise RuntimeError(
                f"sub-environment {i} has ended and autoreset_mode is DISABLED; call "
                "reset(options={'reset_mask': mask}) for the ended sub-environments first"
            )
        if self.autoreset_mode != AutoresetMode.NEXT_STEP:
            resetting[:] = False
        stepped = np.flatnonzero(~resetting)
        index = np.array([self.envs[i]._index for i in stepped.tolist()], dtype=np.int64)
        curves = self.single.curves(index, a[stepped])
        errors = self.single._errors(index, curves)
        obs = np.empty((N, *self.single_observation_space.shape), dtype=np.float32)  # type: ignore[misc]
        rewards = np.zeros(N)
        terminated = np.zeros(N, dtype=bool)
        truncated = np.zeros(N, dtype=bool)
        infos: dict[str, Any] = {}
        j = 0
        for i in range(N):
            env = self.envs[i]
            if resetting[i]:
                obs[i], info = env.reset()
            else:
                obs[i], rewards[i], terminated[i], _, info = env._result(errors[j], curves[j])
                truncated[i] = self._max_steps <= 1
                j += 1
                if self.autoreset_mode == AutoresetMode.SAME_STEP:
                    final = {"final_obs": obs[i].copy(), "final_info": info}
                    infos = self._add_info(infos, final, i)
                    obs[i], info = env.reset()
            infos = self._add_info(infos, info, i)
        self._autoreset = terminated | truncated
        self._obs = obs.copy()
        return obs, rewards, terminated, truncated, infos

    def close_extras(self, **kwargs: Any) -> None:
        for env in self.envs:
            env.close()

    def render(self) -> tuple[NDArray[np.uint8], ...] | None:
        if self.render_mode is None:
            gym.logger.warn("render() called without a render_mode")
            return None
        frames = [env.render() for env in self.envs]
        return tuple(np.asarray(f, dtype=np.uint8) for f in frames)


class OrientationCoefficientsVectorEnv(CoefficientVectorEnv):
    """``num_envs`` copies of :class:`OrientationCoefficientsEnv` (see
    :class:`CoefficientVectorEnv`)."""

    single_class = OrientationCoefficientsEnv


class PositionCoefficientsVectorEnv(CoefficientVectorEnv):
    """``num_envs`` copies of :class:`PositionCoefficientsEnv` (see
    :class:`CoefficientVectorEnv`)."""

    single_class = PositionCoefficientsEnv
