"""Nominal trajectories: the analytic models the environments' agents act on top of.

One module serves both the Gymnasium environments and the offline criterion of
``motion-bench``, so that "the zero-action policy reproduces the model's criterion" holds
by construction: both fit the nominal on a *training* split with the classes below and
call the same :meth:`OrientationNominal.grids` / :meth:`PositionNominal.grids` on the
evaluation split.

Orientation (Faraway & Choe)
----------------------------
All quantities live on the uniform normalised-time grid ``tau_k = k / 49`` (50 points).
With ``q_0``, ``q_n`` a trajectory's first and last orientation (scalar-first unit
quaternions) and ``alpha_bar`` the **training split's** average speed profile
(:func:`~motion_envs.models.speed_profile.average_speed_profile`):

* base slerp ``e(tau) = slerp(q_0, q_n, alpha_bar(tau))``;
* human orientation ``h(tau)``: the recording resampled to the grid
  (:func:`~motion_envs.models.slerp_residual.resample_orientations`);
* **residual definition** (the "Slerp, average" residual of Table 1, against the
  *training* profile): ``r(tau) = logmap(conj(e(tau)) * h(tau))``;
* predicted residual ``rhat(tau)``: 0 for ``"slerp"``; for ``"bezier-null"``,
  ``"bezier-task"``, ``"bezier-subject"`` the Bézier curve of degree ``degree`` whose
  control points the Null / Task / Subject model predicts, the model being fitted on the
  training residuals ``r`` (same definition). Tasks or subjects absent from training
  fall back to the null model (``unseen="global"``); for a split *by subject* every
  test subject is unseen, so ``"bezier-subject"`` equals ``"bezier-null"`` on the test
  split, by design;
* nominal orientation ``n(tau) = e(tau) * expmap(rhat(tau))``.

Error of an orientation ``q`` at grid point ``k`` (radians), measured in the residual
chart at ``e(tau_k)``, exactly the paper's tangent-space distance::

    err_k(q) = | logmap(conj(e_k) * q) - r_k |

so the nominal's error is ``|rhat_k - r_k|`` and the **criterion** of a nominal model is
``median_l max_k |r_lk - rhat_lk|`` (Faraway & Choe's Table 1 criterion,
:func:`motion_envs.models.criteria.median_max_error`). For ``"slerp"`` it is the geodesic
angle between ``e_k`` and ``h_k``; the environments also report the plain geodesic angle
``2 atan2(|v|, |w|)`` of ``conj(q) * h_k``.

Position (Lippi et al.)
-----------------------
See :class:`PositionNominal` and :func:`position_grids`: line, null (mean residual) or
Lippi's sine-series regression, fitted per task on the training demonstrations, on the
same grid and with the same conditions as ``motion-bench position``. The error of a
position is the Euclidean distance to the human's at the same grid point; the
criterion is the median over tasks of the median over their trajectories of the max
error (``motion-bench position``'s aggregation).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from motion_envs.geometry import quaternion as quat
from motion_envs.models.bezier_models import (
    BezierResidualModel,
    NullBezierModel,
    SubjectBezierModel,
    TaskBezierModel,
)
from motion_envs.models.criteria import max_errors
from motion_envs.models.slerp_residual import (
    DEFAULT_N_POINTS,
    normalised_grid,
    resample_orientations,
    slerp_residuals,
)
from motion_envs.models.speed_profile import average_speed_profile

if TYPE_CHECKING:
    from motion_envs.datasets.orientation import OrientationDataset

__all__ = [
    "ORIENTATION_NOMINALS",
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

FloatArray = NDArray[np.float64]

#: Nominal models of the orientation environment and ``motion-bench orientation --nominal``.
ORIENTATION_NOMINALS: tuple[str, ...] = ("slerp", "bezier-null", "bezier-task", "bezier-subject")


@dataclass(frozen=True)
class OrientationGrids:
    """Everything an orientation episode needs, for ``L`` trajectories on the ``n``-grid.

    Attributes
    ----------
    tau:
        ``(n,)`` normalised time grid.
    starts, goals:
        ``(L, 4)`` first and last orientation ``q_0``, ``q_n`` (sign-continuous).
    human:
        ``(L, n, 4)`` the recorded orientation ``h`` resampled to the grid.
    base:
        ``(L, n, 4)`` the base slerp ``e = slerp(q_0, q_n, alpha_bar)``.
    residuals:
        ``(L, n, 3)`` the human residual ``r = logmap(conj(e) h)``.
    predicted_residuals:
        ``(L, n, 3)`` the nominal model's ``rhat``.
    nominal:
        ``(L, n, 4)`` the nominal orientation ``n = e expmap(rhat)``.
    """

    tau: FloatArray
    starts: FloatArray
    goals: FloatArray
    human: FloatArray
    base: FloatArray
    residuals: FloatArray
    predicted_residuals: FloatArray
    nominal: FloatArray

    @property
    def n_trajectories(self) -> int:
        return int(self.human.shape[0])

    def max_errors(self) -> FloatArray:
        """``(L,)`` the nominal's ``max_k |r_k - rhat_k|`` per trajectory."""
        return max_errors(self.residuals, self.predicted_residuals)

    def criterion(self) -> float:
        """``median_l max_k |r_lk - rhat_lk|``: the papers' criterion of the nominal."""
        return float(np.median(self.max_errors()))


