"""One object for the orientation model of Faraway & Choe: quaternions in, quaternions out.

:class:`OrientationModel` wraps the pipeline spread over
:mod:`~motion_envs.models.slerp_residual` (residual curves),
:mod:`~motion_envs.models.bezier_models` (their Bézier control points, predicted from
subject, task or numeric predictors) and
:mod:`~motion_envs.models.orientation_prediction` (back to quaternions):

* ``fit``: every recorded trajectory ``q_l(t)`` (unit quaternions ``(w, x, y, z)`` at
  times in seconds) gives the average speed profile ``alpha_bar(tau)`` on the
  ``n_points`` grid (:func:`~motion_envs.models.speed_profile.average_speed_profile`)
  and its slerp residual ``r_l(tau) = logmap(conj(slerp(q_0, q_n, alpha_bar(tau))) q_l(tau))``
  (section 3.3, "Slerp, average"); a Bézier model of degree ``d`` is fitted to the
  residuals (section 3.4);
* ``predict``: at any times ``t`` in ``[0, T]`` (``tau = t / T``)::

      q(t) = slerp(q_s, q_e, alpha_bar(tau)) * expmap(C(tau; P))

  with ``alpha_bar`` linearly interpolated between grid points and ``C`` the Bézier
  curve of the predicted control points ``P`` (zero at both ends, so the prediction
  starts at ``q_s`` and ends at ``q_e`` exactly).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from motion_envs.datasets.ragged import DEFAULT_N_POINTS, RaggedTrajectories, normalised_grid
from motion_envs.geometry import bezier
from motion_envs.geometry import quaternion as quat
from motion_envs.geometry.resampling import recording_times
from motion_envs.models.bezier_models import (
    BezierResidualModel,
    GroupBezierModel,
    LinearBezierModel,
    NullBezierModel,
)
from motion_envs.models.estimator import Estimator, check_is_fitted
from motion_envs.models.slerp_residual import slerp_residuals
from motion_envs.models.speed_profile import average_speed_profile

__all__ = ["ORIENTATION_PREDICTORS", "OrientationModel"]

FloatArray = NDArray[np.float64]

#: What the residual's control points are predicted from (``by=``).
ORIENTATION_PREDICTORS = ("null", "subject", "task", "linear")


class OrientationModel(Estimator):
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
        if isinstance(n_points, bool) or not isinstance(n_points, (int, np.integer)):
            raise ValueError(f"n_points must be an integer >= 3; got {n_points!r}")
        if n_points < 3:
            raise ValueError(f"n_points must be an integer >= 3; got {n_points!r}")
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

    def fit(
        self,
        quaternions: Sequence[ArrayLike],
        times: Sequence[ArrayLike] | None = None,
        *,
        rate: float | None = None,
        subjects: ArrayLike | None = None,
        tasks: ArrayLike | None = None,
        predictors: Mapping[str, ArrayLike] | ArrayLike | None = None,
    ) -> OrientationModel:
        """Fit to trajectories ``quaternions[l]`` ``(n_l, 4)``; returns ``self``.

        The time base is required: ``times`` (seconds, one array per trajectory) or
        ``rate`` (Hz). ``subjects``/``tasks`` ``(L,)`` or ``predictors`` (``(L, p)`` or a
        mapping of named ``(L,)`` columns) as ``by`` needs.
        """
        if len(quaternions) == 0:
            raise ValueError("quaternions must contain at least one trajectory")
        ts = recording_times(quaternions, times, rate)
        qs = [self._unit(q, f"quaternions[{i}]") for i, q in enumerate(quaternions)]
        traj = RaggedTrajectories.from_sequences(qs, ts)
        alpha = average_speed_profile(traj, int(self.n_points))
        residuals = slerp_residuals(traj, int(self.n_points), average_alpha=alpha)
        model = self._residual_model()
        model.fit(residuals, subjects=subjects, tasks=tasks, predictors=predictors)
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
