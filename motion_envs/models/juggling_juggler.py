"""Deprecated: ``motion_envs.models.juggling_juggler`` moved to
:mod:`motion_envs.models.juggling`; import from there.

This module only re-exports the names it had, and warns (``DeprecationWarning``).
"""

import warnings

from motion_envs.geometry.jerk import (
    minimum_jerk,
)
from motion_envs.models.juggling import (
    AnalyticJuggler,
    PhaseFit,
    phase_conditions,
    plan_catch,
)

__all__ = [
    "AnalyticJuggler",
    "PhaseFit",
    "minimum_jerk",
    "phase_conditions",
    "plan_catch",
]

warnings.warn(
    "motion_envs.models.juggling_juggler is deprecated; import from motion_envs.models.juggling",
    DeprecationWarning,
    stacklevel=2,
)
