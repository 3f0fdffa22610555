"""The minimum-jerk model of point-to-point movements, fitted and predicted like the others.

:class:`MinimumJerk` predicts ``y(t) = s + (e - s)(10 u^3 - 15 u^4 + 6 u^5)``,
``u = t / T`` (:func:`motion_envs.geometry.minimum_jerk.minimum_jerk`; Flash & Hogan
1985). ``fit(X, y)`` (scikit-learn's order: ``X`` the start and end of each movement,
``[s, e]`` ``(n, 2D)``; ``y`` the recordings) learns what the formula leaves open: the
movement duration ``T`` as a linear function of the distance ``|e - s|``
(``T = a + b |e - s|``, least squares; a constant when all distances are equal or
``duration_model="mean"``) and reports how far the recordings are from the model
(``rmse_`` per recording). ``predict`` takes one movement or a batch; ``score`` is the
negative of the papers' criterion.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from motion_envs._typing import FloatArray
from motion_envs.geometry.minimum_jerk import minimum_jerk, minimum_jerk_profile
from motion_envs.geometry.resampling import recording_times
from motion_envs.models._sklearn import check_order, criterion_score, score_times
from motion_envs.models.estimator import check_is_fitted
from motion_envs.models.serialization import SerializableModel, State, StateSchema

__all__ = ["MinimumJerk"]


class MinimumJerk(SerializableModel):
    """Minimum-jerk movements between a start and an end at rest.

    Parameters
    ----------
    duration_model:
        ``"distance"`` (``T = a + b |e - s|``) or ``"mean"`` (``T`` = mean duration).

    Fitted attributes: ``durations_`` ``(n,)`` seconds, ``duration_coef_`` ``(a, b)``
    (``b = 0`` for ``"mean"``), ``rmse_`` ``(n,)`` RMS distance of each recording from
    the minimum-jerk movement between its own end points.
    """

    def __init__(self, duration_model: str = "distance") -> None:
        if duration_model not in ("distance", "mean"):
            raise ValueError(f"duration_model must be 'distance' or 'mean'; got {duration_model!r}")
        self.duration_model = duration_model

    def _ends(self, X: ArrayLike, dims: int) -> tuple[FloatArray, FloatArray]:
        """``X`` ``(n, 2D)`` as the starts and ends ``(n, D)``."""
        x = np.asarray(X, dtype=np.float64)
        if x.ndim != 2 or x.shape[1] != 2 * dims or not np.all(np.isfinite(x)):
            raise ValueError(
                f"X must be the finite starts and ends [s, e] of the movements, (n, 2D = "
                f"{2 * dims}); got shape {x.shape}"
            )
        return x[:, :dims], x[:, dims:]

    def fit(
        self,
        X: ArrayLike,
        y: Sequence[ArrayLike],
        times: Sequence[ArrayLike] | None = None,
        *,
        rate: float | None = None,
    ) -> MinimumJerk:
        """Fit to the starts and ends ``X`` ``(n, 2D)`` (``[s, e]`` per row) and the
        recordings ``y[i]`` ``(n_i, D)`` with ``times`` (s) or ``rate`` (Hz).

        The duration model regresses each recording's duration on ``|e - s|`` of its row
        of ``X``; ``rmse_`` compares each recording with the minimum-jerk movement between
        its own first and last samples.
        """
        check_order(X, y, type(self).__name__, "the starts and ends [s, e] (n, 2D)")
        ts = recording_times(y, times, rate)
        ys = [np.asarray(v, dtype=np.float64) for v in y]
        starts, ends = self._ends(X, ys[0].shape[-1])
        durations = np.array([t[-1] - t[0] for t in ts])
        distances = np.linalg.norm(ends - starts, axis=1)
        if self.duration_model == "distance" and np.ptp(distances) > 0 and len(ys) > 1:
            design = np.column_stack([np.ones_like(distances), distances])
            coef = np.linalg.lstsq(design, durations, rcond=None)[0]
        else:
            coef = np.array([durations.mean(), 0.0])
        rmse = np.empty(len(ys))
        for i, (t, v) in enumerate(zip(ts, ys, strict=True)):
            model = minimum_jerk(v[0], v[-1], (t - t[0]) / (t[-1] - t[0]))
            rmse[i] = np.sqrt(np.mean(np.sum((model - v) ** 2, axis=1)))
        self.durations_ = durations
        self.duration_coef_ = coef
        self.rmse_ = rmse
        return self

    def predict_duration(self, start: ArrayLike, end: ArrayLike) -> FloatArray:
        """Predicted durations ``T = a + b |e - s|`` (s), ``()`` or ``(m,)``."""
        check_is_fitted(self, "duration_coef_")
        s = np.asarray(start, dtype=np.float64)
        e = np.asarray(end, dtype=np.float64)
        a, b = self.duration_coef_
        return np.asarray(a + b * np.linalg.norm(e - s, axis=-1), dtype=np.float64)

    def predict(
        self,
        start: ArrayLike,
        end: ArrayLike,
        times: ArrayLike | None = None,
        *,
        duration: ArrayLike | None = None,
    ) -> FloatArray:
        """Positions at ``times`` (s since the movement start) from ``start`` to ``end``.

        ``start``/``end`` ``(D,)`` give ``(K, D)``; ``(m, D)`` (a batch, as the other
        models take) give ``(m, K, D)``. ``duration`` (scalar or ``(m,)``) defaults to the
        fitted :meth:`predict_duration`; ``times`` ``(K,)`` to 100 uniform samples over
        ``[0, duration]`` of each movement; times past a duration hold the end.
        """
        check_is_fitted(self, "duration_coef_")
        s = np.asarray(start, dtype=np.float64)
        e = np.asarray(end, dtype=np.float64)
        if s.ndim not in (1, 2) or s.shape != e.shape:
            raise ValueError(
                f"start and end must both be (D,) or (m, D); got {s.shape} and {e.shape}"
            )
        single = s.ndim == 1
        s2, e2 = np.atleast_2d(s), np.atleast_2d(e)
        m = s2.shape[0]
        given = self.predict_duration(s2, e2) if duration is None else duration
        T = np.broadcast_to(np.asarray(given, dtype=np.float64), (m,))
        if not np.all(np.isfinite(T)) or np.any(T <= 0):
            raise ValueError(f"duration must be > 0 s; got {np.asarray(given)}")
        if times is not None:
            t = np.asarray(times, dtype=np.float64)
            if t.ndim != 1 or np.any(t < 0) or not np.all(np.isfinite(t)):
                raise ValueError(f"times must be (K,) finite seconds >= 0; got shape {t.shape}")
            u = np.minimum(t[None, :] / T[:, None], 1.0)
        else:
            u = np.broadcast_to(np.linspace(0.0, 1.0, 100), (m, 100))
        shape = minimum_jerk_profile(u)[:, :, None]  # (m, K, 1), each movement's own T
        out = np.asarray(s2[:, None, :] + (e2 - s2)[:, None, :] * shape, dtype=np.float64)
        return out[0] if single else out

    def score(
        self,
        X: ArrayLike,
        y: Sequence[ArrayLike],
        times: Sequence[ArrayLike] | None = None,
        *,
        rate: float | None = None,
    ) -> float:
        """``-median_l max_t |y_l(t) - yhat_l(t)|``: the negative of the papers' criterion.

        ``yhat_l`` is the minimum-jerk movement between the start and end of row ``l`` of
        ``X`` over the recording's own duration, at its times; greater is better. Without
        ``times`` and ``rate`` the samples are taken as uniform (the criterion is the
        same for any rate).
        """
        check_order(X, y, type(self).__name__, "the starts and ends [s, e] (n, 2D)")
        ys = [np.asarray(v, dtype=np.float64) for v in y]
        starts, ends = self._ends(X, ys[0].shape[-1])

        def errors(i: int, t0: FloatArray) -> FloatArray:
            fit = self.predict(starts[i], ends[i], t0, duration=float(t0[-1]))
            return np.linalg.norm(fit - ys[i], axis=1)

        return criterion_score(score_times(y, times, rate), errors)

    state_schema = StateSchema(
        params={"duration_model": "str"},
        arrays={"durations_": ("float64", 1), "duration_coef_": ("float64", 1),
                "rmse_": ("float64", 1)},
    )  # fmt: skip

    def _get_state(self) -> State:
        check_is_fitted(self, "duration_coef_")
        arrays = {name: getattr(self, name) for name in ("durations_", "duration_coef_", "rmse_")}
        return {"duration_model": self.duration_model}, arrays, {}

    def _set_state(self, arrays: dict[str, NDArray[Any]], attributes: dict[str, Any]) -> None:
        n = arrays["durations_"].shape[0]
        if n < 1 or arrays["rmse_"].shape != (n,) or arrays["duration_coef_"].shape != (2,):
            raise ValueError("field arrays: durations_ (n >= 1), rmse_ (n,), duration_coef_ (2,)")
        self.durations_ = arrays["durations_"]
        self.duration_coef_ = arrays["duration_coef_"]
        self.rmse_ = arrays["rmse_"]
