"""The pure-model juggling world: a kinematic hand and a ballistic ball, no physics engine.

Semantics of one :meth:`BallisticWorld.step` (period ``dt``; the MuJoCo scene
``motion_envs.envs.juggling_scene.JugglingScene`` implements the same):

1. the hand moves to ``hand_target`` (kinematic); its velocity and acceleration are
   backward differences ``v_k = (h_k - h_{k-1}) / dt``, ``a_k = (v_k - v_{k-1}) / dt``
   (the hand is at rest before the reset position);
2. held ball: it follows the hand exactly; if ``release_armed`` and ``a_k[z] <
   -toss_threshold`` it is released with velocity ``v_k * f`` (``f = 1 + release * N(0, 1)``
   per component, drawn at reset) and ``released`` is set;
3. free ball: closed-form flight from the release, ``p(s) = p_r + v_r s - [0, g s^2 / 2]``
   with ``s`` the time since the release; once it has been farther than
   ``catch_radius`` from the hand, ``|hand - ball| <= catch_radius`` is a catch: the ball
   is held again (its state copied from the hand) and ``caught`` is set;
4. a free ball whose centre is below ``floor_z`` is dropped (sticky until reset).

The state's ``hand_pos`` is what the controller observes: the true hand plus tracking
noise (``JugglingNoise.tracking``). Noise is drawn at reset by :func:`draw_episode_noise`
(release factor, then one tracking-noise row per step), so a seeded episode is the same
however the world is stepped.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from motion_envs.datasets.juggling_task import JugglingNoise, JugglingState, JugglingTask

__all__ = ["TRACKING_ROWS", "BallisticWorld", "draw_episode_noise"]

FloatArray = NDArray[np.float64]

#: Rows of tracking noise drawn at reset (used cyclically beyond: 10 s at 200 Hz).
TRACKING_ROWS = 2000


def draw_episode_noise(
    noise: JugglingNoise, rng: np.random.Generator | None
) -> tuple[FloatArray, FloatArray | None]:
    """Release-velocity factor ``(2,)`` and tracking noise ``(TRACKING_ROWS, 2)`` (m) or None.

    Draw order (fixed, shared by every world): ``release`` draws 2 normals (only when
    ``noise.release > 0``), then ``tracking`` draws ``TRACKING_ROWS x 2`` normals (only
    when ``noise.tracking > 0``).
    """
    factor = np.ones(2)
    track = None
    if noise.release > 0 or noise.tracking > 0:
        if rng is None:
            raise ValueError("rng is required when noise is non-zero")
    if noise.release > 0:
        factor = 1.0 + noise.release * rng.standard_normal(2)  # type: ignore[union-attr]
    if noise.tracking > 0:
        track = noise.tracking * rng.standard_normal((TRACKING_ROWS, 2))  # type: ignore[union-attr]
    return factor, track


def _vec2(value: ArrayLike, name: str) -> tuple[float, float]:
    if isinstance(value, np.ndarray) and value.shape == (2,):
        x, z = float(value[0]), float(value[1])
    else:
        v = np.asarray(value, dtype=np.float64)
        if v.shape != (2,):
            raise ValueError(f"{name} must have shape (2,) (x, z); got {v.shape}")
        x, z = float(v[0]), float(v[1])
    if not (math.isfinite(x) and math.isfinite(z)):
        raise ValueError(f"{name} contains NaN or infinite values")
    return x, z


class BallisticWorld:
    """Pure-model juggling world (see the module docstring); the contract's JugglingWorld."""

    def __init__(self, task: JugglingTask | None = None) -> None:
        self.task = task or JugglingTask()

    def reset(
        self,
        hand_pos: ArrayLike,
        *,
        noise: JugglingNoise | None = None,
        rng: np.random.Generator | None = None,
    ) -> JugglingState:
        """Hand at rest at ``hand_pos``, ball held in it; draws the episode's noise."""
        self.noise = noise or JugglingNoise()
        self._factor, self._track = draw_episode_noise(self.noise, rng)
        x, z = _vec2(hand_pos, "hand_pos")
        self._hand = [x, z]
        self._prev = [x, z]
        self._prev2 = [x, z]
        self._ball = [x, z]
        self._ball_v = [0.0, 0.0]
        self._held = True
        self._left = False
        self._dropped = False
        self._k = 0
        self.time = 0.0
        self._release = (0.0, 0.0, 0.0, 0.0, 0.0)
        return self._state(False, False)

    @property
    def hand_true(self) -> FloatArray:
        """The hand's true position (without tracking noise)."""
        return np.array(self._hand)

    def _state(self, released: bool, caught: bool) -> JugglingState:
        dt = self.task.dt
        hx, hz = self._hand
        obs = np.array([hx, hz])
        if self._track is not None:
            obs += self._track[self._k % TRACKING_ROWS]
        return JugglingState(
            time=self.time,
            hand_pos=obs,
            hand_vel=np.array([(hx - self._prev[0]) / dt, (hz - self._prev[1]) / dt]),
            ball_pos=np.array(self._ball),
            ball_vel=np.array(self._ball_v),
            held=self._held,
            released=released,
            caught=caught,
            dropped=self._dropped,
        )

    def step(self, hand_target: ArrayLike, release_armed: bool) -> JugglingState:
        """Advance one period ``dt`` (semantics in the module docstring)."""
        task = self.task
        dt, g = task.dt, task.gravity
        x, z = _vec2(hand_target, "hand_target")
        self._k += 1
        self.time = self._k * dt
        self._prev2 = self._prev
        self._prev = self._hand
        self._hand = [x, z]
        vx, vz = (x - self._prev[0]) / dt, (z - self._prev[1]) / dt
        az = (z - 2.0 * self._prev[1] + self._prev2[1]) / (dt * dt)
        released = caught = False
        if self._held:
            if release_armed and az < -task.toss_threshold:
                self._held = False
                self._left = False
                released = True
                bvx, bvz = vx * self._factor[0], vz * self._factor[1]
                self._release = (self.time, x, z, bvx, bvz)
                self._ball, self._ball_v = [x, z], [bvx, bvz]
            else:
                self._ball, self._ball_v = [x, z], [vx, vz]
        else:
            t_r, x_r, z_r, bvx, bvz = self._release
            s = self.time - t_r
            self._ball = [x_r + bvx * s, z_r + bvz * s - 0.5 * g * s * s]
            self._ball_v = [bvx, bvz - g * s]
            dist = math.hypot(x - self._ball[0], z - self._ball[1])
            if self._left and dist <= task.catch_radius and not self._dropped:
                self._held = True
                caught = True
                self._ball, self._ball_v = [x, z], [vx, vz]
            elif dist > task.catch_radius:
                self._left = True
            if not self._held and self._ball[1] < task.floor_z:
                self._dropped = True
        return self._state(released, caught)
