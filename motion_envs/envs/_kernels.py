"""Hot-path arithmetic of the environments, written once for scalars and for batches.

Each kernel takes a *backend* ``m`` (:data:`SCALAR` for Python floats, :data:`BATCH` for
numpy arrays of shape ``(N,)``) and quaternion *components* (``w, x, y, z`` as separate
floats or arrays). The single environment calls a kernel with :data:`SCALAR` (a few
microseconds per step, no numpy call overhead), the native vector environment with
:data:`BATCH`. Both backends evaluate the same expressions in the same order with
correctly rounded ``+ - * / sqrt`` and ``sin``/``cos`` (numpy's float64 ``sin`` and ``cos``
agree with ``math``'s bit for bit; ``arctan2``/``arctan`` do not, so the arc tangent is
the half-angle :func:`half_angle`, built from ``+ - * / sqrt`` only), so a vector environment is
bit-identical to single environments (tested). :func:`orientation_step_scalar` is the
same arithmetic as :func:`orientation_step` with :data:`SCALAR`, inlined by hand for speed
(bit-identity tested on random inputs).

The formulas are those of :mod:`motion_envs.geometry.quaternion` (``expmap``,
``multiply``, ``logmap``, ``angle``), which the tests use as the oracle.

The rewards (:func:`orientation_reward`, :func:`position_reward`) are written once, in
plain arithmetic, and serve every backend: floats (single environments), ``(N,)`` arrays
(the numpy vector path) and, compiled, the numba vector path.

Backends, declared here and nowhere else:

* :data:`SCALAR`: Python floats, the single environments;
* :data:`BATCH`: numpy arrays, the vector environments' ``backend="numpy"``;
* ``"numba"`` (:data:`VECTOR_BACKENDS`): :func:`orientation_step_scalar`,
  :func:`position_step_scalar` and the rewards compiled by numba and looped over the
  sub-environments in :mod:`motion_envs.envs._fused`, the vector environments' default
  when numba is installed (the ``fast`` extra). All three evaluate the same expressions
  in the same order, so they agree bit for bit (tested).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from types import SimpleNamespace
from typing import Any

import numpy as np

__all__ = [
    "BATCH",
    "SCALAR",
    "VECTOR_BACKENDS",
    "expmap",
    "geodesic",
    "half_angle",
    "logmap",
    "multiply",
    "numba_available",
    "orientation_reward",
    "orientation_step",
    "orientation_step_scalar",
    "position_reward",
    "position_step",
    "position_step_scalar",
    "resolve_vector_backend",
]

_SMALL_ANGLE = 1e-4  # as motion_envs.geometry.quaternion._SMALL_ANGLE


SCALAR = SimpleNamespace(
    sqrt=math.sqrt,
    sin=math.sin,
    cos=math.cos,
    abs=abs,
    where=lambda c, a, b: a if c else b,
    maximum=max,
)

BATCH = SimpleNamespace(
    sqrt=np.sqrt,
    sin=np.sin,
    cos=np.cos,
    abs=np.abs,
    where=np.where,
    maximum=np.maximum,
)

Q = tuple[Any, Any, Any, Any]

# Taylor coefficients of atan(t) / t in u = t^2: (-1)^n / (2n + 1), n = 0 .. 7; after three
# half-angle reductions t <= tan(pi/32) < 0.0985, so the first omitted term is < 5e-18.
_ATAN_COEFFS = tuple((-1.0) ** n / (2 * n + 1) for n in range(8))


def half_angle(m: SimpleNamespace, s: Any, w: Any) -> Any:
    """``atan2(s, w)`` for ``s = |v| >= 0``, ``w >= 0`` of a unit quaternion ``(w, v)``.

    Built from ``+ - * / sqrt`` only (so both backends agree bit for bit):
    ``atan2(s, w) = 2 atan(t)``, ``t = s / (sqrt(s^2 + w^2) + w)`` in ``[0, 1]`` (exact for
    any norm, so slightly non-unit inputs, e.g. from a near-linear slerp, are fine); three
    half-angle reductions ``t <- t / (1 + sqrt(1 + t^2))`` (``atan t = 2 atan t'``) bring
    ``t`` below ``tan(pi/32)``, where 8 Taylor terms give full double precision:
    ``atan2(s, w) = 16 t3 (1 - u/3 + u^2/5 - ... - u^7/15)``, ``u = t3^2``.
    """
    t = s / (m.sqrt(s * s + w * w) + w)
    t = t / (1.0 + m.sqrt(1.0 + t * t))
    t = t / (1.0 + m.sqrt(1.0 + t * t))
    t = t / (1.0 + m.sqrt(1.0 + t * t))
    u = t * t
    c = _ATAN_COEFFS
    p = c[7]
    for i in range(6, -1, -1):
        p = p * u + c[i]
    return 16.0 * (t * p)


def expmap(m: SimpleNamespace, vx: Any, vy: Any, vz: Any) -> Q:
    """``(cos(t/2), sin(t/2) v / t)`` with ``t = |v|``; series below ``t = 1e-4``."""
    t2 = vx * vx + vy * vy + vz * vz
    t = m.sqrt(t2)
    small = t < _SMALL_ANGLE
    safe = m.where(small, 1.0, t)
    hs = m.where(small, 0.5 - t2 / 48.0 + t2 * t2 / 3840.0, m.sin(0.5 * safe) / safe)
    return m.cos(0.5 * t), hs * vx, hs * vy, hs * vz


def multiply(pw: Any, px: Any, py: Any, pz: Any, qw: Any, qx: Any, qy: Any, qz: Any) -> Q:
    """Hamilton product ``p * q`` (same expression order as ``quaternion.multiply``)."""
    return (
        pw * qw - px * qx - py * qy - pz * qz,
        pw * qx + px * qw + py * qz - pz * qy,
        pw * qy - px * qz + py * qw + pz * qx,
        pw * qz + px * qy - py * qx + pz * qw,
    )


def _multiply_batch(pw: Any, px: Any, py: Any, pz: Any, qw: Any, qx: Any, qy: Any, qz: Any) -> Q:
    """:func:`multiply` on arrays with fewer temporaries: same operations, same order."""
    t = px * qx
    w = pw * qw
    w -= t
    np.multiply(py, qy, out=t)
    w -= t
    np.multiply(pz, qz, out=t)
    w -= t
    x = pw * qx
    np.multiply(px, qw, out=t)
    x += t
    np.multiply(py, qz, out=t)
    x += t
    np.multiply(pz, qy, out=t)
    x -= t
    y = pw * qy
    np.multiply(px, qz, out=t)
    y -= t
    np.multiply(py, qw, out=t)
    y += t
    np.multiply(pz, qx, out=t)
    y += t
    z = pw * qz
    np.multiply(px, qy, out=t)
    z += t
    np.multiply(py, qx, out=t)
    z -= t
    np.multiply(pz, qw, out=t)
    z += t
    return w, x, y, z


def _half_angle_batch(m: SimpleNamespace, s: Any, w: Any) -> Any:
    """:func:`half_angle` on arrays with fewer temporaries: same operations, same order."""
    t = s * s
    u = w * w
    t += u
    np.sqrt(t, out=t)
    t += w
    np.divide(s, t, out=t)
    for _ in range(3):
        np.multiply(t, t, out=u)
        u += 1.0
        np.sqrt(u, out=u)
        u += 1.0
        t /= u
    np.multiply(t, t, out=u)
    c = _ATAN_COEFFS
    p = u * c[7]
    for i in range(6, -1, -1):
        p += c[i]
        if i:
            p *= u
    # p now holds c0 + u (c1 + u (...)); finish as 16 (t p)
    t *= p
    t *= 16.0
    return t


def logmap(m: SimpleNamespace, w: Any, x: Any, y: Any, z: Any) -> tuple[Any, Any, Any]:
    """Tangent vector of a unit quaternion (``q`` and ``-q`` give the same vector)."""
    sign = m.where(w < 0.0, -1.0, 1.0)
    aw = m.abs(w)
    ux, uy, uz = x * sign, y * sign, z * sign
    s = m.sqrt(ux * ux + uy * uy + uz * uz)
    theta = 2.0 * m.half_angle(m, s, aw)
    small = s < _SMALL_ANGLE
    safe = m.where(small, 1.0, s)
    scale = m.where(small, 2.0 / m.maximum(aw, 1e-300) * (1.0 - s * s / 3.0), theta / safe)
    return scale * ux, scale * uy, scale * uz


def geodesic(m: SimpleNamespace, pw: Any, px: Any, py: Any, pz: Any, q: Q) -> Any:
    """Geodesic angle ``2 atan2(|v|, |w|)`` of ``conj(p) * q`` (as ``quaternion.angle``)."""
    rw, rx, ry, rz = m.multiply(pw, -px, -py, -pz, *q)
    return 2.0 * m.half_angle(m, m.sqrt(rx * rx + ry * ry + rz * rz), m.abs(rw))


def orientation_step(
    m: SimpleNamespace,
    e: Q,
    n: Q,
    h: Q,
    rx: Any,
    ry: Any,
    rz: Any,
    ax: Any,
    ay: Any,
    az: Any,
    scale: float,
) -> tuple[Q, Any, Any]:
    """One step of the orientation environment at grid point ``k``.

    With ``d = expmap(scale * a)``: the agent's orientation ``q = n_k * d``; its residual
    error ``| logmap(expmap(rhat_k) * d) - r_k |`` (``e`` is ``expmap(rhat_k)``, the
    nominal in the residual chart, so ``conj(base_k) * q = e * d``); and the geodesic
    angle between ``q`` and the human ``h_k``. Returns ``(q, error, geodesic)``.
    """
    d = expmap(m, scale * ax, scale * ay, scale * az)
    c = m.multiply(*e, *d)
    lx, ly, lz = logmap(m, *c)
    dx, dy, dz = lx - rx, ly - ry, lz - rz
    err = m.sqrt(dx * dx + dy * dy + dz * dz)
    q = m.multiply(*n, *d)
    geo = geodesic(m, *q, h)
    return q, err, geo


def orientation_step_scalar(
    s: list[float], ax: float, ay: float, az: float, scale: float
) -> tuple[tuple[float, float, float, float], float, float]:
    """:func:`orientation_step` with :data:`SCALAR` for one step row ``s`` (15 floats:
    ``expmap(rhat_k)``, ``n_k``, ``h_k``, ``r_k``), inlined: same expressions, same order."""
    sqrt = math.sqrt
    c0, c1, c2, c3, c4, c5, c6, c7 = _ATAN_COEFFS
    # d = expmap(scale * a)
    vx, vy, vz = scale * ax, scale * ay, scale * az
    t2 = vx * vx + vy * vy + vz * vz
    t = sqrt(t2)
    if t < _SMALL_ANGLE:
        hs = 0.5 - t2 / 48.0 + t2 * t2 / 3840.0
    else:
        hs = math.sin(0.5 * t) / t
    dw, dx, dy, dz = math.cos(0.5 * t), hs * vx, hs * vy, hs * vz
    # c = e * d
    pw, px, py, pz = s[0], s[1], s[2], s[3]
    cw = pw * dw - px * dx - py * dy - pz * dz
    cx = pw * dx + px * dw + py * dz - pz * dy
    cy = pw * dy - px * dz + py * dw + pz * dx
    cz = pw * dz + px * dy - py * dx + pz * dw
    # logmap(c)
    sign = -1.0 if cw < 0.0 else 1.0
    aw = abs(cw)
    ux, uy, uz = cx * sign, cy * sign, cz * sign
    sn = sqrt(ux * ux + uy * uy + uz * uz)
    # half_angle(sn, aw)
    tt = sn / (sqrt(sn * sn + aw * aw) + aw)
    tt = tt / (1.0 + sqrt(1.0 + tt * tt))
    tt = tt / (1.0 + sqrt(1.0 + tt * tt))
    tt = tt / (1.0 + sqrt(1.0 + tt * tt))
    u = tt * tt
    p = ((((((c7 * u + c6) * u + c5) * u + c4) * u + c3) * u + c2) * u + c1) * u + c0
    theta = 2.0 * (16.0 * (tt * p))
    if sn < _SMALL_ANGLE:
        sc = 2.0 / max(aw, 1e-300) * (1.0 - sn * sn / 3.0)
    else:
        sc = theta / sn
    ex, ey, ez = sc * ux - s[12], sc * uy - s[13], sc * uz - s[14]
    err = sqrt(ex * ex + ey * ey + ez * ez)
    # q = n * d
    pw, px, py, pz = s[4], s[5], s[6], s[7]
    qw = pw * dw - px * dx - py * dy - pz * dz
    qx = pw * dx + px * dw + py * dz - pz * dy
    qy = pw * dy - px * dz + py * dw + pz * dx
    qz = pw * dz + px * dy - py * dx + pz * dw
    # geodesic: conj(q) * h
    hw, hx, hy, hz = s[8], s[9], s[10], s[11]
    mx, my, mz = -qx, -qy, -qz
    rw = qw * hw - mx * hx - my * hy - mz * hz
    rx = qw * hx + mx * hw + my * hz - mz * hy
    ry = qw * hy - mx * hz + my * hw + mz * hx
    rz = qw * hz + mx * hy - my * hx + mz * hw
    yv = sqrt(rx * rx + ry * ry + rz * rz)
    xv = abs(rw)
    tt = yv / (sqrt(yv * yv + xv * xv) + xv)
    tt = tt / (1.0 + sqrt(1.0 + tt * tt))
    tt = tt / (1.0 + sqrt(1.0 + tt * tt))
    tt = tt / (1.0 + sqrt(1.0 + tt * tt))
    u = tt * tt
    p = ((((((c7 * u + c6) * u + c5) * u + c4) * u + c3) * u + c2) * u + c1) * u + c0
    geo = 2.0 * (16.0 * (tt * p))
    return (qw, qx, qy, qz), err, geo


def position_step(
    m: SimpleNamespace, n: Sequence[Any], h: Sequence[Any], a: Sequence[Any], scale: float
) -> tuple[list[Any], Any]:
    """One step of the position environment: ``y = n + scale a`` and ``|y - h|``.

    ``n``, ``h``, ``a`` hold the ``D`` coordinates (floats, or ``(N,)`` arrays).
    """
    q = [n[i] + scale * a[i] for i in range(len(a))]
    d = q[0] - h[0]
    acc = d * d
    for i in range(1, len(q)):
        d = q[i] - h[i]
        acc = acc + d * d
    return q, m.sqrt(acc)


def position_step_scalar(row: Any, a: Any, scale: float, q: Any) -> float:
    """:func:`position_step` for one environment, written into ``q``: ``q_i = n_i + scale
    a_i`` and the distance ``|q - h|`` (same expressions, same order). ``row`` holds the
    nominal ``n`` (``D`` values) then the human ``h`` (``D``); ``a`` and ``q`` hold ``D``
    (lists or arrays; numba compiles it unchanged)."""
    D = len(a)
    acc = 0.0
    for i in range(D):
        v = row[i] + scale * a[i]
        q[i] = v
        d = v - row[D + i]
        acc = d * d if i == 0 else acc + d * d
    return math.sqrt(acc)


def orientation_reward(
    err: Any, geo: Any, ax: Any, ay: Any, az: Any, w_res: float, w_geo: float, w_act: float
) -> tuple[Any, Any, Any, Any]:
    """The orientation reward terms and their sum, for floats or ``(N,)`` arrays:
    ``r_res = -w_res err``, ``r_geo = -w_geo geo``, ``r_act = -w_act |a|^2`` and
    ``r_res + r_geo + r_act`` (left to right)."""
    r_res = -w_res * err
    r_geo = -w_geo * geo
    r_act = -w_act * (ax * ax + ay * ay + az * az)
    return r_res, r_geo, r_act, r_res + r_geo + r_act


def position_reward(err: Any, sq: Any, w_dist: float, w_act: float) -> tuple[Any, Any, Any]:
    """The position reward terms and their sum, for floats or ``(N,)`` arrays:
    ``r_dist = -w_dist err``, ``r_act = -w_act sq`` (``sq = |a|^2``, summed over the
    components left to right from 0) and ``r_dist + r_act``."""
    r_dist = -w_dist * err
    r_act = -w_act * sq
    return r_dist, r_act, r_dist + r_act


#: Backends of the native vector environments (``backend=`` argument; ``"auto"`` picks
#: the first available).
VECTOR_BACKENDS: tuple[str, ...] = ("numba", "numpy")


def numba_available() -> bool:
    """Whether numba can be imported (the optional ``fast`` extra)."""
    try:
        import numba  # noqa: F401
    except ImportError:
        return False
    return True


def resolve_vector_backend(backend: str) -> str:
    """``"auto"`` -> ``"numba"`` if installed else ``"numpy"``; a named backend is checked."""
    if backend == "auto":
        return "numba" if numba_available() else "numpy"
    if backend not in VECTOR_BACKENDS:
        choices = ["auto", *VECTOR_BACKENDS]
        raise ValueError(f"backend must be one of {choices}; got {backend!r}")
    if backend == "numba" and not numba_available():
        raise ValueError(
            "backend='numba' needs numba: pip install 'motion-envs[fast]' (or use backend='numpy')"
        )
    return backend


SCALAR.multiply = multiply
SCALAR.half_angle = half_angle
BATCH.multiply = _multiply_batch
BATCH.half_angle = _half_angle_batch
