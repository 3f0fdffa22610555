"""The hand's human-likeness for a single environment, compiled when numba is installed.

:meth:`~motion_envs.models.juggling.HumanLikeness.distance` (the distance of ``(x, z,
tau vx, tau vz)`` to the phase's nearest demonstrated sample) is the reward's
human-likeness term. In plain Python it costs about as much as the world's whole control
period; here the same number comes from the compiled k-d tree search of
:mod:`~motion_envs.envs.juggling._compiled` (the native vector environments' search, the
same result bit for bit: tested), called directly with each phase's tree bound once.
"""

from __future__ import annotations

import weakref
from typing import Any

import numpy as np

from motion_envs.datasets.juggling import PHASES
from motion_envs.envs._kernels import numba_available
from motion_envs.models.juggling import LIKENESS_TAU, HumanLikeness

__all__ = ["LikenessQuery"]

#: Each likeness's compiled trees, per phase (built once: environments share a likeness).
_TREES: weakref.WeakKeyDictionary[HumanLikeness, dict[str, tuple[Any, ...]]] = (
    weakref.WeakKeyDictionary()
)


class LikenessQuery:
    """``distance(phase, hand_pos, hand_vel)`` of ``likeness``, compiled if possible."""

    def __init__(self, likeness: HumanLikeness) -> None:
        self.likeness = likeness
        self._link()

    def _link(self) -> None:
        self._calls: dict[str, tuple[Any, tuple[Any, ...]]] | None = None
        if not numba_available():
            return
        from motion_envs.envs.juggling import _compiled

        self._q = np.zeros(4)
        stack = np.empty(256, dtype=np.int64)
        kernel = _compiled.nearest_point
        trees = _TREES.get(self.likeness)
        if trees is None:
            trees = {p: _compiled.likeness_tree(self.likeness.trees[p].data) for p in PHASES}
            _TREES[self.likeness] = trees
        calls = {}
        for phase in PHASES:
            args = (*trees[phase], self._q, stack)
            entry = _compiled.entry_point(kernel, *args, probe=False)
            calls[phase] = (entry, args)
        self._calls = calls

    def distance(self, phase: str, hand_pos: Any, hand_vel: Any) -> float:
        """m; :meth:`HumanLikeness.distance`'s number."""
        if self._calls is None:
            return self.likeness.distance(phase, hand_pos, hand_vel)
        q = self._q
        q[0], q[1] = float(hand_pos[0]), float(hand_pos[1])
        q[2], q[3] = LIKENESS_TAU * float(hand_vel[0]), LIKENESS_TAU * float(hand_vel[1])
        entry, args = self._calls[phase]
        return float(entry(*args))

    def __getstate__(self) -> dict[str, Any]:
        return {"likeness": self.likeness}

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.likeness = state["likeness"]
        self._link()
