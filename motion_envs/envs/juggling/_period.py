r"""One control period of a juggling world, written once for every world and pattern.

A world (:class:`~motion_envs.envs.juggling._world.HandsWorld`) has ``H`` actuated
hands and ``B`` balls (:class:`~motion_envs.envs.juggling._world_spec.WorldSpec`). One
control period of ``dt`` is, for each world ``i`` in ``envs``:

1. **the servo plan** of each hand (:func:`servo_plan`): the command from the hand's last
   reference point toward its target, rate limited to the spec's speed limit;
2. ``substeps`` **physics steps** (MuJoCo's ``mj_step``), before each one the motors'
   forces ``m a`` from the computed-torque servo (:func:`servo_acceleration`), and after
   each one **the grasp rule** for every flying ball, in this order:

   * it has *left* its thrower once its centre is farther than two radii from that hand;
   * it is *dropped* (sticky) when its lowest point is at or below the floor, or MuJoCo
     reports a contact of it with the floor;
   * a falling (``v_z < 0``) ball that has left is *captured* by the first EMPTY hand
     whose palm it touches (MuJoCo's contact), with its centre above the palm's top face
     and its speed relative to the hand below ``capture_speed``; else the contact
     computes the bounce;
   * with ``impact_capture`` (the rule in the hand's frame), instead: a ball that has
     left is captured by the first EMPTY hand whose palm contact BEGINS at this step
     (reported now, not at the step before), its centre above the palm's top face, when
     its velocity relative to the hand before the step approached the palm (relative
     ``v_z < 0``) slower than ``capture_speed``; a faster ball bounces and is not
     caught during that contact;

3. **held balls follow their hands** (a held ball's contacts are off, so its own motion
   during the period touches nothing: writing it once at the period's end is the same
   world);
4. **the release rule** for each hand holding a ball it did not catch in this period,
   when its release is armed: the second backward difference of the hand's height at
   the control samples, ``(z_k - 2 z_{k-1} + z_{k-2}) / dt^2``, below
   ``-toss_threshold``; the ball's contacts on again. Its velocity is still the hand's:
   the release scatter is drawn by the caller (Python, from the world's generator).

The contacts the rule asks about are the scene's ``contact`` sensors, per ball ``b`` at
``b (1 + H)``: the floor, then each hand's palm.

**Written once, run two ways.** :func:`world_periods` is plain Python: it runs as it
stands (the path without numba, calling MuJoCo's ``mj_step`` through ``ctypes``), and
:mod:`~motion_envs.envs.juggling._compiled` compiles the very same function body with
numba, its global names bound to compiled equivalents (``py_hypot`` is CPython's
``math.hypot`` in both; ``mj_step_c`` the same C function of the same ``libmujoco``).
IEEE ``+ - * / sqrt`` are correctly rounded in both, so the two paths are bit-identical
(tested). The single environment is the batch of one through this function.
"""

from __future__ import annotations

import ctypes
import math
from importlib import resources
from pathlib import Path
from typing import Any

import mujoco
import numpy as np

__all__ = [
    "CONSTANT_NAMES",
    "libmujoco_path",
    "mj_step_c",
    "py_hypot",
    "servo_acceleration",
    "servo_plan",
    "world_periods",
]

#: The order of :func:`world_periods`' ``constants`` (``WorldSpec.constants`` makes them).
CONSTANT_NAMES = (
    "dt",
    "physics_step",
    "ball_radius",
    "floor_z",
    "palm_top",
    "toss_threshold",
    "ball_contype",
    "ball_conaffinity",
    "hand_mass",
    "speed_limit",
    "accel_limit",
    "capture_speed",
    "servo_omega",
    "substeps",
    "impact_capture",
)


def libmujoco_path() -> str:
    """The ``libmujoco`` shared library of the installed ``mujoco`` package (the one its
    Python bindings use)."""
    package = Path(str(resources.files(mujoco)))
    found = sorted(package.glob("libmujoco.so*")) + sorted(package.glob("libmujoco*.dylib"))
    found += sorted(package.glob("mujoco*.dll"))
    if not found:
        raise ImportError(f"no libmujoco shared library in {package}")
    return str(found[0])


_mj_step = ctypes.CDLL(libmujoco_path()).mj_step
_mj_step.argtypes = (ctypes.c_void_p, ctypes.c_void_p)
_mj_step.restype = None
#: ``mj_step(model, data)`` called with the two addresses (``MjModel._address``,
#: ``MjData._address``): the C function ``mujoco.mj_step`` calls.
mj_step_c = _mj_step
#: CPython's exactly rounded ``hypot`` (the compiled path has an equal one).
py_hypot = math.hypot


