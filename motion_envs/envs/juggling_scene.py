"""Deprecated: ``motion_envs.envs.juggling_scene`` moved to
:mod:`motion_envs.envs.juggling`; import from there.

This module only re-exports the names it had, and warns (``DeprecationWarning``).
"""

import warnings

from motion_envs.envs.juggling import (
    SCENE_XML,
    JugglingScene,
    check_task,
    load_juggling_model,
)

__all__ = [
    "SCENE_XML",
    "JugglingScene",
    "check_task",
    "load_juggling_model",
]

warnings.warn(
    "motion_envs.envs.juggling_scene is deprecated; import from motion_envs.envs.juggling",
    DeprecationWarning,
    stacklevel=2,
)
