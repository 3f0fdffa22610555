"""Deprecated: ``motion_envs.datasets.juggling_task`` moved to
:mod:`motion_envs.datasets.juggling`; import from there.

This module only re-exports the names it had, and warns (``DeprecationWarning``).
"""

import warnings

from motion_envs.datasets.juggling import (
    PHASES,
    JugglingNoise,
    JugglingState,
    JugglingTask,
    ballistic_position,
    ballistic_velocity,
)

__all__ = [
    "PHASES",
    "JugglingNoise",
    "JugglingState",
    "JugglingTask",
    "ballistic_position",
    "ballistic_velocity",
]

warnings.warn(
    "motion_envs.datasets.juggling_task is deprecated; import from motion_envs.datasets.juggling",
    DeprecationWarning,
    stacklevel=2,
)
