"""Nominal position trajectories (Lippi et al.): the model the position env's agent acts on.

See :class:`PositionNominal` and :func:`position_grids`: line, null (mean residual) or
Lippi's sine-series regression, fitted per task on the training demonstrations, on the
same grid and with the same conditions as ``motion-bench position``. The error of a
position is the Euclidean distance to the human's at the same grid point; the
criterion is the median over tasks of the median over their trajectories of the max
error (``motion-bench position``'s aggregation).

The folds (:func:`~motion_envs.datasets.splits.position_folds`) and the resampling
(:func:`~motion_envs.datasets.resampling.resample_positions`) live in the datasets layer
and are re-exported here.
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from motion_envs._typing import FloatArray
from motion_envs.datasets.ragged import DEFAULT_N_POINTS
from motion_envs.datasets.resampling import resample_positions
from motion_envs.datasets.splits import POSITION_SPLITS, position_folds
from motion_envs.geometry import sine_series as ss
from motion_envs.models.estimator import not_fitted_error
from motion_envs.models.sine_regression import (
    RankDeficientDesignWarning,
    SineSeriesRegression,
    select_n_sines,
)

__all__ = [
    "CONDITION_KINDS",
    "POSITION_CONDITIONS",
    "POSITION_NOMINALS",
    "POSITION_SPLITS",
    "PositionGrids",
    "PositionNominal",
    "median_of_task_medians",
    "position_conditions",
    "position_folds",
    "position_grids",
    "resample_positions",
    "varying_columns",
]

#: Nominal models of the position environment.
POSITION_NOMINALS: tuple[str, ...] = ("line", "null", "sine")
#: Conditions of the sine-series regression (``motion-bench position``'s default).
POSITION_CONDITIONS: tuple[str, ...] = ("start", "end")
#: Every condition column a position nominal can be regressed on.
CONDITION_KINDS: tuple[str, ...] = ("start", "end", "duration")


def position_conditions(
    y: FloatArray, durations: FloatArray, kinds: Sequence[str] = POSITION_CONDITIONS
) -> FloatArray:
    """Condition matrix ``Q`` of each trajectory, ``(n, c)``: the chosen columns among
    ``start`` (``y_0``, D columns), ``end`` (``y_1``, D columns) and ``duration`` (``T``)."""
    bad = [k for k in kinds if k not in CONDITION_KINDS]
    if bad or not kinds:
        raise ValueError(f"conditions must be among {list(CONDITION_KINDS)}; got {list(kinds)}")
    parts = {"start": y[:, 0], "end": y[:, -1], "duration": np.asarray(durations)[:, None]}
    return np.column_stack([parts[k] for k in kinds])


def varying_columns(q: FloatArray) -> NDArray[np.bool_]:
    """Condition columns that vary over the training set (constant ones are dropped)."""
    scale = max(1.0, float(np.max(np.abs(q), initial=0.0)))
    return np.ptp(q, axis=0) > 1e-9 * scale


class PositionNominal:
    """A nominal position model of one task, fitted on its training demonstrations.

    All trajectories are on the uniform ``n``-point grid of normalised time ``tau``.
    With a trajectory's start ``y_0`` and end ``y_1`` (its task conditions):

    * ``"line"``: ``y_0 + tau (y_1 - y_0)``;
    * ``"null"``: the line plus the mean training residual ``D(tau)`` (eq. 3);
    * ``"sine"``: Lippi et al.'s regression
      (:class:`~motion_envs.models.sine_regression.SineSeriesRegression`) on the
      ``conditions`` (default ``[start, end]``; columns constant over the training set, such as
      LASA's end point at the origin, dropped), ``N`` chosen by leave-one-out
      cross-validation among 0..15 (:func:`~motion_envs.models.sine_regression.select_n_sines`)
      when ``n_sines="auto"``; generation overwrites the first two coefficients from
      the requested start and end.

    This is the protocol of ``motion-bench position`` (its ``line``, ``null`` and
    ``lippi`` columns), so its leave-one-out criterion is reproduced exactly.
    """

    def __init__(
        self,
        kind: str = "sine",
        n_sines: int | str = "auto",
        conditions: Sequence[str] = POSITION_CONDITIONS,
    ) -> None:
        if kind not in POSITION_NOMINALS:
            raise ValueError(f"nominal must be one of {list(POSITION_NOMINALS)}; got {kind!r}")
        if n_sines != "auto" and (
            isinstance(n_sines, bool) or not isinstance(n_sines, (int, np.integer)) or n_sines < 0
        ):
            raise ValueError(f"n_sines must be 'auto' or an integer >= 0; got {n_sines!r}")
        position_conditions(np.zeros((1, 2, 1)), np.ones(1), conditions)  # validates
        self.kind = kind
        self.n_sines = n_sines
        self.conditions = tuple(conditions)

    def fit(self, y: FloatArray, durations: FloatArray) -> PositionNominal:
        """Fit on ``(n, K, D)`` training trajectories on the grid; returns self.

        Sets ``selection_seconds_``: the time spent choosing ``N`` by cross-validation.
        """
        y = np.asarray(y, dtype=np.float64)
        if y.ndim != 3 or y.shape[0] < 1:
            raise ValueError(f"training trajectories must be (n >= 1, K, D); got {y.shape}")
        k = y.shape[1]
        self.tau_ = np.linspace(0.0, 1.0, k)
        self.n_train_ = int(y.shape[0])
        self.selection_seconds_ = 0.0
        if self.kind == "null":
            self.mean_residual_ = ss.residual(self.tau_, y).mean(axis=0)
        elif self.kind == "sine":
            q = position_conditions(y, durations, self.conditions)
            self.keep_ = varying_columns(q)
            q_train = q[:, self.keep_]
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", RankDeficientDesignWarning)
                n_use = self.n_sines
                if n_use == "auto":
                    t0 = time.perf_counter()
                    cands = [c for c in range(16) if c <= k - 2]
                    n_use, _ = select_n_sines(
                        list(y), q_train, candidates=cands, times="normalised"
                    )
                    self.selection_seconds_ = time.perf_counter() - t0
                self.n_sines_ = int(n_use)
                self.model_ = SineSeriesRegression(n_sines=self.n_sines_).fit(
                    q_train, list(y), times="normalised"
                )
        return self

    def predict(self, y: FloatArray, durations: FloatArray) -> FloatArray:
        """Nominal of each trajectory of ``y`` ``(m, K, D)`` from its own conditions."""
        if not hasattr(self, "tau_"):
            raise not_fitted_error(self, "call fit() first")
        y = np.asarray(y, dtype=np.float64)
        tau = self.tau_
        out = np.empty_like(y)
        q_all = position_conditions(y, durations, self.conditions) if self.kind == "sine" else None
        for i in range(y.shape[0]):
            start, end = y[i, 0], y[i, -1]
            line = start + tau[:, None] * (end - start)
            if self.kind == "line":
                out[i] = line
            elif self.kind == "null":
                out[i] = line + self.mean_residual_
            else:
                assert q_all is not None
                p = self.model_.predict_coefficients(q_all[i, self.keep_], start=start, end=end)
                out[i] = ss.evaluate(p, tau)
        return out


@dataclass(frozen=True)
class PositionGrids:
    """Human and nominal positions of the episodes of one split.

    Attributes: ``tau`` ``(n,)``; ``human``, ``nominal`` ``(L, n, D)``; ``index``
    ``(L,)`` the trajectories' indices in the dataset; ``tasks`` ``(L,)``.
    """

    tau: FloatArray
    human: FloatArray
    nominal: FloatArray
    index: NDArray[np.int64]
    tasks: NDArray[np.str_]

    def max_errors(self) -> FloatArray:
        """``(L,)`` the nominal's ``max_k |y_k - yhat_k|``."""
        return np.max(np.linalg.norm(self.human - self.nominal, axis=-1), axis=-1)

    def criterion(self) -> float:
        """Median over tasks of the median over the task's episodes of the max error.

        The aggregation of ``motion-bench position`` (per shape, then across shapes).
        """
        return median_of_task_medians(self.max_errors(), self.tasks)


def median_of_task_medians(values: ArrayLike, tasks: ArrayLike) -> float:
    """``median_task median_{trajectories of the task} values`` (``motion-bench position``)."""
    values = np.asarray(values, dtype=np.float64)
    tasks = np.asarray(tasks).astype(str)
    return float(np.median([np.median(values[tasks == t]) for t in np.unique(tasks)]))


def position_grids(
    dataset: Any,
    split: str = "test",
    nominal: str = "sine",
    n_sines: int | str = "auto",
    test_fraction: float = 0.25,
    seed: int = 0,
    n_points: int = DEFAULT_N_POINTS,
) -> PositionGrids:
    """Episodes of a split of a position dataset with the nominal of each trajectory.

    Nominals are fitted per task (shape) on its training demonstrations only:

    * ``"train"`` / ``"test"``: :func:`~motion_envs.datasets.splits.split_by_replicate`
      holds ``test_fraction`` of each task's demonstrations out (seed ``seed``); the
      nominal of the task is fitted on the training ones and predicts the split's;
    * ``"loo"``: every demonstration, each predicted by the nominal fitted on the other
      demonstrations of its task (``motion-bench position``'s leave-one-out protocol;
      tasks with fewer than 3 demonstrations are skipped, as there).
    """
    folds = position_folds(dataset, split, test_fraction, seed)
    y_all, dur_all = resample_positions(dataset, n_points)
    tasks = np.asarray(dataset.tasks).astype(str)
    idx_out: list[int] = []
    preds: list[FloatArray] = []
    for _, train, scored in folds:
        model = PositionNominal(nominal, n_sines).fit(y_all[train], dur_all[train])
        preds.extend(model.predict(y_all[scored], dur_all[scored]))
        idx_out.extend(int(i) for i in scored)
    if not idx_out:
        raise ValueError(f"the {split!r} split of this dataset holds no trajectory")
    index = np.asarray(idx_out, dtype=np.int64)
    return PositionGrids(
        tau=np.linspace(0.0, 1.0, n_points),
        human=y_all[index],
        nominal=np.stack(preds),
        index=index,
        tasks=tasks[index],
    )
