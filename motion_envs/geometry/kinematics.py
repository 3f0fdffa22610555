"""Smoothed derivatives of sampled trajectories: velocity, acceleration, jerk, speed.

Differentiating raw samples amplifies measurement noise by ``~ sqrt(2) / dt`` per
derivative (0.5 mm of noise at 120 Hz is ~85 mm/s of speed noise). Every derivative here
is a Savitzky-Golay filter (:func:`scipy.signal.savgol_filter`; Savitzky & Golay 1964):
a polynomial of degree ``polyorder`` is fitted by least squares to the ``window`` seconds
of samples centred on each sample (rounded to an odd number ``2 m + 1`` of samples,
at least ``polyorder + 2``) and differentiated analytically; the ends use the fit of the
first/last full window (``mode="interp"``). The filter is centred, hence not causal: a
derivative at sample ``k`` looks ``m`` samples ahead.

Samples must be uniform in time: pass ``rate`` (Hz) or uniform ``times`` (seconds);
resample non-uniform recordings first (:func:`motion_envs.geometry.resampling.resample`).
Arrays are ``(..., K, D)`` (samples on axis -2); results have the same shape.
"""

from __future__ import annotations

from typing import Any, Protocol

import numpy as np
from numpy.typing import ArrayLike

from motion_envs._typing import FloatArray
from motion_envs.geometry.resampling import check_rate, times_in_seconds

__all__ = [
    "DEFAULT_POLYORDER",
    "DEFAULT_WINDOW",
    "Derivative",
    "sample_rate",
    "smoothed_acceleration",
    "smoothed_derivative",
    "smoothed_jerk",
    "smoothed_velocity",
    "speed",
    "window_samples",
]

#: Default Savitzky-Golay window in seconds (13 samples at 120 Hz, 11 at 100 Hz).
DEFAULT_WINDOW = 0.1
#: Default Savitzky-Golay polynomial degree (cubic: exact for velocity up to jerk of a cubic).
DEFAULT_POLYORDER = 3


def sample_rate(
    times: ArrayLike | None = None, rate: float | None = None, rtol: float = 1e-6
) -> float:
    """The sampling rate in Hz from exactly one of ``rate`` (Hz) or uniform ``times`` (s).

    Raises ``ValueError`` when both or neither are given, when ``times`` are integers
    (sample indices are not seconds), not strictly increasing, or not uniform to ``rtol``.
    """
    if (times is None) == (rate is None):
        raise ValueError("give exactly one of times= (seconds) or rate= (Hz)")
    if rate is not None:
        return check_rate(rate)
    assert times is not None
    t = times_in_seconds(times)
    dt = np.diff(t)
    if np.ptp(dt) > rtol * np.mean(dt):
        raise ValueError(
            "times are not uniform; resample to a rate first (motion_envs.geometry.resample)"
        )
    return float(1.0 / np.mean(dt))


def window_samples(window: float, rate: float, polyorder: int = DEFAULT_POLYORDER) -> int:
    """``window`` seconds at ``rate`` Hz as an odd number of samples ``>= polyorder + 2``."""
    if not np.isfinite(window) or window <= 0:
        raise ValueError(f"window must be a duration > 0 in seconds; got {window!r}")
    n = round(float(window) * float(rate))
    n = max(n, polyorder + 2)
    return n if n % 2 else n + 1


def smoothed_derivative(
    positions: ArrayLike,
    order: int,
    times: ArrayLike | None = None,
    rate: float | None = None,
    window: float = DEFAULT_WINDOW,
    polyorder: int = DEFAULT_POLYORDER,
) -> FloatArray:
    """The ``order``-th time derivative (0 = smoothed positions) by Savitzky-Golay.

    ``positions`` ``(..., K, D)`` sampled at ``rate`` Hz (or uniform ``times``);
    ``window`` in seconds, ``polyorder`` the local polynomial degree (``>= order``).
    """
    y = np.asarray(positions, dtype=np.float64)
    if y.ndim < 2:
        raise ValueError(f"positions must be (..., K, D); got shape {y.shape}")
    if not np.all(np.isfinite(y)):
        raise ValueError("positions contains NaN or infinite values")
    if not 0 <= int(order) <= int(polyorder):
        raise ValueError(f"order must be in [0, polyorder = {polyorder}]; got {order}")
    r = sample_rate(times, rate)
    if times is not None and np.shape(times)[0] != y.shape[-2]:
        raise ValueError(f"times must have {y.shape[-2]} samples; got {np.shape(times)[0]}")
    n = window_samples(window, r, int(polyorder))
    if n > y.shape[-2]:
        raise ValueError(
            f"window = {window} s is {n} samples at {r:g} Hz, more than the {y.shape[-2]} "
            "samples of positions; lower window"
        )
    import scipy.signal  # here: importing it costs ~1 s, and most callers never smooth

    return np.asarray(
        scipy.signal.savgol_filter(
            y, n, int(polyorder), deriv=int(order), delta=1.0 / r, axis=-2, mode="interp"
        ),
        dtype=np.float64,
    )


class Derivative(Protocol):
    """Signature of :data:`smoothed_velocity`, :data:`smoothed_acceleration`,
    :data:`smoothed_jerk` and :func:`speed`."""

    def __call__(
        self,
        positions: ArrayLike,
        times: ArrayLike | None = None,
        rate: float | None = None,
        window: float = DEFAULT_WINDOW,
        polyorder: int = DEFAULT_POLYORDER,
    ) -> FloatArray: ...


def _nth_derivative(order: int, what: str) -> Derivative:
    def derivative(positions: ArrayLike, *args: Any, **kwargs: Any) -> FloatArray:
        return smoothed_derivative(positions, order, *args, **kwargs)

    derivative.__doc__ = f"{what} ``(..., K, D)`` (order {order} of :func:`smoothed_derivative`)."
    return derivative


#: ``smoothed_velocity(positions, times=None, rate=None, window=0.1, polyorder=3)``: ``dy/dt``.
smoothed_velocity = _nth_derivative(1, "Velocity ``dy/dt``")
#: ``smoothed_acceleration(positions, times=None, rate=None, ...)``: ``d2y/dt2``.
smoothed_acceleration = _nth_derivative(2, "Acceleration ``d2y/dt2``")
#: ``smoothed_jerk(positions, times=None, rate=None, ...)``: ``d3y/dt3``.
smoothed_jerk = _nth_derivative(3, "Jerk ``d3y/dt3``")


def speed(positions: ArrayLike, *args: Any, **kwargs: Any) -> FloatArray:
    """Speed ``|dy/dt|`` ``(..., K)``; the arguments of :data:`smoothed_velocity`."""
    v = smoothed_velocity(positions, *args, **kwargs)
    return np.asarray(np.linalg.norm(v, axis=-1), dtype=np.float64)
