r"""The Juggling-v1 world: an actuated hand with a palm, a ball, a floor, MuJoCo contacts.

In the style of dm_control's ``ball_in_cup``: the physics lives in the model file
(``juggling_v1.xml`` beside this module: joints, motors with force limits, contacts on),
:class:`JugglingPhysics` offers a few named read-only queries on it, and
:class:`JugglingV1World` is the thin task on top: it servoes the hand onto the
controller's targets within a human hand's limits, and applies the grasp rule.

**The hand** is a 0.5 kg body on two slide joints (``x``, ``z``), gravity compensated
(the arm holds its own weight), driven by two motors. Every 5 ms control period the
controller gives a target ``h_k``; during the period's ``SUBSTEPS`` physics steps the
motor force is ``m a`` with the computed-torque servo

.. math:: a = a_{ref} + k_p (p_{ref} - p) + k_d (v_{ref} - v)

(``p_ref`` moving linearly from ``h_{k-1}`` to ``h_k``, ``v_ref = (h_k - h_{k-1}) / dt``,
``a_ref`` its backward difference; ``k_p = w^2``, ``k_d = 2 w``, ``w = SERVO_OMEGA``),
clipped so that ``|a| <= HAND_ACCEL_LIMIT`` and the hand's speed after the physics step
stays ``<= HAND_SPEED_LIMIT``; the motors' force range is ``m HAND_ACCEL_LIMIT`` per axis.
The command itself is rate limited (a step longer than ``HAND_SPEED_LIMIT dt`` is
shortened), so a target 1 m away is approached at the speed limit, not reached.

Human limits (``HAND_SPEED_LIMIT = 6 m/s``, ``HAND_ACCEL_LIMIT = 120 m/s^2``). Sources:
ISO 13855:2010 takes 2.0 m/s as the approach speed of a person's hand/arm for safety
distances (a typical fast reach, not a maximum); fast ballistic arm movements go far
beyond (hand speeds in overarm throwing exceed 15 m/s, e.g. Atwater, Exerc. Sport Sci.
Rev. 7, 1979); and the SIMULATED demonstrations at 9.81 m/s^2 peak at 5.1 m/s and
91 m/s^2 (99th percentiles 4.6 m/s and 71 m/s^2, measured by ``tests/test_env_juggling_v1``).
The limits are the demonstrations' peaks with a 20-30 % margin: the person the juggler
imitates can move as the demonstrations do, not faster.

**The grasp rule** (the fingers): a held ball is attached to the hand (its state copied
from the hand after each physics step; its contacts off). The controller arms the release;
the ball is released when the hand's vertical acceleration is below ``-toss_threshold``
(``3 g``), measured as the demonstrations measure it: the second backward difference of
the hand's height at the control samples, ``(z_k - 2 z_{k-1} + z_{k-2}) / dt^2``
(:func:`~motion_envs.datasets.juggling.rules.hand_acceleration`; before time 0 the hand
moves at its reset velocity), with the hand's
velocity perturbed in speed and angle (:func:`~motion_envs.models.juggling.perturb_release`).
A flying ball is **captured** only when (1) it is falling (``v_z < 0``), (2) it touches the
palm (a MuJoCo contact between ``ball`` and ``palm``, the ball's centre above the palm's
top face) and (3) its speed relative to the hand is below ``CAPTURE_SPEED`` (5 m/s: a
person's hand cushions a 130 g ball dropped from ~1.3 m; a harder hit bounces off, as the
contact computes). A rising ball is never caught, and the ball must have left the palm
(its centre more than a ball diameter from the hand origin) once since the release.

**A drop** is any contact of the ball with the floor (or the ball's centre below it).
"""

from __future__ import annotations

import math
from importlib import resources

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray

from motion_envs.datasets.juggling import JugglingState, JugglingTask, rules
from motion_envs.models.juggling import perturb_release, xz_pair

__all__ = [
    "CAPTURE_SPEED",
    "HAND_ACCEL_LIMIT",
    "HAND_MASS",
    "HAND_SPEED_LIMIT",
    "SERVO_OMEGA",
    "SUBSTEPS",
    "V1_SCENE_XML",
    "JugglingPhysics",
    "JugglingV1World",
    "load_juggling_v1_model",
]

#: The world's MJCF (package data).
V1_SCENE_XML = "juggling_v1.xml"
#: Peak hand speed, m/s (see the module docstring for the sources).
HAND_SPEED_LIMIT = 6.0
#: Peak hand acceleration, m/s^2.
HAND_ACCEL_LIMIT = 120.0
#: Hand mass, kg (the XML's).
HAND_MASS = 0.5
#: Relative speed (m/s) under which a falling ball touching the palm is captured.
CAPTURE_SPEED = 5.0
#: Servo bandwidth, rad/s (critically damped).
SERVO_OMEGA = 60.0
#: Physics steps per control period.
SUBSTEPS = 5
_FRACTIONS = tuple(j / SUBSTEPS for j in range(1, SUBSTEPS + 1))
_KP, _KD = SERVO_OMEGA**2, 2.0 * SERVO_OMEGA
_AMAX2 = HAND_ACCEL_LIMIT**2


