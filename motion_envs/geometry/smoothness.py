"""Smoothness of a movement: log dimensionless jerk and spectral arc length.

Both follow Balasubramanian, Melendez-Calderon, Roby-Brami & Burdet (2015), "On the
analysis of movement smoothness", J. NeuroEng. Rehabil. 12:112 (doi
10.1186/s12984-015-0090-9), on the speed profile ``v(t) = |dy/dt|`` of one movement
over ``[t_1, t_2]``; both are dimensionless and larger (closer to 0) means smoother.

* Log dimensionless jerk (their eq. 6, velocity form)::

      LDLJ = -ln( (t_2 - t_1)^3 / v_peak^2 * int_{t_1}^{t_2} |d2v/dt2|^2 dt )

  with ``d2v/dt2`` the jerk vector ``d3y/dt3`` (Savitzky-Golay,
  :mod:`motion_envs.geometry.kinematics`) and the integral by the trapezoidal rule.
  A minimum-jerk movement gives ``-ln(720 / 1.875^2) = -5.32``.

* Spectral arc length SPARC (their eqs. 9-10; Balasubramanian et al. 2012): with
  ``V(f)`` the magnitude of the Fourier transform of the speed (zero-padded to
  ``2^(ceil(log2 K) + padlevel)`` points) normalised by ``V(0)``, and ``f_c`` the
  largest frequency ``<= f_max`` (10 Hz) where ``V(f) >= threshold`` (0.05)::

      SPARC = -int_0^{f_c} sqrt( (1 / f_c)^2 + (dV/df)^2 ) df

  computed on the discrete spectrum as ``-sum sqrt((df / f_c)^2 + dV^2)``, as in the
  authors' reference implementation.
"""

from __future__ import annotations

import numpy as np
import scipy.fft
from numpy.typing import ArrayLike

from motion_envs.geometry.kinematics import (
    DEFAULT_WINDOW,
    sample_rate,
    smoothed_jerk,
    smoothed_velocity,
)

__all__ = ["log_dimensionless_jerk", "spectral_arc_length"]


def log_dimensionless_jerk(
    positions: ArrayLike,
    times: ArrayLike | None = None,
    rate: float | None = None,
    window: float = DEFAULT_WINDOW,
    polyorder: int = 5,
) -> float:
    """LDLJ of one movement ``(K, D)`` sampled at ``rate`` Hz (or uniform ``times``).

    Derivatives by Savitzky-Golay over ``window`` seconds, degree ``polyorder``
    (default 5, exact on a minimum-jerk movement).
    """
    r = sample_rate(times, rate)
    v = smoothed_velocity(positions, rate=r, window=window, polyorder=polyorder)
    j = smoothed_jerk(positions, rate=r, window=window, polyorder=polyorder)
    speed = np.linalg.norm(v, axis=-1)
    peak = float(np.max(speed))
    if peak <= 0:
        raise ValueError("positions do not move: the dimensionless jerk is undefined")
    duration = (speed.shape[0] - 1) / r
    integral = float(np.trapezoid(np.sum(j**2, axis=-1), dx=1.0 / r))
    return float(-np.log(duration**3 / peak**2 * integral))


def spectral_arc_length(
    speed: ArrayLike,
    rate: float,
    padlevel: int = 4,
    max_frequency: float = 10.0,
    threshold: float = 0.05,
) -> float:
    """SPARC of a speed profile ``(K,)`` sampled at ``rate`` Hz (see the module docstring).

    Pass the speed of positions with :func:`motion_envs.geometry.kinematics.speed`.
    """
    v = np.asarray(speed, dtype=np.float64)
    if v.ndim != 1 or v.size < 2 or not np.all(np.isfinite(v)):
        raise ValueError(f"speed must be a finite (K,) array with K >= 2; got shape {v.shape}")
    r = sample_rate(rate=rate)
    nfft = int(2 ** (np.ceil(np.log2(v.size)) + padlevel))
    f = np.arange(nfft) * (r / nfft)
    spectrum = np.abs(scipy.fft.fft(v, nfft))
    if spectrum.max() <= 0:
        raise ValueError("speed is zero: the spectral arc length is undefined")
    spectrum = spectrum / spectrum.max()
    keep = f <= max_frequency
    f_sel, m_sel = f[keep], spectrum[keep]
    above = np.flatnonzero(m_sel >= threshold)
    f_sel = f_sel[above[0] : above[-1] + 1]
    m_sel = m_sel[above[0] : above[-1] + 1]
    if f_sel.size < 2:
        raise ValueError("speed spectrum has fewer than 2 points above the threshold")
    df = np.diff(f_sel) / (f_sel[-1] - f_sel[0])
    return float(-np.sum(np.sqrt(df**2 + np.diff(m_sel) ** 2)))
