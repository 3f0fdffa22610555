"""Deprecated: ``motion_envs.datasets.juggling_csv`` moved to
:mod:`motion_envs.datasets.juggling`; import from there.

This module only re-exports the names it had, and warns (``DeprecationWarning``).
"""

import warnings

from motion_envs.datasets.juggling import (
    JUGGLING_COLUMNS,
    MIN_SAMPLES,
    read_juggling_csv,
    write_juggling_csv,
)

__all__ = [
    "JUGGLING_COLUMNS",
    "MIN_SAMPLES",
    "read_juggling_csv",
    "write_juggling_csv",
]

warnings.warn(
    "motion_envs.datasets.juggling_csv is deprecated; import from motion_envs.datasets.juggling",
    DeprecationWarning,
    stacklevel=2,
)
