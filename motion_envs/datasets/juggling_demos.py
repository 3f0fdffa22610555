"""Deprecated: ``motion_envs.datasets.juggling_demos`` moved to
:mod:`motion_envs.datasets.juggling`; import from there.

This module only re-exports the names it had, and warns (``DeprecationWarning``).
"""

import warnings

from motion_envs.datasets.juggling import (
    SIMULATED_LABEL,
    JugglingDemos,
    JugglingRecording,
    PersonStyle,
    PhaseSegment,
    departure_from_line,
    draw_person,
    generate_demonstrations,
    resample_path,
    split_cycles,
)
from motion_envs.geometry.jerk import (
    quintic,
)

__all__ = [
    "SIMULATED_LABEL",
    "JugglingDemos",
    "JugglingRecording",
    "PersonStyle",
    "PhaseSegment",
    "departure_from_line",
    "draw_person",
    "generate_demonstrations",
    "quintic",
    "resample_path",
    "split_cycles",
]

warnings.warn(
    "motion_envs.datasets.juggling_demos is deprecated; import from motion_envs.datasets.juggling",
    DeprecationWarning,
    stacklevel=2,
)
