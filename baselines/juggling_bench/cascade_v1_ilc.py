r"""Juggling-v2's task-error learner (:class:`~baselines.juggling_bench.ilc.TaskErrorILC`:
iterative learning control with a Gauss-Newton update, not RL) on Cascade-v1, per hand.

**The residual** (the env's action space, ``scale`` m per unit): in a hand's catch phase
only, in the hand's own frame (``x`` mirrored for the left hand, ``S_h = diag(s_h, 1)``
with ``s = +1`` right, ``-1`` left),

.. math:: r_h = S_h\,(c + d\,S_h v_h) = S_h c + d\,v_h

with ``v_h`` the velocity of the ball the hand is about to catch, read from the
observation (:func:`~baselines.juggling_bench.cascade_v1_view.catching_velocities`, as the
``velocity_x_mean_delay`` row reads it), ``c = (c_x, c_z)`` one constant for both hands
in their own frames and ``d`` one learned delay (s); 0 in the other phases. Starting
from ``c = 0`` and the level's mean delay it IS ``velocity_x_mean_delay``.

**The task error** (Cascade-v1's ``info["task_error"]`` ``(2, 2)``, per hand at its
catch): the offset ``e_x`` (m, world ``x``) says the palm should have been that much
farther; the timing ``e_t`` says it met the ball ``e_t`` late. The residual that would
have met the ball is ``r* = r + (e_x, v_z e_t)`` (``r`` the hand's last applied residual
in its catch phase), in the hand's own frame ``S_h r*`` against ``S_h v_h``: the samples
of ``TaskErrorILC._solve``'s least squares (``r* ~ c + d v``, ``d`` shared by the
axes). A catch without a timing (outside the hand's catch phase) or without a velocity
read gives no sample. **Within an episode** each catch moves the episode's delay by
``gain e_x / v_x`` (``|v_x| > 0.3`` m/s), as Juggling-v2's learner does.

**Budget**: ``iterations x episodes_per_iteration`` TRAINING episodes (seeds
``SPLIT_SEEDS["train"] + i``, never a validation or test seed); the learned ``(c, d)``
is then scored on validation (the bench's choice) and test episodes.
"""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
from numpy.typing import NDArray

from baselines.agents.cascade_score import record_hand_paths
from baselines.juggling_bench.cascade import CascadeEpisodes
from baselines.juggling_bench.cascade_v1_view import catching_velocities
from baselines.juggling_bench.ilc import ILCConfig, TaskErrorILC
from motion_envs.datasets.juggling import episode_seeds
from motion_envs.models.juggling import pattern_spec

__all__ = ["CascadeTaskErrorILC"]

#: Each hand's own-frame signs of ``(x, z)`` (right, left).
_SIGNS = np.array([[1.0, 1.0], [-1.0, 1.0]])


class CascadeTaskErrorILC(TaskErrorILC):
    """The learner (module docstring) on one level and pattern of Cascade-v1."""

    def __init__(
        self,
        level: str,
        pattern: str,
        scale: float,
        prior_delay: float,
        config: ILCConfig | None = None,
    ) -> None:
        super().__init__(level, scale, prior_delay, config)
        self.pattern = pattern
        self.balls = pattern_spec(pattern).balls

    def _env(self) -> gym.Env:
        from motion_envs.envs.juggling import CascadeV1Env

        return CascadeV1Env(
            level=self.level,
            pattern=self.pattern,
            controller="juggler",
            max_catches=self.config.max_catches,
            residual_scale=self.scale,
        )

    def play(  # type: ignore[override]
        self, env: gym.Env, seed: int, learn: bool
    ) -> tuple[float, int, int, bool]:
        """One episode from ``reset(seed)`` with the current ``(c, d)`` and the
        within-episode delay update; with ``learn`` its catches join :attr:`samples`.
        Returns ``(time, tosses, catches, dropped)``."""
        obs, info = env.reset(seed=seed)
        d = self.d
        last: list[tuple[NDArray[np.float64], NDArray[np.float64]] | None] = [None, None]
        term = trunc = False
        while not (term or trunc):
            vs = catching_velocities(obs, self.balls)
            a = np.zeros(4)
            for h, v in enumerate(vs):
                if v is not None:
                    a[2 * h : 2 * h + 2] = np.clip((_SIGNS[h] * self.c + d * v) / self.scale, -1, 1)
            obs, _, term, trunc, info = env.step(a.astype(np.float32))
            for h, v in enumerate(vs):
                if v is not None:
                    last[h] = (a[2 * h : 2 * h + 2] * self.scale, v)
            if not info["caught"]:
                continue
            for h, (e_x, e_t) in enumerate(np.asarray(info["task_error"]).tolist()):
                seen = last[h]
                if math.isnan(e_x) or seen is None:
                    continue
                r, v = seen
                if learn and not math.isnan(e_t):
                    own = _SIGNS[h] * (r + np.array([e_x, v[1] * e_t]))
                    self.samples.append((_SIGNS[h, 0] * v[0], v[1], own[0], own[1]))
                if abs(v[0]) > 0.3:
                    d += self.config.within_episode_gain * e_x / float(v[0])
                last[h] = None
        return float(info["time"]), int(info["tosses"]), int(info["catches"]), bool(term)

    def evaluate(self, split: str, n: int) -> CascadeEpisodes:  # type: ignore[override]
        """``n`` episodes of ``split`` with the learned ``(c, d)`` (no learning across
        them; the within-episode update runs); on the TEST split with the hands'
        deviation from the held-out demonstrations, as every row's
        (:func:`~baselines.juggling_bench.cascade_v1.cascade_v1_episodes`)."""
        seeds = episode_seeds(split, n)
        env = self._env()
        recorder = record_hand_paths(env, self.pattern) if split == "test" else None
        try:
            played = env if recorder is None else recorder
            out = [self.play(played, int(s), learn=False) for s in seeds.tolist()]
        finally:
            env.close()
        devs = None if recorder is None else recorder.deviations(split)
        return CascadeEpisodes.from_rows(seeds, [(o[2], o[1], o[3], o[0]) for o in out], devs)
