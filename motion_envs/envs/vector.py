"""Native vector environments: ``N`` episodes stepped together in batched numpy.

``gym.make_vec(id, num_envs=N, vectorization_mode="vector_entry_point")`` builds these.
Sub-environment ``i`` is bit-identical to a single environment made with the same
arguments and seeded with ``seed + i`` (as :class:`gymnasium.vector.SyncVectorEnv` seeds
its copies): the step arithmetic is the same kernel
(:mod:`motion_envs.envs._kernels`) evaluated on arrays, each sub-environment draws its
trajectories from its own generator, and episodes end and restart as under
``SyncVectorEnv`` with Gymnasium's default ``AutoresetMode.NEXT_STEP`` (the step after
an episode's end resets that sub-environment, ignores its action and returns reward 0).
``max_episode_steps`` (from the registration) truncates like ``TimeLimit``.

``infos`` follow the vector convention: ``infos[key]`` is an ``(N,)`` array and
``infos["_" + key]`` marks the sub-environments it applies to (entries outside the mask
are unspecified, not necessarily 0 as under ``SyncVectorEnv``).
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
    as_action,
    check_max_episode_steps,
    check_num_envs,
    reset_labels,
)

__all__ = ["OrientationReachVectorEnv", "PositionReachVectorEnv"]

# Below this many sub-environments the orientation step runs the scalar kernel per
# environment (numpy's per-call overhead dominates small batches).
_SCALAR_BELOW = 8

# observations, rewards, terminations, truncations, infos
_StepResult = tuple[
    NDArray[np.float32], NDArray[np.float64], NDArray[np.bool_], NDArray[np.bool_], dict[str, Any]
]


class _ReplayVectorEnv(gym.vector.VectorEnv):
    """Shared episode bookkeeping of the native vector environments."""

    metadata: ClassVar[dict[str, Any]] = {
        "render_modes": ["rgb_array"],
        "render_fps": 25,
        "autoreset_mode": AutoresetMode.NEXT_STEP,
    }

    def _setup(self, num_envs: int, max_episode_steps: int | None, single: Any) -> None:
        """Set up ``num_envs`` copies of ``single`` (a ``_common.ReplayEnv``, already checked)."""
        task = single.task
        self.task = task
        self._n_steps = N_STEPS
        self._n_traj = task.n_trajectories
        self.num_envs = check_num_envs(num_envs)
        self._max_steps = check_max_episode_steps(max_episode_steps, self._n_steps)
        self.single = single  # validated arguments, spaces and rendering
        self.residual_scale = single.residual_scale
        self.reward_weights = single.reward_weights
        self.single_action_space = single.action_space
        self.single_observation_space = single.observation_space
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.render_mode = single.render_mode
        N = self.num_envs
        self._rngs: list[np.random.Generator | None] = [None] * N
        self._index = np.zeros(N, dtype=np.int64)
        self._k = np.zeros(N, dtype=np.int64)
        self._elapsed = np.zeros(N, dtype=np.int64)
        self._max_error = np.zeros(N)
        self._autoreset = np.zeros(N, dtype=bool)
        self._started = False
        self._arange = np.arange(N)
        L, n, width = task.steps.shape
        self._table = np.ascontiguousarray(task.steps.reshape(L * n, width).T)  # (width, L n)
        self._obs_table = task.obs.reshape(L * (n + 1), task.obs_dim)
        self._starts = single._starts
        self._cur = single._cur  # the observation's slice of the current state
        dim = self._cur.stop - self._cur.start
        self._current = np.zeros((N, dim))
        self._history: NDArray[np.float64] | None = (
            np.zeros((N, n + 1, dim)) if self.render_mode is not None else None
        )

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

    def _draw(self, envs: NDArray[np.int64], trajectories: Any = None) -> None:
        """Start new episodes in sub-environments ``envs`` (trajectory from each rng)."""
        for j, i in enumerate(envs.tolist()):
            if trajectories is not None:
                self._index[i] = int(trajectories[j])
            else:
                self._index[i] = int(self._rngs[i].integers(self._n_traj))  # type: ignore[union-attr]
        self._k[envs] = 0
        self._elapsed[envs] = 0
        self._max_error[envs] = 0.0
        self._reset_state(envs)

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
        self._draw(envs, traj)
        self._autoreset[envs] = False
        self._started = True
        obs = self._observe(self._arange, reset=np.isin(self._arange, envs))
        return obs, self._reset_infos(envs)

    def _reset_infos(self, envs: NDArray[np.int64]) -> dict[str, Any]:
        """The single environments' reset infos, batched as ``SyncVectorEnv`` does: the
        same keys, integers in an int array (0 outside the mask), text in an object
        array (None outside the mask)."""
        mask = np.zeros(self.num_envs, dtype=bool)
        mask[envs] = True
        infos: dict[str, Any] = {"trajectory_index": np.where(mask, self._index, 0)}
        for key, labels in self._reset_labels.items():
            column = np.full(self.num_envs, None, dtype=object)
            column[envs] = labels[self._index[envs]]
            infos[key] = column
        for key in list(infos):
            infos["_" + key] = mask.copy()
        return infos

    @property
    def _reset_labels(self) -> dict[str, NDArray[np.object_]]:
        """Text reset infos of the single environment: key -> label of each trajectory."""
        if getattr(self, "_labels", None) is None:
            self._labels = reset_labels(self.task)
        return self._labels

    def _check_actions(
        self, actions: Any, dim: int
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The clipped ``(N, dim)`` actions and the step table's columns of the grid points."""
        if not self._started:
            raise RuntimeError("call reset() before step()")
        a = as_action(actions, (self.num_envs, dim), "actions")
        if not np.isfinite(a).all():
            raise ValueError("actions must be finite; got NaN or infinite entries")
        n = self._n_steps
        k = np.minimum(self._k, n - 1)
        return np.clip(a, -1.0, 1.0), self._table[:, self._index * n + k]

    def _finish_step(
        self,
        q: Sequence[NDArray[np.float64]],
        err: NDArray[np.float64],
        reward: NDArray[np.float64],
        info: dict[str, Any],
    ) -> _StepResult:
        """Record the states ``q`` (components), advance the counters, handle episode ends
        and autoresets, build the outputs."""
        resetting = self._autoreset
        active = ~resetting
        qs = np.stack(q, axis=1)
        self._current = np.where(active[:, None], qs, self._current)
        if self._history is not None:
            rows_a = np.flatnonzero(active)
            self._history[rows_a, self._k[rows_a] + 1] = qs[rows_a]
        self._k += active
        self._elapsed += active
        np.maximum(self._max_error, np.where(active, err, 0.0), out=self._max_error)
        terminated = active & (self._k == self._n_steps)
        truncated = active & (self._elapsed >= self._max_steps)
        reward = np.where(active, reward, 0.0)
        for key in list(info):
            info["_" + key] = active  # entries outside the mask are unspecified
        info["tau"] = (self._k - 1) / (self._n_steps - 1)
        info["_tau"] = active
        if terminated.any():
            self._end_infos(info, terminated)
        reset_envs = np.flatnonzero(resetting)
        if reset_envs.size:
            self._draw(reset_envs)
            for key, value in self._reset_infos(reset_envs).items():
                info[key] = value
        obs = self._observe(self._arange, reset=resetting)
        self._autoreset = terminated | truncated
        return obs, reward, terminated, truncated, info

    def close_extras(self, **kwargs: Any) -> None:
        self.single.close()

    def render(self) -> tuple[NDArray[np.uint8], ...] | None:
        if self.render_mode is None:
            gym.logger.warn("render() called without a render_mode")
            return None
        return tuple(self._render_env(i) for i in range(self.num_envs))

    # -- per environment kind (overridden to add state) ---------------------------------
    def _reset_state(self, envs: NDArray[np.int64]) -> None:
        self._current[envs] = self._starts[self._index[envs]]
        if self._history is not None:
            self._history[envs, 0] = self._current[envs]

    def _observe(self, envs: NDArray[np.int64], reset: NDArray[np.bool_]) -> NDArray[np.float32]:
        obs = self._obs_table[self._index * (self._n_steps + 1) + self._k]
        obs[:, self._cur] = self._current
        return obs

    def _end_infos(self, info: dict[str, Any], ended: NDArray[np.bool_]) -> None:
        info["max_error"] = np.where(ended, self._max_error, 0.0)
        info["_max_error"] = ended

    def _render_env(self, i: int) -> NDArray[np.uint8]:
        single = self.single
        single._index = int(self._index[i])
        assert self._history is not None
        single._history = [tuple(q) for q in self._history[i, : self._k[i] + 1]]
        return single.render()  # type: ignore[return-value]


