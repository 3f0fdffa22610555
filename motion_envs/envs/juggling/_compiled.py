r"""The juggling worlds' kernels compiled by numba: the one control period for ``N`` worlds,
and the rest of the juggling ids' batched steps.

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
    "cascade_advance",
    "cascade_events",
    "cascade_measure",
    "cascade_observations",
    "cascade_record",
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


@njit(cache=True)
def _holds(holder: Any, i: int, h: int) -> bool:
    """Whether hand ``h`` of world ``i`` holds a ball (``holder (N, B)``)."""
    for b in range(holder.shape[1]):
        if holder[i, b] == h:
            return True
    return False


@njit(cache=True)
def cascade_measure(envs: Any, q: Any, v: Any, holder: Any, ring: Any, slot: int) -> Any:
    """The cascade's sensors (:meth:`CascadeSensor.measure`) for ``envs`` before their
    noise: the true balls of ``q, v (N, 4 + 2 B)`` go into the delay line ``ring (S, N,
    B, 5)`` at ``slot``; returns ``rows (m, B, 4)`` (the true state of a held ball, the
    delayed one of a flying ball) and ``noisy (m, B)`` (flying now and then: the noise
    applies)."""
    m, size, nb = envs.shape[0], ring.shape[0], holder.shape[1]
    rows = np.empty((m, nb, 4))
    noisy = np.zeros((m, nb), dtype=np.bool_)
    old = (slot + 1) % size
    for j in range(m):
        i = envs[j]
        for b in range(nb):
            held = holder[i, b] >= 0
            x, z = q[i, 4 + 2 * b], q[i, 5 + 2 * b]
            vx, vz = v[i, 4 + 2 * b], v[i, 5 + 2 * b]
            ring[slot, i, b, 0], ring[slot, i, b, 1] = x, z
            ring[slot, i, b, 2], ring[slot, i, b, 3] = vx, vz
            ring[slot, i, b, 4] = 1.0 if held else 0.0
            if held:
                rows[j, b, 0], rows[j, b, 1], rows[j, b, 2], rows[j, b, 3] = x, z, vx, vz
            else:
                for c in range(4):
                    rows[j, b, c] = ring[old, i, b, c]
                noisy[j, b] = ring[old, i, b, 4] == 0.0
    return rows, noisy


@njit(cache=True)
def cascade_observations(
    envs: Any,
    q: Any,
    v: Any,
    holder: Any,
    history: Any,
    phase: Any,
    duration: Any,
    plan: Any,
    dt: float,
    fast: bool,
    shown: Any,
) -> Any:
    """``CascadeEnv._observation``'s rows for ``envs`` (float64, before the float32 cast
    and the bounds): per hand its true state, whether it holds a ball, its phase one-hot,
    the time in the phase, the plan's duration, the next target and the plan's end
    (world frame); per ball its holder; the measurement ``history (N, B, 16)``.

    ``plan = (k, grid, glen, end)``: the hands' plans in their own frames, read when
    ``fast``; else ``shown = (phase_time, next, end)`` as the controller reported them."""
    k, grid, glen, end = plan
    phase_time, nxt, end_shown = shown
    m, nb = envs.shape[0], holder.shape[1]
    n_hist = history.shape[2]
    rows = np.zeros((m, 2 * 15 + 2 * nb + nb * n_hist))
    for j in range(m):
        i = envs[j]
        for h in range(2):
            o = 15 * h
            rows[j, o], rows[j, o + 1] = q[i, 2 * h], q[i, 2 * h + 1]
            rows[j, o + 2], rows[j, o + 3] = v[i, 2 * h], v[i, 2 * h + 1]
            rows[j, o + 4] = 1.0 if _holds(holder, i, h) else 0.0
            rows[j, o + 5 + phase[i, h]] = 1.0
            rows[j, o + 10] = duration[i, h]
            if fast:
                rows[j, o + 9] = k[i, h] * dt
                r = min(k[i, h] + 1, glen[i, h] - 1)
                x, ex = grid[i, h, r, 0], end[i, h, 0]
                rows[j, o + 11] = -x if h == 1 else x
                rows[j, o + 12] = grid[i, h, r, 1]
                rows[j, o + 13] = -ex if h == 1 else ex
                rows[j, o + 14] = end[i, h, 1]
            else:
                rows[j, o + 9] = phase_time[i, h]
                rows[j, o + 11], rows[j, o + 12] = nxt[i, h, 0], nxt[i, h, 1]
                rows[j, o + 13], rows[j, o + 14] = end_shown[i, h, 0], end_shown[i, h, 1]
        for b in range(nb):
            rows[j, 30 + 2 * b] = 1.0 if holder[i, b] == 0 else 0.0
            rows[j, 31 + 2 * b] = 1.0 if holder[i, b] == 1 else 0.0
        for b in range(nb):
            for c in range(n_hist):
                rows[j, 30 + 2 * nb + n_hist * b + c] = history[i, b, c]
    return rows


@njit(cache=True)
def cascade_events(
    envs: Any,
    plan: Any,
    world: Any,
    measured: Any,
    constants: Any,
    phases: Any,
    correction: bool,
    ahead: bool,
) -> Any:
    """Which of ``envs`` need their :class:`CascadeController` in Python this step, and
    which hands' eq. 10 correction is due: the tests of ``CascadeHand.command`` and
    ``JugglingController.command``/``correct`` on the measured state, with their
    arithmetic (the hand's view: its oldest queued ball, predicted forward by the
    latency-aware controller, else the hand itself; own frame).

    ``plan = (phase, k, end_k, t_start, duration, end, incoming, catch_ball)`` per
    ``(N, 2)`` hand (``end`` own frame); ``world = (holder, caught, released, q, v)``
    (the last step's); ``measured = (time, ball, ball_vel)``; ``constants = (dt,
    gravity, reaim, latency, tolerance)`` (``reaim``: ``REAIM_AFTER`` beats, s);
    ``phases = (toss, go_down, catch)`` indices. Returns ``python (m,)``, ``due (m,
    2)`` and the view's ball ``(m, 2, 4)`` where due."""
    phase, pk, end_k, t_start, duration, end, incoming, catch_ball = plan
    holder, caught, released, q, v = world
    m_time, m_ball, m_ball_vel = measured
    dt, g, reaim, latency, tolerance = (
        constants[0],
        constants[1],
        constants[2],
        constants[3],
        constants[4],
    )
    toss, go_down, catch = phases[0], phases[1], phases[2]
    m = envs.shape[0]
    python = np.zeros(m, dtype=np.bool_)
    due = np.zeros((m, 2), dtype=np.bool_)
    ball = np.zeros((m, 2, 4))
    for j in range(m):
        i = envs[j]
        event = caught[i, 0] >= 0 or caught[i, 1] >= 0
        for h in range(2):
            held = _holds(holder, i, h)
            ph, k, inc = phase[i, h], pk[i, h], incoming[i, h]
            was_caught, was_released = caught[i, h] >= 0, released[i, h] >= 0
            if (
                ((ph == go_down or ph == catch) and held)
                or (
                    ph == catch
                    and inc >= 0
                    and not held
                    and not was_caught
                    and (inc != catch_ball[i, h] or k * dt > duration[i, h] + reaim)
                )
                or (ph == toss and was_released)
                or (ph == catch and was_caught)
                or (end_k[i, h] >= 0 and k >= end_k[i, h])
            ):
                event = True
        python[j] = event
        if event or not correction:
            continue
        for h in range(2):
            if phase[i, h] != catch or _holds(holder, i, h):
                continue
            inc = incoming[i, h]
            if inc >= 0:
                bx, bz = m_ball[i, inc, 0], m_ball[i, inc, 1]
                vx, vz = m_ball_vel[i, inc, 0], m_ball_vel[i, inc, 1]
                if ahead and holder[i, inc] < 0:  # predict_forward(p, v, latency)
                    s = latency - 0.0
                    bx, bz = bx + vx * s, bz + vz * s - 0.5 * g * s * s
                    vz = vz - g * s
            else:
                bx, bz = q[i, 2 * h], q[i, 2 * h + 1]
                vx, vz = v[i, 2 * h], v[i, 2 * h + 1]
            if h == 1:  # the left hand's own frame
                bx, vx = -bx, -vx
            s = t_start[i, h] + duration[i, h] - m_time[i]
            if s <= dt:
                continue
            px = bx + vx * (s - 0.0)
            pz = bz + vz * (s - 0.0) - 0.5 * g * (s - 0.0) * (s - 0.0)
            if py_hypot(px - end[i, h, 0], pz - end[i, h, 1]) > tolerance:
                due[j, h] = True
                ball[j, h, 0], ball[j, h, 1], ball[j, h, 2], ball[j, h, 3] = bx, bz, vx, vz
    return python, due, ball


