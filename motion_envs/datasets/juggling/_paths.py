"""Juggling paths on normalised time: resampling and the departure from the straight line."""

from __future__ import annotations

import numpy as np

from motion_envs._typing import FloatArray

__all__ = ["departure_from_line", "resample_path"]


def resample_path(times: FloatArray, positions: FloatArray, n_points: int) -> FloatArray:
    """``positions (n, 2)`` sampled at ``times`` (increasing), linearly interpolated at
    ``n_points`` equally spaced points of normalised time ``(t - t_0) / (t_last - t_0)``."""
    tau = (times - times[0]) / (times[-1] - times[0])
    grid = np.linspace(0.0, 1.0, n_points)
    return np.column_stack([np.interp(grid, tau, positions[:, d]) for d in range(2)])


def departure_from_line(paths: FloatArray) -> FloatArray:
    """``r(y)_k = y_k - (y_0 + tau_k (y_last - y_0))`` of paths ``(..., n, 2)`` sampled at
    equally spaced ``tau_k = k / (n - 1)``: the path minus the straight line between its
    ends (zero at both ends).

    The quantity of :func:`motion_envs.geometry.sine_series.residual` (eq. 3) on a uniform
    grid, with the line subtracted in one piece: the same to round-off (1e-15), not bit for
    bit; ``motion-bench juggling`` and the agents' deviation are computed with this form.
    """
    n = paths.shape[-2]
    tau = np.linspace(0.0, 1.0, n)[:, None]
    first, last = paths[..., :1, :], paths[..., -1:, :]
    out: FloatArray = paths - (first + tau * (last - first))
    return out
