"""The native vector environments' core, written once over a reaching kind.

:class:`ReachVectorEnv` steps ``N`` episodes of a single reaching environment together
(:mod:`motion_envs.envs.vector` documents the contract: seeding, autoreset modes,
backends, infos). A kind module subclasses it with its single environment class
(``OrientationReachVectorEnv``, ``PositionReachVectorEnv``); the kind
(:class:`~motion_envs.envs._reach.ReachKind`) gives the step kernels and the info keys.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any, ClassVar

import numpy as np
from gymnasium.vector import AutoresetMode
from numpy.typing import NDArray

from motion_envs.envs import _kernels as K
from motion_envs.envs._common import N_STEPS, JsonSpecMixin
from motion_envs.envs._native_vector import SAME_STEP, NativeVectorEnv, StepResult
from motion_envs.envs._reach import ReachEnv, ReachKind, TrajectoryLabelsMixin, reset_labels

__all__ = ["ReachVectorEnv"]

_IDX, _K, _ELAPSED, _AUTORESET, _PTR = 0, 1, 2, 3, 4  # columns of the integer state
_POOL_AT = 5  # first column of the trajectory pool in the integer state
_POOL = 64  # trajectory draws per sub-environment taken from its generator at once
# Below this many sub-environments the numpy backend runs the kind's scalar step per
# environment (numpy's per-call overhead dominates small batches).
_SCALAR_BELOW = 8


class ReachVectorEnv(TrajectoryLabelsMixin, JsonSpecMixin, NativeVectorEnv):
    """``num_envs`` copies of a single reaching environment, stepped together.

    A kind module subclasses it and sets ``single_class`` (its
    :class:`~motion_envs.envs._reach.ReachEnv`); the kind (``single_class.kind``) gives
    the step kernels and the info keys.

    Parameters
    ----------
    num_envs : int
        Number of sub-environments, 1 to ``MAX_NUM_ENVS``.
    max_episode_steps : int or None
        Truncate an episode after this many steps (None: the registration's 50).
    autoreset_mode : AutoresetMode or str
        ``NEXT_STEP`` (default), ``SAME_STEP`` or ``DISABLED`` (see the module docstring).
    backend : str
        ``"auto"`` (default: numba when installed), ``"numba"`` or ``"numpy"``.
    **kwargs
        The single environment's keyword arguments (``data``, ``split``,
        ``reward_weights``, ...), documented and checked by ``single_class``: every
        sub-environment is ``single_class(**kwargs)``.
    """

    metadata: dict[str, Any] = {  # noqa: RUF012  (Gymnasium's instance attribute)
        "render_modes": ["rgb_array"],
        "render_fps": 25,
        "autoreset_mode": AutoresetMode.NEXT_STEP,
    }
    single_class: ClassVar[type[ReachEnv]]

    def __init__(
        self,
        num_envs: int = 1,
        max_episode_steps: int | None = None,
        autoreset_mode: AutoresetMode | str = AutoresetMode.NEXT_STEP,
        backend: str = "auto",
        **kwargs: Any,
    ) -> None:
        single = self.single_class(**kwargs)  # checks the single environment's arguments
        self.kind: ReachKind = single.kind
        self._setup(num_envs, max_episode_steps, single, autoreset_mode, backend)

    def _setup(
        self,
        num_envs: int,
        max_episode_steps: int | None,
        single: ReachEnv,
        autoreset_mode: AutoresetMode | str,
        backend: str,
    ) -> None:
        """Set up ``num_envs`` copies of ``single`` (already checked)."""
        kind = self.kind
        weights = single._weights
        task = single.task
        self.task = task
        self._n_steps = N_STEPS
        self._n_traj = task.n_trajectories
        self._setup_batch(
            single, num_envs, autoreset_mode, max_episode_steps, N_STEPS, type(self).metadata
        )
        self.backend = K.resolve_vector_backend(backend)
        # calibration = K: every reset draws the trajectory, then the calibration reaches,
        # from the sub-environment's generator (the single environment's order); the
        # compiled loop draws trajectories from a pool, so these run the numpy backend
        self._cal = single._calibration
        if self._cal is not None:
            if backend == "numba":
                raise ValueError(
                    "backend 'numba' does not support calibration > 0 (the compiled loop "
                    "pools the trajectory draws); use backend='numpy' or 'auto'"
                )
            self.backend = "numpy"
        self.single = single  # validated arguments, spaces and rendering
        self.residual_scale = single.residual_scale
        self.reward_weights = single.reward_weights
        self._weights = weights
        N = self.num_envs
        # text entries of the single environments' reset infos, per trajectory (not in
        # the vector infos: trajectory_labels)
        self._labels = reset_labels(task)
        L, n, width = task.steps.shape
        self._table = np.ascontiguousarray(task.steps.reshape(L * n, width).T)  # numpy path
        self._obs_table = np.ascontiguousarray(task.obs)  # (L, n + 1, obs_dim)
        self._obs_dim = task.obs_dim + (self._cal.size if self._cal is not None else 0)
        if self._cal is not None:
            self._summary = np.zeros((self.num_envs, self._cal.size), dtype=np.float32)
            self._drawn = np.full((self.num_envs, self._cal.k), -1, dtype=np.int64)
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
        # running maxima of the episode (the kind's end keys) after the state
        self._n_end = len(kind.end_keys)
        self._sf = np.zeros((N, dim + self._n_end))
        self._final_obs = np.zeros((N, self._obs_dim), dtype=np.float32)
        # float outputs: reward, the step keys, tau, the end keys
        self._n_info = len(kind.step_keys)
        self._n_out = 2 + self._n_info + self._n_end
        self._max_src = tuple(kind.step_keys.index(src) for _, src in kind.end_keys)
        self._end_names = tuple(key for key, _ in kind.end_keys)
        self._step_infos = step_info_builder((*kind.step_keys, "tau"))
        self._history: NDArray[np.float64] | None = (
            np.zeros((N, n + 1, self._dim)) if self.render_mode is not None else None
        )
        self._link_backend()

    def _link_backend(self) -> None:
        """The compiled step and its fixed leading arguments (numba backend), else None."""
        self._run: Any = None
        if self.backend == "numba":
            from motion_envs.envs import _fused

            self._run = _fused.batch_step_of(self.kind)
            # the same array objects every step (state is updated in place)
            self._run_args = (
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
        state["_step_infos"] = None  # built again on unpickling
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self._step_infos = step_info_builder((*self.kind.step_keys, "tau"))
        self._pool = self._si[:, _POOL_AT:]  # pickling does not keep views
        self._link_backend()

    # -- seeding and resets -------------------------------------------------------------
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
        if self._cal is not None:
            idx = self._draw_calibrated(envs, trajectories)
        elif trajectories is None:
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

    def _draw_calibrated(self, envs: NDArray[np.int64], trajectories: Any) -> NDArray[np.int64]:
        """``calibration = K``: each sub-environment of ``envs`` draws its trajectory (unless
        given) and then its calibration reaches from its own generator, as the single
        environment's reset does; the summaries are kept for the observations."""
        assert self._cal is not None
        idx = np.empty(len(envs), dtype=np.int64)
        for j, i in enumerate(np.asarray(envs).tolist()):
            rng = self._rngs[i]
            assert rng is not None
            l = int(rng.integers(self._n_traj)) if trajectories is None else int(trajectories[j])
            summary, self._drawn[i] = self._cal.draw(rng, l)
            self._summary[i] = summary.astype(np.float32)
            idx[j] = l
        return idx

    def reset(
        self,
        *,
        seed: int | Sequence[int | None] | None = None,
        options: dict[str, Any] | None = None,
    ) -> tuple[NDArray[np.float32], dict[str, Any]]:
        options = options or {}
        envs = self._reset_targets(options)
        for i in self._seed_rngs(seed):
            if self._cal is None:
                self._refill(i)
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
        batched as ``SyncVectorEnv`` batches the single environments' numeric reset
        infos (the text: :attr:`trajectory_labels`; called only when some
        sub-environment was reset: no per-step work)."""
        idx = self._si[:, _IDX]
        info["trajectory_index"] = np.where(reset, idx, 0)
        info["_trajectory_index"] = reset
        envs = np.flatnonzero(reset)
        if self._cal is not None:
            drawn = np.zeros_like(self._drawn)
            drawn[envs] = self._drawn[envs]
            info["calibration_trajectories"] = drawn
            info["_calibration_trajectories"] = reset

    def _observe(self) -> NDArray[np.float32]:
        si = self._si
        obs = self._obs_table[si[:, _IDX], si[:, _K]]
        obs[:, self._cur] = np.clip(self._sf[:, : self._dim], self._cur_low, self._cur_high)
        if self._cal is not None:
            return np.concatenate([obs, self._summary], axis=1)
        return obs

    def _record_history(self) -> None:
        if self._history is not None:
            # after a step, every sub-environment's current state is at its grid point k
            # (0 right after a reset)
            self._history[self._arange, self._si[:, _K]] = self._sf[:, : self._dim]

    # -- stepping -----------------------------------------------------------------------
    def step(self, actions: Any) -> StepResult:
        a = self._check_actions(actions)
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
        self._raise_ended(i)

    def _infos(
        self, out_f: NDArray[np.float64], out_b: NDArray[np.bool_], n_term: int, n_reset: int
    ) -> dict[str, Any]:
        """The vector infos of a step from the float and flag outputs (views, no copies).

        As ``SyncVectorEnv``, a key is present only when some sub-environment reports it:
        on a step where every sub-environment autoresets (NEXT_STEP) or ends (SAME_STEP)
        the step keys are left out, not given all-False masks.
        """
        if not (n_term or n_reset):
            return self._step_infos(out_f, out_b[2])
        info = self._step_infos(out_f, out_b[2]) if out_b[2].any() else {}
        terminated, reset = out_b[0], out_b[3]
        t = self._n_info + 1  # the row of tau
        if self._mode == SAME_STEP:
            if n_reset:
                final = self._step_infos(out_f, reset)
                if n_term:
                    for r, key in enumerate(self._end_names, start=t + 1):
                        final[key] = out_f[r]
                        final["_" + key] = terminated
                self._add_final(info, self._final_obs, final, reset)
        elif n_term:
            for r, key in enumerate(self._end_names, start=t + 1):
                info[key] = out_f[r]
                info["_" + key] = terminated
        if n_reset:
            self._add_reset_infos(info, reset)
        return info

    def _step_numpy(
        self,
        a: NDArray[np.float64],
        obs: NDArray[np.float32],
        out_f: NDArray[np.float64],
        out_b: NDArray[np.bool_],
    ) -> tuple[int, int, int]:
        """:func:`motion_envs.envs._fused.batch_step` in batched numpy (same results)."""
        si, sf, dim, n = self._si, self._sf, self._dim, self._n_steps
        resetting = self._resetting(si[:, _AUTORESET])
        finite = np.isfinite(a).all(axis=1)
        if not finite.all():
            return 1, int(np.flatnonzero(~finite)[0]), 0
        a = np.clip(a, -1.0, 1.0)
        active = ~resetting
        k = si[:, _K].copy()
        rows = self._table[:, si[:, _IDX] * n + np.minimum(k, n - 1)]
        if self.num_envs < _SCALAR_BELOW:
            q, reward, values = self._scalar_steps(rows, a)
        else:
            q, reward, values = self.kind.batch_step(rows, a, self.residual_scale, self._weights)
        out_f[0] = np.where(active, reward, 0.0)
        for r, value in enumerate(values, start=1):
            out_f[r] = value
        sf[active, :dim] = q[active]
        for j, src in enumerate(self._max_src, start=dim):
            np.maximum(sf[:, j], np.where(active, values[src], 0.0), out=sf[:, j])
        si[:, _K] += active
        si[:, _ELAPSED] += active
        terminated = active & (si[:, _K] == n)
        truncated = active & (si[:, _ELAPSED] >= self._max_steps)
        t = self._n_info + 1  # the row of tau
        out_f[t] = k / (n - 1)
        out_f[t + 1 :] = sf[:, dim:].T
        out_b[0] = terminated
        out_b[1] = truncated
        ended = terminated | truncated
        if self._mode == SAME_STEP:
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

    def _scalar_steps(
        self, rows: NDArray[np.float64], a: NDArray[np.float64]
    ) -> tuple[NDArray[np.float64], Any, list[Any]]:
        """:meth:`ReachKind.batch_step` as the single environment's scalar step per
        sub-environment (the same arithmetic, so the same bits; faster for few)."""
        step, scale, w = self.kind.scalar_step, self.residual_scale, self._weights
        outs = [step(r, act, scale, w) for r, act in zip(rows.T.tolist(), a.tolist(), strict=True)]
        values = [np.array([o[2][key] for o in outs]) for key in self.kind.step_keys]
        return np.array([o[0] for o in outs]), np.array([o[1] for o in outs]), values

    def close_extras(self, **kwargs: Any) -> None:
        self.single.close()

    def _render_env(self, i: int) -> NDArray[np.uint8]:
        single = self.single
        single._index = int(self._si[i, _IDX])
        assert self._history is not None
        single._history = [tuple(q) for q in self._history[i, : self._si[i, _K] + 1]]
        frame = single.render()
        assert frame is not None  # render_mode is "rgb_array"
        return np.asarray(frame, dtype=np.uint8)


def step_info_builder(keys: tuple[str, ...]) -> Callable[[Any, Any], dict[str, Any]]:
    """``build(out_f, mask)``: the per-step vector infos, ``{keys[j]: out_f[1 + j],
    "_" + keys[j]: mask, ...}``, as a function holding one dict display (generated
    once, as :mod:`dataclasses` generates ``__init__``): twice as fast as a loop, and
    built every step."""
    for key in keys:
        if not key.isidentifier():
            raise ValueError(f"an info key must be an identifier; got {key!r}")
    items = ", ".join(f"{key!r}: out_f[{r}], {'_' + key!r}: mask" for r, key in enumerate(keys, 1))
    namespace: dict[str, Any] = {}
    exec(f"def build(out_f, mask):\n    return {{{items}}}\n", namespace)
    build: Callable[[Any, Any], dict[str, Any]] = namespace["build"]
    return build
