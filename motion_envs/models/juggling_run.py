"""Deprecated: ``motion_envs.models.juggling_run`` moved to
:mod:`motion_envs.models.juggling`; import from there.

This module only re-exports the names it had, and warns (``DeprecationWarning``).
"""

import warnings

from motion_envs.models.juggling import (
    CycleResult,
    cycle_rngs,
    fit_juggler,
    run_cycle,
    run_cycles,
    run_cycles_fast,
)

__all__ = [
    "CycleResult",
    "cycle_rngs",
    "fit_juggler",
    "run_cycle",
    "run_cycles",
    "run_cycles_fast",
]

warnings.warn(
    "motion_envs.models.juggling_run is deprecated; import from motion_envs.models.juggling",
    DeprecationWarning,
    stacklevel=2,
)
