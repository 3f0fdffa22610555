"""The path frame: slerp residuals expressed in axes attached to the movement.

A slerp residual ``r(tau)`` (:mod:`motion_envs.models.slerp_residual`) is a tangent
vector in the moving body frame of the slerp. Its direction relative to the movement
(towards the rotation axis, towards "up", sideways) is more alike across movements
than its body-frame coordinates, and its size grows with the rotation. The path frame
uses both facts.

For a trajectory from ``q_s`` to ``q_e`` (unit quaternions ``(w, x, y, z)``), with the
data's vertical axis ``up`` (world frame, unit):

* relative rotation in the start frame ``v = logmap(conj(q_s) * q_e)``, angle
  ``theta = |v|``; the slerp turns about ``v`` so ``v`` is also the rotation axis in
  every slerp body frame;
* ``a = v / theta`` (the rotation axis);
* ``u_b = R(q_s)^T up`` (up seen from the start frame), ``u = (u_b - (u_b . a) a) /
  |...|`` (up made perpendicular to the axis);
* ``w = a x u``; ``F = [a, u, w]`` (a proper rotation matrix, columns are the axes);
* the path-frame residual is ``p(tau) = F^T r(tau) / s`` with scale
  ``s = max(theta, min_scale)``; the exact inverse is ``r(tau) = s F p(tau)``.

Degenerate cases (each one keeps ``F`` orthonormal, so the inverse stays exact):

* ``theta < axis_tol`` (no rotation; the axis is noise or undefined): ``a`` is the start
  frame's unit vector most perpendicular to ``u_b`` made perpendicular to it
  (``a`` lies in the horizontal plane);
* the axis within ``asin(vertical_tol)`` of up (``|u_b - (u_b . a) a| < vertical_tol``):
  ``up`` is replaced by the start frame's unit vector most perpendicular to ``a``;
* ``theta < min_scale``: the scale is clamped at ``min_scale``, so a predicted
  path-frame residual maps back to a body residual of size at most
  ``min_scale * |p|``: predictions vanish smoothly as the rotation does.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from motion_envs._typing import FloatArray
from motion_envs.datasets.orientation import DEFAULT_UP, check_up
from motion_envs.geometry import quaternion as quat

__all__ = [
    "DEFAULT_UP",
    "FRAMES",
    "MIN_SCALE",
    "check_up",
    "from_path_frame",
    "path_frames",
    "to_path_frame",
]

#: The frames a residual model can work in.
FRAMES: tuple[str, ...] = ("body", "path")
#: Smallest scale (radians) a residual is divided by.
MIN_SCALE = 1e-3
_AXIS_TOL = 1e-9
_VERTICAL_TOL = 1e-6


def _most_perpendicular(v: FloatArray) -> FloatArray:
    """Per row, the unit basis vector least aligned with ``v`` made perpendicular to it."""
    e = np.eye(3)[np.argmin(np.abs(v), axis=-1)]
    p = e - np.einsum("li,li->l", e, v)[:, None] * v
    return p / np.linalg.norm(p, axis=-1, keepdims=True)


def path_frames(
    starts: ArrayLike,
    ends: ArrayLike,
    up: ArrayLike = DEFAULT_UP,
    min_scale: float = MIN_SCALE,
) -> tuple[FloatArray, FloatArray]:
    """Path frames ``F`` ``(L, 3, 3)`` (columns ``a, u, w``) and scales ``s`` ``(L,)``.

    See the module docstring for the formula and the degenerate cases.
    """
    qs = quat.as_unit(np.atleast_2d(starts), name="starts")
    qe = quat.as_unit(np.atleast_2d(ends), name="ends")
    if qs.shape != qe.shape or qs.ndim != 2:
        raise ValueError(f"starts and ends must both be (L, 4); got {qs.shape} and {qe.shape}")
    if not min_scale > 0:
        raise ValueError(f"min_scale must be > 0; got {min_scale!r}")
    up_w = check_up(up)
    v = quat.logmap(quat.multiply(quat.conjugate(qs), qe), validate=False)
    theta = np.linalg.norm(v, axis=1)
    u_b = quat.to_rotation(qs).inv().apply(up_w)
    u_b = u_b / np.linalg.norm(u_b, axis=1, keepdims=True)
    still = theta < _AXIS_TOL
    a = v / np.where(still, 1.0, theta)[:, None]
    if np.any(still):
        a[still] = _most_perpendicular(u_b[still])
    u = u_b - np.einsum("li,li->l", u_b, a)[:, None] * a
    nu = np.linalg.norm(u, axis=1)
    vertical = nu < _VERTICAL_TOL
    u = u / np.where(vertical, 1.0, nu)[:, None]
    if np.any(vertical):
        u[vertical] = _most_perpendicular(a[vertical])
    w = np.cross(a, u)
    F = np.stack([a, u, w], axis=2)
    return F, np.maximum(theta, min_scale)


def to_path_frame(
    residuals: ArrayLike,
    starts: ArrayLike,
    ends: ArrayLike,
    up: ArrayLike = DEFAULT_UP,
    min_scale: float = MIN_SCALE,
) -> FloatArray:
    """Body-frame residual curves ``(L, n, 3)`` -> path frame: ``p = F^T r / s``."""
    R, F, s = _curves_and_frames(residuals, "residuals", starts, ends, up, min_scale)
    return np.einsum("lij,lti->ltj", F, R) / s[:, None, None]


def from_path_frame(
    path_residuals: ArrayLike,
    starts: ArrayLike,
    ends: ArrayLike,
    up: ArrayLike = DEFAULT_UP,
    min_scale: float = MIN_SCALE,
) -> FloatArray:
    """Path-frame curves ``(L, n, 3)`` -> body frame: ``r = s F p`` (inverse of the above)."""
    P, F, s = _curves_and_frames(path_residuals, "path_residuals", starts, ends, up, min_scale)
    return np.einsum("lij,ltj->lti", F, P) * s[:, None, None]


def _curves_and_frames(
    curves: ArrayLike,
    name: str,
    starts: ArrayLike,
    ends: ArrayLike,
    up: ArrayLike,
    min_scale: float,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """``curves`` as float ``(L, n, 3)`` (``ValueError`` naming ``name``), ``F`` and ``s``."""
    C = np.asarray(curves, dtype=np.float64)
    F, s = path_frames(starts, ends, up, min_scale)
    if C.ndim != 3 or C.shape[2] != 3 or C.shape[0] != F.shape[0]:
        raise ValueError(f"{name} must have shape ({F.shape[0]}, n, 3); got {C.shape}")
    return C, F, s
