"""A residual learner from the task-error vector (not RL): iterative learning control of
Juggling-v2's catch with a Gauss-Newton update, in the spirit of Ploeger & Peters (2026:
residuals on an analytic prior, learned from the task error rather than a scalar reward).

**The residual** (the env's action space, :data:`~baselines.juggling_bench.v2.RESIDUAL_SCALE`
m per unit): in the catch phase only,

.. math:: r = c + d\\,\\hat v

with ``v`` the ball's velocity ``(v_x, v_z)`` from the oldest and newest observed frame
(as the two-line row reads it), ``c = (c_x, c_z)`` a constant and ``d`` a learned delay
(s), shared by the axes; 0 in the other phases.

**The task error.** At each catch Juggling-v2's ``info["task_error"]``: its offset says where the
ball met the palm relative to its centre (m, along ``x``): the palm should have been
that much farther, so the residual that would have zeroed it is ``r* = r_applied + e``
(``r_applied``: the residual of the catch's last command). Its Jacobian in ``(c, d)`` is
``[1, v_x]``. Along ``z`` the timing error ``e_t`` (the catch time minus the plan's)
says the palm met the ball ``e_t`` late: the residual that would have met it on time is
``r*_z = r_z + v_z e_t`` (Jacobian ``[1, v_z]``).

**Learning** (the budget: ``iterations x episodes_per_iteration`` TRAINING episodes,
seeds ``SPLIT_SEEDS["train"] + i``, never a validation or test seed): each iteration
plays its episodes with the current ``(c, d)`` and then solves the least squares of
``r* ~ c + d v_x`` over every catch seen so far (a Gauss-Newton step of the linear
model, ``d`` shared by the axes; ridge ``1e-6``). **Within an episode** (the delay is one per
episode) each catch also moves the episode's own delay by a damped Newton step ``d <-
d + gain e / v_x`` (when ``|v_x| > 0.3`` m/s), starting from the learned ``d`` at every
reset. The learner uses catches only: a drop's ``info["miss_error"]`` (the vector at the
falling ball's closest approach) was tried as a catch's and made the linear update
diverge (the closest approach of a miss comes while the hand is still travelling: the
medium level's validation catch rate fell to 0.06), so the learner sees only what its
catches tell.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import gymnasium as gym
import numpy as np
from numpy.typing import NDArray

import motion_envs  # noqa: F401  (registers the ids)
from baselines.agents.juggling_score import (
    JugglingEpisodes,
    demonstration_paths,
    episodes_from_paths,
)
from motion_envs.datasets.juggling import episode_seeds

__all__ = ["ILCConfig", "TaskErrorILC"]

_CATCH, _FRAME0 = 7, 16


@dataclass(frozen=True)
class ILCConfig:
    """The learner's budget and gains."""

    iterations: int = 6
    episodes_per_iteration: int = 10
    within_episode_gain: float = 0.5
    max_catches: int = 3


def _ball_v(obs: NDArray[np.floating]) -> tuple[float, float] | None:
    """The ball's ``(v_x, v_z)`` from the newest and oldest valid frame (None without
    two)."""
    frames = np.asarray(obs[_FRAME0 : _FRAME0 + 16], dtype=np.float64).reshape(4, 4)
    valid = np.flatnonzero(frames[:, 3] > 0.5)
    if valid.size < 2 or valid[0] != 0:
        return None
    old = frames[valid[-1]]
    span = old[2] - frames[0, 2]
    if span <= 0:
        return None
    return float((frames[0, 0] - old[0]) / span), float((frames[0, 1] - old[1]) / span)


