"""The episodic (black-box) reaching environments, re-exported.

``MotionEnvs/OrientationCoefficients-v0`` lives in
:mod:`motion_envs.envs.orientation_coefficients`, ``MotionEnvs/PositionCoefficients-v0``
in :mod:`motion_envs.envs.position_coefficients`, their shared core in
:mod:`motion_envs.envs._coefficients`; this module keeps the former import path.
"""

from motion_envs.envs._coefficients import (
    MAX_COEFFICIENT_SINES,
    CoefficientEnv,
    CoefficientVectorEnv,
    line_frames,
)
from motion_envs.envs.orientation_coefficients import (
    OrientationCoefficientsEnv,
    OrientationCoefficientsVectorEnv,
)
from motion_envs.envs.position_coefficients import (
    PositionCoefficientsEnv,
    PositionCoefficientsVectorEnv,
)

__all__ = [
    "MAX_COEFFICIENT_SINES",
    "CoefficientEnv",
    "CoefficientVectorEnv",
    "OrientationCoefficientsEnv",
    "OrientationCoefficientsVectorEnv",
    "PositionCoefficientsEnv",
    "PositionCoefficientsVectorEnv",
    "line_frames",
]
