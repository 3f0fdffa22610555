"""The pure-model juggling world: a kinematic hand and a ballistic ball, no physics engine.

One :meth:`BallisticWorld.step` (period ``dt``) applies the world's rules in the order
documented in :mod:`motion_envs.datasets.juggling.rules` (``hand_velocity``,
``hand_acceleration``, ``release_fires``, ``release_velocity``, ``flight``,
``catch_fires``, ``has_left``, ``drop_fires``), the same functions the MuJoCo scene
(:class:`motion_envs.envs.juggling.JugglingScene`), the vectorised runner, the
demonstration generator and the segmentation call. Every world satisfies the
:class:`JugglingWorld` protocol.

The state's ``hand_pos`` is what the controller observes: the true hand plus tracking
noise (``JugglingNoise.tracking``, :func:`tracked_hand`). Noise is drawn at reset by
:func:`draw_episode_noise` (release factor, then one tracking-noise row per step) and kept
in the public fields ``release_factor`` and ``tracking_noise``, so a seeded episode is the
same however the world is stepped.
"""

from __future__ import annotations

import math
from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike

from motion_envs._typing import FloatArray
from motion_envs.datasets.juggling import JugglingNoise, JugglingState, JugglingTask, rules

__all__ = [
    "TRACKING_ROWS",
    "BallisticWorld",
    "JugglingWorld",
    "draw_episode_noise",
    "tracked_hand",
    "xz_pair",
]

#: Rows of tracking noise drawn at reset (used cyclically beyond: 10 s at 200 Hz).
TRACKING_ROWS = 2000


@runtime_checkable
class JugglingWorld(Protocol):
    """What a juggling world offers a controller or a runner (``BallisticWorld``, the
    MuJoCo ``JugglingScene``): the task, ``reset`` and ``step`` returning the state."""

    task: JugglingTask

    def reset(
        self,
        hand_pos: ArrayLike,
        *,
        noise: JugglingNoise | None = None,
        rng: np.random.Generator | None = None,
    ) -> JugglingState:
        """Hand at rest at ``hand_pos``, ball held in it, time 0; draws the episode's noise."""
        ...

    def step(self, hand_target: ArrayLike, release_armed: bool) -> JugglingState:
        """Move the hand to ``hand_target`` over one ``dt``; hold, release, catch or drop."""
        ...


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


def tracked_hand(hand: FloatArray, tracking: FloatArray | None, k: int) -> FloatArray:
    """The hand the controller observes at step ``k``: ``hand`` ``(2,)`` (or ``(N, 2)``
    with ``tracking`` ``(N, TRACKING_ROWS, 2)``) plus row ``k mod TRACKING_ROWS`` of the
    episode's tracking noise (None: no noise)."""
    if tracking is None:
        return hand
    out: FloatArray = hand + tracking[..., k % TRACKING_ROWS, :]
    return out


def xz_pair(value: ArrayLike, name: str) -> tuple[float, float]:
    """``value`` as a finite ``(x, z)`` pair of floats; ValueError naming ``name``."""
    if isinstance(value, tuple) and len(value) == 2 and all(type(v) is float for v in value):
        x, z = value
    elif isinstance(value, np.ndarray) and value.shape == (2,):
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
    """Pure-model juggling world (see the module docstring); a :class:`JugglingWorld`.

    Attributes ``release_factor`` ``(2,)`` and ``tracking_noise``
    (``(TRACKING_ROWS, 2)`` or None) are the episode's noise, drawn at reset.
    """

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
        self.release_factor, self.tracking_noise = draw_episode_noise(self.noise, rng)
        x, z = xz_pair(hand_pos, "hand_pos")
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
        return JugglingState(
            time=self.time,
            hand_pos=tracked_hand(np.array([hx, hz]), self.tracking_noise, self._k),
            hand_vel=np.array(
                [
                    rules.hand_velocity(hx, self._prev[0], dt),
                    rules.hand_velocity(hz, self._prev[1], dt),
                ]
            ),
            ball_pos=np.array(self._ball),
            ball_vel=np.array(self._ball_v),
            held=self._held,
            released=released,
            caught=caught,
            dropped=self._dropped,
        )

    def step(self, hand_target: ArrayLike, release_armed: bool) -> JugglingState:
        """Advance one period ``dt`` (the rules' order in the module docstring)."""
        task = self.task
        dt = task.dt
        x, z = xz_pair(hand_target, "hand_target")
        self._k += 1
        self.time = self._k * dt
        self._prev2 = self._prev
        self._prev = self._hand
        self._hand = [x, z]
        vx, vz = (
            rules.hand_velocity(x, self._prev[0], dt),
            rules.hand_velocity(z, self._prev[1], dt),
        )
        az = rules.hand_acceleration(z, self._prev[1], self._prev2[1], dt)
        released = caught = False
        if self._held:
            if rules.release_fires(release_armed, az, task.toss_threshold):
                self._held = False
                self._left = False
                released = True
                factor = self.release_factor
                bvx, bvz = rules.release_velocity(vx, vz, factor[0], factor[1])
                self._release = (self.time, x, z, bvx, bvz)
                self._ball, self._ball_v = [x, z], [bvx, bvz]
            else:
                self._ball, self._ball_v = [x, z], [vx, vz]
        else:
            bx0, bz0 = self._ball
            bx, bz, bvx, bvz = rules.flight(self._release, self.time, task.gravity)
            self._ball, self._ball_v = [bx, bz], [bvx, bvz]
            dist = math.hypot(x - bx, z - bz)
            px, pz = self._prev
            swept = float(rules.swept_distance(px - bx0, pz - bz0, x - bx, z - bz))
            caught = bool(rules.catch_fires(swept, self._left, self._dropped, task.catch_radius))
            self._left = bool(rules.has_left(dist, self._left, caught, task.catch_radius))
            if caught:
                self._held = True
                self._ball, self._ball_v = [x, z], [vx, vz]
            self._dropped = self._dropped or bool(rules.drop_fires(bz, self._held, task.floor_z))
        return self._state(released, caught)
