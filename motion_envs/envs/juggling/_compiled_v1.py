"""Juggling-v1's step beyond the world's period compiled by numba: the functions of
:mod:`~motion_envs.envs.juggling._v1_step` (the same bodies, their global names bound to
the compiled equivalents, as :mod:`~motion_envs.envs.juggling._compiled` compiles the
period; bit-identical to the plain-Python path: tested), the human-likeness by the k-d
tree search (:func:`hand_likeness`).

Importing this module imports numba (the ``fast`` extra).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numba import njit

from motion_envs.envs.juggling import _v1_step
from motion_envs.envs.juggling._compiled import bound, py_hypot, world_periods
from motion_envs.envs.juggling._compiled_likeness import nearest_in_tree

__all__ = ["hand_likeness", "v1_advance", "v1_aim", "v1_command", "v1_finish", "v1_observe"]
__all__ += ["v1_rest", "v1_step"]


@njit(cache=True)
def hand_likeness(trees: Any, phase: int, point: Any, tau: float, stack: Any) -> float:
    """:func:`~motion_envs.envs.juggling._v1_step.hand_likeness`'s number from the phase's
    k-d tree (``trees = (forest, roots)``: the phases' trees as one
    :func:`~motion_envs.envs.juggling._compiled_likeness.likeness_forest`; ``stack``: the
    search's work array)."""
    q = np.empty(4)
    q[0], q[1], q[2], q[3] = point[0], point[1], tau * point[2], tau * point[3]
    return nearest_in_tree(trees[0], q, stack, trees[1][phase])


_advance = njit(cache=True)(bound(_v1_step.advance))
_aim = njit(cache=True)(bound(_v1_step.aim))
#: :func:`~motion_envs.envs.juggling._v1_step.v1_command` compiled.
v1_command = njit(cache=True)(
    bound(_v1_step.v1_command, py_hypot=py_hypot, advance=_advance, aim=_aim)
)
#: :func:`~motion_envs.envs.juggling._v1_step.v1_advance` compiled.
v1_advance = njit(cache=True)(bound(_v1_step.v1_advance, advance=_advance, aim=_aim))
#: :func:`~motion_envs.envs.juggling._v1_step.v1_aim` compiled.
v1_aim = njit(cache=True)(bound(_v1_step.v1_aim, aim=_aim))
#: :func:`~motion_envs.envs.juggling._v1_step.v1_observe` compiled.
v1_observe = njit(cache=True)(bound(_v1_step.v1_observe))
#: :func:`~motion_envs.envs.juggling._v1_step.v1_finish` compiled.
v1_finish = njit(cache=True)(
    bound(_v1_step.v1_finish, hand_likeness=hand_likeness, v1_observe=v1_observe)
)
#: :func:`~motion_envs.envs.juggling._v1_step.v1_rest` compiled (the period and the finish
#: in one call).
v1_rest = njit(cache=True)(
    bound(_v1_step.v1_rest, world_periods=world_periods, v1_finish=v1_finish)
)
#: :func:`~motion_envs.envs.juggling._v1_step.v1_step` compiled (a whole step in one call).
v1_step = njit(cache=True)(bound(_v1_step.v1_step, v1_command=v1_command, v1_rest=v1_rest))
