"""Deprecated: ``motion_envs.models.juggling_segmentation`` moved to
:mod:`motion_envs.models.juggling`; import from there.

This module only re-exports the names it had, and warns (``DeprecationWarning``).
"""

import warnings

from motion_envs.models.juggling import (
    load_juggling_csv,
    segment_demos,
    segment_juggling,
)

__all__ = [
    "load_juggling_csv",
    "segment_demos",
    "segment_juggling",
]

warnings.warn(
    "motion_envs.models.juggling_segmentation is deprecated; "
    "import from motion_envs.models.juggling",
    DeprecationWarning,
    stacklevel=2,
)