class OrientationNominal:
    """A nominal orientation model fitted on a training split (see the module docstring).

    Parameters
    ----------
    kind:
        One of :data:`ORIENTATION_NOMINALS`.
    degree:
        Bézier degree of the ``"bezier-*"`` kinds (ignored by ``"slerp"``).
    n_points:
        Size of the normalised-time grid (the paper's 50).

    Fitted attributes: ``average_alpha_`` ``(n_points,)``; ``residual_model_`` (a
    :class:`~motion_envs.models.bezier_models.BezierResidualModel`, or None for
    ``"slerp"``); ``n_train_`` the number of training trajectories.
    """

    def __init__(self, kind: str = "slerp", degree: int = 2, n_points: int = DEFAULT_N_POINTS):
        if kind not in ORIENTATION_NOMINALS:
            raise ValueError(f"nominal must be one of {list(ORIENTATION_NOMINALS)}; got {kind!r}")
        if isinstance(degree, bool) or not isinstance(degree, (int, np.integer)) or degree < 1:
            raise ValueError(f"degree must be an integer >= 1; got {degree!r}")
        if isinstance(n_points, bool) or not isinstance(n_points, (int, np.integer)):
            raise ValueError(f"n_points must be an integer >= 3; got {n_points!r}")
        if n_points < 3:
            raise ValueError(f"n_points must be an integer >= 3; got {n_points!r}")
        self.kind = kind
        self.degree = int(degree)
        self.n_points = int(n_points)

    def __repr__(self) -> str:
        return f"OrientationNominal(kind={self.kind!r}, degree={self.degree})"

    def _make_residual_model(self) -> BezierResidualModel | None:
        if self.kind == "bezier-null":
            return NullBezierModel(self.degree)
        if self.kind == "bezier-task":
            return TaskBezierModel(self.degree, unseen="global")
        if self.kind == "bezier-subject":
            return SubjectBezierModel(self.degree, unseen="global")
        return None

    def fit(self, train: OrientationDataset) -> OrientationNominal:
        """Fit the average speed profile and the residual model on ``train``; returns self."""
        if len(train) < 1:
            raise ValueError("train must contain at least one trajectory")
        traj = train.ragged
        self.average_alpha_ = average_speed_profile(traj, self.n_points)
        model = self._make_residual_model()
        if model is not None:
            R = slerp_residuals(traj, self.n_points, average_alpha=self.average_alpha_)
            model.fit(R, subjects=train.subjects, tasks=train.tasks)
        self.residual_model_ = model
        self.n_train_ = len(train)
        return self

    def _check_fitted(self) -> None:
        if not hasattr(self, "average_alpha_"):
            raise RuntimeError("OrientationNominal is not fitted; call fit(train) first")

    def predict_residuals(self, dataset: OrientationDataset) -> FloatArray:
        """``(L, n_points, 3)`` predicted residual ``rhat`` of every trajectory of ``dataset``."""
        self._check_fitted()
        L = len(dataset)
        if self.residual_model_ is None:
            return np.zeros((L, self.n_points, 3))
        return self.residual_model_.predict(
            n=L, subjects=dataset.subjects, tasks=dataset.tasks, n_points=self.n_points
        )

    def grids(self, dataset: OrientationDataset) -> OrientationGrids:
        """Human, base slerp, residuals and nominal of every trajectory of ``dataset``."""
        self._check_fitted()
        if len(dataset) < 1:
            raise ValueError("dataset must contain at least one trajectory")
        traj = dataset.ragged
        tau = normalised_grid(self.n_points)
        q0, qn = traj.starts, traj.ends
        human = resample_orientations(traj, tau)
        base = quat.slerp(q0[:, None, :], qn[:, None, :], self.average_alpha_[None, :])
        residuals = slerp_residuals(traj, self.n_points, average_alpha=self.average_alpha_)
        rhat = self.predict_residuals(dataset)
        nominal = quat.multiply(base, quat.expmap(rhat))
        return OrientationGrids(
            tau=tau,
            starts=q0.copy(),
            goals=qn.copy(),
            human=human,
            base=base,
            residuals=residuals,
            predicted_residuals=rhat,
            nominal=nominal,
        )

    def criterion(self, dataset: OrientationDataset) -> float:
        """The papers' criterion ``median_l max_k |r_lk - rhat_lk|`` on ``dataset``."""
        return self.grids(dataset).criterion()


