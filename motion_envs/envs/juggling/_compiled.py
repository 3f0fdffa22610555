r"""The juggling worlds' control period for many episodes at once, compiled by numba.

The native vector environments (:mod:`motion_envs.envs.juggling._vector`) step ``N``
MuJoCo worlds, each its own ``MjModel``/``MjData`` as in ``N`` single environments. Per
control period a single world runs Python around five ``mj_step`` calls: the servo
(:func:`~motion_envs.envs.juggling.servo_plan`,
:func:`~motion_envs.envs.juggling.servo_acceleration`), the physics and the grasp rule
(:class:`~motion_envs.envs.juggling.JugglingV1World`). Here the same arithmetic runs
compiled, in one loop over the worlds, and calls MuJoCo's own ``mj_step`` from it (the C
function of the ``libmujoco`` the ``mujoco`` package loads, declared to numba as an
external function): the
physics is MuJoCo's, call for call, so the worlds are bit-identical to the single
environments' (tested). The contacts the grasp rule asks about come from the scene's
``contact`` sensors (``ball_palm``, ``ball_floor``: MuJoCo's count of those contacts,
computed in the same ``mj_step``).

Every expression is written as the scalar code writes it, in the same order (IEEE
``+ - * / sqrt`` are correctly rounded in both), and ``math.hypot`` is
:func:`py_hypot`: CPython's ``math.hypot`` (since 3.10 an exactly rounded
``sqrt(x^2 + y^2)`` from an error-free square and compensated sum; the C library's
``hypot``, which numba's ``math.hypot`` calls, differs from it in about 0.3 % of
arguments).

Importing this module imports numba (the ``fast`` extra).
"""

from __future__ import annotations

import math
from importlib import resources
from pathlib import Path
from typing import Any

import llvmlite.binding as llvm
import mujoco
import numpy as np
from numba import njit, types

from motion_envs.envs.juggling._v1_scene import (
    CAPTURE_SPEED,
    HAND_ACCEL_LIMIT,
    HAND_MASS,
    HAND_SPEED_LIMIT,
    SERVO_OMEGA,
    SUBSTEPS,
)

__all__ = [
    "hypot_rows",
    "mj_step_c",
    "nearest_rows",
    "py_hypot",
    "v1_finish",
    "v1_periods",
]

_DBL_MIN = 2.2250738585072014e-308
_SPLIT = 134217729.0  # 2^27 + 1, Veltkamp's splitting constant for doubles
_KP, _KD = SERVO_OMEGA**2, 2.0 * SERVO_OMEGA
_AMAX2 = HAND_ACCEL_LIMIT**2


def _libmujoco_path() -> str:
    """The ``libmujoco`` shared library of the installed ``mujoco`` package (the one its
    Python bindings use)."""
    package = Path(str(resources.files(mujoco)))
    found = sorted(package.glob("libmujoco.so*")) + sorted(package.glob("libmujoco*.dylib"))
    found += sorted(package.glob("mujoco*.dll"))
    if not found:
        raise ImportError(f"no libmujoco shared library in {package}")
    return str(found[0])


# The symbol is resolved in the library the bindings loaded (loading it again returns the
# same handle), so compiled code calls the very mj_step that mujoco.mj_step calls.
llvm.load_library_permanently(_libmujoco_path())
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