class OrientationReachVectorEnv(_ReplayVectorEnv):
    """``num_envs`` copies of :class:`~motion_envs.envs.orientation_reach.OrientationReachEnv`.

    Takes the single environment's keyword arguments plus ``num_envs`` and
    ``max_episode_steps`` (default: the registration's 50). Observations, rewards,
    terminations and truncations are bit-identical to ``SyncVectorEnv`` of single
    environments with the same seeds; ``infos`` carry the same per-step terms and, at an
    episode's end, ``max_error`` and ``max_geodesic_error``.
    """

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
        )
        self._setup(num_envs, max_episode_steps, single)
        self._max_geodesic = np.zeros(self.num_envs)

    def _reset_state(self, envs: NDArray[np.int64]) -> None:
        super()._reset_state(envs)
        self._max_geodesic[envs] = 0.0

    def step(self, actions: Any) -> _StepResult:
        a, rows = self._check_actions(actions, 3)
        ax, ay, az = a[:, 0], a[:, 1], a[:, 2]
        if self.num_envs < _SCALAR_BELOW:
            # few environments: the scalar kernel (same arithmetic, bit-identical) is faster
            outs = [
                K.orientation_step_scalar(row, *act, self.residual_scale)
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
        w = self.reward_weights
        r_res = -w["residual"] * err
        r_geo = -w["geodesic"] * geo
        r_act = -w["action"] * (ax * ax + ay * ay + az * az)
        reward = r_res + r_geo + r_act
        active = ~self._autoreset
        np.maximum(self._max_geodesic, np.where(active, geo, 0.0), out=self._max_geodesic)
        info = {
            "error": err,
            "geodesic_error": geo,
            "reward_residual": r_res,
            "reward_geodesic": r_geo,
            "reward_action": r_act,
        }
        return self._finish_step(q, err, reward, info)

    def _end_infos(self, info: dict[str, Any], ended: NDArray[np.bool_]) -> None:
        super()._end_infos(info, ended)
        info["max_geodesic_error"] = np.where(ended, self._max_geodesic, 0.0)
        info["_max_geodesic_error"] = ended


class PositionReachVectorEnv(_ReplayVectorEnv):
    """``num_envs`` copies of :class:`~motion_envs.envs.position_reach.PositionReachEnv`.

    Takes the single environment's keyword arguments plus ``num_envs`` and
    ``max_episode_steps`` (default: the registration's 50); bit-identical to
    ``SyncVectorEnv`` of single environments with the same seeds.
    """

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
        )
        self._setup(num_envs, max_episode_steps, single)
        self._D = self.task.n_dims

    def step(self, actions: Any) -> _StepResult:
        D = self._D
        a, rows = self._check_actions(actions, D)
        cols = [a[:, i] for i in range(D)]
        q, err = K.position_step(K.BATCH, rows[:D], rows[D:], cols, self.residual_scale)
        w = self.reward_weights
        sq = 0.0
        for c in cols:
            sq = sq + c * c
        r_dist = -w["distance"] * err
        r_act = -w["action"] * sq
        reward = r_dist + r_act
        info = {"error": err, "reward_distance": r_dist, "reward_action": r_act}
        return self._finish_step(q, err, reward, info)
