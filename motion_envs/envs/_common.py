"""Argument checks and mixins shared by the environments (reaching and juggling).

The reaching environments' episode mechanics are in :mod:`motion_envs.envs._reach`.
"""

from __future__ import annotations

import dataclasses
import math
import os
from collections.abc import Mapping, Sequence
from typing import Any

import gymnasium as gym
import numpy as np
from numpy.typing import NDArray

__all__ = [
    "MAX_FRAME_SIZE",
    "MAX_NUM_ENVS",
    "MAX_REWARD_WEIGHT",
    "N_STEPS",
    "PER_ENV_ARRAYS",
    "JsonSpecMixin",
    "LazyRendererMixin",
    "SideCameraMixin",
    "as_action",
    "check_autoreset_mode",
    "check_choice",
    "check_data",
    "check_fraction",
    "check_integer",
    "check_max_episode_steps",
    "check_num_envs",
    "check_number",
    "check_render",
    "check_reward_weights",
    "check_scale",
    "check_seed",
    "check_val_fraction",
    "clipped_pair",
    "draw_trajectory",
    "env_footprint",
    "has_render_mode",
    "physical_memory",
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
    try:
        v = float(value)
    except OverflowError:  # an int beyond float64's range (10**400)
        v = math.inf
    below = v <= low if low_open else v < low
    if not math.isfinite(v) or below or v > high:
        bracket = "(" if low_open else "["
        raise ValueError(
            f"{name} must be finite and in {bracket}{low:g}, {high:g}]; got {_short(value)}"
        )
    return v


def check_integer(value: Any, name: str, low: int, high: int) -> int:
    """``value`` as an ``int`` in ``[low, high]``; ``ValueError`` naming ``name`` else."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise ValueError(f"{name} must be an integer in [{low}, {high}]; got {value!r}")
    if not low <= value <= high:
        raise ValueError(f"{name} must be an integer in [{low}, {high}]; got {_short(value)}")
    return int(value)


def check_render(render_mode: Any, render_modes: Sequence[str], width: Any, height: Any) -> None:
    """``render_mode`` None or one of ``render_modes``, ``width`` and ``height`` integers in
    ``[16, MAX_FRAME_SIZE]``; ``ValueError`` naming the argument else."""
    if render_mode is not None and render_mode not in render_modes:
        raise ValueError(f"render_mode must be None or one of {render_modes}; got {render_mode!r}")
    for name, value in (("width", width), ("height", height)):
        check_integer(value, name, 16, MAX_FRAME_SIZE)


def draw_trajectory(options: Mapping[str, Any] | None, n: int, rng: np.random.Generator) -> int:
    """The episode's trajectory at ``reset``: ``options["trajectory"]`` (an integer in
    ``[0, n)``, else ``ValueError``) when given, else one drawn uniformly with ``rng``."""
    if options is not None and options.get("trajectory") is not None:
        index = options["trajectory"]
        if isinstance(index, bool) or not isinstance(index, (int, np.integer)):
            raise ValueError(f"options['trajectory'] must be an integer; got {index!r}")
        if not 0 <= index < n:
            raise ValueError(f"options['trajectory'] must be in [0, {n}); got {index}")
        return int(index)
    return int(rng.integers(n))


def _short(value: Any) -> str:
    """``repr(value)``, abbreviated when it is long (a 400-digit integer)."""
    text = repr(value)
    return text if len(text) <= 40 else f"{text[:20]}...({len(text)} characters)"


def check_fraction(test_fraction: Any) -> float:
    """``test_fraction`` as a float strictly between 0 and 1."""
    v = check_number(test_fraction, "test_fraction", 0.0, 1.0, low_open=True)
    if v >= 1.0:
        raise ValueError(f"test_fraction must be finite and in (0, 1); got {test_fraction!r}")
    return v


def check_data(data: Any) -> str | os.PathLike[str]:
    """``data`` of a reaching environment: a non-empty name, path or ``FILE?options``
    string (``str`` or ``os.PathLike``); a one-line ``ValueError`` otherwise (``None``)."""
    if isinstance(data, os.PathLike):
        data = os.fspath(data)
    if not isinstance(data, str) or not data.strip():
        raise ValueError(
            f"data must be a built-in dataset name, a CSV path or a recording "
            f"'FILE.c3d|.bvh|.tsv?options'; got {data!r}"
        )
    return data


def check_seed(value: Any, name: str = "split_seed") -> int:
    """A seed: an integer in ``[0, 2**63 - 1]``."""
    return check_integer(value, name, 0, 2**63 - 1)


def physical_memory() -> int:
    """This machine's physical memory in bytes (``2**40`` where the OS does not say)."""
    try:
        return int(os.sysconf("SC_PHYS_PAGES")) * int(os.sysconf("SC_PAGE_SIZE"))
    except (AttributeError, ValueError, OSError):  # pragma: no cover - not POSIX
        return 2**40


#: Arrays a vector environment keeps per sub-environment, each at most the size of an
#: observation plus an action (observations, actions, rewards, flags, infos, episode
#: state): the multiplier of :func:`env_footprint`.
PER_ENV_ARRAYS = 64


