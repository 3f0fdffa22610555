"""Nominal trajectories of both motion kinds, in one namespace.

The code lives in :mod:`motion_envs.models.orientation_nominal` (Faraway & Choe) and
:mod:`motion_envs.models.position_nominal` (Lippi et al.); this module re-exports their
public names so ``from motion_envs.models.nominal import ...`` keeps working.
"""

from __future__ import annotations

from motion_envs.models.orientation_nominal import (
    ORIENTATION_NOMINALS,
    OrientationGrids,
    OrientationNominal,
    orientation_criterion,
)
from motion_envs.models.position_nominal import (
    CONDITION_KINDS,
    POSITION_CONDITIONS,
    POSITION_NOMINALS,
    POSITION_SPLITS,
    PositionGrids,
    PositionNominal,
    median_of_task_medians,
    position_conditions,
    position_folds,
    position_grids,
    resample_positions,
    varying_columns,
)

__all__ = [
    "CONDITION_KINDS",
    "ORIENTATION_NOMINALS",
    "POSITION_CONDITIONS",
    "POSITION_NOMINALS",
    "POSITION_SPLITS",
    "OrientationGrids",
    "OrientationNominal",
    "PositionGrids",
    "PositionNominal",
    "median_of_task_medians",
    "orientation_criterion",
    "position_conditions",
    "position_folds",
    "position_grids",
    "resample_positions",
    "varying_columns",
]
