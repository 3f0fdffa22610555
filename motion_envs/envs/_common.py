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
    "N_STEPS",
    "JsonSpecMixin",
    "ReplayEnv",
    "ReplayTask",
    "check_choice",
    "check_reward_weights",
    "check_scale",
    "check_val_fraction",
    "timing_bounds",
]

#: Steps per episode: the 50 points of the normalised-time grid.
N_STEPS = 50


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
        if not math.isfinite(value) or value < 0:
            raise ValueError(f"reward_weights[{key!r}] must be finite and >= 0; got {value!r}")
        out[key] = float(value)
    return out


def check_scale(residual_scale: float) -> float:
    """``residual_scale`` as a finite ``float > 0``."""
    if isinstance(residual_scale, bool) or not isinstance(
        residual_scale, (int, float, np.floating)
    ):
        raise ValueError(f"residual_scale must be a number > 0; got {residual_scale!r}")
    if not math.isfinite(residual_scale) or residual_scale <= 0:
        raise ValueError(f"residual_scale must be finite and > 0; got {residual_scale!r}")
    return float(residual_scale)


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


class ReplayEnv(JsonSpecMixin, gym.Env):
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
    ) -> None:
        """Check and store the arguments every replay environment takes; no episode yet."""
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(
                f"render_mode must be None or one of {self.metadata['render_modes']}; "
                f"got {render_mode!r}"
            )
        for name, value in (("width", width), ("height", height)):
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 16:
                raise ValueError(f"{name} must be an integer >= 16; got {value!r}")
        self.residual_scale = check_scale(residual_scale)
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

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

    def __getstate__(self) -> dict[str, Any]:
        state = self.__dict__.copy()
        state["_renderer"] = None
        return state
