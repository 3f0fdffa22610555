"""stable-baselines3 glue for motion-envs' environments.

* :class:`GymnasiumVecEnv`: an SB3 ``VecEnv`` over a Gymnasium ``VectorEnv`` (e.g. the
  native batched-numpy environments from
  ``gym.make_vec(id, num_envs=N, vectorization_mode="vector_entry_point")``), so PPO,
  SAC, ... train on thousands of environments without one Python object per copy;
* :class:`TqdmCallback`: a progress bar (stderr) with the latest mean episode return.

Needs the ``rl`` extra (stable-baselines3, torch); importing this module imports SB3.

SB3 expects a finished sub-environment to be reset within the same ``step``, with its
last observation in ``infos[i]["terminal_observation"]``; Gymnasium's vector
environments (``AutoresetMode.NEXT_STEP``) reset it on the *next* step instead. The
adapter therefore resets the finished sub-environments at once with
``reset(options={"reset_mask": done})`` and returns their first observation. At an
episode's end ``info["max_error"]`` (the papers' per-trajectory criterion) is passed on
in ``infos[i]``, and ``infos[i]["TimeLimit.truncated"]`` tells truncation from
termination, as SB3's own wrappers do.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence
from typing import Any

import gymnasium as gym
import numpy as np
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.vec_env.base_vec_env import VecEnv
from tqdm import tqdm

__all__ = ["GymnasiumVecEnv", "TqdmCallback"]


class GymnasiumVecEnv(VecEnv):
    """SB3 ``VecEnv`` over a Gymnasium ``VectorEnv`` with ``AutoresetMode.NEXT_STEP``.

    Parameters
    ----------
    venv:
        The Gymnasium vector environment (its ``metadata["autoreset_mode"]``, when set,
        must be ``NEXT_STEP``, Gymnasium's default). ``close()`` closes it.
    """

    def __init__(self, venv: gym.vector.VectorEnv) -> None:
        mode = venv.metadata.get("autoreset_mode")
        if mode is not None and mode != gym.vector.AutoresetMode.NEXT_STEP:
            raise ValueError(f"venv must use AutoresetMode.NEXT_STEP; got {mode}")
        self.venv = venv
        super().__init__(venv.num_envs, venv.single_observation_space, venv.single_action_space)
        self._actions: np.ndarray | None = None

    def reset(self) -> np.ndarray:
        seeds = None if all(s is None for s in self._seeds) else list(self._seeds)
        obs, _ = self.venv.reset(seed=seeds)
        self._reset_seeds()
        self._reset_options()
        return obs

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = actions

    def step_wait(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[dict[str, Any]]]:
        obs, reward, terminated, truncated, info = self.venv.step(self._actions)
        done = np.asarray(terminated) | np.asarray(truncated)
        infos: list[dict[str, Any]] = [{} for _ in range(self.num_envs)]
        for i in np.flatnonzero(done).tolist():
            infos[i]["terminal_observation"] = obs[i].copy()
            infos[i]["TimeLimit.truncated"] = bool(truncated[i] and not terminated[i])
            if "max_error" in info and info["_max_error"][i]:
                infos[i]["max_error"] = float(info["max_error"][i])
        if done.any():
            obs_reset, _ = self.venv.reset(options={"reset_mask": done})
            obs = np.where(done[:, None], obs_reset, obs)
        return obs, np.asarray(reward, dtype=np.float32), done, infos

    def close(self) -> None:
        self.venv.close()

    def get_attr(self, attr_name: str, indices: Any = None) -> list[Any]:
        value = getattr(self.venv, attr_name)
        return [value for _ in self._get_indices(indices)]

    def set_attr(self, attr_name: str, value: Any, indices: Any = None) -> None:
        raise NotImplementedError("GymnasiumVecEnv does not set sub-environment attributes")

    def env_method(
        self, method_name: str, *args: Any, indices: Any = None, **kwargs: Any
    ) -> list[Any]:
        raise NotImplementedError("GymnasiumVecEnv does not call sub-environment methods")

    def env_is_wrapped(self, wrapper_class: type, indices: Any = None) -> list[bool]:
        return [False for _ in self._get_indices(indices)]

    def get_images(self) -> Sequence[np.ndarray | None]:
        frames = self.venv.render()
        return list(frames) if frames is not None else [None] * self.num_envs


class TqdmCallback(BaseCallback):
    """A tqdm progress bar over ``total`` environment steps, on stderr, showing the mean
    return of the latest episodes (SB3's ``ep_info_buffer``, filled by ``VecMonitor``)."""

    def __init__(self, total: int, desc: str = "training") -> None:
        super().__init__()
        self.total = int(total)
        self.desc = desc

    def _on_training_start(self) -> None:
        self.bar = tqdm(total=self.total, desc=self.desc, unit="step", file=sys.stderr)

    def _on_step(self) -> bool:
        self.bar.update(self.training_env.num_envs)
        return True

    def _on_rollout_end(self) -> None:
        buf = self.model.ep_info_buffer
        if buf:
            self.bar.set_postfix(ep_return=f"{np.mean([e['r'] for e in buf]):.3g}")

    def _on_training_end(self) -> None:
        self.bar.close()