def servo_plan(
    ref: Any, vref: Any, tx: float, tz: float, dt: float, speed: float, plan: Any
) -> None:
    """One hand's servo reference for a control period: ``plan (8,)`` receives
    ``(sx, sz, dx, dz, vrx, vrz, arx, arz)``, the period's start ``ref``, its step toward
    ``(tx, tz)`` (shortened to ``speed dt``), the reference velocity and its backward
    difference from the last one ``vref``; ``ref (2,)`` and ``vref (2,)`` move on to the
    period's end."""
    step_max = speed * dt
    sx, sz = ref[0], ref[1]
    dx, dz = tx - sx, tz - sz
    dist = py_hypot(dx, dz)
    if dist > step_max:  # the command moves at most at the speed limit
        dx, dz = dx * step_max / dist, dz * step_max / dist
    vrx, vrz = dx / dt, dz / dt
    plan[0], plan[1], plan[2], plan[3] = sx, sz, dx, dz
    plan[4], plan[5] = vrx, vrz
    plan[6], plan[7] = (vrx - vref[0]) / dt, (vrz - vref[1]) / dt
    ref[0], ref[1] = sx + dx, sz + dz
    vref[0], vref[1] = vrx, vrz


def servo_acceleration(
    f: float,
    plan: Any,
    hx: float,
    hz: float,
    vx: float,
    vz: float,
    h: float,
    kp: float,
    kd: float,
    amax2: float,
    speed: float,
) -> tuple[float, float]:
    r"""The hand's commanded acceleration at the fraction ``f`` of the period, the hand at
    ``(hx, hz)`` moving at ``(vx, vz)``, physics step ``h``:
    :math:`a = a_{ref} + k_p (p_{ref} - p) + k_d (v_{ref} - v)` with ``p_ref`` moving
    linearly over the period (:func:`servo_plan`'s ``plan``), clipped to
    ``|a|^2 <= amax2`` and so that the speed after the step stays ``<= speed``."""
    sx, sz, dx, dz = plan[0], plan[1], plan[2], plan[3]
    vrx, vrz, arx, arz = plan[4], plan[5], plan[6], plan[7]
    ax = arx + kp * (sx + f * dx - hx) + kd * (vrx - vx)
    az = arz + kp * (sz + f * dz - hz) + kd * (vrz - vz)
    n2 = ax * ax + az * az
    if n2 > amax2:
        s = math.sqrt(amax2 / n2)
        ax, az = ax * s, az * s
    nvx, nvz = vx + ax * h, vz + az * h
    sp = py_hypot(nvx, nvz)
    if sp > speed:  # the speed limit: aim at the limit along the new direction
        nvx, nvz = nvx * speed / sp, nvz * speed / sp
        ax, az = (nvx - vx) / h, (nvz - vz) / h
    return ax, az


