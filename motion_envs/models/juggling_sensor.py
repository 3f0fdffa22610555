"""Deprecated alias of :mod:`motion_envs.models.juggling` (warns); import from there."""

import warnings

from motion_envs.models.juggling import *  # noqa: F403

warnings.warn(
    f"{__name__} is deprecated; import from motion_envs.models.juggling", DeprecationWarning, 2
)
