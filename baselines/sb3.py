"""stable-baselines3 glue for motion-envs' environments.

* :class:`GymnasiumVecEnv`: an SB3 ``VecEnv`` over a Gymnasium ``VectorEnv`` (e.g. the
  native batched-numpy environments from
  ``gym.make_vec(id, num_envs=N, vectorization_mode="vector_entry_point")``), so PPO,
  SAC, ... train on thousands of environments without one Python object per copy;
* :class:`TqdmCallback`: a progress bar (stderr) over the steps ``learn`` really takes
  (PPO rounds up to whole rollouts), kept moving during policy updates, with the
  latest mean episode return. SB3's own ``progress_bar=True`` (rich) and
  ``tensorboard_log`` work too: the ``rl`` extra installs ``rich`` and ``tensorboard``.

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
import threading
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
        # Gymnasium's vector envs take a list of per-env seeds; its stubs say int only
        obs, _ = self.venv.reset(seed=seeds)  # type: ignore[arg-type]
        self._reset_seeds()
        self._reset_options()
        return np.asarray(obs)

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
        frames: Any = self.venv.render()  # a tuple of frames; Gymnasium's stubs are wider
        return list(frames) if frames is not None else [None] * self.num_envs


class TqdmCallback(BaseCallback):
    """A tqdm progress bar over the environment steps ``learn`` will really take.

    The bar's total is what SB3 runs, not what was asked: an on-policy algorithm (PPO,
    A2C) collects whole rollouts of ``n_steps * n_envs`` steps, so ``learn(T)`` takes
    ``ceil(T / (n_steps n_envs)) n_steps n_envs`` steps; others take whole vector steps,
    ``ceil(T / n_envs) n_envs``. The rate is the average over the whole run (tqdm
    ``smoothing=0``: environment steps per wall-clock second, gradient updates
    included), and a background thread redraws the bar every ``refresh_seconds`` so the
    elapsed time and the rate keep moving while the policy is being updated (the
    postfix says ``collecting`` or ``updating``). The postfix also shows the mean return
    of the latest episodes (SB3's ``ep_info_buffer``, filled by ``VecMonitor``).

    Parameters
    ----------
    total:
        The ``total_timesteps`` given to ``learn`` (None: read from ``learn`` itself).
    desc:
        The bar's label.
    refresh_seconds:
        Redraw interval while no step happens (``0`` disables the thread).
    file:
        Where the bar is drawn (default ``sys.stderr``).
    """

    def __init__(
        self,
        total: int | None = None,
        desc: str = "training",
        refresh_seconds: float = 1.0,
        file: Any = None,
    ) -> None:
        super().__init__()
        self.total = None if total is None else int(total)
        self.desc = desc
        self.refresh_seconds = float(refresh_seconds)
        self.file = file
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._postfix: dict[str, str] = {}

    def real_total(self, requested: int) -> int:
        """Steps ``learn(requested)`` takes from the model's current ``num_timesteps``."""
        n_envs = int(self.training_env.num_envs)
        n_steps = getattr(self.model, "n_steps", None)
        chunk = n_envs * int(n_steps) if isinstance(n_steps, int) else n_envs
        return -(-max(int(requested), 0) // chunk) * chunk

    def _on_training_start(self) -> None:
        target = int(self.locals.get("total_timesteps", 0))  # after SB3's _setup_learn
        requested = target - int(self.model.num_timesteps) if target else self.total or 0
        self.bar = tqdm(
            total=self.real_total(requested),
            desc=self.desc,
            unit="step",
            file=self.file if self.file is not None else sys.stderr,
            smoothing=0,
            dynamic_ncols=True,
        )
        if self.refresh_seconds > 0:
            self._stop.clear()
            self._thread = threading.Thread(target=self._refresh_loop, daemon=True)
            self._thread.start()

    def _refresh_loop(self) -> None:
        while not self._stop.wait(self.refresh_seconds):
            self.bar.refresh()

    def _set_postfix(self, **items: str) -> None:
        self._postfix.update(items)
        self.bar.set_postfix(self._postfix, refresh=True)

    def _on_rollout_start(self) -> None:
        self._set_postfix(phase="collecting")

    def _on_step(self) -> bool:
        self.bar.update(self.training_env.num_envs)
        return True

    def _on_rollout_end(self) -> None:
        buf = self.model.ep_info_buffer
        if buf:
            self._postfix["ep_return"] = f"{np.mean([e['r'] for e in buf]):.3g}"
        if getattr(self.model, "n_steps", None) is not None:
            self._set_postfix(phase="updating")

    def _on_training_end(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join()
            self._thread = None
        self._postfix.pop("phase", None)
        self.bar.set_postfix(self._postfix, refresh=False)
        self.bar.close()