@njit(cache=True)
def cascade_advance(
    rows: Any, pk: Any, grid: Any, glen: Any, last: Any, phase: Any, constants: Any
) -> Any:
    """``JugglingController.command`` without events for both hands of ``rows``: the
    next grid point (``k + 1``), the last two commands, the release armed in the toss
    after ``release_after``; ``constants = (dt, release_after, toss)``. Returns the
    targets ``(r, 2, 2)`` (world frame) and ``armed (r, 2)``."""
    dt, release_after, toss = constants[0], constants[1], int(constants[2])
    r = rows.shape[0]
    targets = np.empty((r, 2, 2))
    armed = np.empty((r, 2), dtype=np.bool_)
    for j in range(r):
        i = rows[j]
        for h in range(2):
            k = pk[i, h] + 1
            pk[i, h] = k
            g = min(k, glen[i, h] - 1)
            tx, tz = grid[i, h, g, 0], grid[i, h, g, 1]
            last[i, h, 0, 0], last[i, h, 0, 1] = last[i, h, 1, 0], last[i, h, 1, 1]
            last[i, h, 1, 0], last[i, h, 1, 1] = tx, tz
            targets[j, h, 0] = -tx if h == 1 else tx
            targets[j, h, 1] = tz
            armed[j, h] = phase[i, h] == toss and k * dt >= release_after
    return targets, armed


