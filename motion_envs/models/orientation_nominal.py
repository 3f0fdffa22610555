"""Nominal orientation trajectories (Faraway & Choe): the model the orientation env's agent acts on.

The Gymnasium environment and ``motion-bench orientation --nominal`` share this code, so
that "the zero-action policy reproduces the model's criterion" holds by construction:
both fit the nominal on a *training* split and call :meth:`OrientationNominal.grids` on
the evaluation split.

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
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from motion_envs._typing import FloatArray
from motion_envs.datasets.ragged import DEFAULT_N_POINTS, check_n_points, normalised_grid
from motion_envs.datasets.resampling import resample_orientations
from motion_envs.geometry import bezier
from motion_envs.geometry import quaternion as quat
from motion_envs.models.bezier_models import (
    BezierResidualModel,
    GroupBezierModel,
    NullBezierModel,
    SubjectBezierModel,
    TaskBezierModel,
)
from motion_envs.models.criteria import max_errors
from motion_envs.models.estimator import not_fitted_error
from motion_envs.models.slerp_residual import slerp_residuals
from motion_envs.models.speed_profile import average_speed_profile

if TYPE_CHECKING:
    from motion_envs.datasets.orientation import OrientationDataset

__all__ = [
    "ORIENTATION_NOMINALS",
    "OrientationGrids",
    "OrientationNominal",
    "orientation_criterion",
]

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
        bezier.check_degree(degree)
        check_n_points(n_points)
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
            raise not_fitted_error(self, "call fit() first")

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
    if isinstance(rm, GroupBezierModel):
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