class TaskErrorILC:
    """The learner (module docstring) on one level of Juggling-v2."""

    def __init__(
        self, level: str, scale: float, prior_delay: float, config: ILCConfig | None = None
    ) -> None:
        self.level = level
        self.scale = float(scale)
        self.config = ILCConfig() if config is None else config
        self.c = np.zeros(2)
        self.d = float(prior_delay)
        #: every training catch: ``(v_x, v_z, r*_x, r*_z)``
        self.samples: list[tuple[float, float, float, float]] = []
        self.history: list[dict[str, float]] = []

    def _env(self) -> gym.Env:
        return gym.make(
            "MotionEnvs/Juggling-v2",
            level=self.level,
            max_catches=self.config.max_catches,
            residual_scale=self.scale,
        )

    def play(
        self, env: gym.Env, seed: int, learn: bool
    ) -> tuple[list[float], list[NDArray[np.float64]], list[str], int, int, bool]:
        """One episode from ``reset(seed)`` with the current ``(c, d)`` and the
        within-episode delay update; with ``learn`` its catches join :attr:`samples`.
        Returns the path (times, hands, phases) and tosses, catches, dropped."""
        obs, info = env.reset(seed=seed)
        d = self.d
        times, hands, phases = [float(info["time"])], [info["hand"]], [str(info["phase"])]
        last_r, last_v = np.zeros(2), None
        done = term = False
        while not done:
            v = _ball_v(obs) if obs[_CATCH] > 0.5 else None
            r = np.zeros(2) if v is None else self.c + d * np.array(v)
            a = np.clip(r / self.scale, -1.0, 1.0)
            obs, _, term, trunc, info = env.step(a.astype(np.float32))
            done = term or trunc
            times.append(float(info["time"]))
            hands.append(info["hand"])
            phases.append(str(info["phase"]))
            if v is not None:
                last_r, last_v = a * self.scale, v
            if info["caught"] and last_v is not None:
                e_x, e_t = (float(e) for e in info["task_error"])
                vx, vz = last_v
                target = last_r + np.array([e_x, vz * e_t])
                if learn:
                    self.samples.append((vx, vz, float(target[0]), float(target[1])))
                if abs(vx) > 0.3:
                    d += self.config.within_episode_gain * e_x / vx
                last_v = None
        return times, hands, phases, int(info["tosses"]), int(info["catches"]), bool(term)

    def _solve(self) -> None:
        """Least squares of ``r* ~ c + d v`` (both axes, ``d`` shared) over every
        sample, ridge 1e-6 toward the current values."""
        if not self.samples:
            return
        s = np.array(self.samples)
        n = len(s)
        a = np.zeros((2 * n, 3))
        a[:n, 0], a[n:, 1] = 1.0, 1.0
        a[:n, 2], a[n:, 2] = s[:, 0], s[:, 1]
        y = np.concatenate([s[:, 2], s[:, 3]])
        prior = np.array([*self.c, self.d])
        theta = np.linalg.solve(a.T @ a + 1e-6 * np.eye(3), a.T @ y + 1e-6 * prior)
        self.c, self.d = theta[:2].copy(), float(theta[2])

    def train(self) -> ILCConfig:
        """Learn on the budget of TRAINING episodes (module docstring)."""
        cfg = self.config
        seeds = episode_seeds("train", cfg.iterations * cfg.episodes_per_iteration).tolist()
        env = self._env()
        try:
            for it in range(cfg.iterations):
                batch = seeds[
                    it * cfg.episodes_per_iteration : (it + 1) * cfg.episodes_per_iteration
                ]
                caught = tossed = 0
                for seed in batch:
                    *_, tosses, catches, _ = self.play(env, int(seed), learn=True)
                    caught, tossed = caught + catches, tossed + tosses
                self._solve()
                self.history.append(
                    {"iteration": it, "catch_rate": caught / max(tossed, 1),
                     "c_x": float(self.c[0]), "c_z": float(self.c[1]), "d": self.d,
                     "catches_seen": len(self.samples)}
                )  # fmt: skip
        finally:
            env.close()
        return cfg

    def evaluate(self, split: str, n: int) -> JugglingEpisodes:
        """``n`` episodes of ``split`` with the learned ``(c, d)`` (no learning across
        them; the within-episode update runs), as :class:`JugglingEpisodes`."""
        seeds = episode_seeds(split, n)
        env = self._env()
        out: list[Any] = []
        try:
            out = [self.play(env, int(s), learn=False) for s in seeds.tolist()]
        finally:
            env.close()
        demos = demonstration_paths({"gravity": 9.81}, split)
        return episodes_from_paths(
            seeds,
            [np.asarray(p[0]) for p in out],
            [np.stack(p[1]) for p in out],
            [p[2] for p in out],
            np.array([p[3] for p in out], dtype=np.int64),
            np.array([p[4] for p in out], dtype=np.int64),
            np.array([p[5] for p in out], dtype=bool),
            demos,
        )
