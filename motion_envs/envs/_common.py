"""Argument checks and episode mechanics shared by the single replay environments.

Both environments replay one precomputed trajectory of a task per episode on the
:data:`N_STEPS`-point grid (``task.steps`` and ``task.obs``, see the task dataclasses);
:class:`ReplayEnv` holds what does not depend on the kind of motion: argument checks,
drawing the trajectory at reset, the per-step bookkeeping, the render guard, ``close``
and pickling. The step arithmetic and the reward stay in the environment modules.
"""

from __future__ import annotations

import dataclasses
import math
import os
from collections.abc import Mapping
from typing import Any

import gymnasium as gym
import numpy as np
from numpy.typing import NDArray

__all__ = [
    "MAX_FRAME_SIZE",
    "MAX_NUM_ENVS",
    "MAX_REWARD_WEIGHT",
    "N_STEPS",
    "JsonSpecMixin",
    "LazyRendererMixin",
    "ReplayEnv",
    "ReplayTask",
    "SideCameraMixin",
    "as_action",
    "check_choice",
    "check_fraction",
    "check_integer",
    "check_max_episode_steps",
    "check_num_envs",
    "check_number",
    "check_reward_weights",
    "check_scale",
    "check_seed",
    "check_val_fraction",
    "clipped_pair",
    "has_render_mode",
    "reset_labels",
    "timing_bounds",
]

#: Steps per episode: the 50 points of the normalised-time grid.
N_STEPS = 50

#: Largest accepted reward weight (keeps every reward finite: errors are bounded).
MAX_REWARD_WEIGHT = 1e6

#: Largest accepted frame ``width`` / ``height`` in pixels.
MAX_FRAME_SIZE = 4096

#: Largest accepted ``num_envs`` of a native vector environment.
MAX_NUM_ENVS = 2**24

# The checks below are shared by the single and the native vector environments (the
# vector environments build a single one first), so the same bad argument raises the
# same ValueError in both.


def check_number(value: Any, name: str, low: float, high: float, low_open: bool = False) -> float:
    """``value`` as a finite ``float`` in ``[low, high]`` (``(low, high]`` if ``low_open``).

    Bools, strings, complex and NaN/inf are rejected with ``ValueError`` naming ``name``.
    """
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ValueError(f"{name} must be a real number; got {value!r}")
    v = float(value)
    below = v <= low if low_open else v < low
    if not math.isfinite(v) or below or v > high:
        bracket = "(" if low_open else "["
        raise ValueError(f"{name} must be finite and in {bracket}{low:g}, {high:g}]; got {value!r}")
    return v


