r"""The juggling worlds' kernels compiled by numba: the one control period for ``N`` worlds
(the ids' steps beyond it: :mod:`~motion_envs.envs.juggling._compiled_v1`,
:mod:`~motion_envs.envs.juggling._compiled_cascade`).

:func:`world_periods` is :func:`motion_envs.envs.juggling._period.world_periods` compiled:
the same function body, its global names bound to the compiled equivalents below
(:func:`py_hypot`, the servo, and :data:`mj_step_c`, MuJoCo's own ``mj_step``: the C
function of the ``libmujoco`` the ``mujoco`` package loads, declared to numba as an
external function). The physics is MuJoCo's, call for call, so the compiled worlds are
bit-identical to the plain-Python path (tested).

Every expression is written as the scalar code writes it, in the same order (IEEE
``+ - * / sqrt`` are correctly rounded in both), and ``math.hypot`` is
:func:`py_hypot`: CPython's ``math.hypot`` (since 3.10 an exactly rounded
``sqrt(x^2 + y^2)`` from an error-free square and compensated sum; the C library's
``hypot``, which numba's ``math.hypot`` calls, differs from it in about 0.3 % of
arguments).

The likeness search lives in :mod:`~motion_envs.envs.juggling._compiled_likeness` (its
names re-exported here). Importing this module imports numba (the ``fast`` extra).
"""

from __future__ import annotations

import math
import types as pytypes
from collections.abc import Callable, Sequence
from typing import Any

import llvmlite.binding as llvm
import numpy as np
from numba import njit, types

from motion_envs.envs.juggling import _period
from motion_envs.envs.juggling._compiled_likeness import likeness_tree, nearest_point, nearest_rows

__all__ = [
    "bound",
    "entry_point",
    "hypot_rows",
    "likeness_tree",
    "mj_step_c",
    "nearest_point",
    "nearest_rows",
    "py_hypot",
    "servo_acceleration",
    "servo_plan",
    "world_links",
    "world_periods",
]

_DBL_MIN = 2.2250738585072014e-308
_SPLIT = 134217729.0  # 2^27 + 1, Veltkamp's splitting constant for doubles


# The symbol is resolved in the library the bindings loaded (loading it again returns the
# same handle), so compiled code calls the very mj_step that mujoco.mj_step calls.
llvm.load_library_permanently(_period.libmujoco_path())
#: ``void mj_step(const mjModel*, mjData*)`` for compiled code, called with the two
#: addresses ``MjModel._address`` and ``MjData._address`` (pointer-sized integers).
mj_step_c = types.ExternalFunction("mj_step", types.void(types.uint64, types.uint64))


@njit(cache=True)
def _two_product(a: float, b: float) -> tuple[float, float]:
    """``a b = hi + lo`` exactly (Dekker's product with Veltkamp's split)."""
    hi = a * b
    c = _SPLIT * a
    ah = c - (c - a)
    al = a - ah
    c = _SPLIT * b
    bh = c - (c - b)
    bl = b - bh
    lo = ((ah * bh - hi) + ah * bl + al * bh) + al * bl
    return hi, lo


@njit(cache=True)
def _norm(x: float, y: float, largest: float) -> float:
    """CPython's ``vector_norm`` of the two magnitudes ``x, y <= largest`` (finite,
    ``largest`` > 0 and normal)."""
    _, e = math.frexp(largest)
    scale = math.ldexp(1.0, -e)
    csum, frac1, frac2 = 1.0, 0.0, 0.0
    for v in (x, y):
        v = v * scale  # lossless
        hi, lo = _two_product(v, v)  # lossless square
        s = csum + hi  # lossless sum (|csum| >= |hi|)
        frac2 += (csum - s) + hi
        csum = s
        frac1 += lo
    h = math.sqrt(csum - 1.0 + (frac1 + frac2))
    hi, lo = _two_product(-h, h)
    s = csum + hi
    frac2 += (csum - s) + hi
    csum = s
    frac1 += lo
    v = csum - 1.0 + (frac1 + frac2)
    h += v / (2.0 * h)  # differential correction
    return h / scale