def servo_plan(
    ref: tuple[float, float], vref: tuple[float, float], tx: float, tz: float, dt: float
) -> tuple[float, float, float, float, float, float, float, float]:
    """One control period's servo reference (module docstring): the command from the last
    reference point ``ref`` toward ``(tx, tz)``, rate limited to ``HAND_SPEED_LIMIT``;
    ``(sx, sz, dx, dz, vrx, vrz, arx, arz)``: the period's start, step, reference velocity
    and its backward difference from the last reference velocity ``vref``."""
    step_max = HAND_SPEED_LIMIT * dt
    sx, sz = ref
    dx, dz = tx - sx, tz - sz
    dist = math.hypot(dx, dz)
    if dist > step_max:  # the command moves at most at the speed limit
        dx, dz = dx * step_max / dist, dz * step_max / dist
    vrx, vrz = dx / dt, dz / dt
    return sx, sz, dx, dz, vrx, vrz, (vrx - vref[0]) / dt, (vrz - vref[1]) / dt


def servo_acceleration(
    f: float,
    plan: tuple[float, float, float, float, float, float, float, float],
    hx: float,
    hz: float,
    vx: float,
    vz: float,
    h: float,
) -> tuple[float, float]:
    """The hand's commanded acceleration at the fraction ``f`` of the period
    (:func:`servo_plan`'s ``plan``), the hand at ``(hx, hz)`` moving at ``(vx, vz)``,
    physics step ``h``: the computed-torque servo clipped to ``HAND_ACCEL_LIMIT`` and so
    that the speed after the step stays within ``HAND_SPEED_LIMIT``."""
    sx, sz, dx, dz, vrx, vrz, arx, arz = plan
    ax = arx + _KP * (sx + f * dx - hx) + _KD * (vrx - vx)
    az = arz + _KP * (sz + f * dz - hz) + _KD * (vrz - vz)
    n2 = ax * ax + az * az
    if n2 > _AMAX2:
        s = math.sqrt(_AMAX2 / n2)
        ax, az = ax * s, az * s
    nvx, nvz = vx + ax * h, vz + az * h
    sp = math.hypot(nvx, nvz)
    if sp > HAND_SPEED_LIMIT:  # the speed limit: aim at the limit along the new direction
        nvx, nvz = nvx * HAND_SPEED_LIMIT / sp, nvz * HAND_SPEED_LIMIT / sp
        ax, az = (nvx - vx) / h, (nvz - vz) / h
    return ax, az


def load_juggling_v1_model(task: JugglingTask) -> mujoco.MjModel:
    """Compile ``juggling_v1.xml`` with ``task``'s gravity, ball and floor; the
    timestep is ``task.dt / SUBSTEPS``."""
    xml = resources.files("motion_envs.envs.juggling").joinpath(V1_SCENE_XML)
    model = mujoco.MjModel.from_xml_string(xml.read_text())
    model.opt.timestep = task.dt / SUBSTEPS
    model.opt.gravity[:] = (0.0, 0.0, -task.gravity)
    ball = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "ball")
    palm = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "palm")
    floor = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "floor")
    model.geom_size[ball, 0] = task.ball_radius
    model.geom_pos[palm, 2] = -(task.ball_radius + float(model.geom_size[palm, 2]))
    model.geom_pos[floor, 2] = task.floor_z
    body = model.geom_bodyid[ball]
    model.body_mass[body] = task.ball_mass
    model.body_inertia[body] = 0.4 * task.ball_mass * task.ball_radius**2
    model.actuator_forcerange[:] = (-HAND_MASS * HAND_ACCEL_LIMIT, HAND_MASS * HAND_ACCEL_LIMIT)
    return model