@njit(cache=True)
def cascade_record(
    envs: Any, rows: Any, world: Any, measured: Any, counts: Any, constants: Any
) -> Any:
    """The bookkeeping of ``CascadeEnv.step`` after the world and the sensor for
    ``envs``: the measured balls ``rows (m, B, 4)`` become what the controller sees next
    (``measured = (time, ball, ball_vel, history)``, the history shifted by one
    measurement, newest first), the step's catches and releases are counted
    (``counts (N, 2)``: catches, tosses) from ``world = (k, caught, released,
    dropped)``; ``constants = (dt, max_catches, time_limit)``. Returns ``time``,
    ``caught`` (catches this step), ``dropped``, ``terminated`` and ``truncated``
    ``(m,)``."""
    k, caught, released, dropped = world
    m_time, m_ball, m_ball_vel, history = measured
    dt, max_catches, time_limit = constants[0], constants[1], constants[2]
    m = envs.shape[0]
    n_hist = history.shape[2]
    time = np.empty(m)
    caught_n = np.zeros(m, dtype=np.int64)
    any_dropped = np.zeros(m, dtype=np.bool_)
    terminated = np.zeros(m, dtype=np.bool_)
    truncated = np.zeros(m, dtype=np.bool_)
    for j in range(m):
        i = envs[j]
        t = k[i] * dt
        time[j] = t
        m_time[i] = t
        for b in range(rows.shape[1]):
            m_ball[i, b, 0], m_ball[i, b, 1] = rows[j, b, 0], rows[j, b, 1]
            m_ball_vel[i, b, 0], m_ball_vel[i, b, 1] = rows[j, b, 2], rows[j, b, 3]
            for c in range(n_hist - 1, 3, -1):
                history[i, b, c] = history[i, b, c - 4]
            for c in range(4):
                history[i, b, c] = rows[j, b, c]
            if dropped[i, b]:
                any_dropped[j] = True
        for h in range(2):
            if caught[i, h] >= 0:
                caught_n[j] += 1
            if released[i, h] >= 0:
                counts[i, 1] += 1
        counts[i, 0] += caught_n[j]
        terminated[j] = any_dropped[j]
        truncated[j] = not any_dropped[j] and (counts[i, 0] >= max_catches or t >= time_limit)
    return time, caught_n, any_dropped, terminated, truncated
