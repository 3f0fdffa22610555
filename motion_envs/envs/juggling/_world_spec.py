"""What a juggling world is: :class:`WorldSpec`, a frozen dataclass of its hands, balls,
task constants and the human limits of the hands and the catch (every field checked).

The physics each field stands for is described in :mod:`motion_envs.envs.juggling._world`;
the MJCF written from a spec is :mod:`motion_envs.envs.juggling._world_mjcf`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Any

import numpy as np
from numpy.typing import NDArray

from motion_envs.datasets.juggling import JugglingTask
from motion_envs.envs.juggling import _period

__all__ = [
    "AIR_DENSITY",
    "BALL_CONAFFINITY",
    "BALL_CONTYPE",
    "CAPTURE_SPEED",
    "HAND_ACCEL_LIMIT",
    "HAND_MASS",
    "HAND_SPEED_LIMIT",
    "IMPACT_CONTACT_DAMPING",
    "MAX_BALLS",
    "PALM_HALF_THICKNESS",
    "SERVO_OMEGA",
    "SUBSTEPS",
    "WorldSpec",
]

#: The palm box's half-thickness, m.
PALM_HALF_THICKNESS = 0.008
#: A flying ball's ``contype`` and ``conaffinity`` (a held ball's are 0: in the fingers):
#: it collides with palms and the floor (contype 1), not with another ball (2 & 1 = 0).
BALL_CONTYPE, BALL_CONAFFINITY = 2, 1
#: The most balls a world holds.
MAX_BALLS = 5
#: kg/m^3, the air of the worlds with drag (Juggling-v2, Cascade-v1): sea level, 20 C.
AIR_DENSITY = 1.2
#: The damping ratio of the palm's and ball's contact in the worlds with the capture at
#: impact (Juggling-v2, Cascade-v1): a restitution of about 0.5, so a ball met too fast
#: bounces out of the hand.
IMPACT_CONTACT_DAMPING = 0.2


@dataclass(frozen=True)
class WorldSpec:
    """What a juggling world is (module docstring); every field is checked.

    Parameters
    ----------
    hands, balls : int
        1 or 2 hands; 1 to :data:`MAX_BALLS` balls.
    gravity, dt, ball_radius, ball_mass, floor_z, toss_threshold : float
        The task's (:class:`~motion_envs.datasets.juggling.JugglingTask`): m/s^2, the
        control period s, m, kg, m, m/s^2 (the release rule's threshold).
    hand_mass : float
        kg.
    speed_limit, accel_limit : float
        The hand's peak speed (m/s) and acceleration (m/s^2).
    capture_speed : float
        Relative speed (m/s) under which a falling ball touching a palm is caught.
    servo_omega : float
        The computed-torque servo's bandwidth, rad/s (critically damped).
    substeps : int
        Physics steps per control period.
    air_density : float
        kg/m^3 of the air the balls fly through (MuJoCo's fluid model, ``option
        density``); 0 (the default): no air. With air, each ball's quadratic drag is set
        per episode by :meth:`HandsWorld.set_drag` (module docstring, *Air drag*).
    impact_capture : bool
        The capture rule in the hand's frame (module docstring, *Capture at impact*);
        False (the default): the contact rule above.
    contact_damping : float
        The damping ratio of the balls' and palms' contacts (MuJoCo ``solref``'s second
        number; time constant 4 ms). 1 (the default): critically damped, a ball does not
        bounce; below 1 a palm met too fast throws the ball back (0.2: a restitution of
        about 0.5), as a stiff hand does.
    """

    hands: int = 1
    balls: int = 1
    gravity: float = 9.81
    dt: float = 0.005
    ball_radius: float = 0.035
    ball_mass: float = 0.13
    floor_z: float = 0.5
    toss_threshold: float = 29.43
    hand_mass: float = 0.5
    speed_limit: float = 6.0
    accel_limit: float = 120.0
    capture_speed: float = 5.0
    servo_omega: float = 60.0
    substeps: int = 5
    air_density: float = 0.0
    impact_capture: bool = False
    contact_damping: float = 1.0

    def __post_init__(self) -> None:
        if not isinstance(self.impact_capture, (bool, np.bool_)):
            raise ValueError(
                f"WorldSpec.impact_capture must be a bool; got {self.impact_capture!r}"
            )
        if not (
            isinstance(self.air_density, (int, float))
            and math.isfinite(self.air_density)
            and 0 <= self.air_density <= 100
        ):
            raise ValueError(
                "WorldSpec.air_density must be a number in [0, 100] kg/m^3; "
                f"got {self.air_density!r}"
            )
        for name in ("hands", "balls", "substeps"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
                raise ValueError(f"WorldSpec.{name} must be an int; got {value!r}")
        if self.hands not in (1, 2):
            raise ValueError(f"WorldSpec.hands must be 1 or 2; got {self.hands}")
        if not 1 <= self.balls <= MAX_BALLS:
            raise ValueError(f"WorldSpec.balls must be 1 to {MAX_BALLS}; got {self.balls}")
        if not 1 <= self.substeps <= 100:
            raise ValueError(f"WorldSpec.substeps must be 1 to 100; got {self.substeps}")
        for f in fields(self):
            value = getattr(self, f.name)
            if f.name in ("hands", "balls", "substeps", "floor_z", "air_density", "impact_capture"):
                continue
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise ValueError(f"WorldSpec.{f.name} must be a finite number > 0; got {value!r}")
        if not math.isfinite(self.floor_z):
            raise ValueError(f"WorldSpec.floor_z must be finite; got {self.floor_z!r}")

    @classmethod
    def of(cls, task: JugglingTask, hands: int = 1, balls: int = 1, **limits: Any) -> WorldSpec:
        """The spec of ``task``'s world with ``hands`` and ``balls`` (and any of the hands'
        limits given by name)."""
        return cls(
            hands=hands,
            balls=balls,
            gravity=task.gravity,
            dt=task.dt,
            ball_radius=task.ball_radius,
            ball_mass=task.ball_mass,
            floor_z=task.floor_z,
            toss_threshold=task.toss_threshold,
            **limits,
        )

    @property
    def physics_step(self) -> float:
        """MuJoCo's timestep, ``dt / substeps``."""
        return self.dt / self.substeps

    @property
    def palm_top(self) -> float:
        """Height of a palm's top face above its hand origin (``-ball_radius``)."""
        return -(self.ball_radius + PALM_HALF_THICKNESS) + PALM_HALF_THICKNESS

    @property
    def hand_names(self) -> tuple[str, ...]:
        """``("hand",)`` or ``("hand_right", "hand_left")`` (the right hand first)."""
        return ("hand",) if self.hands == 1 else ("hand_right", "hand_left")

    @property
    def ball_names(self) -> tuple[str, ...]:
        """``("ball",)`` or ``("ball0", "ball1", ...)``."""
        return ("ball",) if self.balls == 1 else tuple(f"ball{i}" for i in range(self.balls))

    def constants(self) -> NDArray[np.float64]:
        """The period's ``constants``, in ``_period.CONSTANT_NAMES``' order."""
        values = {f.name: getattr(self, f.name) for f in fields(self)}
        values.update(
            physics_step=self.physics_step,
            palm_top=self.palm_top,
            ball_contype=BALL_CONTYPE,
            ball_conaffinity=BALL_CONAFFINITY,
            impact_capture=float(self.impact_capture),
        )
        return np.array([float(values[name]) for name in _period.CONSTANT_NAMES])


#: The default spec's hand and catch limits (each a :class:`WorldSpec` field's default).
HAND_SPEED_LIMIT: float = WorldSpec.speed_limit
HAND_ACCEL_LIMIT: float = WorldSpec.accel_limit
HAND_MASS: float = WorldSpec.hand_mass
CAPTURE_SPEED: float = WorldSpec.capture_speed
SERVO_OMEGA: float = WorldSpec.servo_omega
SUBSTEPS: int = WorldSpec.substeps
