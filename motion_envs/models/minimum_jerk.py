"""The minimum-jerk model of point-to-point movements, fitted and predicted like the others.

:class:`MinimumJerk` predicts ``y(t) = s + (e - s)(10 u^3 - 15 u^4 + 6 u^5)``,
``u = t / T`` (:func:`motion_envs.geometry.minimum_jerk.minimum_jerk`; Flash & Hogan
1985). ``fit`` learns what the formula leaves open from recordings: the movement
duration ``T`` as a linear function of the distance ``|e - s|``
(``T = a + b |e - s|``, least squares; a constant when all distances are equal or
``duration_model="mean"``) and reports how far the recordings are from the model
(``rmse_`` per recording).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from motion_envs.geometry.minimum_jerk import minimum_jerk
from motion_envs.geometry.resampling import recording_times
from motion_envs.models.estimator import check_is_fitted
from motion_envs.models.serialization import SerializableModel, State, StateSchema

__all__ = ["MinimumJerk"]

FloatArray = NDArray[np.float64]


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

    def fit(
        self,
        positions: Sequence[ArrayLike],
        times: Sequence[ArrayLike] | None = None,
        *,
        rate: float | None = None,
    ) -> MinimumJerk:
        """Fit to recordings ``positions[i]`` ``(n_i, D)`` with ``times`` (s) or ``rate`` (Hz)."""
        if len(positions) == 0:
            raise ValueError("positions must contain at least one recording")
        ts = recording_times(positions, times, rate)
        ys = [np.asarray(y, dtype=np.float64) for y in positions]
        durations = np.array([t[-1] - t[0] for t in ts])
        distances = np.array([np.linalg.norm(y[-1] - y[0]) for y in ys])
        if self.duration_model == "distance" and np.ptp(distances) > 0 and len(ys) > 1:
            design = np.column_stack([np.ones_like(distances), distances])
            coef = np.linalg.lstsq(design, durations, rcond=None)[0]
        else:
            coef = np.array([durations.mean(), 0.0])
        rmse = np.empty(len(ys))
        for i, (t, y) in enumerate(zip(ts, ys, strict=True)):
            model = minimum_jerk(y[0], y[-1], (t - t[0]) / (t[-1] - t[0]))
            rmse[i] = np.sqrt(np.mean(np.sum((model - y) ** 2, axis=1)))
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
        duration: float | None = None,
    ) -> FloatArray:
        """Positions ``(K, D)`` at ``times`` (s since the movement start) from ``start`` to ``end``.

        ``duration`` defaults to the fitted :meth:`predict_duration`; ``times`` to 100
        uniform samples over ``[0, duration]``; times past ``duration`` hold the end.
        """
        check_is_fitted(self, "duration_coef_")
        s = np.asarray(start, dtype=np.float64)
        e = np.asarray(end, dtype=np.float64)
        if s.ndim != 1 or s.shape != e.shape:
            raise ValueError(f"start and end must both be (D,); got {s.shape} and {e.shape}")
        T = float(self.predict_duration(s, e) if duration is None else duration)
        if not np.isfinite(T) or T <= 0:
            raise ValueError(f"duration must be > 0 s; got {T}")
        t = np.linspace(0.0, T, 100) if times is None else np.asarray(times, dtype=np.float64)
        if t.ndim != 1 or np.any(t < 0) or not np.all(np.isfinite(t)):
            raise ValueError(f"times must be (K,) finite seconds >= 0; got shape {t.shape}")
        return minimum_jerk(s, e, np.minimum(t / T, 1.0))

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
