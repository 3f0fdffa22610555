"""One object for the orientation model of Faraway & Choe: quaternions in, quaternions out.

:class:`OrientationModel` wraps the pipeline spread over
:mod:`~motion_envs.models.slerp_residual` (residual curves),
:mod:`~motion_envs.models.bezier_models` (their Bézier control points, predicted from
subject, task or numeric predictors) and
:mod:`~motion_envs.models.orientation_prediction` (back to quaternions):

* ``fit(X, y)`` (scikit-learn's order: ``X`` what the residual is predicted from, one
  row per trajectory, as ``by`` says; ``y`` the trajectories): every recorded
  trajectory ``q_l(t)`` (unit quaternions ``(w, x, y, z)`` at times in seconds) gives
  the average speed profile ``alpha_bar(tau)`` on the ``n_points`` grid
  (:func:`~motion_envs.models.speed_profile.average_speed_profile`)
  and its slerp residual ``r_l(tau) = logmap(conj(slerp(q_0, q_n, alpha_bar(tau))) q_l(tau))``
  (section 3.3, "Slerp, average"); a Bézier model of degree ``d`` is fitted to the
  residuals (section 3.4);
* ``score(X, y)``: the negative of the papers' criterion (radians);
* ``predict``: at any times ``t`` in ``[0, T]`` (``tau = t / T``)::

      q(t) = slerp(q_s, q_e, alpha_bar(tau)) * expmap(C(tau; P))

  with ``alpha_bar`` linearly interpolated between grid points and ``C`` the Bézier
  curve of the predicted control points ``P`` (zero at both ends, so the prediction
  starts at ``q_s`` and ends at ``q_e`` exactly).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from motion_envs._typing import FloatArray
from motion_envs.datasets.ragged import (
    DEFAULT_N_POINTS,
    RaggedTrajectories,
    check_n_points,
    normalised_grid,
)
from motion_envs.geometry import bezier
from motion_envs.geometry import quaternion as quat
from motion_envs.geometry.resampling import recording_times
from motion_envs.models._sklearn import (
    batch_row,
    check_order,
    criterion_score,
    score_times,
)
from motion_envs.models.bezier_models import (
    BezierResidualModel,
    GroupBezierModel,
    LinearBezierModel,
    NullBezierModel,
)
from motion_envs.models.estimator import check_is_fitted
from motion_envs.models.serialization import SerializableModel, State, StateSchema
from motion_envs.models.slerp_residual import slerp_residuals
from motion_envs.models.speed_profile import average_speed_profile

__all__ = ["ORIENTATION_PREDICTORS", "OrientationModel"]

#: What the residual's control points are predicted from (``by=``).
ORIENTATION_PREDICTORS = ("null", "subject", "task", "linear")


class OrientationModel(SerializableModel):
    """Fit quaternion trajectories; predict quaternions at the times asked for.

    Parameters
    ----------
    degree:
        Bézier degree ``d`` of the residual (``d - 1`` interior control points).
    by:
        ``"null"`` (one mean residual), ``"subject"``/``"task"`` (the mean of the same
        label), ``"linear"`` (linear in numeric ``predictors``).
    unseen:
        For ``by="subject"``/``"task"``: ``"global"`` predicts the overall mean for a
        label not seen in ``fit``, ``"error"`` raises.
    n_points:
        Size of the normalised-time grid of the speed profile and residuals (the paper's 50).
    normalize:
        Renormalise input quaternions (any finite non-zero norm) instead of requiring
        unit norm within :data:`motion_envs.geometry.quaternion.UNIT_TOLERANCE`.

    Fitted attributes: ``average_alpha_`` ``(n_points,)``, ``residual_model_`` (the
    fitted Bézier model), ``durations_`` ``(L,)`` seconds, ``n_trajectories_``.
    ``save``/``load`` use the JSON model format (the residual model's fitted points are
    stored as groups of control points: one group for ``"null"`` and ``"linear"``).
    """

    def __init__(
        self,
        degree: int = 2,
        by: str = "null",
        unseen: str = "global",
        n_points: int = DEFAULT_N_POINTS,
        normalize: bool = False,
    ) -> None:
        if by not in ORIENTATION_PREDICTORS:
            raise ValueError(f"by must be one of {ORIENTATION_PREDICTORS}; got {by!r}")
        if unseen not in ("error", "global"):
            raise ValueError(f"unseen must be 'error' or 'global'; got {unseen!r}")
        check_n_points(n_points)
        NullBezierModel(degree)  # validates degree
        self.degree = degree
        self.by = by
        self.unseen = unseen
        self.n_points = n_points
        self.normalize = normalize

    def _residual_model(self) -> BezierResidualModel:
        if self.by == "null":
            return NullBezierModel(self.degree)
        if self.by == "linear":
            return LinearBezierModel(self.degree)
        return GroupBezierModel(self.degree, by=self.by, unseen=self.unseen)

    def _unit(self, q: ArrayLike, name: str) -> FloatArray:
        return quat.as_unit(q, name, normalize=self.normalize)

    def labels(self, X: Any) -> dict[str, Any]:
        """``X`` as the keyword :meth:`predict` takes for ``by``: ``{}`` for ``"null"``
        (``X`` unused; None allowed), ``{"subjects": ..}``/``{"tasks": ..}`` ``(L,)`` labels
        (a column vector or one-column table also), ``{"predictors": ..}`` for
        ``"linear"`` (``(L, p)`` numbers, a mapping of named ``(L,)`` columns or a pandas
        DataFrame)."""
        if self.by == "null" or X is None:
            if self.by != "null":
                raise ValueError(f"X must hold the {self.by} of each trajectory (by={self.by!r})")
            return {}
        if self.by == "linear":
            if hasattr(X, "columns"):  # a pandas DataFrame: its named columns
                return {"predictors": {str(c): np.asarray(X[c]) for c in X.columns}}
            return {"predictors": X}
        values = np.asarray(X)
        if values.ndim == 2 and values.shape[1] == 1:
            values = values[:, 0]
        if values.ndim != 1:
            raise ValueError(
                f"X must be the {self.by} label of each trajectory, (L,); got {values.shape}"
            )
        return {"subjects" if self.by == "subject" else "tasks": values}

    def fit(
        self,
        X: Any,
        y: Sequence[ArrayLike],
        times: Sequence[ArrayLike] | None = None,
        *,
        rate: float | None = None,
    ) -> OrientationModel:
        """Fit to trajectories ``y[l]`` ``(n_l, 4)``; returns ``self``.

        scikit-learn's order: ``X`` what ``by`` predicts from (:meth:`labels`: None for
        ``"null"``, the subject or task labels ``(L,)``, or predictors ``(L, p)``), ``y``
        the trajectories. The time base is required: ``times`` (seconds, one array per
        trajectory) or ``rate`` (Hz).
        """
        check_order(X, y, type(self).__name__, f"what by={self.by!r} predicts from")
        ts = recording_times(y, times, rate)
        qs = [self._unit(q, f"y[{i}]") for i, q in enumerate(y)]
        traj = RaggedTrajectories.from_sequences(qs, ts)
        alpha = average_speed_profile(traj, int(self.n_points))
        residuals = slerp_residuals(traj, int(self.n_points), average_alpha=alpha)
        model = self._residual_model()
        model.fit(residuals, **self.labels(X))
        self.average_alpha_ = alpha
        self.residual_model_ = model
        self.durations_ = traj.durations
        self.n_trajectories_ = traj.n_trajectories
        return self

    def predict(
        self,
        starts: ArrayLike,
        ends: ArrayLike,
        times: ArrayLike | None = None,
        *,
        duration: ArrayLike | None = None,
        subjects: ArrayLike | None = None,
        tasks: ArrayLike | None = None,
        predictors: Mapping[str, ArrayLike] | ArrayLike | None = None,
    ) -> FloatArray:
        """Quaternions at ``times`` (seconds since the movement start).

        ``starts``/``ends`` are ``(4,)`` (one movement: returns ``(K, 4)``) or ``(L, 4)``
        (returns ``(L, K, 4)``). ``times`` ``(K,)`` lie in ``[0, T]`` with ``T`` =
        ``duration`` (scalar or ``(L,)``; default ``times[-1]``); ``times=None`` answers
        on the ``n_points`` normalised grid. Labels/predictors as in :meth:`fit`.
        """
        check_is_fitted(self, "residual_model_")
        qs = self._unit(starts, "starts")
        qe = self._unit(ends, "ends")
        single = qs.ndim == 1
        qs2, qe2 = np.atleast_2d(qs), np.atleast_2d(qe)
        if qs2.shape != qe2.shape or qs2.ndim != 2:
            raise ValueError(
                f"starts and ends must both be (4,) or (L, 4); got {qs.shape}, {qe.shape}"
            )
        n = qs2.shape[0]
        if times is None:
            taus = np.broadcast_to(normalised_grid(int(self.n_points)), (n, int(self.n_points)))
        else:
            t = np.asarray(times, dtype=np.float64)
            if t.ndim != 1 or t.size == 0 or not np.all(np.isfinite(t)) or np.any(t < 0):
                raise ValueError(f"times must be (K,) finite seconds >= 0; got shape {t.shape}")
            span = np.broadcast_to(
                np.asarray(t[-1] if duration is None else duration, dtype=np.float64), (n,)
            )
            if np.any(span <= 0) or np.any(t[None, :] > span[:, None] * (1 + 1e-12)):
                raise ValueError("times must lie within [0, duration] and duration must be > 0")
            taus = np.minimum(t[None, :] / span[:, None], 1.0)
        points = self.residual_model_.predict_control_points(
            n=n, subjects=subjects, tasks=tasks, predictors=predictors
        )
        grid = normalised_grid(int(self.n_points))
        out = np.empty((n, taus.shape[1], 4))
        for i in range(n):
            alpha = np.interp(taus[i], grid, self.average_alpha_)
            path = quat.slerp(qs2[i], qe2[i], alpha, validate=False)
            curve = bezier.evaluate(points[i], taus[i], int(self.degree))
            out[i] = quat.multiply(path, quat.expmap(curve))
        return out[0] if single else out

    def score(
        self,
        X: Any,
        y: Sequence[ArrayLike],
        times: Sequence[ArrayLike] | None = None,
        *,
        rate: float | None = None,
    ) -> float:
        """``-median_l max_t angle(q_l(t), qhat_l(t))``: the negative of the papers'
        criterion (radians; the rotation angle ``|logmap(conj(qhat) q)|``).

        ``qhat_l = predict(q_l(t_0), q_l(t_end), t - t_0, duration=T_l, <row l of X>)``,
        as :func:`~motion_envs.models.fit_errors.orientation_fit_errors`; greater is
        better. Without ``times`` and ``rate`` the samples are taken as uniform (the
        criterion is the same for any rate).
        """
        check_order(X, y, type(self).__name__, f"what by={self.by!r} predicts from")
        labels = self.labels(X)

        def errors(i: int, t0: FloatArray) -> FloatArray:
            q = self._unit(y[i], f"y[{i}]")
            row = {k: batch_row(v, i) for k, v in labels.items()}
            fit = self.predict(q[0], q[-1], t0, duration=float(t0[-1]), **row)
            return quat.angle(fit, q)

        return criterion_score(score_times(y, times, rate), errors)

    # -- serialization --------------------------------------------------------------
    state_schema = StateSchema(
        params={"degree": "int", "by": "str", "unseen": "str", "n_points": "int",
                "normalize": "bool"},
        arrays={
            "average_alpha_": ("float64", 1),
            "durations_": ("float64", 1),
            "control_points": ("float64", 3),
            "global_control_points": ("float64", 2),
            "group_sizes": ("int64", 1),
            "coef": ("float64", 3),
        },
        attributes={"groups": "str_list", "predictor_names": "str_list", "n_points_": "int"},
    )  # fmt: skip

    def _get_state(self) -> State:
        check_is_fitted(self, "residual_model_")
        m = self.residual_model_
        k = int(self.degree) - 1
        groups: list[str] = []
        names: list[str] = []
        coef = np.zeros((0, k, 3))
        sizes = np.array([self.n_trajectories_], dtype=np.int64)
        if isinstance(m, GroupBezierModel):
            points, mean = m.control_points_, m.global_control_points_
            groups, sizes = m.groups_.tolist(), m.group_sizes_
        elif isinstance(m, LinearBezierModel):
            points, mean = m.intercept_[None], m.intercept_
            coef, names = m.coef_, list(m.predictor_names_)
        elif isinstance(m, NullBezierModel):
            points, mean = m.control_points_[None], m.control_points_
        else:
            raise TypeError(f"cannot save a residual model of type {type(m).__name__}")
        params = {
            "degree": int(self.degree),
            "by": self.by,
            "unseen": self.unseen,
            "n_points": int(self.n_points),
            "normalize": bool(self.normalize),
        }
        arrays = {
            "average_alpha_": self.average_alpha_,
            "durations_": self.durations_,
            "control_points": points,
            "global_control_points": mean,
            "group_sizes": sizes,
            "coef": coef,
        }
        attributes = {"groups": groups, "predictor_names": names, "n_points_": m.n_points_}
        return params, arrays, attributes

    def _set_state(self, arrays: dict[str, NDArray[Any]], attributes: dict[str, Any]) -> None:
        k = int(self.degree) - 1
        points, mean = arrays["control_points"], arrays["global_control_points"]
        coef, sizes = arrays["coef"], arrays["group_sizes"]
        groups, names = list(attributes["groups"]), list(attributes["predictor_names"])
        n_groups = len(groups) if self.by in ("subject", "task") else 1
        checks = {
            "arrays.control_points": points.shape == (n_groups, k, 3),
            "arrays.global_control_points": mean.shape == (k, 3),
            "arrays.group_sizes": sizes.shape == (n_groups,) and bool(np.all(sizes >= 1)),
            "arrays.coef": coef.shape == (len(names) if self.by == "linear" else 0, k, 3),
            "arrays.average_alpha_": arrays["average_alpha_"].shape == (int(self.n_points),),
            "attributes.groups": groups == sorted(set(groups)),
        }
        for field_name, ok in checks.items():
            if not ok:
                raise ValueError(f"field {field_name}: does not match by={self.by!r}, degree")
        residual = self._residual_model()
        if isinstance(residual, GroupBezierModel):
            residual.groups_ = np.asarray(groups, dtype=str)
            residual.group_sizes_ = sizes.astype(np.int64)
            residual.control_points_ = points
            residual.global_control_points_ = mean
        elif isinstance(residual, LinearBezierModel):
            residual.intercept_, residual.coef_, residual.predictor_names_ = mean, coef, names
        elif isinstance(residual, NullBezierModel):
            residual.control_points_ = mean
        residual.n_points_ = int(attributes["n_points_"])
        self.residual_model_ = residual
        self.average_alpha_ = arrays["average_alpha_"]
        self.durations_ = arrays["durations_"]
        self.n_trajectories_ = int(self.durations_.shape[0])