def world_periods(
    envs: Any,
    worlds: Any,
    ball_geoms: Any,
    target: Any,
    armed: Any,
    ref: Any,
    vref: Any,
    z_before: Any,
    holder: Any,
    thrower: Any,
    left: Any,
    dropped: Any,
    k: Any,
    constants: Any,
    caught: Any,
    released: Any,
) -> None:
    """One control period (module docstring) of each world ``i`` in ``envs``.

    ``worlds = (model_addr, data_addr, qpos, qvel, ctrl, sensors, contype,
    conaffinity)``: each world's ``MjModel``/``MjData`` address and views of its arrays
    (qpos/qvel: each hand's ``x, z``, then each ball's); ``ball_geoms (B,)``;
    ``target (N, H, 2)`` the hands' targets, ``armed (N, H)``; the world's state, updated
    in place: ``ref, vref (N, H, 2)`` (the servo's reference point and velocity),
    ``z_before (N, H)`` (each hand's height one control sample before the current one),
    ``holder, thrower (N, B)`` (a hand or -1), ``left, dropped (N, B)``, ``k (N,)``
    (control periods since the reset); ``constants`` in :data:`CONSTANT_NAMES`' order.
    Out: ``caught (N, H)``, the ball each hand caught in this period, and
    ``released (N, H)``, the ball it let go, or -1.
    """
    model_addr, data_addr, qpos, qvel, ctrl, sensors, contype, conaffinity = worlds
    dt, h, radius, floor_z = constants[0], constants[1], constants[2], constants[3]
    palm_top, threshold = constants[4], constants[5]
    ball_contype, ball_conaffinity = int(constants[6]), int(constants[7])
    mass, speed, accel_limit = constants[8], constants[9], constants[10]
    capture_speed, omega, substeps = constants[11], constants[12], int(constants[13])
    impact = constants[14] > 0.0
    kp, kd, amax2 = omega**2, 2.0 * omega, accel_limit**2
    hands, balls = ref.shape[1], holder.shape[1]
    plan = np.empty((hands, 9))  # per hand: the servo plan, the height at the start
    # impact capture: per ball and hand, the contact at the step before, and the relative
    # speed and vertical velocity before the current step
    touch = np.zeros((balls, hands), dtype=np.bool_)
    approach = np.zeros((balls, hands, 2))
    for i in envs:
        for hh in range(hands):
            servo_plan(ref[i, hh], vref[i, hh], target[i, hh, 0], target[i, hh, 1], dt, speed,
                       plan[hh])  # fmt: skip
        qp, qv, u, sens = qpos[i], qvel[i], ctrl[i], sensors[i]
        ct, ca = contype[i], conaffinity[i]
        for hh in range(hands):
            caught[i, hh] = -1
            released[i, hh] = -1
            plan[hh, 8] = qp[2 * hh + 1]  # the hand's height at the period's start
        if impact:  # the contacts of the last physics step (its sensors persist)
            for b in range(balls):
                for hh in range(hands):
                    touch[b, hh] = sens[b * (1 + hands) + 1 + hh] > 0.0
        for j in range(1, substeps + 1):
            f = j / substeps
            for hh in range(hands):
                ax, az = servo_acceleration(
                    f, plan[hh], qp[2 * hh], qp[2 * hh + 1], qv[2 * hh], qv[2 * hh + 1], h,
                    kp, kd, amax2, speed,
                )  # fmt: skip
                u[2 * hh] = mass * ax
                u[2 * hh + 1] = mass * az
            if impact:  # the velocities relative to each hand before the step
                for b in range(balls):
                    c = 2 * hands + 2 * b
                    for hh in range(hands):
                        rvx, rvz = qv[c] - qv[2 * hh], qv[c + 1] - qv[2 * hh + 1]
                        approach[b, hh, 0] = py_hypot(rvx, rvz)
                        approach[b, hh, 1] = rvz
            mj_step_c(model_addr[i], data_addr[i])
            for b in range(balls):
                if holder[i, b] >= 0:  # held: follows its hand (written at the period's end)
                    continue
                c = 2 * hands + 2 * b
                bx, bz = qp[c], qp[c + 1]
                if not left[i, b]:
                    t = thrower[i, b]
                    if py_hypot(bx - qp[2 * t], bz - qp[2 * t + 1]) > 2 * radius:
                        left[i, b] = True
                if dropped[i, b]:
                    continue
                s = b * (1 + hands)
                if bz - radius <= floor_z or sens[s] > 0.0:
                    dropped[i, b] = True
                    continue
                if (qv[c + 1] >= 0.0 and not impact) or not left[i, b]:
                    continue
                for hh in range(hands):
                    busy = False
                    for bb in range(balls):
                        if holder[i, bb] == hh:
                            busy = True
                    if busy or bz < qp[2 * hh + 1] + palm_top:
                        continue
                    if impact:
                        grip = (
                            sens[s + 1 + hh] > 0.0
                            and not touch[b, hh]
                            and approach[b, hh, 1] < 0.0
                            and approach[b, hh, 0] < capture_speed
                        )
                    else:
                        rel = py_hypot(qv[c] - qv[2 * hh], qv[c + 1] - qv[2 * hh + 1])
                        grip = rel < capture_speed and sens[s + 1 + hh] > 0.0
                    if grip:
                        holder[i, b] = hh
                        caught[i, hh] = b
                        ct[ball_geoms[b]] = 0
                        ca[ball_geoms[b]] = 0
                        break
            if impact:
                for b in range(balls):
                    for hh in range(hands):
                        touch[b, hh] = sens[b * (1 + hands) + 1 + hh] > 0.0
        for b in range(balls):  # held balls follow their hands
            hh = holder[i, b]
            if hh >= 0:
                c = 2 * hands + 2 * b
                qp[c], qp[c + 1] = qp[2 * hh], qp[2 * hh + 1]
                qv[c], qv[c + 1] = qv[2 * hh], qv[2 * hh + 1]
        k[i] += 1
        for hh in range(hands):  # the release rule
            zp, zp2 = plan[hh, 8], z_before[i, hh]
            z_before[i, hh] = zp
            b = -1
            for bb in range(balls):
                if holder[i, bb] == hh:
                    b = bb
            if b < 0 or caught[i, hh] >= 0 or not armed[i, hh]:
                continue
            a_z = (qp[2 * hh + 1] - 2.0 * zp + zp2) / (dt * dt)
            if a_z < -threshold:
                holder[i, b] = -1
                thrower[i, b] = hh
                left[i, b] = False
                released[i, hh] = b
                ct[ball_geoms[b]] = ball_contype
                ca[ball_geoms[b]] = ball_conaffinity