def _v1_periods(
    envs: Any,
    model_addr: Any,
    data_addr: Any,
    qpos: Any,
    qvel: Any,
    ctrl: Any,
    sensors: Any,
    contype: Any,
    conaffinity: Any,
    ball_geom: int,
    target: Any,
    armed: Any,
    ref: Any,
    vref: Any,
    z_before: Any,
    flags: Any,
    k: Any,
    constants: Any,
    hand: Any,
    hand_vel: Any,
    ball: Any,
    ball_vel: Any,
    events: Any,
) -> None:
    """One control period of Juggling-v1's world for each world ``i`` in ``envs``: what
    :meth:`~motion_envs.envs.juggling.JugglingV1World.advance` does, up to the release's
    noise (drawn in Python: ``events[i, 1]`` says the release fires).

    ``qpos, qvel, ctrl, sensors, contype, conaffinity``: per world, the ``MjData``'s and
    ``MjModel``'s arrays (numba typed lists of views); ``target (N, 2)`` the commanded
    hand targets (the residual added); ``armed (N,)``; the world's state ``ref, vref (N,
    2)``, ``z_before (N,)``, ``flags (N, 3)`` (held, left the palm, dropped) and ``k (N,)``
    (control periods since the reset), updated in place; ``constants`` = ``(dt, h,
    ball_radius, floor_z, palm_top, toss_threshold)``. Out: the true ``hand``,
    ``hand_vel``, ``ball``, ``ball_vel`` and ``events[i] = (caught, release fires)``.
    """
    dt, h, radius, floor_z, palm_top, threshold = (
        constants[0],
        constants[1],
        constants[2],
        constants[3],
        constants[4],
        constants[5],
    )
    step_max = HAND_SPEED_LIMIT * dt
    for i in envs:
        # servo_plan
        sx, sz = ref[i, 0], ref[i, 1]
        dx, dz = target[i, 0] - sx, target[i, 1] - sz
        dist = py_hypot(dx, dz)
        if dist > step_max:
            dx, dz = dx * step_max / dist, dz * step_max / dist
        vrx, vrz = dx / dt, dz / dt
        arx, arz = (vrx - vref[i, 0]) / dt, (vrz - vref[i, 1]) / dt
        ref[i, 0], ref[i, 1] = sx + dx, sz + dz
        vref[i, 0], vref[i, 1] = vrx, vrz
        qp, qv, u, sens = qpos[i], qvel[i], ctrl[i], sensors[i]
        hx, hz, bx, bz = qp[0], qp[1], qp[2], qp[3]
        vx, vz, ux, uz = qv[0], qv[1], qv[2], qv[3]
        z_prev, z_prev2 = hz, z_before[i]
        held, left, dropped = flags[i, 0], flags[i, 1], flags[i, 2]
        caught = False
        for j in range(1, SUBSTEPS + 1):
            f = j / SUBSTEPS
            # servo_acceleration
            ax = arx + _KP * (sx + f * dx - hx) + _KD * (vrx - vx)
            az = arz + _KP * (sz + f * dz - hz) + _KD * (vrz - vz)
            n2 = ax * ax + az * az
            if n2 > _AMAX2:
                s = math.sqrt(_AMAX2 / n2)
                ax, az = ax * s, az * s
            nvx, nvz = vx + ax * h, vz + az * h
            sp = py_hypot(nvx, nvz)
            if sp > HAND_SPEED_LIMIT:
                nvx, nvz = nvx * HAND_SPEED_LIMIT / sp, nvz * HAND_SPEED_LIMIT / sp
                ax, az = (nvx - vx) / h, (nvz - vz) / h
            u[0] = HAND_MASS * ax
            u[1] = HAND_MASS * az
            mj_step_c(model_addr[i], data_addr[i])
            if held:
                hx, hz = qp[0], qp[1]
                vx, vz = qv[0], qv[1]
                continue
            hx, hz, bx, bz = qp[0], qp[1], qp[2], qp[3]
            vx, vz, ux, uz = qv[0], qv[1], qv[2], qv[3]
            if not left and py_hypot(bx - hx, bz - hz) > 2 * radius:
                left = True
            if not dropped and (bz - radius <= floor_z or sens[1] > 0.0):
                dropped = True
            if (
                not dropped
                and left
                and bz >= hz + palm_top
                and uz < 0.0
                and py_hypot(ux - vx, uz - vz) < CAPTURE_SPEED
                and sens[0] > 0.0
            ):
                held = caught = True
                contype[i][ball_geom] = 0
                conaffinity[i][ball_geom] = 0
                qp[2] = hx
                qp[3] = hz
                qv[2] = vx
                qv[3] = vz
        if held:
            bx, bz, ux, uz = hx, hz, vx, vz
            qp[2] = hx
            qp[3] = hz
            qv[2] = vx
            qv[3] = vz
        flags[i, 0], flags[i, 1], flags[i, 2] = held, left, dropped
        k[i] += 1
        z_before[i] = z_prev
        fires = False
        if held and not caught and armed[i]:
            a_z = (hz - 2.0 * z_prev + z_prev2) / (dt * dt)
            fires = a_z < -threshold
        hand[i, 0], hand[i, 1] = hx, hz
        hand_vel[i, 0], hand_vel[i, 1] = vx, vz
        ball[i, 0], ball[i, 1] = bx, bz
        ball_vel[i, 0], ball_vel[i, 1] = ux, uz
        events[i, 0], events[i, 1] = caught, fires


v1_periods = njit(cache=True)(_v1_periods)