def check_integer(value: Any, name: str, low: int, high: int) -> int:
    """``value`` as an ``int`` in ``[low, high]``; ``ValueError`` naming ``name`` else."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise ValueError(f"{name} must be an integer in [{low}, {high}]; got {value!r}")
    if not low <= value <= high:
        raise ValueError(f"{name} must be an integer in [{low}, {high}]; got {value!r}")
    return int(value)


def check_fraction(test_fraction: Any) -> float:
    """``test_fraction`` as a float strictly between 0 and 1."""
    v = check_number(test_fraction, "test_fraction", 0.0, 1.0, low_open=True)
    if v >= 1.0:
        raise ValueError(f"test_fraction must be finite and in (0, 1); got {test_fraction!r}")
    return v


def check_seed(value: Any, name: str = "split_seed") -> int:
    """A seed: an integer in ``[0, 2**63 - 1]``."""
    return check_integer(value, name, 0, 2**63 - 1)


def check_num_envs(num_envs: Any) -> int:
    """``num_envs`` of a native vector environment: an integer in ``[1, MAX_NUM_ENVS]``."""
    return check_integer(num_envs, "num_envs", 1, MAX_NUM_ENVS)


def check_max_episode_steps(max_episode_steps: Any, default: int) -> int:
    """``max_episode_steps`` (``None``: ``default``): an integer ``>= 1``."""
    if max_episode_steps is None:
        return default
    return check_integer(max_episode_steps, "max_episode_steps", 1, 2**62)


def as_action(action: Any, shape: tuple[int, ...], name: str = "action") -> NDArray[np.float64]:
    """``action`` as a float64 array of ``shape``.

    ``ValueError`` for a non-numeric action (a dict, a string, complex numbers, objects)
    or a wrong shape; finiteness and clipping are left to the caller's hot path.
    """
    a = np.asarray(action)
    if a.dtype.kind not in "fiu":
        raise ValueError(
            f"{name} must be an array of real numbers; got {type(action).__name__} "
            f"(dtype {a.dtype})"
        )
    if a.shape != shape:
        raise ValueError(f"{name} must have shape {shape}; got shape {a.shape}")
    return a.astype(np.float64, copy=False)


def check_choice(value: Any, name: str, choices: tuple[str, ...]) -> str:
    """``value`` as ``str`` if it is one of ``choices``; else ``ValueError`` naming ``name``."""
    if value not in choices:
        raise ValueError(f"{name} must be one of {list(choices)}; got {value!r}")
    return str(value)


def check_reward_weights(
    weights: Mapping[str, float] | None, defaults: Mapping[str, float]
) -> dict[str, float]:
    """``defaults`` updated with ``weights`` (known keys, finite numbers ``>= 0``)."""
    out = dict(defaults)
    if weights is None:
        return out
    if not isinstance(weights, Mapping):
        raise ValueError(f"reward_weights must be a mapping; got {type(weights).__name__}")
    for key, value in weights.items():
        if key not in out:
            raise ValueError(f"reward_weights has unknown key {key!r}; expected keys {list(out)}")
        if isinstance(value, bool) or not isinstance(value, (int, float, np.floating)):
            raise ValueError(f"reward_weights[{key!r}] must be a number; got {value!r}")
        if not math.isfinite(value) or not 0 <= value <= MAX_REWARD_WEIGHT:
            raise ValueError(
                f"reward_weights[{key!r}] must be finite and in [0, {MAX_REWARD_WEIGHT:g}]; "
                f"got {value!r}"
            )
        out[key] = float(value)
    return out


def check_scale(residual_scale: Any, maximum: float = math.inf) -> float:
    """``residual_scale`` as a finite ``float`` in ``(0, maximum]``."""
    return check_number(residual_scale, "residual_scale", 0.0, maximum, low_open=True)


def reset_labels(task: Any) -> dict[str, NDArray[np.object_]]:
    """The text entries of a single environment's reset ``info``, for every trajectory.

    ``trajectory_id`` and ``task`` (and ``subject`` when the task has subjects) ->
    ``(L,)`` object array of ``str``; the native vector environments batch these exactly
    as ``SyncVectorEnv`` batches the single environments' reset infos.
    """
    fields = {"trajectory_id": "trajectory_ids", "task": "tasks", "subject": "subjects"}
    return {
        key: np.asarray(getattr(task, attr)).astype(str).astype(object)
        for key, attr in fields.items()
        if hasattr(task, attr)
    }


def check_val_fraction(val_fraction: float, split: str) -> float:
    """``val_fraction`` as a ``float`` in ``[0, 1)``; ``split="val"`` needs it ``> 0``.

    The validation split holds out this share of the *training* subjects (orientation)
    or demonstrations (position), so hyper-parameters and checkpoints can be chosen
    without touching the test split.
    """
    if isinstance(val_fraction, bool) or not isinstance(val_fraction, (int, float, np.floating)):
        raise ValueError(f"val_fraction must be a number in [0, 1); got {val_fraction!r}")
    if not 0.0 <= float(val_fraction) < 1.0:
        raise ValueError(f"val_fraction must be in [0, 1); got {val_fraction!r}")
    if split == "val" and val_fraction == 0:
        raise ValueError("split='val' needs val_fraction > 0 (the share of training data held out)")
    return float(val_fraction)


def timing_bounds(max_duration: float) -> tuple[float, float]:
    """Bounds ``(0, high)`` of the v1 timing observations (duration, elapsed; seconds):
    the dataset's longest movement, padded, so they hold on every split."""
    return 0.0, float(np.float32(max_duration * 1.001 + 1e-6))


class ReplayTask:
    """Properties of the precomputed episodes of a split (the task dataclasses)."""

    steps: NDArray[np.float64]  # (L, n, row width)
    obs: NDArray[np.float32]  # (L, n + 1, obs_dim)

    @property
    def n_trajectories(self) -> int:
        return int(self.steps.shape[0])

    @property
    def obs_dim(self) -> int:
        return int(self.obs.shape[2])


