"""Whole-array numpy forms of slerp, multiply, logmap and expmap: the "plain numpy" anchor.

These were motion_envs' implementation before the block-wise fast paths of
``motion_envs/geometry/quaternion.py``; the benchmarks time them as the plain-numpy
baseline (same formulas, one array operation per term over the whole batch). Inputs are
assumed valid (shapes, unit norms): nothing here validates.
"""

from __future__ import annotations

import numpy as np

from motion_envs._typing import FloatArray

#: Same small-angle threshold as motion_envs.geometry.quaternion.
SMALL_ANGLE = 1e-4


def multiply(p: FloatArray, q: FloatArray) -> FloatArray:
    """Whole-array form of :func:`multiply` ."""
    pw, px, py, pz = np.moveaxis(p, -1, 0)
    qw, qx, qy, qz = np.moveaxis(q, -1, 0)
    return np.stack(
        [
            pw * qw - px * qx - py * qy - pz * qz,
            pw * qx + px * qw + py * qz - pz * qy,
            pw * qy - px * qz + py * qw + pz * qx,
            pw * qz + px * qy - py * qx + pz * qw,
        ],
        axis=-1,
    )


def expmap(v: FloatArray) -> FloatArray:
    """Whole-array form of :func:`expmap` (sine and cosine; the benchmarks' plain numpy)."""
    theta2 = np.einsum("...i,...i->...", v, v)
    theta = np.sqrt(theta2)
    small = theta < SMALL_ANGLE
    safe = np.where(small, 1.0, theta)
    half_sinc = np.where(
        small, 0.5 - theta2 / 48.0 + theta2 * theta2 / 3840.0, np.sin(0.5 * safe) / safe
    )
    out = np.empty((*v.shape[:-1], 4))
    out[..., 0] = np.cos(0.5 * theta)
    out[..., 1:] = half_sinc[..., None] * v
    return out


def logmap(q: FloatArray) -> FloatArray:
    """Whole-array form of :func:`logmap` ."""
    sign = np.where(q[..., :1] < 0.0, -1.0, 1.0)
    w = np.abs(q[..., 0])
    u = q[..., 1:] * sign
    s = np.sqrt(np.einsum("...i,...i->...", u, u))
    theta = 2.0 * np.arctan2(s, w)
    small = s < SMALL_ANGLE
    safe = np.where(small, 1.0, s)
    # theta / s; for small s: theta = 2 s / w (1 - s^2/(3 w^2) + ...) -> 2/w + s^2 ...
    scale = np.where(small, 2.0 / np.maximum(w, 1e-300) * (1.0 - s * s / 3.0), theta / safe)
    return scale[..., None] * u


def slerp(q0: FloatArray, q1: FloatArray, alpha: FloatArray) -> FloatArray:
    """Whole-array form of :func:`slerp` ."""
    dot = np.einsum("...i,...i->...", q0, q1)
    sign = np.where(dot < 0.0, -1.0, 1.0)[..., None]
    # half angle h = theta/2 = 2 atan2(|q0 - q1|, |q0 + q1|): accurate at 0 and at pi/2.
    diff = q0 - sign * q1
    summ = q0 + sign * q1
    half = 2.0 * np.arctan2(
        np.sqrt(np.einsum("...i,...i->...", diff, diff)),
        np.sqrt(np.einsum("...i,...i->...", summ, summ)),
    )
    sign = sign[..., 0]
    small = half < SMALL_ANGLE
    sin_half = np.where(small, 1.0, np.sin(half))
    a = alpha
    h2 = half * half / 6.0
    w0 = np.where(
        small, (1.0 - a) * (1.0 + (1.0 - (1.0 - a) ** 2) * h2), np.sin((1.0 - a) * half) / sin_half
    )
    w1 = np.where(small, a * (1.0 + (1.0 - a * a) * h2), np.sin(a * half) / sin_half) * sign
    return w0[..., None] * q0 + w1[..., None] * q1
