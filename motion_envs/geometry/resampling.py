"""Sample times of recordings: seconds from a rate, resampling to a rate, time normalisation.

A recording is positions ``(K, D)`` at times ``(K,)`` in seconds. Sample indices are not
seconds: every entry point that takes ``times`` refuses integer arrays and asks for
``times=`` in seconds or ``rate=`` in Hz (``t_k = k / rate``).

* :func:`recording_times`: one float time array per recording from ``times`` or ``rate``;
* :func:`resample`: positions at a new uniform ``rate`` (Hz) over the same time span;
* :func:`time_normalise`: positions on ``n_points`` uniform samples of normalised time
  ``tau = (t - t_0) / (t_last - t_0)`` in ``[0, 1]``.

Both resamplers interpolate each coordinate with a cubic spline through the samples
(:class:`scipy.interpolate.CubicSpline`, not-a-knot ends; ``kind="linear"`` for
:func:`numpy.interp`-style piecewise-linear interpolation).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Literal

import numpy as np
import scipy.interpolate
from numpy.typing import ArrayLike

from motion_envs._typing import FloatArray
from motion_envs.geometry.sine_series import normalised_time

__all__ = [
    "check_rate",
    "normalised_time",
    "recording_times",
    "resample",
    "time_normalise",
    "times_in_seconds",
]

Kind = Literal["cubic", "linear"]


def times_in_seconds(times: ArrayLike, name: str = "times") -> FloatArray:
    """``times`` as a finite, strictly increasing float ``(K,)`` array in seconds.

    Raises ``ValueError`` for integer arrays (sample indices are not seconds).
    """
    raw = np.asarray(times)
    if raw.dtype.kind in "iub":
        raise ValueError(
            f"{name} are integers: sample indices are not seconds; pass {name} in seconds "
            "(float) or rate= in Hz"
        )
    t = raw.astype(np.float64)
    if t.ndim != 1 or t.size < 2:
        raise ValueError(f"{name} must be (K,) with K >= 2; got shape {t.shape}")
    if not np.all(np.isfinite(t)):
        raise ValueError(f"{name} contains NaN or infinite values")
    if np.any(np.diff(t) <= 0):
        raise ValueError(f"{name} must be strictly increasing")
    return t


def check_rate(rate: float, name: str = "rate") -> float:
    """``rate`` as a float sampling rate in Hz; ``ValueError`` unless finite and > 0."""
    r = float(rate)
    if not np.isfinite(r) or r <= 0:
        raise ValueError(f"{name} must be a finite sampling rate > 0 in Hz; got {rate!r}")
    return r


def recording_times(
    positions: Sequence[ArrayLike],
    times: Sequence[ArrayLike] | None = None,
    rate: float | None = None,
) -> list[FloatArray]:
    """One float time array ``(n_i,)`` in seconds per recording ``positions[i]`` ``(n_i, D)``.

    Exactly one of ``times`` (seconds, one array per recording) and ``rate`` (Hz,
    ``t_k = k / rate``) must be given.
    """
    if (times is None) == (rate is None):
        raise ValueError(
            "give exactly one of times= (seconds, one array per recording) or rate= (Hz)"
        )
    if rate is not None:
        r = check_rate(rate)
        return [np.arange(np.shape(y)[0]) / r for y in positions]
    assert times is not None
    if len(times) != len(positions):
        raise ValueError(
            f"times must have one array per recording; got {len(times)} for {len(positions)}"
        )
    out = []
    for i, (t, y) in enumerate(zip(times, positions, strict=True)):
        ti = times_in_seconds(t, f"times[{i}]")
        if ti.shape[0] != np.shape(y)[0]:
            raise ValueError(f"times[{i}] must have {np.shape(y)[0]} samples; got {ti.shape[0]}")
        out.append(ti)
    return out


def _interpolate(t: FloatArray, y: FloatArray, new_t: FloatArray, kind: Kind) -> FloatArray:
    if kind == "cubic":
        return np.asarray(scipy.interpolate.CubicSpline(t, y, axis=0)(new_t), dtype=np.float64)
    if kind == "linear":
        return np.stack([np.interp(new_t, t, y[:, d]) for d in range(y.shape[1])], axis=1)
    raise ValueError(f"kind must be 'cubic' or 'linear'; got {kind!r}")


def _recording(positions: ArrayLike, times: ArrayLike) -> tuple[FloatArray, FloatArray]:
    y = np.asarray(positions, dtype=np.float64)
    if y.ndim != 2 or not np.all(np.isfinite(y)):
        raise ValueError(f"positions must be a finite (K, D) array; got shape {y.shape}")
    t = times_in_seconds(times)
    if t.shape[0] != y.shape[0]:
        raise ValueError(f"times must have {y.shape[0]} samples; got {t.shape[0]}")
    return t, y


def resample(
    positions: ArrayLike, times: ArrayLike, rate: float, kind: Kind = "cubic"
) -> tuple[FloatArray, FloatArray]:
    """Positions ``(K', D)`` at ``t_0 + k / rate`` (``k = 0 .. floor((t_last - t_0) rate)``).

    Returns ``(new_times, new_positions)``; ``times`` are the recording's in seconds.
    """
    t, y = _recording(positions, times)
    r = check_rate(rate)
    n = int(np.floor((t[-1] - t[0]) * r * (1 + 1e-12))) + 1
    new_t = t[0] + np.arange(n) / r
    return new_t, _interpolate(t, y, new_t, kind)


def time_normalise(
    positions: ArrayLike, times: ArrayLike, n_points: int = 101, kind: Kind = "cubic"
) -> tuple[FloatArray, FloatArray]:
    """Positions ``(n_points, D)`` on uniform normalised time ``tau = k / (n_points - 1)``.

    Returns ``(tau, positions_on_tau)``; the duration ``t_last - t_0`` is what it drops.
    """
    t, y = _recording(positions, times)
    if int(n_points) < 2:
        raise ValueError(f"n_points must be >= 2; got {n_points}")
    tau = np.linspace(0.0, 1.0, int(n_points))
    return tau, _interpolate(normalised_time(t), y, tau, kind)