def orientation_criterion(
    train: OrientationDataset,
    test: OrientationDataset,
    nominal: str = "slerp",
    degree: int = 2,
    n_points: int = DEFAULT_N_POINTS,
) -> dict[str, Any]:
    """Fit ``nominal`` on ``train`` and score it on ``test``; the offline criterion.

    Returns a dict with ``criterion`` (radians), ``max_errors`` (per test trajectory),
    ``nominal``, ``degree``, ``n_train``, ``n_test`` and ``n_unseen`` (test trajectories
    whose task/subject the group model had not seen and scored with the null fallback).
    """
    model = OrientationNominal(nominal, degree, n_points).fit(train)
    g = model.grids(test)
    unseen = 0
    rm = model.residual_model_
    if rm is not None and hasattr(rm, "groups_"):
        labels = test.subjects if rm.by == "subject" else test.tasks
        unseen = int(np.count_nonzero(~np.isin(np.asarray(labels).astype(str), rm.groups_)))
    errs = g.max_errors()
    return {
        "nominal": nominal,
        "degree": int(degree),
        "criterion": float(np.median(errs)),
        "max_errors": errs,
        "n_train": len(train),
        "n_test": len(test),
        "n_unseen": unseen,
    }


# ---------------------------------------------------------------------------------------
# Position (Lippi, Avizzano & Ruffaldi)
# ---------------------------------------------------------------------------------------

#: Nominal models of the position environment.
POSITION_NOMINALS: tuple[str, ...] = ("line", "null", "sine")
#: Splits of a position dataset (see :func:`position_grids`).
POSITION_SPLITS: tuple[str, ...] = ("train", "test", "loo")
#: Conditions of the sine-series regression (``motion-bench position``'s default).
POSITION_CONDITIONS: tuple[str, ...] = ("start", "end")
#: Every condition column a position nominal can be regressed on.
CONDITION_KINDS: tuple[str, ...] = ("start", "end", "duration")


def resample_positions(
    dataset: Any, n_points: int = DEFAULT_N_POINTS
) -> tuple[FloatArray, FloatArray]:
    """Every trajectory linearly interpolated on ``n_points`` uniform ``tau = (t - t_0)/T``.

    Returns ``(L, n_points, D)`` positions and ``(L,)`` durations ``T`` (the same
    resampling as ``motion-bench position``).
    """
    from motion_envs.geometry import sine_series as ss

    if n_points < 5:
        raise ValueError(f"n_points must be >= 5; got {n_points}")
    tau = np.linspace(0.0, 1.0, n_points)
    out = np.empty((len(dataset), n_points, dataset.n_dims))
    for i, (y, t) in enumerate(zip(dataset.positions, dataset.times, strict=True)):
        src = ss.normalised_time(t)
        for j in range(y.shape[1]):
            out[i, :, j] = np.interp(tau, src, y[:, j])
    durations = np.array([t[-1] - t[0] for t in dataset.times])
    return out, durations


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
        import time
        import warnings

        from motion_envs.geometry import sine_series as ss
        from motion_envs.models.sine_regression import (
            RankDeficientDesignWarning,
            SineSeriesRegression,
            select_n_sines,
        )

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
                    n_use, _ = select_n_sines(list(y), q_train, candidates=cands)
                    self.selection_seconds_ = time.perf_counter() - t0
                self.n_sines_ = int(n_use)
                self.model_ = SineSeriesRegression(n_sines=self.n_sines_).fit(list(y), q_train)
        return self

    def predict(self, y: FloatArray, durations: FloatArray) -> FloatArray:
        """Nominal of each trajectory of ``y`` ``(m, K, D)`` from its own conditions."""
        from motion_envs.geometry import sine_series as ss

        if not hasattr(self, "tau_"):
            raise RuntimeError("PositionNominal is not fitted; call fit() first")
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


def position_folds(
    dataset: Any,
    split: str = "loo",
    test_fraction: float = 0.25,
    seed: int = 0,
) -> list[tuple[str, NDArray[np.int64], NDArray[np.int64]]]:
    """The ``(task, train indices, scored indices)`` folds of a split of a position
    dataset (anything with ``.tasks``), tasks in order of first appearance.

    * ``"loo"``: one fold per demonstration, trained on the other demonstrations of its
      task (tasks with fewer than 3 demonstrations are skipped);
    * ``"train"`` / ``"test"``: one fold per task, trained on the task's training
      demonstrations of :func:`~motion_envs.datasets.splits.split_by_replicate`
      (``test_fraction``, ``seed``) and scoring the split's own (tasks with none skipped).
    """
    from motion_envs.datasets.splits import split_by_replicate

    if split not in POSITION_SPLITS:
        raise ValueError(f"split must be one of {list(POSITION_SPLITS)}; got {split!r}")
    tasks = np.asarray(dataset.tasks).astype(str)
    folds: list[tuple[str, NDArray[np.int64], NDArray[np.int64]]] = []
    if split != "loo":
        is_test = split_by_replicate(dataset, test_fraction=test_fraction, seed=seed, mask=True)
    for task in dict.fromkeys(tasks.tolist()):
        members = np.flatnonzero(tasks == task)
        if split == "loo":
            if members.size < 3:
                continue
            folds.extend((task, members[members != i], np.array([i])) for i in members)
        else:
            in_task = tasks == task
            scored = np.flatnonzero(in_task & (is_test if split == "test" else ~is_test))
            if scored.size:
                folds.append((task, np.flatnonzero(in_task & ~is_test), scored))
    return folds


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
