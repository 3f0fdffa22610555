"""Pure-numpy geometry: unit quaternions, Bézier curves, sine series, Beta speed profiles,
minimum jerk, smoothed derivatives, smoothness measures, resampling.

Every function works on batches (leading axes) and states its formula in the docstring.
Every public name of the submodules is exported here (``from motion_envs.geometry import
slerp, smoothed_velocity, resample``), loaded on first use so that importing the package
stays cheap. The submodules are exported too; the names two of them would share are
reached through their module: ``bezier.evaluate`` / ``sine_series.evaluate`` and
``minimum_jerk.minimum_jerk`` (``geometry.minimum_jerk`` is the module).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from motion_envs._lazy import lazy_exports
from motion_envs.geometry import beta_profile, bezier, quaternion, sine_series

if TYPE_CHECKING:
    from motion_envs.geometry import kinematics, minimum_jerk, resampling, smoothness
    from motion_envs.geometry.beta_profile import beta_alpha, beta_speed
    from motion_envs.geometry.bezier import bernstein_interior, fit, fit_operator
    from motion_envs.geometry.kinematics import (
        DEFAULT_POLYORDER,
        DEFAULT_WINDOW,
        Derivative,
        sample_rate,
        smoothed_acceleration,
        smoothed_derivative,
        smoothed_jerk,
        smoothed_velocity,
        speed,
        window_samples,
    )
    from motion_envs.geometry.minimum_jerk import minimum_jerk_profile, quintic, quintic_evaluate
    from motion_envs.geometry.quaternion import (
        IDENTITY,
        UNIT_TOLERANCE,
        angle,
        as_unit,
        conjugate,
        expmap,
        from_rotation,
        logmap,
        make_continuous,
        multiply,
        normalize,
        slerp,
        to_rotation,
    )
    from motion_envs.geometry.resampling import (
        check_rate,
        recording_times,
        resample,
        time_normalise,
        times_in_seconds,
    )
    from motion_envs.geometry.sine_series import (
        acceleration,
        basis,
        basis_derivative,
        basis_second_derivative,
        dst_coefficients,
        fit_coefficients,
        is_uniform,
        lstsq_coefficients,
        normalised_time,
        residual,
        velocity,
    )
    from motion_envs.geometry.smoothness import log_dimensionless_jerk, spectral_arc_length

#: Exported name -> the submodule that defines it.
_EXPORTS: dict[str, str] = {
    "DEFAULT_POLYORDER": "kinematics",
    "DEFAULT_WINDOW": "kinematics",
    "Derivative": "kinematics",
    "IDENTITY": "quaternion",
    "UNIT_TOLERANCE": "quaternion",
    "acceleration": "sine_series",
    "angle": "quaternion",
    "as_unit": "quaternion",
    "basis": "sine_series",
    "basis_derivative": "sine_series",
    "basis_second_derivative": "sine_series",
    "bernstein_interior": "bezier",
    "beta_alpha": "beta_profile",
    "beta_speed": "beta_profile",
    "check_rate": "resampling",
    "conjugate": "quaternion",
    "dst_coefficients": "sine_series",
    "expmap": "quaternion",
    "fit": "bezier",
    "fit_coefficients": "sine_series",
    "fit_operator": "bezier",
    "from_rotation": "quaternion",
    "is_uniform": "sine_series",
    "log_dimensionless_jerk": "smoothness",
    "logmap": "quaternion",
    "lstsq_coefficients": "sine_series",
    "make_continuous": "quaternion",
    "minimum_jerk_profile": "minimum_jerk",
    "multiply": "quaternion",
    "normalised_time": "sine_series",
    "quintic": "minimum_jerk",
    "quintic_evaluate": "minimum_jerk",
    "normalize": "quaternion",
    "recording_times": "resampling",
    "resample": "resampling",
    "residual": "sine_series",
    "sample_rate": "kinematics",
    "slerp": "quaternion",
    "smoothed_acceleration": "kinematics",
    "smoothed_derivative": "kinematics",
    "smoothed_jerk": "kinematics",
    "smoothed_velocity": "kinematics",
    "spectral_arc_length": "smoothness",
    "speed": "kinematics",
    "time_normalise": "resampling",
    "times_in_seconds": "resampling",
    "to_rotation": "quaternion",
    "velocity": "sine_series",
    "window_samples": "kinematics",
}
_SUBMODULES = (
    "beta_profile",
    "bezier",
    "kinematics",
    "minimum_jerk",
    "quaternion",
    "resampling",
    "sine_series",
    "smoothness",
)

__all__ = [
    "DEFAULT_POLYORDER",
    "DEFAULT_WINDOW",
    "IDENTITY",
    "UNIT_TOLERANCE",
    "Derivative",
    "acceleration",
    "angle",
    "as_unit",
    "basis",
    "basis_derivative",
    "basis_second_derivative",
    "bernstein_interior",
    "beta_alpha",
    "beta_profile",
    "beta_speed",
    "bezier",
    "check_rate",
    "conjugate",
    "dst_coefficients",
    "expmap",
    "fit",
    "fit_coefficients",
    "fit_operator",
    "from_rotation",
    "is_uniform",
    "kinematics",
    "log_dimensionless_jerk",
    "logmap",
    "lstsq_coefficients",
    "make_continuous",
    "minimum_jerk",
    "minimum_jerk_profile",
    "multiply",
    "normalised_time",
    "normalize",
    "quaternion",
    "quintic",
    "quintic_evaluate",
    "recording_times",
    "resample",
    "resampling",
    "residual",
    "sample_rate",
    "sine_series",
    "slerp",
    "smoothed_acceleration",
    "smoothed_derivative",
    "smoothed_jerk",
    "smoothed_velocity",
    "smoothness",
    "spectral_arc_length",
    "speed",
    "time_normalise",
    "times_in_seconds",
    "to_rotation",
    "velocity",
    "window_samples",
]


__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, _SUBMODULES)
