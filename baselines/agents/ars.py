"""ARS for ``motion-bench train --algo ars``: sb3-contrib's Augmented Random Search
(Mania, Guy & Recht 2018), optionally with paired episode seeds.

ARS explores in PARAMETER space: each iteration draws ``n_delta`` directions
``delta_i`` and plays the deterministic policies ``w + delta_std delta_i`` and ``w -
delta_std delta_i`` for ``n_eval_episodes`` episodes each, then steps ``w`` along the
``n_top`` best directions' return differences (scaled by the returns' standard
deviation). No action noise is added within an episode, so an actuated hand is never
jittered by the exploration itself (what PPO's per-step noise does on the juggling
envs, ``BENCHMARKS.md``).

:class:`ARS` is sb3-contrib's class; with ``paired_seeds=True`` the two candidates of a
direction play episodes of the SAME reset seeds (``VecEnv.seed`` before each candidate;
one fresh seed per direction and iteration), the method of common random numbers for
finite-difference gradient estimates (Kleinman, Spall & Naiman 1999, *Management
Science* 45(11)): the difference ``r(w + delta) - r(w - delta)`` then measures what the
direction changed, not which delay, drag and release noise the two episodes happened to
draw. The seeds are drawn from the run's seed and stay below ``seed_bound`` (the
environment's first validation seed, so no validation or test episode is trained on).
Every other step is sb3-contrib's (single-process evaluation; its ``AsyncEval`` is not
used: the machines this runs on have a few cores shared by several runs).
"""

from __future__ import annotations

import copy
from functools import partial
from typing import Any, cast

import numpy as np
import torch as th
from sb3_contrib import ARS as ContribARS
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.evaluation import evaluate_policy
from stable_baselines3.common.vec_env import VecEnv

__all__ = ["ARS", "PAIR_SEED_STREAM"]

#: Mixed into the run's seed for the stream of paired episode seeds (so it is not the
#: stream of the directions, which the run's seed also seeds through torch).
PAIR_SEED_STREAM = 0x415253


class ARS(ContribARS):
    """sb3-contrib's ``ARS`` with ``paired_seeds`` (see the module docstring).

    ``seed_bound``: the paired seeds ``s`` satisfy ``s + n_envs <= seed_bound`` (each
    copy ``i`` of the vector env is reset with ``s + i``).
    """

    def __init__(
        self, *args: Any, paired_seeds: bool = False, seed_bound: int = 2**31 - 1, **kwargs: Any
    ) -> None:
        self.paired_seeds = bool(paired_seeds)
        self.seed_bound = int(seed_bound)
        super().__init__(*args, **kwargs)
        self._pair_rng = np.random.default_rng([PAIR_SEED_STREAM, int(self.seed or 0)])

    def pair_seeds(self) -> list[int]:
        """The reset seeds of one iteration's directions (one per direction)."""
        high = self.seed_bound - int(self._vec_env().num_envs) + 1  # s + n_envs - 1 < seed_bound
        if high < 1:
            raise ValueError(f"seed_bound {self.seed_bound} leaves no seed for paired episodes")
        return [int(s) for s in self._pair_rng.integers(0, high, size=self.n_delta)]

    def _vec_env(self) -> VecEnv:
        """The training vector env (set once the model is built with one)."""
        if self.env is None:
            raise RuntimeError("ARS has no environment: build it with one before training")
        return self.env

    def evaluate_candidates(
        self, candidate_weights: th.Tensor, callback: BaseCallback, async_eval: Any
    ) -> th.Tensor:
        """sb3-contrib's single-process evaluation, each candidate ``k`` reset with the
        seed of direction ``k mod n_delta`` when ``paired_seeds`` (candidates ``i`` and
        ``i + n_delta`` are ``w + delta_i`` and ``w - delta_i``)."""
        if not self.paired_seeds:
            return super().evaluate_candidates(candidate_weights, callback, async_eval)
        if async_eval is not None:
            raise ValueError("paired_seeds needs the single-process evaluation (no async_eval)")
        seeds, env = self.pair_seeds(), self._vec_env()
        returns = th.zeros(self.pop_size, device=self.device)
        train_policy = copy.deepcopy(self.policy)
        self.ep_info_buffer = []  # type: ignore[assignment]  # as sb3-contrib: this iteration's logs
        callback.on_rollout_start()
        step = partial(self._trigger_callback, callback=callback, n_envs=env.num_envs)
        for k in range(self.pop_size):
            train_policy.load_from_vector(candidate_weights[k].cpu().numpy())
            env.seed(seeds[k % self.n_delta])
            rewards, lengths = evaluate_policy(
                train_policy,
                env,
                n_eval_episodes=self.n_eval_episodes,
                return_episode_rewards=True,
                callback=step,
                warn=False,
            )
            rewards, lengths = cast(list[float], rewards), cast(list[int], lengths)
            returns[k] = sum(rewards) + self.alive_bonus_offset * sum(lengths)
            self._mimic_monitor_wrapper(cast(Any, rewards), cast(Any, lengths))
        callback.on_rollout_end()
        return returns