@njit(cache=True)
def py_hypot(x: float, y: float) -> float:
    """``math.hypot(x, y)`` as CPython (>= 3.10) computes it, bit for bit (tested on
    random and special arguments)."""
    x, y = abs(x), abs(y)
    if math.isinf(x) or math.isinf(y):
        return math.inf
    if math.isnan(x) or math.isnan(y):
        return math.nan
    largest = x if x > y else y
    if largest == 0.0:
        return largest
    _, e = math.frexp(largest)
    if e < -1023:  # deep subnormal: scale to normals first, as CPython does
        return _DBL_MIN * _norm(x / _DBL_MIN, y / _DBL_MIN, largest / _DBL_MIN)
    return _norm(x, y, largest)


@njit(cache=True)
def hypot_rows(x: Any, y: Any) -> Any:
    """:func:`py_hypot` of each pair ``x[i], y[i]`` (1-d arrays)."""
    out = np.empty(x.shape[0])
    for i in range(x.shape[0]):
        out[i] = py_hypot(x[i], y[i])
    return out


def bound(func: Any, **names: Any) -> Any:
    """``func``'s body with some of its global names bound to other objects (the compiled
    equivalents), for numba to compile: one source, two paths."""
    scope = dict(func.__globals__)
    scope.update(names)
    out = pytypes.FunctionType(func.__code__, scope, func.__name__, func.__defaults__)
    out.__qualname__, out.__doc__, out.__module__ = func.__qualname__, func.__doc__, __name__
    return out


#: :func:`~motion_envs.envs.juggling._period.servo_plan` compiled.
servo_plan = njit(cache=True)(bound(_period.servo_plan, py_hypot=py_hypot))
#: :func:`~motion_envs.envs.juggling._period.servo_acceleration` compiled.
servo_acceleration = njit(cache=True)(bound(_period.servo_acceleration, py_hypot=py_hypot))
#: :func:`~motion_envs.envs.juggling._period.world_periods` compiled (releases the GIL).
world_periods = njit(cache=True, nogil=True)(
    bound(
        _period.world_periods,
        py_hypot=py_hypot,
        mj_step_c=mj_step_c,
        servo_plan=servo_plan,
        servo_acceleration=servo_acceleration,
    )
)


def world_links(worlds: Sequence[Any]) -> tuple[Any, ...]:
    """What :func:`world_periods` takes as ``worlds`` for these worlds (each a
    :class:`~motion_envs.envs.juggling._world.HandsWorld`): each one's ``MjModel`` and
    ``MjData`` address, then views of its qpos, qvel, ctrl, sensordata and the model's
    geom_contype and geom_conaffinity (numba typed lists)."""
    from numba.typed import List

    return (
        np.array([w.model._address for w in worlds], dtype=np.uint64),
        np.array([w.data._address for w in worlds], dtype=np.uint64),
        List([w.data.qpos for w in worlds]),
        List([w.data.qvel for w in worlds]),
        List([w.data.ctrl for w in worlds]),
        List([w.data.sensordata for w in worlds]),
        List([w.model.geom_contype for w in worlds]),
        List([w.model.geom_conaffinity for w in worlds]),
    )


def entry_point(kernel: Any, *args: Any, probe: bool = True) -> Callable[..., Any]:
    """The compiled function numba's dispatcher ``kernel`` runs for ``args``, to be
    called directly: the dispatcher types its arguments in Python on every call (~40 µs
    for a tuple of typed lists, holding the GIL), while the arguments' types of one
    caller never change. ``probe``: compile (or load) the version for these types by a
    call with no world stepped (``args[0]`` a 1-d int64 array of worlds, called with
    ``args[0][:0]``); else by calling ``kernel(*args)`` once (a pure function)."""
    if probe:
        kernel(args[0][:0], *args[1:])
    else:
        kernel(*args)
    try:
        signature = tuple(kernel.typeof_pyval(a) for a in args)
        return kernel.overloads[signature].entry_point  # type: ignore[no-any-return]
    except (AttributeError, KeyError):  # a numba without them: the dispatcher
        return kernel  # type: ignore[no-any-return]