class JugglingPhysics:
    """The compiled model and its data, with named read-only queries (dm_control style)."""

    def __init__(self, task: JugglingTask) -> None:
        self.model = load_juggling_v1_model(task)
        self.data = mujoco.MjData(self.model)
        m = self.model
        self.ball_geom = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, "ball")
        self.palm_geom = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, "palm")
        self.floor_geom = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, "floor")
        #: height of the palm's top face above the hand origin (``-ball_radius``)
        self.palm_top = float(m.geom_pos[self.palm_geom, 2] + m.geom_size[self.palm_geom, 2])

    # qpos/qvel layout: hand_x, hand_z, ball_x, ball_z
    def hand_position(self) -> NDArray[np.float64]:
        """The hand origin (where a held ball's centre sits), ``(x, z)`` m."""
        return np.array(self.data.qpos[0:2], dtype=np.float64)

    def hand_velocity(self) -> NDArray[np.float64]:
        """``(vx, vz)`` m/s."""
        return np.array(self.data.qvel[0:2], dtype=np.float64)

    def ball_position(self) -> NDArray[np.float64]:
        """The ball's centre ``(x, z)`` m."""
        return np.array(self.data.qpos[2:4], dtype=np.float64)

    def ball_velocity(self) -> NDArray[np.float64]:
        """``(vx, vz)`` m/s."""
        return np.array(self.data.qvel[2:4], dtype=np.float64)

    def ball_touches(self, geom: int) -> bool:
        """Whether a contact between the ball and ``geom`` is active."""
        d, b = self.data, self.ball_geom
        if d.ncon == 0:
            return False
        for i in range(d.ncon):
            c = d.contact[i]
            if (c.geom1 == b and c.geom2 == geom) or (c.geom2 == b and c.geom1 == geom):
                return True
        return False

    def set_ball_contacts(self, on: bool) -> None:
        """Switch the ball's contacts on (flying) or off (held in the fingers)."""
        self.model.geom_contype[self.ball_geom] = int(on)
        self.model.geom_conaffinity[self.ball_geom] = int(on)


class HandsWorld:
    """The task constants and the release noise of a world of actuated hands
    (:class:`JugglingV1World`, :class:`~motion_envs.envs.juggling.CascadeWorld`)."""

    def __init__(
        self, task: JugglingTask, release_speed_std: float = 0.0, release_angle_std: float = 0.0
    ) -> None:
        self.task = task
        self.release_speed_std = float(release_speed_std)
        self.release_angle_std = float(release_angle_std)
        self._rng: np.random.Generator | None = None


