"""Person calibration in the environments' observations (``calibration=K``).

With ``calibration=K > 0`` an orientation environment's observation ends with the
calibration summary of :mod:`motion_envs.models.person_calibration`
(:func:`~motion_envs.models.person_calibration.calibration_summaries`): the mean over
``K`` other reaches of the episode's person, drawn at ``reset`` with the environment's
generator among the person's trajectories *of the same split* (without replacement,
never the episode's own; all of them when the person has fewer), of their own
path-frame residual's first sine coefficients (clipped), then the share drawn ``m / K``.
The coefficient environments (:mod:`motion_envs.envs._coefficients`) and the reaching
step environments (:mod:`motion_envs.envs._reach`) hold one :class:`CalibrationDraws`
each; the native vector environments draw with every sub-environment's generator in the
same order as the single environment (trajectory first, then the calibration reaches).
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from numpy.typing import NDArray

from motion_envs._typing import FloatArray
from motion_envs.envs._common import check_integer
from motion_envs.models.person_calibration import (
    SUMMARY_BOUND,
    calibration_features,
    calibration_summaries,
)

__all__ = [
    "MAX_CALIBRATION",
    "CalibrationDraws",
    "check_calibration",
    "orientation_calibration_features",
]

#: Largest ``calibration`` (reaches of the person in the summary).
MAX_CALIBRATION = 1000


def check_calibration(calibration: Any) -> int:
    """``calibration`` as an integer in ``[0, MAX_CALIBRATION]`` (``ValueError`` naming it)."""
    return check_integer(calibration, "calibration", 0, MAX_CALIBRATION)


def orientation_calibration_features(task: Any) -> FloatArray:
    """``(L, f)`` calibration features of an orientation task's trajectories: each one's
    own human residual (``task.grids.residuals``, against the environment's base slerp)
    in its path frame (:func:`motion_envs.models.path_frame.path_frames`, the task's
    ``up``), as :func:`~motion_envs.models.person_calibration.calibration_features`."""
    from motion_envs.models.path_frame import path_frames

    g = task.grids
    frames, scales = path_frames(g.starts, g.goals, task.up)
    local = np.einsum("lij,lti->ltj", frames, np.asarray(g.residuals)) / scales[:, None, None]
    return calibration_features(local)


class CalibrationDraws:
    """The calibration reaches of a split and the summary of a draw.

    Parameters
    ----------
    calibration : int
        ``K`` (checked, 0 to :data:`MAX_CALIBRATION`); 0 draws nothing.
    subjects : array-like
        ``(L,)`` the person of every trajectory of the split.
    features : ndarray
        ``(L, f)`` calibration features of every trajectory of the split.
    """

    def __init__(self, calibration: Any, subjects: Any, features: FloatArray) -> None:
        self.k = check_calibration(calibration)
        labels = np.asarray(subjects).astype(str)
        self.features = np.asarray(features, dtype=np.float64)
        if self.features.shape[0] != labels.size:
            raise ValueError(
                f"features must have one row per trajectory ({labels.size}); got "
                f"{self.features.shape}"
            )
        rows = np.arange(labels.size)
        self.others = [np.flatnonzero((labels == s) & (rows != l)) for l, s in enumerate(labels)]

    @property
    def size(self) -> int:
        """Entries the summary adds to the observation (0 without calibration)."""
        return int(self.features.shape[1]) + 1 if self.k else 0

    def extend(self, space: gym.spaces.Box) -> gym.spaces.Box:
        """``space`` with the summary's bounds appended (unchanged when ``K = 0``)."""
        if not self.k:
            return space
        f = self.features.shape[1]
        low = np.concatenate([space.low, np.full(f, -SUMMARY_BOUND), [0.0]])
        high = np.concatenate([space.high, np.full(f, SUMMARY_BOUND), [1.0]])
        return gym.spaces.Box(low.astype(np.float32), high.astype(np.float32), dtype=np.float32)

    def draw(self, rng: np.random.Generator, index: int) -> tuple[FloatArray, NDArray[np.int64]]:
        """Draw the calibration reaches of trajectory ``index`` with ``rng`` (one
        ``choice`` call; none when the person has no other trajectory) and return the
        summary ``(f + 1,)`` and the drawn indices, sorted and padded with ``-1`` to
        ``(K,)``."""
        others = self.others[index]
        m = min(self.k, others.size)
        drawn = np.full(self.k, -1, dtype=np.int64)
        if m:
            drawn[:m] = np.sort(rng.choice(others, size=m, replace=False))
        return calibration_summaries(self.features, drawn, self.k), drawn