def env_footprint(env: Any) -> int:
    """An estimate, from below, of the bytes one sub-environment like ``env`` holds:
    MuJoCo's model and data buffers (``nbuffer``; the arena is touched lazily and not
    counted) when it has them, plus :data:`PER_ENV_ARRAYS` float64 arrays of its
    observation and action size. Measured (resident memory of 100,000 reaching
    sub-environments, 200 Cascade-v0 ones): 1.9-6.1 kB per reaching sub-environment against
    22-25 kB estimated here, 0.57-0.87 MB per juggling one against 0.24-0.26 MB."""
    size = 0
    for name in ("model", "data"):
        size += int(getattr(getattr(env, name, None), "nbuffer", 0) or 0)
    width = 0
    for space in (getattr(env, "observation_space", None), getattr(env, "action_space", None)):
        shape = getattr(space, "shape", None) or ()
        width += math.prod(shape)
    return max(size + PER_ENV_ARRAYS * 8 * width, 1)


def check_num_envs(num_envs: Any, footprint: int = 0) -> int:
    """``num_envs`` of a vector environment: an integer in ``[1, MAX_NUM_ENVS]`` whose
    sub-environments, ``footprint`` bytes each (:func:`env_footprint`; 0: not checked),
    fit in this machine's physical memory (a one-line ``ValueError`` otherwise)."""
    n = check_integer(num_envs, "num_envs", 1, MAX_NUM_ENVS)
    memory = physical_memory()
    if footprint > 0 and n * footprint > memory:
        raise ValueError(
            f"num_envs={n} needs at least {n * footprint / 1e9:.3g} GB ({footprint / 1e3:.3g} kB "
            f"per sub-environment), more than this machine's {memory / 1e9:.3g} GB of memory; "
            f"use at most {memory // footprint}"
        )
    return n


def check_max_episode_steps(max_episode_steps: Any, default: int) -> int:
    """``max_episode_steps`` (``None``: ``default``): an integer ``>= 1``."""
    if max_episode_steps is None:
        return default
    return check_integer(max_episode_steps, "max_episode_steps", 1, 2**62)


def as_action(action: Any, shape: tuple[int, ...], name: str = "action") -> NDArray[np.float64]:
    """``action`` as a float64 array of ``shape``: THE action check of every environment.

    ``ValueError`` for a non-numeric action (a dict, a string, complex numbers, objects,
    bools) or a wrong shape; finiteness and clipping are left to the caller's hot path.
    """
    try:
        a = np.asarray(action)
    except (ValueError, TypeError, OverflowError) as exc:  # ragged nesting, huge ints
        raise ValueError(f"{name} must be an array of real numbers; got {exc}") from None
    if a.dtype.kind not in "fiu":
        raise ValueError(
            f"{name} must be an array of real numbers; got {type(action).__name__} "
            f"(dtype {a.dtype})"
        )
    if a.shape != shape:
        raise ValueError(f"{name} must have shape {shape}; got shape {a.shape}")
    return a.astype(np.float64, copy=False)


def check_autoreset_mode(mode: Any) -> Any:
    """``mode`` as a ``gymnasium.vector.AutoresetMode`` (the enum or its value, e.g.
    ``"SameStep"``); ``ValueError`` else."""
    from gymnasium.vector import AutoresetMode

    try:
        return mode if isinstance(mode, AutoresetMode) else AutoresetMode(mode)
    except (ValueError, TypeError):
        values = [m.value for m in AutoresetMode]
        raise ValueError(
            f"autoreset_mode must be a gymnasium.vector.AutoresetMode or one of {values}; "
            f"got {mode!r}"
        ) from None


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
        out[key] = check_number(value, f"reward_weights[{key!r}]", 0.0, MAX_REWARD_WEIGHT)
    return out


def check_scale(residual_scale: Any, maximum: float = math.inf) -> float:
    """``residual_scale`` as a finite ``float`` in ``(0, maximum]``."""
    return check_number(residual_scale, "residual_scale", 0.0, maximum, low_open=True)


def check_val_fraction(val_fraction: float, split: str) -> float:
    """``val_fraction`` as a ``float`` in ``[0, 1)``; ``split="val"`` needs it ``> 0``.

    The validation split holds out this share of the *training* subjects (orientation)
    or demonstrations (position), so hyper-parameters and checkpoints can be chosen
    without touching the test split.
    """
    if isinstance(val_fraction, bool) or not isinstance(val_fraction, (int, float, np.floating)):
        raise ValueError(f"val_fraction must be a number in [0, 1); got {val_fraction!r}")
    v = check_number(val_fraction, "val_fraction", 0.0, 1.0)
    if v >= 1.0:
        raise ValueError(f"val_fraction must be in [0, 1); got {val_fraction!r}")
    if split == "val" and v == 0:
        raise ValueError("split='val' needs val_fraction > 0 (the share of training data held out)")
    return v


def timing_bounds(max_duration: float) -> tuple[float, float]:
    """Bounds ``(0, high)`` of the v1 timing observations (duration, elapsed; seconds):
    the dataset's longest movement, padded, so they hold on every split."""
    return 0.0, float(np.float32(max_duration * 1.001 + 1e-6))


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
    if type(action) is np.ndarray and action.shape == (2,) and action.dtype.kind == "f":
        ax, az = action.tolist()  # a float array (the usual action): its values as floats
    else:
        a = as_action(action, (2,))
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
