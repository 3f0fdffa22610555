"""A scripted juggler with the AnalyticJuggler interface, for testing the environment's
mechanics independently of the fitted controller (test double, not a model)."""

from __future__ import annotations

import numpy as np

from motion_envs.models.juggling_task import JugglingState, JugglingTask


class ScriptedJuggler:
    """Toss straight up with a seeded speed, go down, wait under the ball, return home."""

    def __init__(self, task: JugglingTask) -> None:
        self.task = task
        self.home = np.asarray(task.home, float)
        self.phase = "toss"
        self.phase_time = 0.0

    def reset(self, state: JugglingState, rng: np.random.Generator | None = None) -> None:
        self._rng = rng if rng is not None else np.random.default_rng(0)
        self._start(state.hand_pos)

    def _start(self, hand: np.ndarray) -> None:
        self.phase, self.phase_time, self._k = "toss", 0.0, 0
        self._speed = 1.2 + 0.2 * float(self._rng.random())
        self._from = np.array(self.home)
        self._next = self._plan(1)

    def _plan(self, k: int) -> np.ndarray:
        dt = self.task.dt
        if self.phase == "toss":
            top = self._speed + 0.2
            n = min(k, 30)
            rise = top * dt * n * (n + 1) / 60  # velocity ramps to `top` over 30 steps
            if k > 30:
                rise += self._speed * dt
            return self._from + np.array([0.0, rise])
        if self.phase == "go_down":
            s = min(1.0, k / 60)
            return self._from + (self._to - self._from) * s
        if self.phase == "catch":
            return self._to.copy()
        s = min(1.0, k / 80)
        return self._from + (self.home - self._from) * s

    def command(self, state: JugglingState) -> tuple[np.ndarray, bool]:
        dt = self.task.dt
        if self.phase == "toss" and not state.held:
            self.phase, self._k, self._from = "go_down", 0, state.hand_pos.copy()
            self._to = self._from + np.array([0.0, -0.15])
        elif self.phase == "go_down" and self._k >= 60:
            self.phase, self._k, self._from = "catch", 0, state.hand_pos.copy()
            g, (bx, bz), (vx, vz) = self.task.gravity, state.ball_pos, state.ball_vel
            drop = max(bz - self._from[1], 0.0)
            t_land = (vz + np.sqrt(vz * vz + 2 * g * drop)) / g  # ball back at hand height
            self._to = np.array([bx + vx * t_land, self._from[1]])
        elif self.phase == "catch" and state.held:
            self.phase, self._k, self._from = "return", 0, state.hand_pos.copy()
        elif self.phase == "return" and self._k >= 80:
            self._start(state.hand_pos)
        self._k += 1
        self.phase_time = self._k * dt
        target = self._plan(self._k)
        self._next = self._plan(self._k + 1)
        return target, self.phase == "toss"

    def nominal_next(self) -> np.ndarray:
        return self._next
