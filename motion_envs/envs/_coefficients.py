"""The shared core of the episodic (black-box) reaching environments: one step per movement.

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

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np
from gymnasium.vector import AutoresetMode
from numpy.typing import NDArray

from motion_envs._typing import FloatArray
from motion_envs.envs._calibration import MAX_CALIBRATION, CalibrationDraws
from motion_envs.envs._common import (
    N_STEPS,
    JsonSpecMixin,
    LazyRendererMixin,
    as_action,
    check_fraction,
    check_integer,
    check_render,
    check_scale,
    check_seed,
)
from motion_envs.envs._native_vector import SAME_STEP, NativeVectorEnv, StepResult
from motion_envs.envs._reach import FrameAfterResetMixin, TrajectoryLabelsMixin, reset_labels
from motion_envs.models.person_calibration import SUMMARY_BOUND, SUMMARY_SINES

__all__ = [
    "CALIBRATION_BOUND",
    "CALIBRATION_SINES",
    "MAX_CALIBRATION",
    "MAX_COEFFICIENT_SINES",
    "CoefficientEnv",
    "CoefficientVectorEnv",
    "FloatArray",
    "line_frames",
]

#: Largest ``n_sines`` (the interior points of the grid).
MAX_COEFFICIENT_SINES = N_STEPS - 2
#: Sine terms per path axis of a calibration summary (9 values).
CALIBRATION_SINES = SUMMARY_SINES
#: The calibration summary is clipped to ``[-CALIBRATION_BOUND, CALIBRATION_BOUND]``.
CALIBRATION_BOUND = SUMMARY_BOUND


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


class CoefficientEnv(JsonSpecMixin, FrameAfterResetMixin, LazyRendererMixin, gym.Env):
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
        self,
        n_sines: int,
        residual_scale: float,
        render_mode: str | None,
        width: int,
        height: int,
        test_fraction: float = 0.25,
        split_seed: int = 0,
    ) -> None:
        """Check the arguments every coefficient env takes (the split's too, before the task
        is built)."""
        check_fraction(test_fraction)
        check_seed(split_seed)
        check_render(render_mode, self.metadata["render_modes"], width, height)
        self.n_sines = check_integer(n_sines, "n_sines", 1, MAX_COEFFICIENT_SINES)
        self.residual_scale = check_scale(residual_scale)
        self.render_mode = render_mode
        self.width, self.height = int(width), int(height)
        self._renderer: Any = None
        self._index = -1
        self._done = True
        self._predicted: FloatArray | None = None

    def _setup_calibration(self, calibration: int, subjects: Any, features: FloatArray) -> None:
        """``calibration = K``: the observation gains the summary of ``K`` other
        trajectories of the episode's subject (within the split), drawn at reset with the
        environment's generator (:class:`~motion_envs.envs._calibration.CalibrationDraws`,
        ``features`` ``(L, f)``)."""
        self._calibration = CalibrationDraws(calibration, subjects, features)
        self.calibration = self._calibration.k
        self._drawn: NDArray[np.int64] = np.zeros(0, dtype=np.int64)
        self.observation_space = self._calibration.extend(self.observation_space)  # type: ignore[arg-type]

    def _observe(self, index: int) -> NDArray[np.float32]:
        """The episode's observation: the context, then (``calibration = K``) the
        calibration summary of ``K`` other reaches of the same person, drawn now."""
        context: NDArray[np.float32] = self._context[index].copy()
        if not getattr(self, "calibration", 0):
            return context
        summary, self._drawn = self._calibration.draw(self.np_random, index)
        return np.concatenate([context, summary]).astype(np.float32)

    def twin(self) -> CoefficientEnv:
        """A new environment equal to one made with the same arguments, sharing this one's
        read-only arrays (task, frames, nominal errors: nothing to recompute) and with its
        own episode state, generator and spaces (the vector environment's sub-envs)."""
        import copy

        own = ("_np_random", "_np_random_seed", "_obs")
        state = {k: v for k, v in vars(self).items() if k not in own}
        twin = copy.copy(self)
        twin.__dict__.clear()
        twin.__dict__.update(state)
        twin.action_space = copy.deepcopy(self.action_space)
        twin.observation_space = copy.deepcopy(self.observation_space)
        twin._renderer = None
        twin._index, twin._done, twin._predicted = -1, True, None
        twin._drawn = np.zeros(0, dtype=np.int64)
        return twin

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
    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[NDArray[np.float32], dict[str, Any]]:
        super().reset(seed=seed)
        index = self._draw_episode(options, self.np_random)
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


class CoefficientVectorEnv(TrajectoryLabelsMixin, JsonSpecMixin, NativeVectorEnv):
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
        first = self.single_class(**kwargs)
        self._setup_batch(
            first, num_envs, autoreset_mode, max_episode_steps, 2**62, type(self).metadata
        )
        self.envs = [first] + [first.twin() for _ in range(self.num_envs - 1)]
        self.single = first
        self._labels = first._labels
        self._autoreset = np.zeros(self.num_envs, dtype=bool)

    def reset(
        self,
        *,
        seed: int | Sequence[int | None] | None = None,
        options: dict[str, Any] | None = None,
    ) -> tuple[NDArray[np.float32], dict[str, Any]]:
        N = self.num_envs
        seeds = self._seeds(seed)
        options = dict(options or {})
        envs = self._reset_targets(options)
        options.pop("reset_mask", None)
        traj = options.pop("trajectory", None)
        if traj is not None:  # one trajectory per sub-environment (broadcast)
            traj = np.broadcast_to(np.asarray(traj), (N,))
        obs = np.zeros((N, *self.single_observation_space.shape), dtype=np.float32)  # type: ignore[misc]
        if self._started:
            obs[:] = self._obs
        infos: dict[str, Any] = {}
        for i in envs.tolist():
            sub = dict(options)
            if traj is not None:
                t = traj[i]
                sub["trajectory"] = int(t) if np.asarray(t).dtype.kind in "iu" else t
            obs[i], info = self.envs[i].reset(seed=seeds[i], options=sub or None)
            infos = self._add_info(infos, self._numeric(info), i)
            self._autoreset[i] = False
        self._started = True
        self._obs = obs.copy()
        return obs, infos

    def step(self, actions: Any) -> StepResult:
        N = self.num_envs
        a = self._check_actions(actions)
        bad = ~np.isfinite(a).all(axis=1)
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            raise ValueError(f"actions must be finite; got {a[i].tolist()} at index {i}")
        resetting = self._resetting(self._autoreset)
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
                if self._mode == SAME_STEP:
                    final = {"final_obs": obs[i].copy(), "final_info": info}
                    infos = self._add_info(infos, final, i)
                    obs[i], info = env.reset()
            infos = self._add_info(infos, self._numeric(info), i)
        self._autoreset = terminated | truncated
        self._obs = obs.copy()
        return obs, rewards, terminated, truncated, infos

    def _numeric(self, info: dict[str, Any]) -> dict[str, Any]:
        """A single environment's info without its text (:attr:`trajectory_labels`)."""
        return {k: v for k, v in info.items() if k not in self._labels}

    def close_extras(self, **kwargs: Any) -> None:
        for env in self.envs:
            env.close()

    def _render_env(self, i: int) -> NDArray[np.uint8]:
        return np.asarray(self.envs[i].render(), dtype=np.uint8)
