"""The ball as a person sees it: a delayed, noisy measurement, and the release's scatter.

Juggling-v1's agent and analytic juggler observe the flying ball through the same
:class:`BallSensor`: the measurement available at control step ``k`` is the true ball
state of step ``k - d`` (``d = round(latency / dt)`` control periods: the visuomotor
delay, 100-200 ms in people) plus white Gaussian noise (``position_std`` m on the
position, ``velocity_std`` m/s on the velocity). While the ball is held the hand knows
where it is (touch, no delay): the measurement is the true state.

:func:`perturb_release` scatters a toss as a person's release does: the release speed by
a relative error and the release direction by an angle (not each velocity component
apart, which would leave a vertical toss without sideways error).

Pure numpy (the ``models`` layer); :func:`predict_forward` is the ballistic prediction a
latency-aware controller uses to bring a measurement ``latency`` seconds forward.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

import numpy as np

from motion_envs._typing import FloatArray
from motion_envs.datasets.juggling import rules

__all__ = ["BallMeasurement", "BallSensor", "perturb_release", "predict_forward"]


def perturb_release(
    velocity: FloatArray,
    speed_std: float,
    angle_std: float,
    rng: np.random.Generator | None,
) -> FloatArray:
    """``velocity (2,)`` with its speed times ``1 + speed_std N(0, 1)`` and its direction
    turned by ``angle_std N(0, 1)`` radians (counter-clockwise in the ``x, z`` plane).

    Two normals are drawn (speed, then angle) when either std is positive; none otherwise.
    """
    v = np.asarray(velocity, dtype=np.float64)
    if speed_std == 0 and angle_std == 0:
        return v.copy()
    if rng is None:
        raise ValueError("rng is required when the release noise is non-zero")
    e_speed, e_angle = rng.standard_normal(2)
    factor = 1.0 + speed_std * float(e_speed)
    theta = angle_std * float(e_angle)
    c, s = math.cos(theta), math.sin(theta)
    return np.array([c * v[0] - s * v[1], s * v[0] + c * v[1]]) * factor


def predict_forward(
    position: FloatArray, velocity: FloatArray, seconds: float, gravity: float
) -> tuple[FloatArray, FloatArray]:
    """The ballistic state ``seconds`` later (the world's flight rule,
    :func:`motion_envs.datasets.juggling.rules.flight`)."""
    x, z, vx, vz = rules.flight(
        (0.0, float(position[0]), float(position[1]), float(velocity[0]), float(velocity[1])),
        float(seconds),
        gravity,
    )
    return np.array([x, z]), np.array([vx, vz])


@dataclass(frozen=True)
class BallMeasurement:
    """What the sensor reports at one control step: ``(x, z)`` position and velocity."""

    position: FloatArray
    velocity: FloatArray


class BallSensor:
    """A delayed, noisy view of the ball (see the module docstring).

    Parameters
    ----------
    delay_steps:
        Control periods between the ball's state and its measurement (``>= 0``).
    position_std, velocity_std:
        Std of the white measurement noise, m and m/s (``>= 0``).
    """

    def __init__(self, delay_steps: int, position_std: float, velocity_std: float) -> None:
        if isinstance(delay_steps, bool) or int(delay_steps) != delay_steps or delay_steps < 0:
            raise ValueError(f"delay_steps must be an integer >= 0; got {delay_steps!r}")
        for name, value in (("position_std", position_std), ("velocity_std", velocity_std)):
            if not math.isfinite(value) or value < 0:
                raise ValueError(f"{name} must be finite and >= 0; got {value!r}")
        self.delay_steps = int(delay_steps)
        self.position_std = float(position_std)
        self.velocity_std = float(velocity_std)
        self._buffer: deque[tuple[float, float, float, float, bool]] = deque(
            maxlen=self.delay_steps + 1
        )
        self._rng: np.random.Generator | None = None

    def reset(
        self, position: FloatArray, velocity: FloatArray, rng: np.random.Generator | None
    ) -> BallMeasurement:
        """Start with the ball held at ``position``; the buffer is filled with that state."""
        self._rng = rng
        self._buffer.clear()
        px, pz = (float(v) for v in position)
        vx, vz = (float(v) for v in velocity)
        for _ in range(self.delay_steps + 1):
            self._buffer.append((px, pz, vx, vz, True))
        return BallMeasurement(np.array([px, pz]), np.array([vx, vz]))

    def measure(self, position: FloatArray, velocity: FloatArray, held: bool) -> BallMeasurement:
        """Record the true state of this step; return the measurement it makes available.

        A held ball is measured exactly (the hand feels it). A flying ball is reported as it
        was ``delay_steps`` steps ago (held then: exactly; flying: plus the noise).
        """
        px, pz, vx, vz = self.measure_values(
            float(position[0]), float(position[1]), float(velocity[0]), float(velocity[1]), held
        )
        return BallMeasurement(np.array([px, pz]), np.array([vx, vz]))

    def measure_values(
        self, px: float, pz: float, vx: float, vz: float, held: bool
    ) -> tuple[float, float, float, float]:
        """:meth:`measure` of the true ``(x, z, vx, vz)`` as floats (the env's hot path)."""
        self._buffer.append((px, pz, vx, vz, held))
        if held:
            return px, pz, vx, vz
        px, pz, vx, vz, was_held = self._buffer[0]
        if not was_held and (self.position_std > 0 or self.velocity_std > 0):
            if self._rng is None:
                raise ValueError("rng is required when the measurement noise is non-zero")
            e = self._rng.standard_normal(4).tolist()
            px += self.position_std * e[0]
            pz += self.position_std * e[1]
            vx += self.velocity_std * e[2]
            vz += self.velocity_std * e[3]
        return px, pz, vx, vz