def json_safe_spec(spec: Any) -> Any:
    """``spec`` with a path-like ``data`` argument stored as ``str`` (``os.fspath``), so
    ``spec.to_json()`` works and the spec remakes the same environment."""
    if spec is None or not isinstance(spec.kwargs.get("data"), os.PathLike):
        return spec
    return dataclasses.replace(spec, kwargs={**spec.kwargs, "data": os.fspath(spec.kwargs["data"])})


class JsonSpecMixin:
    """``spec`` property whose setter (called by ``gym.make``/``gym.make_vec``) stores a
    path-like ``data`` argument as a string: see :func:`json_safe_spec`."""

    _spec: Any = None

    @property
    def spec(self) -> Any:
        return self._spec

    @spec.setter
    def spec(self, value: Any) -> None:
        self._spec = json_safe_spec(value)


class LazyRendererMixin:
    """``close`` and pickling for an environment that opens its renderer (``_renderer``)
    on the first ``render()``: ``close`` releases it, a pickled copy leaves it out (a
    copy opens its own)."""

    _renderer: Any = None

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

    def __getstate__(self) -> dict[str, Any]:
        state = self.__dict__.copy()
        state["_renderer"] = None
        return state


def clipped_pair(action: Any) -> tuple[float, float, bool]:
    """A 2-vector action as ``(ax, az, invalid)``: each entry clipped to ``[-1, 1]``, NaN
    counted as 0 (``invalid`` True when an entry was not finite); ValueError for another
    shape (the juggling environments' residual)."""
    a = np.asarray(action, dtype=np.float64)
    if a.shape != (2,):
        raise ValueError(f"action must have shape (2,); got shape {a.shape}")
    ax, az = float(a[0]), float(a[1])
    invalid = not (math.isfinite(ax) and math.isfinite(az))
    if invalid:
        ax = 0.0 if math.isnan(ax) else ax
        az = 0.0 if math.isnan(az) else az
    ax = -1.0 if ax < -1.0 else (1.0 if ax > 1.0 else ax)
    az = -1.0 if az < -1.0 else (1.0 if az > 1.0 else az)
    return ax, az, invalid


def has_render_mode(render_mode: str | None) -> bool:
    """False (with Gymnasium's warning) when ``render()`` is called without a mode."""
    if render_mode is None:
        gym.logger.warn(
            "render() called without a render_mode; pass render_mode='rgb_array' to gym.make(...)"
        )
        return False
    return True


class SideCameraMixin(LazyRendererMixin):
    """``render()`` of a MuJoCo environment seen through its ``side`` camera: the
    environment has ``render_mode``, ``width``, ``height``, ``model``, ``data``, an
    episode state ``_state`` (None before ``reset``) and :meth:`_sync_scene` (poses,
    camera and lights recomputed for drawing)."""

    render_mode: str | None
    width: int
    height: int
    model: Any
    data: Any
    _state: Any = None

    def _sync_scene(self) -> None:
        raise NotImplementedError

    def render(self) -> NDArray[np.uint8] | None:
        if not has_render_mode(self.render_mode):
            return None
        if self._state is None:
            raise RuntimeError("call reset() before render()")
        if self._renderer is None:
            from motion_envs.envs.rendering import new_mujoco_renderer

            self.model.vis.global_.offwidth = max(self.model.vis.global_.offwidth, self.width)
            self.model.vis.global_.offheight = max(self.model.vis.global_.offheight, self.height)
            self._renderer = new_mujoco_renderer(self.model, self.height, self.width)
        self._sync_scene()
        self._renderer.update_scene(self.data, camera="side")
        frame: NDArray[np.uint8] = self._renderer.render()
        return frame


