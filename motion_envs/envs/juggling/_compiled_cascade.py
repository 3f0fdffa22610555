"""Cascade-v0's step beyond the worlds' period compiled by numba: the functions of
:mod:`~motion_envs.envs.juggling._cascade_step` (the same bodies, their global names bound
to the compiled equivalents, as :mod:`~motion_envs.envs.juggling._compiled` compiles the
period; bit-identical to the plain-Python path: tested), the human-likeness by the k-d
tree search (:func:`~motion_envs.envs.juggling._compiled_v1.hand_likeness`).

Importing this module imports numba (the ``fast`` extra).
"""

from __future__ import annotations

from numba import njit

from motion_envs.envs.juggling import _cascade_step
from motion_envs.envs.juggling._compiled import bound, py_hypot, world_periods
from motion_envs.envs.juggling._compiled_v1 import hand_likeness

__all__ = [
    "cascade_advance",
    "cascade_aim",
    "cascade_command",
    "cascade_finish",
    "cascade_observe",
    "cascade_period",
]

_holds = njit(cache=True)(bound(_cascade_step.holds))
_advance = njit(cache=True)(bound(_cascade_step.advance))
_aim = njit(cache=True)(bound(_cascade_step.aim))
#: :func:`~motion_envs.envs.juggling._cascade_step.cascade_command` compiled.
cascade_command = njit(cache=True)(
    bound(_cascade_step.cascade_command, py_hypot=py_hypot, holds=_holds, advance=_advance,
          aim=_aim)
)  # fmt: skip
#: :func:`~motion_envs.envs.juggling._cascade_step.cascade_advance` compiled.
cascade_advance = njit(cache=True)(bound(_cascade_step.cascade_advance, advance=_advance, aim=_aim))
#: :func:`~motion_envs.envs.juggling._cascade_step.cascade_aim` compiled.
cascade_aim = njit(cache=True)(bound(_cascade_step.cascade_aim, aim=_aim))
#: :func:`~motion_envs.envs.juggling._cascade_step.cascade_observe` compiled.
cascade_observe = njit(cache=True)(bound(_cascade_step.cascade_observe, holds=_holds))
#: :func:`~motion_envs.envs.juggling._cascade_step.cascade_finish` compiled.
cascade_finish = njit(cache=True)(
    bound(_cascade_step.cascade_finish, hand_likeness=hand_likeness, holds=_holds,
          cascade_observe=cascade_observe)
)  # fmt: skip
#: :func:`~motion_envs.envs.juggling._cascade_step.cascade_period` compiled.
cascade_period = njit(cache=True)(
    bound(_cascade_step.cascade_period, world_periods=world_periods, cascade_finish=cascade_finish)
)
