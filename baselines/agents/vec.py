"""The SB3 vector environment an agent trains on (or is rebuilt on to load it).

Environments with a native vector environment (the reaching ones: one compiled loop for
all sub-environments) are used through :class:`baselines.sb3.GymnasiumVecEnv`; the others
(``Juggling-v0``: one MuJoCo scene per sub-environment) through SB3's ``DummyVecEnv`` of
``gym.make`` instances, as rl-baselines3-zoo does for any Gymnasium id.
"""

from __future__ import annotations

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
    env_id: str, n_envs: int, env_kwargs: Mapping[str, Any], split: str = "train"
) -> Any:
    """An SB3 ``VecEnv`` of ``n_envs`` copies of ``env_id`` (``split`` passed to the
    environments that take one)."""
    import gymnasium as gym

    import motion_envs  # noqa: F401

    kwargs = dict(env_kwargs)
    if takes_keyword(env_id, "split"):
        kwargs["split"] = split
    if has_native_vector_env(env_id):
        from baselines.sb3 import GymnasiumVecEnv

        venv = gym.make_vec(
            env_id, num_envs=n_envs, vectorization_mode="vector_entry_point", **kwargs
        )
        return GymnasiumVecEnv(venv)
    from stable_baselines3.common.vec_env import DummyVecEnv

    def factory() -> Any:
        return gym.make(env_id, **kwargs)

    return DummyVecEnv([factory] * n_envs)
