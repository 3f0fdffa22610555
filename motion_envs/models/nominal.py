"""Nominal trajectories of both motion kinds, in one namespace.

The code lives in :mod:`motion_envs.models.orientation_nominal` (Faraway & Choe) and
:mod:`motion_envs.models.position_nominal` (Lippi et al.); this module re-exports their
public names so ``from motion_envs.models.nominal import ...`` keeps working (explicit
re-exports, no ``__all__``: the names are documented once, in their own modules).
"""

from __future__ import annotations

from motion_envs.models.orientation_nominal import (
    ORIENTATION_NOMINALS as ORIENTATION_NOMINALS,
)
from motion_envs.models.orientation_nominal import (
    OrientationGrids as OrientationGrids,
)
from motion_envs.models.orientation_nominal import (
    OrientationNominal as OrientationNominal,
)
from motion_envs.models.orientation_nominal import (
    orientation_criterion as orientation_criterion,
)
from motion_envs.models.position_nominal import (
    CONDITION_KINDS as CONDITION_KINDS,
)
from motion_envs.models.position_nominal import (
    POSITION_CONDITIONS as POSITION_CONDITIONS,
)
from motion_envs.models.position_nominal import (
    POSITION_NOMINALS as POSITION_NOMINALS,
)
from motion_envs.models.position_nominal import (
    POSITION_SPLITS as POSITION_SPLITS,
)
from motion_envs.models.position_nominal import (
    PositionGrids as PositionGrids,
)
from motion_envs.models.position_nominal import (
    PositionNominal as PositionNominal,
)
from motion_envs.models.position_nominal import (
    median_of_task_medians as median_of_task_medians,
)
from motion_envs.models.position_nominal import (
    position_conditions as position_conditions,
)
from motion_envs.models.position_nominal import (
    position_folds as position_folds,
)
from motion_envs.models.position_nominal import (
    position_grids as position_grids,
)
from motion_envs.models.position_nominal import (
    resample_positions as resample_positions,
)
from motion_envs.models.position_nominal import (
    varying_columns as varying_columns,
)
