"""How far one's own fitted model is from the recordings: per sample, per trajectory, per subject.

The papers judge a model by the median over trajectories of the maximum over time of the
distance between a recording and its prediction (:mod:`motion_envs.models.criteria`)::

    e_l(t) = | y_l(t) - yhat_l(t) |,   criterion = median_l  max_t  e_l(t)

Here ``yhat_l`` is the fitted model's prediction of recording ``l`` from what the model
is given at prediction time:

* position (:class:`~motion_envs.models.sine_regression.SineSeriesRegression`):
  ``model.predict(Q_l, duration=T_l, times=t - t_0, start=y_l(t_0), end=y_l(t_end))``
  (eqs. 7-8 with the recording's own end points), ``|.|`` the Euclidean distance (the
  unit of the positions);
* orientation (:class:`~motion_envs.models.orientation_model.OrientationModel`):
  ``model.predict(q_l(t_0), q_l(t_end), t - t_0, duration=T_l, <labels of l>)``,
  ``|.|`` the rotation angle ``|logmap(conj(qhat) q)|`` in radians (the tangent-space
  distance of the papers' criterion, here between quaternions at the recorded times
  rather than between residuals on the 50-point grid).

:class:`FitErrors` holds the data, the fit and the errors; :meth:`FitErrors.to_frame`
exports one row per trajectory and :func:`fit_summary` the number of trajectories and
the criterion per subject (and task) as pandas DataFrames.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from motion_envs._typing import FloatArray
from motion_envs.geometry import quaternion as quat
from motion_envs.geometry.resampling import recording_times
from motion_envs.models._sklearn import batch_row
from motion_envs.models.orientation_model import OrientationModel
from motion_envs.models.sine_regression import SineSeriesRegression

if TYPE_CHECKING:
    import pandas as pd

__all__ = ["FitErrors", "fit_summary", "orientation_fit_errors", "position_fit_errors"]


@dataclass(frozen=True)
class FitErrors:
    """A fitted model's prediction of each recording, and its error.

    Attributes
    ----------
    kind:
        ``"position"`` or ``"orientation"``.
    times:
        ``times[l]`` ``(n_l,)`` seconds since the recording's start.
    data:
        ``data[l]`` ``(n_l, D)`` the recording (``D = 4``, ``(w, x, y, z)``, for
        orientations).
    fit:
        ``fit[l]`` ``(n_l, D)`` the model's prediction at the same times (quaternions with
        the sign of the recorded ones: ``q`` and ``-q`` are the same rotation).
    errors:
        ``errors[l]`` ``(n_l,)`` the distance ``e_l(t)`` (module docstring).
    unit:
        The unit of ``errors`` (``"rad"`` for orientations, ``"m"`` for positions
        recorded in metres).
    """

    kind: str
    times: list[FloatArray]
    data: list[FloatArray]
    fit: list[FloatArray]
    errors: list[FloatArray]
    unit: str

    @property
    def n_trajectories(self) -> int:
        """The number ``L`` of recordings."""
        return len(self.errors)

    @property
    def max_errors(self) -> FloatArray:
        """``max_t e_l(t)`` per recording, ``(L,)``."""
        return np.array([e.max() for e in self.errors])

    @property
    def max_error_times(self) -> FloatArray:
        """The time (s since the start) of each recording's maximum error, ``(L,)``."""
        return np.array(
            [t[int(np.argmax(e))] for t, e in zip(self.times, self.errors, strict=True)]
        )

    @property
    def criterion(self) -> float:
        """``median_l max_t e_l(t)``."""
        return float(np.median(self.max_errors))

    @property
    def median_trajectory(self) -> int:
        """Index of the recording whose maximum error is the median (the lower one of the
        middle two when ``L`` is even)."""
        order = np.argsort(self.max_errors, kind="stable")
        return int(order[(self.n_trajectories - 1) // 2])

    def to_frame(self, labels: Mapping[str, ArrayLike] | None = None) -> pd.DataFrame:
        """One row per recording: ``trajectory``, the labels (one value per recording,
        e.g. ``{"subject": ..., "task": ...}``), ``n_samples``, ``duration`` (s),
        ``max_error`` and ``t_max_error`` (s)."""
        import pandas as pd

        data: dict[str, object] = {"trajectory": np.arange(self.n_trajectories)}
        data.update(_labels(labels, self.n_trajectories))
        data["n_samples"] = np.array([len(t) for t in self.times])
        data["duration"] = np.array([t[-1] - t[0] for t in self.times])
        data["max_error"] = self.max_errors
        data["t_max_error"] = self.max_error_times
        return pd.DataFrame(data)


def _labels(labels: Mapping[str, ArrayLike] | None, n: int) -> dict[str, NDArray[np.generic]]:
    out = {}
    for name, values in (labels or {}).items():
        v = np.asarray(values)
        if v.shape != (n,):
            raise ValueError(f"labels[{name!r}] must have one value per trajectory ({n})")
        out[name] = v
    return out


def position_fit_errors(
    model: SineSeriesRegression,
    positions: Sequence[ArrayLike],
    conditions: ArrayLike,
    times: Sequence[ArrayLike] | None = None,
    *,
    rate: float | None = None,
) -> FitErrors:
    """Errors of a fitted :class:`SineSeriesRegression` on recordings ``positions[l]``
    ``(n_l, D)`` with conditions ``(L, q)`` and ``times`` (s) or ``rate`` (Hz).

    Each recording is predicted from its conditions, duration and own start and end
    (eqs. 7-8); the error is the Euclidean distance per sample.
    """
    ts = recording_times(positions, times, rate)
    q = np.asarray(conditions, dtype=np.float64)
    q = q[:, None] if q.ndim == 1 else q
    if q.shape[0] != len(ts):
        raise ValueError(f"conditions must have one row per recording ({len(ts)}); got {q.shape}")
    rel, ys, fits, errors = [], [], [], []
    for t, y_in, q_l in zip(ts, positions, q, strict=True):
        y = np.asarray(y_in, dtype=np.float64)
        t0 = t - t[0]
        fit = model.predict(q_l, duration=float(t0[-1]), times=t0, start=y[0], end=y[-1])
        rel.append(t0)
        ys.append(y)
        fits.append(fit)
        errors.append(np.linalg.norm(fit - y, axis=1))
    return FitErrors("position", rel, ys, fits, errors, "m")


def orientation_fit_errors(
    model: OrientationModel,
    quaternions: Sequence[ArrayLike],
    times: Sequence[ArrayLike] | None = None,
    *,
    rate: float | None = None,
    subjects: ArrayLike | None = None,
    tasks: ArrayLike | None = None,
    predictors: Mapping[str, ArrayLike] | ArrayLike | None = None,
) -> FitErrors:
    """Errors of a fitted :class:`OrientationModel` on recordings ``quaternions[l]``
    ``(n_l, 4)`` with ``times`` (s) or ``rate`` (Hz) and the labels its ``by`` needs
    (one per recording).

    Each recording is predicted from its own first and last quaternion at its own times;
    the error is the rotation angle between recording and prediction (rad).
    """
    ts = recording_times(quaternions, times, rate)
    rel, qs, fits, errors = [], [], [], []
    for i, (t, q_in) in enumerate(zip(ts, quaternions, strict=True)):
        q = quat.as_unit(q_in, f"quaternions[{i}]", normalize=bool(model.normalize))
        t0 = t - t[0]
        fit = model.predict(
            q[0], q[-1], t0, duration=float(t0[-1]),
            subjects=batch_row(subjects, i), tasks=batch_row(tasks, i),
            predictors=batch_row(predictors, i),
        )  # fmt: skip
        fit = fit * np.where(np.sum(fit * q, axis=1) < 0.0, -1.0, 1.0)[:, None]
        rel.append(t0)
        qs.append(q)
        fits.append(fit)
        between = quat.multiply(quat.conjugate(fit), q)
        errors.append(np.linalg.norm(quat.logmap(between, validate=False), axis=1))
    return FitErrors("orientation", rel, qs, fits, errors, "rad")


def fit_summary(
    errors: FitErrors, subjects: ArrayLike, tasks: ArrayLike | None = None
) -> pd.DataFrame:
    """Per subject (and task, when ``tasks`` is given): ``n_trajectories`` and the
    ``criterion`` ``median max_t e_l(t)`` over that group's recordings.

    ``subjects``/``tasks`` have one label per recording of ``errors``; rows are sorted
    by the labels. Also the mean and largest of the maximum errors (``mean_max_error``,
    ``worst_max_error``).
    """
    labels: dict[str, ArrayLike] = {"subject": subjects}
    if tasks is not None:
        labels["task"] = tasks
    frame = errors.to_frame(labels)
    keys = list(labels)
    grouped = frame.groupby(keys, sort=True)["max_error"]
    out = grouped.agg(
        n_trajectories="size", criterion="median", mean_max_error="mean", worst_max_error="max"
    )
    return out.reset_index()
