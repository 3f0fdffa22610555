"""The juggling task of Lippi, Avizzano & Ruffaldi (section III-A): constants and states.

One ball, one (right) hand, the vertical plane ``(x, z)`` (``x`` horizontal, ``z`` up),
SI units. Every physical constant lives in :class:`JugglingTask`; the pure-model world
(:class:`motion_envs.models.juggling.BallisticWorld`) and the MuJoCo scene
(:class:`motion_envs.envs.juggling.JugglingScene`) share the states defined here, and
their rules (:mod:`motion_envs.datasets.juggling.rules`).

Gravity. The paper's ball is virtual and its phases (150-200 samples at 200 Hz, i.e.
0.75-1.0 s each) need a flight of about 1.6-1.9 s through go-down and catch. A one-hand
toss in front of a screen leaves the hand at about 0.6-0.9 m/s; under 9.81 m/s^2 that
flight would last 0.2 s. With apex height ``h`` above the catch point and flight time
``T``, ``g ~ 8 h / T^2``; the default ``gravity = 1.0`` m/s^2 makes the simulated phases
match the paper's sizes (see the demonstration generator). ``JugglingTask(gravity=9.81)``
is real gravity (shorter phases, a faster toss is then needed).

Ballistic flight (closed form, used everywhere)::

    x(t) = x0 + vx t,     z(t) = z0 + vz t - g t^2 / 2
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from motion_envs._typing import FloatArray

__all__ = [
    "PHASES",
    "JugglingNoise",
    "JugglingState",
    "JugglingTask",
    "ballistic_position",
    "ballistic_velocity",
]

#: The four phases of one juggling cycle, in order.
PHASES: tuple[str, ...] = ("toss", "go_down", "catch", "return")


@dataclass(frozen=True)
class JugglingTask:
    """Every physical constant of the juggling task in one place (SI units, plane x, z).

    Attributes
    ----------
    gravity:
        m/s^2, downwards. Default 1.0: the paper's virtual world (see the module docstring);
        9.81 for real gravity.
    dt:
        Control period, s (the paper's 200 Hz Polhemus tracker).
    ball_radius, ball_mass:
        m and kg (a juggling ball, 7 cm, 130 g).
    catch_radius:
        Hand centre to ball centre distance (m) that counts as a catch.
    toss_threshold:
        m/s^2: the ball is released when the hand's vertical acceleration (second
        backward difference over ``dt``) drops below ``-toss_threshold``. Default (NaN):
        ``3 * gravity`` (3.0 at the default gravity): accelerations of the same movement
        sizes scale with ``g`` (times with ``1 / sqrt(g)``), so the toss stays the same
        gesture under real gravity.
    floor_z:
        Ball centre below this height (m) is a drop and ends the cycle.
    home:
        Default start of a cycle, the hand's rest position ``(x, z)`` in m.
    """

    gravity: float = 1.0
    dt: float = 1 / 200
    ball_radius: float = 0.035
    ball_mass: float = 0.13
    catch_radius: float = 0.06
    toss_threshold: float = math.nan  # NaN: 3 * gravity
    floor_z: float = 0.5
    home: tuple[float, float] = field(default=(0.2, 1.0))

    def __post_init__(self) -> None:
        for name in ("gravity", "dt", "ball_radius", "ball_mass", "catch_radius"):
            value = getattr(self, name)
            if not np.isfinite(value) or value <= 0:
                raise ValueError(f"JugglingTask.{name} must be finite and > 0; got {value}")
        if math.isnan(self.toss_threshold):
            object.__setattr__(self, "toss_threshold", 3.0 * float(self.gravity))
        if not np.isfinite(self.toss_threshold) or self.toss_threshold <= 0:
            raise ValueError(
                f"JugglingTask.toss_threshold must be finite and > 0; got {self.toss_threshold}"
            )
        if not np.isfinite(self.floor_z) or self.floor_z >= self.home[1]:
            raise ValueError(
                f"JugglingTask.floor_z must be finite and below home z = {self.home[1]}; "
                f"got {self.floor_z}"
            )


@dataclass(frozen=True)
class JugglingState:
    """The world after one step (or at reset); arrays are ``(2,)`` ``(x, z)``."""

    time: float
    hand_pos: FloatArray
    hand_vel: FloatArray
    ball_pos: FloatArray
    ball_vel: FloatArray
    held: bool
    released: bool  # a toss happened during the last step
    caught: bool  # a catch happened during the last step
    dropped: bool  # the ball went below floor_z


@dataclass(frozen=True)
class JugglingNoise:
    """Perturbations of a run.

    ``release``: relative std of the release velocity (0.05 = 5 %), one Gaussian draw per
    component: ``v_ball = v_hand * (1 + release * N(0, 1))``. ``tracking``: std (m) of the
    hand position the controller observes (Gaussian, independent per step and axis).
    """

    release: float = 0.0
    tracking: float = 0.0

    def __post_init__(self) -> None:
        for name in ("release", "tracking"):
            value = getattr(self, name)
            if not np.isfinite(value) or value < 0:
                raise ValueError(f"JugglingNoise.{name} must be finite and >= 0; got {value}")


def ballistic_position(p0: ArrayLike, v0: ArrayLike, t: ArrayLike, gravity: float) -> FloatArray:
    """``p0 + v0 t - [0, g t^2 / 2]`` at times ``t`` (scalar or ``(K,)``): ``(2,)``/``(K, 2)``."""
    p0 = np.asarray(p0, dtype=np.float64)
    v0 = np.asarray(v0, dtype=np.float64)
    t = np.asarray(t, dtype=np.float64)
    tt = t[..., None]
    out = p0 + v0 * tt
    out[..., 1] -= 0.5 * gravity * t**2
    return out


def ballistic_velocity(v0: ArrayLike, t: ArrayLike, gravity: float) -> FloatArray:
    """``v0 - [0, g t]``: ``(2,)`` or ``(K, 2)``."""
    v0 = np.asarray(v0, dtype=np.float64)
    t = np.asarray(t, dtype=np.float64)
    out = np.broadcast_to(v0, (*t.shape, 2)).copy()
    out[..., 1] -= gravity * t
    return out