class ReplayEnv(JsonSpecMixin, LazyRendererMixin, gym.Env):
    """Episode mechanics of a single replay environment.

    A subclass sets ``task`` (``n_trajectories``, ``steps``, ``obs``, ``trajectory_ids``,
    ``tasks``), ``_starts`` (the ``(L, D)`` start of each trajectory), ``_cur`` (the
    slice of the observation that holds the current state) and, if the observation clips
    the current state, ``_cur_bounds`` (its ``(low, high)`` per component) in ``__init__``, after
    :meth:`_check_arguments`; and implements ``step`` (ending with :meth:`_end_step`) and
    :meth:`_render_frame`.
    """

    task: Any
    _starts: NDArray[np.float64]
    _cur: slice
    _cur_bounds: tuple[tuple[float, ...], tuple[float, ...]] | None = None

    def _check_arguments(
        self,
        render_mode: str | None,
        width: int,
        height: int,
        residual_scale: float,
        reward_weights: Mapping[str, float] | None,
        default_weights: Mapping[str, float],
        max_scale: float = math.inf,
        test_fraction: float = 0.25,
        split_seed: int = 0,
    ) -> None:
        """Check and store the arguments every replay environment takes; no episode yet.

        ``residual_scale`` must lie in ``(0, max_scale]``, ``test_fraction`` in ``(0, 1)``,
        ``split_seed`` be an integer ``>= 0``, ``width`` and ``height`` integers in
        ``[16, MAX_FRAME_SIZE]``, reward weights in ``[0, MAX_REWARD_WEIGHT]``.
        """
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(
                f"render_mode must be None or one of {self.metadata['render_modes']}; "
                f"got {render_mode!r}"
            )
        for name, value in (("width", width), ("height", height)):
            check_integer(value, name, 16, MAX_FRAME_SIZE)
        self.residual_scale = check_scale(residual_scale, max_scale)
        check_fraction(test_fraction)
        check_seed(split_seed)
        self.reward_weights = check_reward_weights(reward_weights, default_weights)
        self.render_mode = render_mode
        self.width, self.height = int(width), int(height)
        self._renderer: Any = None
        self._index = -1
        self._k = N_STEPS
        self._history: list[tuple[float, ...]] = []

    # -- episode --------------------------------------------------------------------
    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[NDArray[np.float32], dict[str, Any]]:
        super().reset(seed=seed)
        L = self.task.n_trajectories
        if options is not None and options.get("trajectory") is not None:
            index = options["trajectory"]
            if isinstance(index, bool) or not isinstance(index, (int, np.integer)):
                raise ValueError(f"options['trajectory'] must be an integer; got {index!r}")
            if not 0 <= index < L:
                raise ValueError(f"options['trajectory'] must be in [0, {L}); got {index}")
            index = int(index)
        else:
            index = int(self.np_random.integers(L))
        self._index = index
        self._k = 0
        self._steps = self.task.steps[index].tolist()
        self._obs = self.task.obs[index]
        start = tuple(self._starts[index].tolist())
        self._history = [start]
        self._max_error = 0.0
        obs = self._obs[0].copy()
        obs[self._cur] = start
        info = {
            "trajectory_index": index,
            "trajectory_id": str(self.task.trajectory_ids[index]),
            "task": str(self.task.tasks[index]),
        }
        return obs, info

    def _end_step(
        self, k: int, q: tuple[float, ...], err: float, info: dict[str, Any]
    ) -> tuple[NDArray[np.float32], bool]:
        """Record state ``q`` with error ``err`` at grid point ``k``; add ``tau`` (and, at
        the episode's end, ``max_error``) to ``info``; the next observation and whether
        the episode terminated."""
        self._k = k + 1
        self._history.append(q)
        if err > self._max_error:
            self._max_error = err
        obs = self._obs[k + 1].copy()
        if self._cur_bounds is None:
            obs[self._cur] = q
        else:
            lo, hi = self._cur_bounds
            obs[self._cur] = [min(max(v, a), b) for v, a, b in zip(q, lo, hi, strict=True)]
        info["tau"] = k / (N_STEPS - 1)
        terminated = k + 1 == N_STEPS
        if terminated:
            info["max_error"] = self._max_error
        return obs, terminated

    # -- rendering ------------------------------------------------------------------
    def render(self) -> NDArray[np.uint8] | None:
        if not has_render_mode(self.render_mode):
            return None
        if self._index < 0:
            raise RuntimeError("call reset() before render()")
        return self._render_frame()

    def _render_frame(self) -> NDArray[np.uint8]:
        raise NotImplementedError
