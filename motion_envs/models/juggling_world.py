"""Deprecated: ``motion_envs.models.juggling_world`` moved to
:mod:`motion_envs.models.juggling`; import from there.

This module only re-exports the names it had, and warns (``DeprecationWarning``).
"""

import warnings

from motion_envs.models.juggling import (
    TRACKING_ROWS,
    BallisticWorld,
    draw_episode_noise,
)

__all__ = [
    "TRACKING_ROWS",
    "BallisticWorld",
    "draw_episode_noise",
]

warnings.warn(
    "motion_envs.models.juggling_world is deprecated; import from motion_envs.models.juggling",
    DeprecationWarning,
    stacklevel=2,
)