@njit(cache=True)
def nearest_rows(columns: Any, key: Any, axis: int, queries: Any, last: Any, out: Any) -> None:
    """Nearest-sample distances of ``queries (n, 4)`` among the samples ``columns (4, M)``
    sorted along coordinate ``axis`` (``key = columns[axis]``): what
    :class:`~motion_envs.models.juggling.HumanLikeness` computes (its ``_SortedSamples``,
    the k-d tree's number), for many queries. ``last (n,)`` holds each query's previous
    nearest sample (a start only: any start gives the same distance) and is updated;
    ``out (n,)`` receives the distances (NaN for a NaN query)."""
    for r in range(queries.shape[0]):
        q0, q1, q2, q3 = queries[r, 0], queries[r, 1], queries[r, 2], queries[r, 3]
        j = last[r]
        d0, d1 = columns[0, j] - q0, columns[1, j] - q1
        d2, d3 = columns[2, j] - q2, columns[3, j] - q3
        bound = math.sqrt(((d0 * d0 + d1 * d1) + d2 * d2) + d3 * d3)
        if not math.isfinite(bound):
            out[r] = math.nan
            continue
        width = bound * (1.0 + 1e-9) + 1e-12
        qc = queries[r, axis]
        lo = np.searchsorted(key, qc - width, side="left")
        hi = np.searchsorted(key, qc + width, side="right")
        best, at = math.inf, lo
        for m in range(lo, hi):
            e0, e1 = columns[0, m] - q0, columns[1, m] - q1
            e2, e3 = columns[2, m] - q2, columns[3, m] - q3
            s = ((e0 * e0 + e1 * e1) + e2 * e2) + e3 * e3
            if s < best:
                best, at = s, m
        last[r] = at
        out[r] = math.sqrt(best)


