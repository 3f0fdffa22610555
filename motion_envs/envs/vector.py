"""Native vector environments: ``N`` episodes stepped together, in one compiled loop.

``gym.make_vec(id, num_envs=N)`` builds these (the registration's
``vector_entry_point``; ``vectorization_mode="vector_entry_point"`` says so explicitly).
Sub-environment ``i`` is bit-identical to a single environment made with the same
arguments and seeded with ``seed + i`` (as :class:`gymnasium.vector.SyncVectorEnv` seeds
its copies): the step arithmetic and the reward are the same kernels
(:mod:`motion_envs.envs._kernels`), each sub-environment draws its trajectories from its
own generator (the same sequence as ``Generator.integers`` one call per reset), and
episodes end and restart as under ``SyncVectorEnv`` with the same ``autoreset_mode``:

* ``AutoresetMode.NEXT_STEP`` (default): the step after an episode's end resets that
  sub-environment, ignores its action and returns reward 0, not terminated/truncated;
* ``AutoresetMode.SAME_STEP``: the step that ends an episode returns the first
  observation of the next one; the last observation and infos are in
  ``infos["final_obs"]`` (object array) and ``infos["final_info"]`` (masked by
  ``infos["_final_obs"]``/``infos["_final_info"]``), as CleanRL-style loops expect;
* ``AutoresetMode.DISABLED``: no autoreset; reset ended sub-environments with
  ``reset(options={"reset_mask": mask})`` before stepping them again.

Pass the mode as ``gym.make_vec(id, N, autoreset_mode=AutoresetMode.SAME_STEP)`` (or
its value ``"SameStep"``); Gymnasium forwards only keyword arguments, not
``vector_kwargs``, to a ``vector_entry_point``. ``max_episode_steps`` (from the
registration) truncates like ``TimeLimit``.

Backends (``backend=``, see :mod:`motion_envs.envs._kernels`): ``"numba"`` runs the
whole step as one compiled loop (:mod:`motion_envs.envs._fused`), ``"numpy"`` as
batched numpy calls; ``"auto"`` (default) takes numba when installed. Both are
bit-identical to ``SyncVectorEnv`` (tested).

``infos`` follow the vector convention: ``infos[key]`` is an ``(N,)`` array and
``infos["_" + key]`` marks the sub-environments it applies to (entries outside the mask
are unspecified, not necessarily 0 as under ``SyncVectorEnv``). A reset (and an
autoreset, in the step's infos) reports the single environments' reset keys as
``SyncVectorEnv`` batches them: ``trajectory_index`` (int64, 0 outside the mask) and
``trajectory_id``, ``task`` (and ``subject`` for orientation) as object arrays of
``str`` (None outside the mask); steps without a reset carry none of them.
Observations, rewards, flags and infos are new arrays every step. Bad arguments raise
the same ``ValueError`` as the single environment's (the checks of
:mod:`motion_envs.envs._common`); a non-numeric ``actions`` (dict, string, complex)
raises ``ValueError``.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode
from gymnasium.vector.utils import batch_space
from numpy.typing import NDArray

from motion_envs.envs import _kernels as K
from motion_envs.envs._common import (
    N_STEPS,
    JsonSpecMixin,
    as_action,
    check_max_episode_steps,
    check_num_envs,
    reset_labels,
)

__all__ = ["OrientationReachVectorEnv", "PositionReachVectorEnv"]

# observations, rewards, terminations, truncations, infos
_StepResult = tuple[
    NDArray[np.float32], NDArray[np.float64], NDArray[np.bool_], NDArray[np.bool_], dict[str, Any]
]

_MODES = {AutoresetMode.NEXT_STEP: 0, AutoresetMode.SAME_STEP: 1, AutoresetMode.DISABLED: 2}
_NEXT, _SAME, _DISABLED = 0, 1, 2
_IDX, _K, _ELAPSED, _AUTORESET, _PTR = 0, 1, 2, 3, 4  # columns of the integer state
# Below this many sub-environments the numpy backend runs the orientation step as the
# scalar kernel per environment (numpy's per-call overhead dominates small batches).
_SCALAR_BELOW = 8
_POOL_AT = 5  # first column of the trajectory pool in the integer state
_POOL = 64  # trajectory draws per sub-environment taken from its generator at once


def _check_autoreset_mode(mode: AutoresetMode | str) -> AutoresetMode:
    try:
        return mode if isinstance(mode, AutoresetMode) else AutoresetMode(mode)
    except ValueError:
        values = [m.value for m in AutoresetMode]
        raise ValueError(
            f"autoreset_mode must be a gymnasium.vector.AutoresetMode or one of {values}; "
            f"got {mode!r}"
        ) from None


class _ReplayVectorEnv(JsonSpecMixin, gym.vector.VectorEnv):
    """Shared episode bookkeeping of the native vector environments.

    A subclass sets ``_KIND`` (the :mod:`~motion_envs.envs._fused` kind), ``_STEP_KEYS``
    (the info keys of rows ``1 ..`` of the float outputs, ending with ``"tau"``),
    ``_END_KEYS`` (the keys of the two rows after ``tau``, set at termination) and
    implements :meth:`_physics_numpy`.
    """

    metadata: dict[str, Any] = {  # noqa: RUF012  (Gymnasium's instance attribute)
        "render_modes": ["rgb_array"],
        "render_fps": 25,
        "autoreset_mode": AutoresetMode.NEXT_STEP,
    }
    _KIND: ClassVar[int]
    _STEP_KEYS: ClassVar[tuple[str, ...]]
    _END_KEYS: ClassVar[tuple[str, ...]]

    def _setup(
        self,
        num_envs: int,
        max_episode_steps: int | None,
        single: Any,
        autoreset_mode: AutoresetMode | str,
        backend: str,
        weights: tuple[float, ...],
    ) -> None:
        """Set up ``num_envs`` copies of ``single`` (a ``_common.ReplayEnv``, already checked)."""
        task = single.task
        self.task = task
        self._n_steps = N_STEPS
        self._n_traj = task.n_trajectories
        self.num_envs = check_num_envs(num_envs)
        self._max_steps = check_max_episode_steps(max_episode_steps, self._n_steps)
        self.autoreset_mode = _check_autoreset_mode(autoreset_mode)
        self._mode = _MODES[self.autoreset_mode]
        self.metadata = {**type(self).metadata, "autoreset_mode": self.autoreset_mode}
        self.backend = K.resolve_vector_backend(backend)
        self.single = single  # validated arguments, spaces and rendering
        self.residual_scale = single.residual_scale
        self.reward_weights = single.reward_weights
        self._weights = np.asarray(weights, dtype=np.float64)
        self.single_action_space = single.action_space
        self.single_observation_space = single.observation_space
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.render_mode = single.render_mode
        N = self.num_envs
        self._action_shape: tuple[int, ...] = (N, *self.single_action_space.shape)  # type: ignore[misc]
        self._rngs: list[np.random.Generator | None] = [None] * N
        # text entries of the single environments' reset infos, per trajectory
        self._labels = reset_labels(task)
        self._started = False
        self._arange = np.arange(N)
        L, n, width = task.steps.shape
        self._table = np.ascontiguousarray(task.steps.reshape(L * n, width).T)  # numpy path
        self._obs_table = np.ascontiguousarray(task.obs)  # (L, n + 1, obs_dim)
        self._obs_dim = task.obs_dim
        self._starts = np.ascontiguousarray(single._starts, dtype=np.float64)
        self._cur = single._cur  # the observation's slice of the current state
        self._cur_lo = self._cur.start
        self._dim = dim = self._cur.stop - self._cur.start
        bounds = single._cur_bounds or ((-np.inf,) * dim, (np.inf,) * dim)
        self._cur_low, self._cur_high = (np.asarray(b, dtype=np.float64) for b in bounds)
        # the compiled loop's table: the step rows, then a row with the start, the bounds
        # of the current state in the observation and the parameters
        extra = (*bounds[0], *bounds[1], self.residual_scale, *weights)
        self._steps = np.zeros((L, n + 1, max(width, dim + len(extra))))
        self._steps[:, :n, :width] = task.steps
        self._steps[:, n, :dim] = self._starts
        self._steps[:, n, dim : dim + len(extra)] = extra
        self._si = np.zeros((N, _POOL_AT + _POOL), dtype=np.int64)
        self._pool = self._si[:, _POOL_AT:]  # a view: the compiled loop reads the pool in si
        self._sf = np.zeros((N, dim + 2))
        self._final_obs = np.zeros((N, self._obs_dim), dtype=np.float32)
        self._n_out = 3 + len(self._STEP_KEYS)
        self._history: NDArray[np.float64] | None = (
            np.zeros((N, n + 1, self._dim)) if self.render_mode is not None else None
        )
        self._link_backend()

    def _link_backend(self) -> None:
        """The compiled step and its fixed leading arguments (numba backend), else None."""
        self._run: Any = None
        if self.backend == "numba":
            from motion_envs.envs import _fused

            self._run = _fused.batch_step
            # the same array objects every step (state is updated in place)
            self._run_args = (
                self._KIND,
                self._mode,
                self._max_steps,
                self._cur_lo,
                self._steps,
                self._obs_table,
                self._si,
                self._sf,
                self._final_obs,
            )

    def __getstate__(self) -> dict[str, Any]:
        state = self.__dict__.copy()
        state["_run"] = state["_run_args"] = None  # linked again on unpickling
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self._pool = self._si[:, _POOL_AT:]  # pickling does not keep views
        self._link_backend()

    # -- seeding and resets -------------------------------------------------------------
    def _seed_rngs(self, seed: int | Sequence[int | None] | None) -> None:
        N = self.num_envs
        if seed is None:
            seeds: list[int | None] = [None] * N
        elif isinstance(seed, (int, np.integer)) and not isinstance(seed, bool):
            seeds = [int(seed) + i for i in range(N)]
        else:
            seeds = list(seed)  # type: ignore[arg-type]
            if len(seeds) != N:
                raise ValueError(f"seed must be an int or a list of {N} seeds; got {len(seeds)}")
        for i, s in enumerate(seeds):
            if s is not None or self._rngs[i] is None:
                self._rngs[i], _ = seeding.np_random(s)
                self._refill(i)

    def _refill(self, i: int) -> None:
        """Draw the next :data:`_POOL` trajectories of sub-environment ``i``: the same
        sequence as one ``integers(L)`` per reset (numpy's bounded integers take 32-bit
        halves of the generator's 64-bit outputs in turn either way; tested)."""
        self._pool[i] = self._rngs[i].integers(self._n_traj, size=_POOL)  # type: ignore[union-attr]
        self._si[i, _PTR] = 0

    def _refill_exhausted(self) -> None:
        for i in np.flatnonzero(self._si[:, _PTR] >= _POOL).tolist():
            self._refill(i)

    def _reset_envs(self, envs: NDArray[np.int64], trajectories: Any = None) -> None:
        """Start new episodes in sub-environments ``envs`` (next trajectory of each pool,
        or ``trajectories``)."""
        si, sf, dim = self._si, self._sf, self._dim
        if trajectories is None:
            idx = self._pool[envs, si[envs, _PTR]]
            si[envs, _PTR] += 1
            self._refill_exhausted()
        else:
            idx = np.asarray(trajectories, dtype=np.int64)
        si[envs, _IDX] = idx
        si[envs, _K] = 0
        si[envs, _ELAPSED] = 0
        si[envs, _AUTORESET] = 0
        sf[envs, :dim] = self._starts[idx]
        sf[envs, dim:] = 0.0

    def reset(
        self,
        *,
        seed: int | Sequence[int | None] | None = None,
        options: dict[str, Any] | None = None,
    ) -> tuple[NDArray[np.float32], dict[str, Any]]:
        self._seed_rngs(seed)
        options = options or {}
        mask = options.get("reset_mask")
        if mask is None:
            envs = self._arange
        else:
            mask = np.asarray(mask)
            if mask.shape != (self.num_envs,) or mask.dtype != bool:
                raise ValueError(f"options['reset_mask'] must be a bool array ({self.num_envs},)")
            if not self._started and not mask.all():
                raise ValueError("the first reset must reset every sub-environment")
            envs = np.flatnonzero(mask)
        traj = options.get("trajectory")
        if traj is not None:
            traj = np.broadcast_to(np.asarray(traj), (self.num_envs,))[envs]
            if traj.dtype.kind not in "iu" or np.any((traj < 0) | (traj >= self._n_traj)):
                raise ValueError(f"options['trajectory'] must hold integers in [0, {self._n_traj})")
        self._reset_envs(envs, traj)
        self._started = True
        obs = self._observe()
        self._record_history()
        reset = np.zeros(self.num_envs, dtype=bool)
        reset[envs] = True
        info: dict[str, Any] = {}
        self._add_reset_infos(info, reset)
        return obs, info

    def _add_reset_infos(self, info: dict[str, Any], reset: NDArray[np.bool_]) -> None:
        """Add the reset infos of the sub-environments under ``reset`` to ``info``,
        batched as ``SyncVectorEnv`` batches the single environments' reset infos
        (called only when some sub-environment was reset: no per-step work)."""
        idx = self._si[:, _IDX]
        info["trajectory_index"] = np.where(reset, idx, 0)
        info["_trajectory_index"] = reset
        envs = np.flatnonzero(reset)
        for key, labels in self._labels.items():
            column = np.full(self.num_envs, None, dtype=object)
            column[envs] = labels[idx[envs]]
            info[key] = column
            info["_" + key] = reset

    def _observe(self) -> NDArray[np.float32]:
        si = self._si
        obs = self._obs_table[si[:, _IDX], si[:, _K]]
        obs[:, self._cur] = np.clip(self._sf[:, : self._dim], self._cur_low, self._cur_high)
        return obs

    def _record_history(self) -> None:
        if self._history is not None:
            # after a step, every sub-environment's current state is at its grid point k
            # (0 right after a reset)
            self._history[self._arange, self._si[:, _K]] = self._sf[:, : self._dim]

    # -- stepping -----------------------------------------------------------------------
    def step(self, actions: Any) -> _StepResult:
        if type(actions) is np.ndarray and actions.dtype.kind == "f":
            a = np.ascontiguousarray(actions, dtype=np.float64)  # one compiled layout
        else:  # lists, integers; a dict, string or complex raise ValueError
            a = np.ascontiguousarray(as_action(actions, self._action_shape, "actions"))
        if a.shape != self._action_shape:
            raise ValueError(f"actions must have shape {self._action_shape}; got {a.shape}")
        if not self._started:
            raise RuntimeError("call reset() before step()")
        N = self.num_envs
        obs = np.empty((N, self._obs_dim), dtype=np.float32)
        out_f = np.empty((self._n_out, N))
        out_b = np.empty((4, N), dtype=bool)
        run = self._run
        if run is not None:
            status, n_term, n_reset, n_exhausted = run(*self._run_args, a, obs, out_f, out_b)
            if n_exhausted:
                self._refill_exhausted()
        else:
            status, n_term, n_reset = self._step_numpy(a, obs, out_f, out_b)
        if status:
            self._raise_step_error(status, n_term, a)
        if self._history is not None:
            self._record_history()
        return obs, out_f[0], out_b[0], out_b[1], self._infos(out_f, out_b, n_term, n_reset)

    def _raise_step_error(self, status: int, i: int, a: NDArray[np.float64]) -> None:
        if status == 1:
            raise ValueError(f"actions must be finite; got {a[i].tolist()} at index {i}")
        raise RuntimeError(
            f"sub-environment {i} has ended and autoreset_mode is DISABLED; call "
            "reset(options={'reset_mask': mask}) for the ended sub-environments first"
        )

    def _infos(
        self, out_f: NDArray[np.float64], out_b: NDArray[np.bool_], n_term: int, n_reset: int
    ) -> dict[str, Any]:
        """The vector infos of a step from the float and flag outputs (views, no copies)."""
        info = self._step_infos(out_f, out_b[2])
        if not (n_term or n_reset):
            return info
        terminated, reset = out_b[0], out_b[3]
        t = len(self._STEP_KEYS)
        if self._mode == _SAME:
            if n_reset:
                final = self._step_infos(out_f, reset)
                if n_term:
                    for r, key in enumerate(self._END_KEYS, start=t + 1):
                        final[key] = out_f[r]
                        final["_" + key] = terminated
                final_obs = np.full(self.num_envs, None, dtype=object)
                for i in np.flatnonzero(reset).tolist():
                    final_obs[i] = self._final_obs[i].copy()
                info["final_obs"] = final_obs
                info["_final_obs"] = reset
                info["final_info"] = final
                info["_final_info"] = reset
        elif n_term:
            for r, key in enumerate(self._END_KEYS, start=t + 1):
                info[key] = out_f[r]
                info["_" + key] = terminated
        if n_reset:
            self._add_reset_infos(info, reset)
        return info

    def _step_infos(self, out_f: NDArray[np.float64], mask: NDArray[np.bool_]) -> dict[str, Any]:
        """The per-step infos: rows ``1 ..`` of ``out_f`` under :attr:`_STEP_KEYS`, each
        with ``mask`` (a dict literal in each subclass: the fastest way to build it)."""
        raise NotImplementedError

    def _step_numpy(
        self,
        a: NDArray[np.float64],
        obs: NDArray[np.float32],
        out_f: NDArray[np.float64],
        out_b: NDArray[np.bool_],
    ) -> tuple[int, int, int]:
        """:func:`motion_envs.envs._fused.batch_step` in batched numpy (same results)."""
        si, sf, dim, n = self._si, self._sf, self._dim, self._n_steps
        autoreset = si[:, _AUTORESET] != 0
        if self._mode == _DISABLED and autoreset.any():
            return 2, int(np.flatnonzero(autoreset)[0]), 0
        finite = np.isfinite(a).all(axis=1)
        if not finite.all():
            return 1, int(np.flatnonzero(~finite)[0]), 0
        a = np.clip(a, -1.0, 1.0)
        resetting = autoreset if self._mode == _NEXT else np.zeros(self.num_envs, dtype=bool)
        active = ~resetting
        k = si[:, _K].copy()
        rows = self._table[:, si[:, _IDX] * n + np.minimum(k, n - 1)]
        q, err = self._physics_numpy(a, rows, out_f, active)
        sf[active, :dim] = q[active]
        np.maximum(sf[:, dim], np.where(active, err, 0.0), out=sf[:, dim])
        si[:, _K] += active
        si[:, _ELAPSED] += active
        terminated = active & (si[:, _K] == n)
        truncated = active & (si[:, _ELAPSED] >= self._max_steps)
        t = len(self._STEP_KEYS)
        out_f[0] = np.where(active, out_f[0], 0.0)
        out_f[t] = k / (n - 1)
        out_f[t + 1] = sf[:, dim]
        out_f[t + 2] = sf[:, dim + 1]
        out_b[0] = terminated
        out_b[1] = truncated
        ended = terminated | truncated
        if self._mode == _SAME:
            obs[:] = self._observe()
            self._final_obs[ended] = obs[ended]
            reset = ended
            out_b[2] = ~ended
        else:
            reset = resetting
            out_b[2] = active
            si[:, _AUTORESET] = ended
        out_b[3] = reset
        envs = np.flatnonzero(reset)
        if envs.size:
            self._reset_envs(envs)
        obs[:] = self._observe()
        return 0, int(np.count_nonzero(terminated)), int(envs.size)

    def _physics_numpy(
        self,
        a: NDArray[np.float64],
        rows: NDArray[np.float64],
        out_f: NDArray[np.float64],
        active: NDArray[np.bool_],
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """States ``(N, dim)`` and errors of one step; fills reward and info rows."""
        raise NotImplementedError

    def close_extras(self, **kwargs: Any) -> None:
        self.single.close()

    def render(self) -> tuple[NDArray[np.uint8], ...] | None:
        if self.render_mode is None:
            gym.logger.warn("render() called without a render_mode")
            return None
        return tuple(self._render_env(i) for i in range(self.num_envs))

    def _render_env(self, i: int) -> NDArray[np.uint8]:
        single = self.single
        single._index = int(self._si[i, _IDX])
        assert self._history is not None
        single._history = [tuple(q) for q in self._history[i, : self._si[i, _K] + 1]]
        frame = single.render()
        assert frame is not None  # render_mode is "rgb_array"
        return np.asarray(frame, dtype=np.uint8)


class OrientationReachVectorEnv(_ReplayVectorEnv):
    """``num_envs`` copies of :class:`~motion_envs.envs.orientation_reach.OrientationReachEnv`.

    Takes the single environment's keyword arguments plus ``num_envs``,
    ``max_episode_steps`` (default: the registration's 50), ``autoreset_mode`` (default
    ``NEXT_STEP``) and ``backend`` (``"auto"``, ``"numba"``, ``"numpy"``). Observations,
    rewards, terminations and truncations are bit-identical to ``SyncVectorEnv`` of single
    environments with the same seeds and autoreset mode; ``infos`` carry the same
    per-step terms and, at an episode's end, ``max_error`` and ``max_geodesic_error``.
    """

    _KIND: ClassVar[int] = 0
    _STEP_KEYS: ClassVar[tuple[str, ...]] = (
        "error",
        "geodesic_error",
        "reward_residual",
        "reward_geodesic",
        "reward_action",
        "tau",
    )
    _END_KEYS: ClassVar[tuple[str, ...]] = ("max_error", "max_geodesic_error")

    def __init__(
        self,
        num_envs: int = 1,
        max_episode_steps: int | None = None,
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
        autoreset_mode: AutoresetMode | str = AutoresetMode.NEXT_STEP,
        backend: str = "auto",
    ) -> None:
        from motion_envs.envs.orientation_reach import OrientationReachEnv

        single = OrientationReachEnv(
            data=data,
            split=split,
            nominal=nominal,
            degree=degree,
            residual_scale=residual_scale,
            reward_weights=reward_weights,
            test_fraction=test_fraction,
            split_seed=split_seed,
            min_deg=min_deg,
            render_mode=render_mode,
            width=width,
            height=height,
            val_fraction=val_fraction,
            observe_timing=observe_timing,
        )
        w = single.reward_weights
        weights = (w["residual"], w["geodesic"], w["action"])
        self._setup(num_envs, max_episode_steps, single, autoreset_mode, backend, weights)

    def _step_infos(self, out_f: NDArray[np.float64], mask: NDArray[np.bool_]) -> dict[str, Any]:
        return {
            "error": out_f[1],
            "_error": mask,
            "geodesic_error": out_f[2],
            "_geodesic_error": mask,
            "reward_residual": out_f[3],
            "_reward_residual": mask,
            "reward_geodesic": out_f[4],
            "_reward_geodesic": mask,
            "reward_action": out_f[5],
            "_reward_action": mask,
            "tau": out_f[6],
            "_tau": mask,
        }

    def _physics_numpy(
        self,
        a: NDArray[np.float64],
        rows: NDArray[np.float64],
        out_f: NDArray[np.float64],
        active: NDArray[np.bool_],
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        ax, ay, az = a[:, 0], a[:, 1], a[:, 2]
        if self.num_envs < _SCALAR_BELOW:
            # few environments: the scalar kernel (same arithmetic, bit-identical) is faster
            outs = [
                K.orientation_step_scalar(row, act[0], act[1], act[2], self.residual_scale)
                for row, act in zip(rows.T.tolist(), a.tolist(), strict=True)
            ]
            q = tuple(np.array([o[0][c] for o in outs]) for c in range(4))
            err = np.array([o[1] for o in outs])
            geo = np.array([o[2] for o in outs])
        else:
            q, err, geo = K.orientation_step(
                K.BATCH,
                (rows[0], rows[1], rows[2], rows[3]),
                (rows[4], rows[5], rows[6], rows[7]),
                (rows[8], rows[9], rows[10], rows[11]),
                rows[12],
                rows[13],
                rows[14],
                ax,
                ay,
                az,
                self.residual_scale,
            )
        w = self._weights
        r_res, r_geo, r_act, reward = K.orientation_reward(err, geo, ax, ay, az, *w.tolist())
        out_f[0] = reward
        out_f[1] = err
        out_f[2] = geo
        out_f[3] = r_res
        out_f[4] = r_geo
        out_f[5] = r_act
        dim = self._dim
        np.maximum(self._sf[:, dim + 1], np.where(active, geo, 0.0), out=self._sf[:, dim + 1])
        return np.stack(q, axis=1), err


class PositionReachVectorEnv(_ReplayVectorEnv):
    """``num_envs`` copies of :class:`~motion_envs.envs.position_reach.PositionReachEnv`.

    Takes the single environment's keyword arguments plus ``num_envs``,
    ``max_episode_steps`` (default: the registration's 50), ``autoreset_mode`` and
    ``backend`` (as :class:`OrientationReachVectorEnv`); bit-identical to
    ``SyncVectorEnv`` of single environments with the same seeds and autoreset mode.
    """

    _KIND: ClassVar[int] = 1
    _STEP_KEYS: ClassVar[tuple[str, ...]] = ("error", "reward_distance", "reward_action", "tau")
    _END_KEYS: ClassVar[tuple[str, ...]] = ("max_error",)

    def __init__(
        self,
        num_envs: int = 1,
        max_episode_steps: int | None = None,
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
        autoreset_mode: AutoresetMode | str = AutoresetMode.NEXT_STEP,
        backend: str = "auto",
    ) -> None:
        from motion_envs.envs.position_reach import PositionReachEnv

        single = PositionReachEnv(
            data=data,
            shapes=shapes,
            split=split,
            nominal=nominal,
            n_sines=n_sines,
            residual_scale=residual_scale,
            reward_weights=reward_weights,
            test_fraction=test_fraction,
            split_seed=split_seed,
            render_mode=render_mode,
            width=width,
            height=height,
            val_fraction=val_fraction,
            observe_timing=observe_timing,
        )
        w = single.reward_weights
        weights = (w["distance"], w["action"])
        self._setup(num_envs, max_episode_steps, single, autoreset_mode, backend, weights)

    def _step_infos(self, out_f: NDArray[np.float64], mask: NDArray[np.bool_]) -> dict[str, Any]:
        return {
            "error": out_f[1],
            "_error": mask,
            "reward_distance": out_f[2],
            "_reward_distance": mask,
            "reward_action": out_f[3],
            "_reward_action": mask,
            "tau": out_f[4],
            "_tau": mask,
        }

    def _physics_numpy(
        self,
        a: NDArray[np.float64],
        rows: NDArray[np.float64],
        out_f: NDArray[np.float64],
        active: NDArray[np.bool_],
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        D = self._dim
        cols = [a[:, i] for i in range(D)]
        q, err = K.position_step(K.BATCH, rows[:D], rows[D:], cols, self.residual_scale)
        sq: Any = 0.0
        for c in cols:
            sq = sq + c * c
        r_dist, r_act, reward = K.position_reward(err, sq, *self._weights.tolist())
        out_f[0] = reward
        out_f[1] = err
        out_f[2] = r_dist
        out_f[3] = r_act
        self._sf[:, D + 1] = 0.0
        return np.stack(q, axis=1), err
