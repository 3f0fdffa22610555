"""Unit quaternions for orientation trajectories.

Convention used everywhere in motion-envs: a quaternion is stored **scalar first**,
``q = (w, x, y, z)`` along the last axis, with ``w = cos(theta/2)`` and
``(x, y, z) = sin(theta/2) * axis``. This is MuJoCo's order and the order of the
``qw, qx, qy, qz`` columns of the data files; scipy uses ``(x, y, z, w)`` by default,
so conversions happen only in :func:`to_rotation` / :func:`from_rotation`.

All functions are pure numpy and broadcast over any number of leading (batch) axes.
Functions that *require* unit quaternions validate their input and raise
``ValueError`` naming the argument; pass ``validate=False`` on hot paths where the
input is known to be valid.

Unit-norm tolerance: one number, :data:`UNIT_TOLERANCE` (``| |q| - 1 | <= 1e-6``), is
what every entry point accepts as a unit quaternion. Data that is only approximately
unit is renormalised only when asked: ``normalize=True`` on :func:`as_unit` and
:func:`to_rotation` (and on the models that take quaternions, e.g.
``OrientationModel(normalize=True)``); the CSV readers of :mod:`motion_envs.datasets`
renormalise by design and refuse norms off by more than their documented data
tolerance (``1e-3``), which flags corrupt rows, not rounding.

References: Faraway & Choe (2008), section 3.2; Shoemake (1985); Grassia (1998).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from motion_envs._typing import FloatArray

__all__ = [
    "IDENTITY",
    "UNIT_TOLERANCE",
    "angle",
    "as_unit",
    "conjugate",
    "expmap",
    "from_rotation",
    "logmap",
    "make_continuous",
    "multiply",
    "normalize",
    "slerp",
    "to_rotation",
]

#: The identity rotation ``(w, x, y, z) = (1, 0, 0, 0)``.
IDENTITY: FloatArray = np.array([1.0, 0.0, 0.0, 0.0])

#: Largest accepted deviation ``| |q| - 1 |`` for an input said to be a unit quaternion.
UNIT_TOLERANCE = 1e-6

# Below this angle the series expansions are used instead of the closed forms.
_SMALL_ANGLE = 1e-4

# Hot paths (slerp, multiply, logmap, expmap) work on blocks of this many quaternions,
# copied to contiguous component rows, so that every temporary stays in the CPU cache and
# is reused (``out=``) instead of being allocated per operation. The results equal the
# plain whole-array formulas to rounding (~1e-16); see benchmarks/quaternion_ops.py.
_BLOCK = 8192

# Inputs with at least this many entries are tested for NaN/inf by a sum first.
_FINITE_BY_REDUCTION = 4096


def _blocks(n: int) -> Iterator[tuple[int, int]]:
    """``(start, stop)`` of consecutive blocks covering ``range(n)``."""
    for start in range(0, n, _BLOCK):
        yield start, min(start + _BLOCK, n)


#: ``kernel(columns, work, small, rows)`` of :func:`_row_blocks`.
_BlockKernel = Callable[[FloatArray, FloatArray, NDArray[np.bool_], FloatArray], None]


def _row_blocks(flat: FloatArray, width: int, n_work: int, kernel: _BlockKernel) -> FloatArray:
    """The ``(n, width)`` rows ``kernel`` writes for the ``(n, w)`` rows of ``flat``, by block.

    For each block of at most :data:`_BLOCK` rows, ``kernel`` gets the block transposed
    (``(w, k)`` columns), ``(n_work, k)`` and ``(k,)`` boolean scratch buffers (reused
    across blocks) and the ``(k, width)`` rows of the result to fill.
    """
    n = flat.shape[0]
    out = np.empty((n, width))
    m = min(n, _BLOCK)
    columns, work = np.empty((flat.shape[1], m)), np.empty((n_work, m))
    small = np.empty(m, dtype=bool)
    for start, stop in _blocks(n):
        k = stop - start
        np.copyto(columns[:, :k], flat[start:stop].T)
        kernel(columns[:, :k], work[:, :k], small[:k], out[start:stop])
    return out


def _flatten(arr: FloatArray, batch: tuple[int, ...], trailing: tuple[int, ...]) -> FloatArray:
    """``arr`` broadcast to ``batch + trailing`` and viewed (or copied) as ``(n, *trailing)``."""
    full = np.broadcast_to(arr, batch + trailing)
    return full.reshape((-1, *trailing))


def _store_columns(dst: FloatArray, rows: FloatArray) -> None:
    """``dst[:, c] = rows[c]`` column by column (faster than one transposed copy)."""
    for c in range(rows.shape[0]):
        np.copyto(dst[:, c], rows[c])


def _sign_of(w: FloatArray, out: FloatArray) -> FloatArray:
    """``-1`` where ``w < 0`` else ``+1`` (``-0.0`` counts as ``+1``), written to ``out``."""
    np.add(w, 0.0, out=out)  # -0.0 + 0.0 = +0.0
    return np.copysign(1.0, out, out=out)


def _checked(x: ArrayLike, name: str, width: int, finite: bool = True) -> FloatArray:
    """``x`` as a float64 array whose last axis has length ``width``, every entry finite.

    The one input check of :func:`multiply`, :func:`conjugate`, :func:`expmap`,
    :func:`logmap` (and, through :func:`_as_quaternion_array`, of the validating
    functions). Raises ``ValueError`` naming ``name`` for a non-numeric (string, object,
    complex) input, a scalar or a wrong last axis, and (unless ``finite=False``, for a
    caller whose next check reads every entry anyway, like :func:`as_unit`) NaN or
    infinite entries.

    Small inputs are tested with ``isfinite(x).all()``. Large ones with one pairwise sum
    (no temporary array): a finite sum implies every entry is finite, since NaN and inf
    propagate through ``+``; only a non-finite sum (a NaN, an inf, or finite values summing
    beyond float64's range) pays for the exact element-wise test.
    """
    arr = np.asarray(x)
    if arr.dtype.kind not in "fiub":
        raise ValueError(
            f"{name} must hold real numbers; got an array of dtype {arr.dtype} ({type(x).__name__})"
        )
    if arr.dtype != np.float64:
        arr = arr.astype(np.float64)
    if arr.ndim == 0 or arr.shape[-1] != width:
        axes = "(w, x, y, z)" if width == 4 else "(x, y, z)"
        raise ValueError(
            f"{name} must have a last axis of length {width} {axes}; got shape {arr.shape}"
        )
    if not finite:
        return arr
    if arr.size < _FINITE_BY_REDUCTION:
        finite = bool(np.isfinite(arr).all())
    else:
        with np.errstate(over="ignore", invalid="ignore"):
            finite = math.isfinite(np.add.reduce(arr, axis=None))
        if not finite:
            finite = bool(np.isfinite(arr).all())
    if not finite:
        raise ValueError(f"{name} contains NaN or infinite values")
    return arr


def _as_quaternion_array(q: ArrayLike, name: str) -> FloatArray:
    """Return ``q`` as a float64 array with last axis 4, finite, or raise ``ValueError``."""
    return _checked(q, name, 4)


def _all_unit_fast(flat: FloatArray, tol: float) -> bool:
    """Block-wise ``all(| |q| - 1 | <= tol - 1e-12)`` over ``(n, 4)``; False on NaN/inf.

    A True answer implies :func:`as_unit`'s exact checks pass (the 1e-12 margin covers
    the rounding differences of the two sums); False only sends the input to them.
    """
    strict = tol - 1e-12
    if not strict >= 0.0:
        return False
    n = flat.shape[0]
    m = min(n, _BLOCK)
    Q, norm, t = np.empty((4, m)), np.empty(m), np.empty(m)
    with np.errstate(over="ignore", invalid="ignore"):  # the slow path reports those
        for start, stop in _blocks(n):
            k = stop - start
            Qk, nk, tk = Q[:, :k], norm[:k], t[:k]
            np.copyto(Qk, flat[start:stop].T)
            np.multiply(Qk[0], Qk[0], out=nk)
            for c in (1, 2, 3):
                np.multiply(Qk[c], Qk[c], out=tk)
                nk += tk
            np.sqrt(nk, out=nk)
            nk -= 1.0
            np.abs(nk, out=nk)
            if not (nk <= strict).all():  # NaN and inf compare False
                return False
    return True


def as_unit(
    q: ArrayLike, name: str = "q", tol: float = UNIT_TOLERANCE, normalize: bool = False
) -> FloatArray:
    """Validate that ``q`` holds unit quaternions ``(w, x, y, z)`` and return it as float64.

    Raises ``ValueError`` naming ``name`` if the last axis is not 4, a value is NaN or
    infinite, or a norm differs from 1 by more than ``tol`` (default
    :data:`UNIT_TOLERANCE`). With ``normalize=True`` every finite non-zero quaternion is
    divided by its norm instead (:func:`normalize`): say so explicitly when your data
    (a CSV rounded to a few digits, a tracker's output) is only approximately unit.
    """
    if normalize:
        return _normalized(q, name)
    arr = np.asarray(q, dtype=np.float64)
    if arr.ndim > 0 and arr.shape[-1] == 4 and _all_unit_fast(arr.reshape(-1, 4), tol):
        return arr
    # Slow path: the exact checks below, and their error messages.
    arr = _as_quaternion_array(q, name)
    norms = np.sqrt(np.einsum("...i,...i->...", arr, arr))
    bad = np.abs(norms - 1.0) > tol
    if np.any(bad):
        worst = float(norms.flat[np.argmax(np.abs(norms - 1.0).ravel())])
        raise ValueError(
            f"{name} must contain unit quaternions (|q| = 1 within {tol:g}); "
            f"{int(np.count_nonzero(bad))} are not (worst norm {worst:.6g}); pass "
            "normalize=True to renormalise them"
        )
    return arr


def normalize(q: ArrayLike, name: str = "q") -> FloatArray:
    """Return ``q / |q|`` for quaternions ``(w, x, y, z)``.

    Raises ``ValueError`` naming ``name`` for NaN/inf entries, a wrong last axis or a
    (near) zero norm, which has no direction to normalise to.
    """
    return _normalized(q, name)


def _normalized(q: ArrayLike, name: str) -> FloatArray:
    arr = _as_quaternion_array(q, name)
    norms = np.sqrt(np.einsum("...i,...i->...", arr, arr))
    if np.any(norms < 1e-12):
        raise ValueError(f"{name} contains a quaternion of zero norm, which cannot be normalised")
    return arr / norms[..., None]


def multiply(p: ArrayLike, q: ArrayLike) -> FloatArray:
    """Hamilton product ``p * q`` of quaternions ``(w, x, y, z)``, broadcast over batches.

    With ``p = [v1, w1]`` and ``q = [v2, w2]`` (vector, scalar)::

        p * q = [w1 v2 + w2 v1 + v1 x v2,  w1 w2 - v1 . v2]

    As rotations, ``p * q`` applies ``q`` first, then ``p`` (same as scipy's ``P * Q``).
    A wrong last axis, non-numeric, NaN or infinite input raises ``ValueError``.
    """
    p = _checked(p, "p", 4)
    q = _checked(q, "q", 4)
    batch = np.broadcast_shapes(p.shape[:-1], q.shape[:-1])
    pf = _flatten(p, batch, (4,))
    qf = _flatten(q, batch, (4,))
    n = pf.shape[0]
    out = np.empty((n, 4))
    m = min(n, _BLOCK)
    P, Q, R = np.empty((4, m)), np.empty((4, m)), np.empty((4, m))
    t = np.empty(m)
    # (sign, index into p, index into q) of the terms of each output component, in the
    # order of the docstring formula (left to right, as in _multiply_reference).
    terms = (
        ((1, 0, 0), (-1, 1, 1), (-1, 2, 2), (-1, 3, 3)),
        ((1, 0, 1), (1, 1, 0), (1, 2, 3), (-1, 3, 2)),
        ((1, 0, 2), (-1, 1, 3), (1, 2, 0), (1, 3, 1)),
        ((1, 0, 3), (1, 1, 2), (-1, 2, 1), (1, 3, 0)),
    )
    for start, stop in _blocks(n):
        k = stop - start
        Pk, Qk, Rk, tk = P[:, :k], Q[:, :k], R[:, :k], t[:k]
        np.copyto(Pk, pf[start:stop].T)
        np.copyto(Qk, qf[start:stop].T)
        for c, component in enumerate(terms):
            rc = Rk[c]
            _, i0, j0 = component[0]
            np.multiply(Pk[i0], Qk[j0], out=rc)
            for sign, i, j in component[1:]:
                np.multiply(Pk[i], Qk[j], out=tk)
                (np.add if sign > 0 else np.subtract)(rc, tk, out=rc)
        _store_columns(out[start:stop], Rk)
    return out.reshape((*batch, 4))


def conjugate(q: ArrayLike) -> FloatArray:
    """Conjugate ``q* = (w, -x, -y, -z)``; the inverse of a unit quaternion.

    Raises ``ValueError`` for a wrong last axis, non-numeric, NaN or infinite input.
    """
    out = np.array(_checked(q, "q", 4), copy=True)
    out[..., 1:] *= -1.0
    return out


def expmap(v: ArrayLike, name: str = "v") -> FloatArray:
    """Exponential map from the tangent space at the identity to unit quaternions.

    For ``v`` in R^3 with ``theta = |v|``::

        expmap(v) = (cos(theta/2), sin(theta/2) v / theta),   expmap(0) = (1, 0, 0, 0)

    i.e. the rotation by ``theta`` about ``v/theta`` (equal to scipy's
    ``Rotation.from_rotvec(v)``). ``sin(theta/2)/theta`` is evaluated by its series
    ``1/2 - theta^2/48 + theta^4/3840`` for small ``theta`` so nothing divides by a tiny
    number. Returns shape ``v.shape[:-1] + (4,)``. A wrong last axis, non-numeric, NaN or
    infinite input raises ``ValueError`` naming ``name``.
    """
    v = _checked(v, name, 3)
    return _row_blocks(v.reshape(-1, 3), 4, 4, _expmap_block).reshape((*v.shape[:-1], 4))


def _expmap_block(
    V: FloatArray, work: FloatArray, small: NDArray[np.bool_], block: FloatArray
) -> None:
    # sin(theta/2) and cos(theta/2) from one tangent: with t = tan(theta/4),
    # sin(theta/2) = 2t / (1 + t^2) and cos(theta/2) = (1 - t^2) / (1 + t^2).
    theta2, theta, t, den = work
    np.multiply(V[0], V[0], out=theta2)
    for c in (1, 2):
        np.multiply(V[c], V[c], out=t)
        theta2 += t
    np.sqrt(theta2, out=theta)
    np.multiply(theta, 0.25, out=t)
    np.tan(t, out=t)
    np.multiply(t, t, out=den)
    np.subtract(1.0, den, out=block[:, 0])
    den += 1.0
    np.divide(block[:, 0], den, out=block[:, 0])  # cos(theta/2)
    # half_sinc = sin(theta/2) / theta = 2t / ((1 + t^2) theta)
    np.multiply(den, theta, out=den)
    np.add(t, t, out=t)
    with np.errstate(invalid="ignore", divide="ignore"):
        np.divide(t, den, out=t)
    np.less(theta, _SMALL_ANGLE, out=small)
    if small.any():
        th2 = theta2[small]
        t[small] = 0.5 - th2 / 48.0 + th2 * th2 / 3840.0
    for c in range(3):
        np.multiply(t, V[c], out=block[:, c + 1])


def logmap(q: ArrayLike, name: str = "q", validate: bool = True) -> FloatArray:
    """Logarithm map from unit quaternions to the tangent space at the identity.

    Inverse of :func:`expmap` on rotation angles in ``[0, pi]``: ``q`` and ``-q`` map to
    the same vector (the sign is chosen so that ``w >= 0``). With ``q = (w, u)``::

        theta = 2 atan2(|u|, w),   logmap(q) = theta u / |u|,   logmap(identity) = 0

    ``theta / sin(theta/2)`` is evaluated by its series ``2 + theta^2/12`` near 0, and
    the ``atan2`` form stays accurate near ``theta = pi`` where ``arccos(w)`` would not.
    Returns shape ``q.shape[:-1] + (3,)``. A wrong last axis, non-numeric, NaN or
    infinite input raises ``ValueError`` always; ``validate=False`` skips only the check
    that the quaternions are unit.
    """
    q = _checked(q, name, 4, finite=not validate)
    if validate:
        q = as_unit(q, name)  # NaN/inf fail its unit check
    return _row_blocks(q.reshape(-1, 4), 3, 4, _logmap_block).reshape((*q.shape[:-1], 3))


def _logmap_block(
    Q: FloatArray, work: FloatArray, small: NDArray[np.bool_], block: FloatArray
) -> None:
    s, w, scale, sign = work
    _sign_of(Q[0], sign)
    np.abs(Q[0], out=w)
    np.multiply(Q[1], Q[1], out=s)
    for c in (2, 3):
        np.multiply(Q[c], Q[c], out=scale)
        s += scale
    np.sqrt(s, out=s)
    np.arctan2(s, w, out=scale)
    scale *= 2.0  # theta
    with np.errstate(invalid="ignore", divide="ignore"):
        np.divide(scale, s, out=scale)
    np.less(s, _SMALL_ANGLE, out=small)
    if small.any():
        ss, ws = s[small], w[small]
        scale[small] = 2.0 / np.maximum(ws, 1e-300) * (1.0 - ss * ss / 3.0)
    scale *= sign  # u = sign * (x, y, z)
    for c in range(3):
        np.multiply(scale, Q[c + 1], out=block[:, c])


def angle(p: ArrayLike, q: ArrayLike, name_p: str = "p", name_q: str = "q") -> FloatArray:
    """Geodesic angle between orientations, in radians in ``[0, pi]``.

    ``angle(p, q) = 2 * arccos(|p . q|)`` with the dot product clipped to ``[0, 1]``, so a
    value rounded above 1 never gives NaN and ``angle(q, -q) = 0``. Near 0 the
    equivalent ``2 * atan2(|p* q|_vec, |p . q|)`` is used for full precision.
    """
    p = as_unit(p, name_p)
    q = as_unit(q, name_q)
    rel = multiply(conjugate(p), q)
    vec = np.sqrt(np.einsum("...i,...i->...", rel[..., 1:], rel[..., 1:]))
    return 2.0 * np.arctan2(vec, np.abs(rel[..., 0]))


def slerp(
    q0: ArrayLike,
    q1: ArrayLike,
    alpha: ArrayLike,
    validate: bool = True,
) -> FloatArray:
    """Spherical linear interpolation along the shortest arc.

    With ``cos(theta/2) = q0 . q1`` (after flipping ``q1`` to ``-q1`` when the dot is
    negative, so the arc is the short one)::

        slerp(q0, q1, a) = sin((1 - a) theta/2) / sin(theta/2) q0 + sin(a theta/2) / sin(theta/2) q1

    Near ``q0 == q1`` (``theta/2 = h < 1e-4``) the weights use their series
    ``sin(c h) / sin(h) = c (1 + (1 - c^2) h^2 / 6)`` (``c = 1 - a`` and ``a``), so nearly
    coincident ends stay unit to rounding and coincident ends give a constant trajectory
    with no NaN. ``q0``, ``q1``
    and ``alpha`` broadcast together: ``q0``/``q1`` have shape ``(..., 4)`` and ``alpha``
    shape ``(...)``; e.g. ``q0[:, None]``, ``q1[:, None]`` and ``alpha`` of shape ``(B, T)``
    give ``(B, T, 4)``.
    """
    if validate:
        q0 = as_unit(q0, "q0")
        q1 = as_unit(q1, "q1")
        alpha = np.asarray(alpha, dtype=np.float64)
        if not np.all(np.isfinite(alpha)):
            raise ValueError("alpha contains NaN or infinite values")
    else:
        q0 = np.asarray(q0, dtype=np.float64)
        q1 = np.asarray(q1, dtype=np.float64)
        alpha = np.asarray(alpha, dtype=np.float64)
    for name, arr in (("q0", q0), ("q1", q1)):
        if arr.ndim == 0 or arr.shape[-1] != 4:
            raise ValueError(
                f"{name} must have a last axis of length 4 (w, x, y, z); got shape {arr.shape}"
            )
    batch = np.broadcast_shapes(q0.shape[:-1], q1.shape[:-1], alpha.shape)
    q0f = _flatten(q0, batch, (4,))
    q1f = _flatten(q1, batch, (4,))
    af = _flatten(alpha, batch, ())
    n = af.shape[0]
    out = np.empty((n, 4))
    m = min(n, _BLOCK)
    P, Q, D, S = (np.empty((4, m)) for _ in range(4))
    work, x, den = np.empty((5, m)), np.empty((2, m)), np.empty((2, m))
    small = np.empty(m, dtype=bool)
    small_phi = 0.5 * _SMALL_ANGLE  # half < _SMALL_ANGLE  <=>  phi = half / 2 < this
    # Same formula as the docstring, organised for speed: with d = |q0 - q1|, s = |q0 + q1|
    # (swapped when q0 . q1 < 0, i.e. when |q0 + q1| < |q0 - q1|) and phi = atan2(d, s), the
    # half angle is 2 phi, sin(2 phi) = 2 d s / (d^2 + s^2), and each weight
    # sin(c 2 phi) = 2 tan(c phi) / (1 + tan^2(c phi)) needs one tangent, no sine.
    with np.errstate(invalid="ignore", divide="ignore"):
        for start, stop in _blocks(n):
            k = stop - start
            Pk, Qk, Dk, Sk, xk, denk, smallk = (
                P[:, :k],
                Q[:, :k],
                D[:, :k],
                S[:, :k],
                x[:, :k],
                den[:, :k],
                small[:k],
            )
            A, B, sign, phi, g = work[:, :k]
            ak = af[start:stop]
            np.copyto(Pk, q0f[start:stop].T)
            np.copyto(Qk, q1f[start:stop].T)
            np.subtract(Pk, Qk, out=Dk)
            np.add(Pk, Qk, out=Sk)
            np.multiply(Dk, Dk, out=Dk)
            np.multiply(Sk, Sk, out=Sk)
            np.add.reduce(Dk, axis=0, out=A)  # |q0 - q1|^2
            np.add.reduce(Sk, axis=0, out=B)  # |q0 + q1|^2
            np.subtract(B, A, out=sign)  # 4 q0 . q1
            np.copysign(1.0, sign, out=sign)
            d2, s2, d, s = Dk[0], Sk[0], Dk[1], Sk[1]
            np.minimum(A, B, out=d2)
            np.maximum(A, B, out=s2)
            np.sqrt(d2, out=d)
            np.sqrt(s2, out=s)
            np.arctan2(d, s, out=phi)
            np.multiply(d, s, out=g)
            np.add(d2, s2, out=d2)
            np.divide(g, d2, out=g)  # sin(half) / 2
            np.subtract(1.0, ak, out=xk[0])
            np.multiply(xk[0], phi, out=xk[0])
            np.multiply(ak, phi, out=xk[1])
            np.tan(xk, out=xk)
            np.multiply(xk, xk, out=denk)
            denk += 1.0
            denk *= g
            np.divide(xk, denk, out=xk)  # w0, w1
            xk[1] *= sign
            np.less(phi, small_phi, out=smallk)
            if smallk.any():
                # sin(c h) / sin(h) = c (1 + (1 - c^2) h^2 / 6) + O(h^4), h = 2 phi
                a_small = ak[smallk]
                h2 = 4.0 * phi[smallk] ** 2
                b_small = 1.0 - a_small
                xk[0][smallk] = b_small * (1.0 + (1.0 - b_small * b_small) * h2 / 6.0)
                xk[1][smallk] = a_small * (1.0 + (1.0 - a_small * a_small) * h2 / 6.0)
                xk[1][smallk] *= sign[smallk]
            np.multiply(Pk, xk[0], out=Pk)
            np.multiply(Qk, xk[1], out=Qk)
            Pk += Qk
            _store_columns(out[start:stop], Pk)
    return out.reshape((*batch, 4))


def make_continuous(q: ArrayLike, name: str = "q", axis: int = -2) -> FloatArray:
    """Remove antipodal jumps along a trajectory (Faraway & Choe, step 2).

    Flips ``q_i`` to ``-q_i`` whenever ``q_i . q_{i-1} < 0`` (after the previous flips),
    so that consecutive samples lie on the same hemisphere. ``axis`` is the time axis
    (default: the one before the quaternion axis); leading axes are batches. The first
    sample keeps its sign; a single quaternion ``(4,)`` is returned unchanged (a copy).
    """
    arr = _as_quaternion_array(q, name)
    if arr.ndim == 1:
        return arr.copy()
    arr = np.moveaxis(arr, axis, 0)
    if arr.shape[0] < 2:
        return np.moveaxis(arr.copy(), 0, axis)
    dots = np.einsum("t...i,t...i->t...", arr[1:], arr[:-1])
    flips = np.cumsum(dots < 0.0, axis=0) % 2
    signs = np.concatenate([np.ones((1, *flips.shape[1:])), 1.0 - 2.0 * flips], axis=0)
    out = arr * signs[..., None]
    return np.moveaxis(out, 0, axis)


def to_rotation(q: ArrayLike, name: str = "q", normalize: bool = False) -> Rotation:
    """Convert unit quaternions ``(w, x, y, z)`` to a scipy ``Rotation`` of the same batch shape.

    ``(4,)`` gives a single rotation, ``(n, 4)`` ``n`` rotations and ``(..., 4)`` a
    rotation array of shape ``...`` (scipy >= 1.17 for more than one batch axis).
    ``normalize`` as in :func:`as_unit`.
    """
    arr = as_unit(q, name, normalize=normalize)
    return Rotation.from_quat(arr[..., [1, 2, 3, 0]])


def from_rotation(rotation: Rotation) -> FloatArray:
    """Quaternions ``(..., 4)`` ``(w, x, y, z)`` with ``w >= 0`` of a scipy ``Rotation``.

    The batch shape is kept (a single rotation gives ``(4,)``).
    """
    xyzw = np.asarray(rotation.as_quat(), dtype=np.float64)
    q = xyzw[..., [3, 0, 1, 2]]
    return np.asarray(q * np.where(q[..., :1] < 0.0, -1.0, 1.0), dtype=np.float64)