@njit(cache=True)
def v1_finish(
    envs: Any,
    hand: Any,
    hand_vel: Any,
    ball: Any,
    ball_vel: Any,
    flags: Any,
    events: Any,
    k: Any,
    scalars: Any,
    ring: Any,
    slot: int,
    noise: Any,
    noise_at: Any,
    noise_std: Any,
    counts: Any,
    history: Any,
    phases: Any,
    plan_k: Any,
    duration: Any,
    plan_end: Any,
    grid: Any,
    glen: Any,
    nominal: Any,
    fast: bool,
    samples: Any,
    bounds: Any,
    nearest: Any,
    actions: Any,
    measured: Any,
    m_flags: Any,
    obs: Any,
    out: Any,
    ends: Any,
) -> None:
    """The rest of Juggling-v1's step for each world ``i = envs[j]`` after its period
    (:meth:`JugglingV1Env._advance` after the world, then ``step``'s likeness, reward and
    observation), written as those write it:

    * the sensor (:meth:`~motion_envs.models.juggling.BallSensor.measure_values`): the
      delay line ``ring (R, N, 5)`` takes the true ball ``(x, z, vx, vz, held)`` at
      ``slot``; the measurement is the true state while held, else the oldest entry,
      plus the next row of ``noise[i]`` (drawn ahead from the sensor's generator; every
      world has one left) times ``noise_std`` when that entry was flying and
      ``noise_std`` is not zero;
    * the measured state for the controller ``measured[i] = (time, x, z, vx, vz)``,
      ``m_flags[i] = (held, released, caught)``; the ``history`` shifted; the catches
      and tosses ``counts``; the episode's end;
    * the human-likeness (:func:`nearest_rows` on the phase's sorted samples
      ``samples[phase] = (columns, axis)``, start ``nearest[i, phase]``), the reward
      terms and the reward;
    * the observation, clipped to ``bounds = (low, high)``.

    ``scalars = (dt, likeness_tau, w_catch, w_drop, w_likeness, w_action, max_catches,
    time_limit, noisy)``; ``phases, plan_k, duration, plan_end`` the plans after the
    commands (phase index, step in the phase, duration, end point); ``nominal[i]`` the
    next nominal target when not ``fast`` (else it is read from ``grid``). Out per row
    ``j``: ``obs[j]``, ``out[j] = (reward, r_catch, r_drop, r_likeness, r_action,
    likeness, time)``, ``ends[j] = (terminated, truncated)``.
    """
    dt, tau = scalars[0], scalars[1]
    w_catch, w_drop, w_like, w_act = scalars[2], scalars[3], scalars[4], scalars[5]
    max_catches, time_limit, noisy = scalars[6], scalars[7], scalars[8] > 0.0
    size = ring.shape[0]
    oldest_slot = (slot + 1) % size
    n_hist = history.shape[1]
    q = np.empty((1, 4))
    last = np.empty(1, dtype=np.int64)
    found = np.empty(1)
    low, high = bounds[0], bounds[1]
    for j in range(envs.shape[0]):
        i = envs[j]
        held, dropped = flags[i, 0], flags[i, 2]
        caught, released = events[i, 0], events[i, 1]
        time = k[i] * dt
        bx, bz, ux, uz = ball[i, 0], ball[i, 1], ball_vel[i, 0], ball_vel[i, 1]
        # the sensor
        ring[slot, i, 0], ring[slot, i, 1] = bx, bz
        ring[slot, i, 2], ring[slot, i, 3] = ux, uz
        ring[slot, i, 4] = 1.0 if held else 0.0
        if held:
            px, pz, vx, vz = bx, bz, ux, uz
        else:
            px, pz = ring[oldest_slot, i, 0], ring[oldest_slot, i, 1]
            vx, vz = ring[oldest_slot, i, 2], ring[oldest_slot, i, 3]
            if ring[oldest_slot, i, 4] == 0.0 and noisy:
                r = noise_at[i]
                px += noise_std[0] * noise[i, r, 0]
                pz += noise_std[1] * noise[i, r, 1]
                vx += noise_std[2] * noise[i, r, 2]
                vz += noise_std[3] * noise[i, r, 3]
                noise_at[i] = r + 1
        measured[i, 0], measured[i, 1], measured[i, 2] = time, px, pz
        measured[i, 3], measured[i, 4] = vx, vz
        m_flags[i, 0], m_flags[i, 1], m_flags[i, 2] = held, released, caught
        for h in range(n_hist - 1, 0, -1):
            for c in range(4):
                history[i, h, c] = history[i, h - 1, c]
        history[i, 0, 0], history[i, 0, 1] = px, pz
        history[i, 0, 2], history[i, 0, 3] = vx, vz
        if caught:
            counts[i, 0] += 1
        if released:
            counts[i, 1] += 1
        terminated = dropped
        truncated = not terminated and (counts[i, 0] >= max_catches or time >= time_limit)
        # the likeness of the hand's state in the plan's phase
        phase = phases[i]
        q[0, 0], q[0, 1] = hand[i, 0], hand[i, 1]
        q[0, 2], q[0, 3] = tau * hand_vel[i, 0], tau * hand_vel[i, 1]
        columns, axis = samples[phase]
        last[0] = nearest[i, phase]
        nearest_rows(columns, columns[axis], axis, q, last, found)
        nearest[i, phase] = last[0]
        like = found[0] if math.isfinite(found[0]) else math.inf
        # the reward (LevelsEnvMixin._rewards)
        ax, az = actions[j, 0], actions[j, 1]
        r_catch = w_catch * (1 if caught else 0)
        r_drop = -w_drop * (1.0 if dropped else 0.0)
        r_like = -w_like * like
        r_act = -w_act * (ax * ax + az * az)
        out[j, 0] = r_catch + r_drop + r_like + r_act
        out[j, 1], out[j, 2], out[j, 3], out[j, 4] = r_catch, r_drop, r_like, r_act
        out[j, 5], out[j, 6] = like, time
        ends[j, 0], ends[j, 1] = terminated, truncated
        # the observation (JugglingV1Env._observation)
        row = obs[j]
        row[0], row[1] = hand[i, 0], hand[i, 1]
        row[2], row[3] = hand_vel[i, 0], hand_vel[i, 1]
        row[4] = 1.0 if held else 0.0
        for p in range(4):
            row[5 + p] = 1.0 if p == phase else 0.0
        row[9] = plan_k[i] * dt
        row[10] = duration[i]
        if fast:
            g = min(plan_k[i] + 1, glen[i] - 1)
            row[11], row[12] = grid[i, g, 0], grid[i, g, 1]
        else:
            row[11], row[12] = nominal[i, 0], nominal[i, 1]
        row[13], row[14] = plan_end[i, 0], plan_end[i, 1]
        for h in range(n_hist):
            for c in range(4):
                row[15 + 4 * h + c] = history[i, h, c]
        for c in range(row.shape[0]):
            if row[c] > high[c]:
                row[c] = high[c]
            if row[c] < low[c]:
                row[c] = low[c]