class JugglingV1World(HandsWorld):
    """The task on top of :class:`JugglingPhysics` (see the module docstring).

    ``reset(hand_pos, rng=...)`` and ``step(hand_target, release_armed)`` return the TRUE
    :class:`~motion_envs.datasets.juggling.JugglingState` (what a controller sees goes
    through :class:`~motion_envs.models.juggling.BallSensor`).

    Parameters
    ----------
    task:
        The task constants (gravity, dt, ball, floor, toss threshold).
    release_speed_std, release_angle_std:
        Release noise: relative speed error and direction error (rad), per toss.
    """

    def __init__(
        self, task: JugglingTask, release_speed_std: float = 0.0, release_angle_std: float = 0.0
    ) -> None:
        super().__init__(task, release_speed_std, release_angle_std)
        self.physics = JugglingPhysics(task)
        self.model, self.data = self.physics.model, self.physics.data
        self._ref = (0.0, 0.0)
        self._vref = (0.0, 0.0)
        #: the hand's height one control sample before the current one (the release rule's)
        self._z_before = 0.0
        self._held = True
        self._left = False
        self._dropped = False
        self._k = 0
        self.state: JugglingState | None = None

    def reset(
        self,
        hand_pos: ArrayLike,
        *,
        rng: np.random.Generator | None = None,
        hand_vel: ArrayLike = (0.0, 0.0),
    ) -> JugglingState:
        """Hand at ``hand_pos`` moving at ``hand_vel`` (default at rest), ball held in it,
        time 0; the scene placed (camera and lights included) before any physics step."""
        x, z = xz_pair(hand_pos, "hand_pos")
        vx, vz = xz_pair(hand_vel, "hand_vel")
        self._rng = rng
        mujoco.mj_resetData(self.model, self.data)
        self.data.qpos[:] = (x, z, x, z)
        self.data.qvel[:] = (vx, vz, vx, vz)
        self._ref = (x, z)
        self._vref = (vx, vz)
        dt = self.task.dt
        self._z_before = z - vz * dt
        self._held, self._left, self._dropped = True, False, False
        self._k = 0
        self.physics.set_ball_contacts(False)
        mujoco.mj_forward(self.model, self.data)
        self.state = self._make_state(False, False)
        return self.state

    def step(self, hand_target: ArrayLike, release_armed: bool) -> JugglingState:
        """One control period: servo the hand toward ``hand_target`` (rate limited), grasp
        rule after every physics step, release decision at the period's end."""
        if self.state is None:
            raise RuntimeError("call reset() before step()")
        tx, tz = xz_pair(hand_target, "hand_target")
        return self.advance(tx, tz, release_armed)

    def advance(self, tx: float, tz: float, release_armed: bool) -> JugglingState:
        """:meth:`step` toward the finite floats ``(tx, tz)``, unchecked (the env's hot
        path; the episode must have been reset)."""
        task, dt = self.task, self.task.dt
        plan = servo_plan(self._ref, self._vref, tx, tz, dt)
        self._ref = (plan[0] + plan[2], plan[1] + plan[3])
        self._vref = (plan[4], plan[5])
        m, d, phys = self.model, self.data, self.physics
        qpos, qvel, ctrl = d.qpos, d.qvel, d.ctrl
        step, accel = mujoco.mj_step, servo_acceleration
        hx, hz, bx, bz = qpos.tolist()
        vx, vz, ux, uz = qvel.tolist()
        z_prev, z_prev2 = hz, self._z_before
        h = m.opt.timestep
        radius, floor_z = task.ball_radius, task.floor_z
        palm_top = phys.palm_top
        held, left, dropped = self._held, self._left, self._dropped
        caught = False
        for f in _FRACTIONS:
            ax, az = accel(f, plan, hx, hz, vx, vz, h)
            ctrl[0] = HAND_MASS * ax
            ctrl[1] = HAND_MASS * az
            step(m, d)
            if held:  # the ball rides in the hand (its state written after the loop)
                hx, hz, _, _ = qpos.tolist()
                vx, vz, _, _ = qvel.tolist()
                continue
            hx, hz, bx, bz = qpos.tolist()
            vx, vz, ux, uz = qvel.tolist()
            if not left and math.hypot(bx - hx, bz - hz) > 2 * radius:
                left = True
            if not dropped and (bz - radius <= floor_z or phys.ball_touches(phys.floor_geom)):
                dropped = True
            if (
                not dropped
                and left
                and bz >= hz + palm_top
                and uz < 0.0
                and math.hypot(ux - vx, uz - vz) < CAPTURE_SPEED
                and phys.ball_touches(phys.palm_geom)
            ):
                held = caught = True
                phys.set_ball_contacts(False)
                qpos[2] = hx
                qpos[3] = hz
                qvel[2] = vx
                qvel[3] = vz
        if held:  # a held ball is copied from the hand after the physics steps: with its
            # contacts off it acts on nothing, so only its state after the last one counts
            bx, bz, ux, uz = hx, hz, vx, vz
            qpos[2] = hx
            qpos[3] = hz
            qvel[2] = vx
            qvel[3] = vz
        self._held, self._left, self._dropped = held, left, dropped
        self._k += 1
        time = self._k * dt
        d.time = time
        self._z_before = z_prev
        released = False
        if held and not caught and release_armed:
            a_z = rules.hand_acceleration(hz, z_prev, z_prev2, dt)
            if rules.release_fires(True, a_z, task.toss_threshold):
                v = perturb_release(
                    np.array((vx, vz)), self.release_speed_std, self.release_angle_std, self._rng
                )
                ux, uz = float(v[0]), float(v[1])
                qvel[2], qvel[3] = ux, uz
                self._held = self._left = False
                released = True
                phys.set_ball_contacts(True)
        self.state = JugglingState(
            time=time,
            hand_pos=np.array((hx, hz)),
            hand_vel=np.array((vx, vz)),
            ball_pos=np.array((bx, bz)),
            ball_vel=np.array((ux, uz)),
            held=self._held,
            released=released,
            caught=caught,
            dropped=dropped,
        )
        return self.state

    def launch(self, ball_pos: ArrayLike, ball_vel: ArrayLike) -> JugglingState:
        """Put the ball in flight at ``ball_pos`` with ``ball_vel`` (as if tossed long ago:
        it may be captured at once), the hand unchanged; for tests and demonstrations."""
        self.data.qpos[2:4] = xz_pair(ball_pos, "ball_pos")
        self.data.qvel[2:4] = xz_pair(ball_vel, "ball_vel")
        self._held, self._left = False, True
        self.physics.set_ball_contacts(True)
        mujoco.mj_forward(self.model, self.data)
        self.state = self._make_state(False, False)
        return self.state

    @property
    def held(self) -> bool:
        """Whether the ball is in the hand."""
        return self._held

    def sync(self) -> None:
        """Recompute the poses and the camera/lights (``mj_forward``) for drawing."""
        mujoco.mj_forward(self.model, self.data)

    def _make_state(self, released: bool, caught: bool) -> JugglingState:
        q, v = self.data.qpos, self.data.qvel
        return JugglingState(
            time=float(self.data.time),
            hand_pos=q[0:2].copy(),
            hand_vel=v[0:2].copy(),
            ball_pos=q[2:4].copy(),
            ball_vel=v[2:4].copy(),
            held=self._held,
            released=released,
            caught=caught,
            dropped=self._dropped,
        )
