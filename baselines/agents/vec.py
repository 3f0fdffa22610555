"""The SB3 vector environment an agent trains on (or is rebuilt on to load it).

Environments with a native vector environment (the reaching ones: one compiled loop for
all sub-environments) are used through :class:`baselines.sb3.GymnasiumVecEnv`; the others
(``Juggling-v0``: one MuJoCo scene per sub-environment) through SB3's ``DummyVecEnv`` of
``gym.make`` instances, as rl-baselines3-zoo does for any Gymnasium id.
"""

from __future__ import annotations

import functools
import inspect
from collections.abc import Mapping
from typing import Any

__all__ = ["constructor_keywords", "has_native_vector_env", "make_sb3_vec_env", "takes_keyword"]


def has_native_vector_env(env_id: str) -> bool:
    """True when ``env_id`` is registered with a ``vector_entry_point``."""
    import gymnasium as gym

    import motion_envs  # noqa: F401  (registers the ids, also inside Ray workers)

    return gym.spec(env_id).vector_entry_point is not None


def constructor_keywords(env_id: str) -> frozenset[str] | None:
    """The keyword arguments the constructor of ``env_id`` takes (``self`` left out), or
    None when it takes any (``**kwargs``) or cannot be inspected."""
    import gymnasium as gym
    from gymnasium.envs.registration import load_env_creator

    import motion_envs  # noqa: F401

    entry = gym.spec(env_id).entry_point
    creator = load_env_creator(entry) if isinstance(entry, str) else entry
    if creator is None:
        return None
    params = inspect.signature(creator).parameters
    if any(p.kind is inspect.Parameter.VAR_KEYWORD for p in params.values()):
        return None
    return frozenset(k for k in params if k != "self")


def takes_keyword(env_id: str, name: str) -> bool:
    """True when the constructor of ``env_id`` takes the keyword ``name`` (``split``,
    ``val_fraction``)."""
    keywords = constructor_keywords(env_id)
    return keywords is None or name in keywords


def make_sb3_vec_env(
    env_id: str,
    n_envs: int,
    env_kwargs: Mapping[str, Any],
    split: str = "train",
    vec_env: str = "dummy",
    frame_stack: int = 1,
) -> Any:
    """An SB3 ``VecEnv`` of ``n_envs`` copies of ``env_id`` (``split`` passed to the
    environments that take one). Without a native vector env: ``DummyVecEnv``
    (``vec_env="dummy"``) or ``SubprocVecEnv`` (``"subproc"``, one process per copy,
    started with ``forkserver``; the same episodes as ``DummyVecEnv``), each copy
    observing its last ``frame_stack`` observations (:func:`baselines.agents.memory.stack_env`;
    with a stack the copies are built one by one even where a native vector env exists:
    Gymnasium has no vector frame-stack wrapper)."""
    import gymnasium as gym

    import motion_envs  # noqa: F401

    kwargs = dict(env_kwargs)
    if takes_keyword(env_id, "split"):
        kwargs["split"] = split
    if frame_stack == 1 and has_native_vector_env(env_id):
        from baselines.sb3 import GymnasiumVecEnv

        venv = gym.make_vec(
            env_id, num_envs=n_envs, vectorization_mode="vector_entry_point", **kwargs
        )
        return GymnasiumVecEnv(venv)
    if vec_env not in ("dummy", "subproc"):
        raise ValueError(f"vec_env must be 'dummy' or 'subproc'; got {vec_env!r}")
    from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv

    factory = functools.partial(_make_registered, env_id, kwargs, frame_stack)
    if vec_env == "subproc" and n_envs > 1:
        return SubprocVecEnv([factory] * n_envs, start_method="forkserver")
    return DummyVecEnv([factory] * n_envs)


def _make_registered(env_id: str, kwargs: Mapping[str, Any], frame_stack: int = 1) -> Any:
    """``gym.make`` after registering the ids (also inside a fresh worker process),
    stacked over ``frame_stack`` observations."""
    import gymnasium as gym

    import motion_envs  # noqa: F401
    from baselines.agents.memory import stack_env

    return stack_env(gym.make(env_id, **kwargs), frame_stack)
