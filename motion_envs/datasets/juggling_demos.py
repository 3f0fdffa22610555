"""Deprecated alias of :mod:`motion_envs.datasets.juggling` (warns); import from there."""

import warnings

from motion_envs.datasets.juggling import *  # noqa: F403
from motion_envs.geometry.minimum_jerk import quintic  # noqa: F401

warnings.warn(
    f"{__name__} is deprecated; import from motion_envs.datasets.juggling", DeprecationWarning, 2
)
