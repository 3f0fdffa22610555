r"""The Cascade-v0 world: two actuated hands, three balls, a floor, MuJoCo contacts.

The same physics as Juggling-v1's world (:mod:`~motion_envs.envs.juggling._v1_scene`), per
hand and per ball: ``cascade.xml`` beside this module holds the bodies, joints, motors
and contacts; :class:`CascadeWorld` servoes each hand onto its controller's target within
the same human limits (``HAND_SPEED_LIMIT``, ``HAND_ACCEL_LIMIT``, the computed-torque
servo of ``SERVO_OMEGA``, the command rate limited), and applies the grasp rule per hand:

* a hand holds at most one ball; a held ball follows the hand origin with its contacts
  off (in the fingers);
* a held ball is released at the end of a control period when its hand's release is
  armed and the hand's vertical acceleration is below ``-toss_threshold``, measured as
  the demonstrations and Juggling-v1 measure it (the second backward difference of the
  hand's height at the control samples,
  :func:`~motion_envs.datasets.juggling.rules.hand_acceleration`; the hands rest before
  time 0); it leaves with the hand's velocity scattered in speed and angle
  (:func:`~motion_envs.models.juggling.perturb_release`);
* a flying ball that has left its thrower (farther than two radii from it) is captured by
  an EMPTY hand when it falls, touches that hand's palm and is slower than
  ``CAPTURE_SPEED`` relative to the hand; otherwise it bounces off the palm;
* a ball touching the floor (or below ``floor_z`` plus its radius) is dropped (sticky).

Balls do not collide with each other (``contype``/``conaffinity`` in the XML), palms
neither with each other nor with the floor.
"""

from __future__ import annotations

import math
from importlib import resources

import mujoco
import numpy as np
from numpy.typing import ArrayLike

from motion_envs.datasets.juggling import CASCADE_BALLS, CASCADE_HANDS, JugglingTask, rules
from motion_envs.envs.juggling._v1_scene import (
    CAPTURE_SPEED,
    HAND_ACCEL_LIMIT,
    HAND_MASS,
    SUBSTEPS,
    HandsWorld,
    servo_acceleration,
    servo_plan,
)
from motion_envs.models.juggling import CascadeState, perturb_release

__all__ = [
    "BALL_CONAFFINITY",
    "BALL_CONTYPE",
    "CASCADE_SCENE_XML",
    "CascadeWorld",
    "load_cascade_model",
]

#: The world's MJCF (package data).
CASCADE_SCENE_XML = "cascade.xml"
_HANDS = ("right", "left")
#: A flying ball's ``contype`` and ``conaffinity`` (a held ball's are 0: in the fingers).
BALL_CONTYPE, BALL_CONAFFINITY = 2, 1


def load_cascade_model(task: JugglingTask) -> mujoco.MjModel:
    """Compile ``cascade.xml`` with ``task``'s gravity, balls and floor; the timestep is
    ``task.dt / SUBSTEPS``."""
    xml = resources.files("motion_envs.envs.juggling").joinpath(CASCADE_SCENE_XML)
    model = mujoco.MjModel.from_xml_string(xml.read_text())
    model.opt.timestep = task.dt / SUBSTEPS
    model.opt.gravity[:] = (0.0, 0.0, -task.gravity)
    name = mujoco.mj_name2id
    geom = mujoco.mjtObj.mjOBJ_GEOM
    for h in _HANDS:
        palm = name(model, geom, f"palm_{h}")
        model.geom_pos[palm, 2] = -(task.ball_radius + float(model.geom_size[palm, 2]))
    for i in range(CASCADE_BALLS):
        ball = name(model, geom, f"ball{i}")
        model.geom_size[ball, 0] = task.ball_radius
        body = model.geom_bodyid[ball]
        model.body_mass[body] = task.ball_mass
        model.body_inertia[body] = 0.4 * task.ball_mass * task.ball_radius**2
    model.geom_pos[name(model, geom, "floor"), 2] = task.floor_z
    model.actuator_forcerange[:] = (-HAND_MASS * HAND_ACCEL_LIMIT, HAND_MASS * HAND_ACCEL_LIMIT)
    return model


class CascadeWorld(HandsWorld):
    """The cascade task on MuJoCo (see the module docstring).

    ``reset(hand_pos, flying=..., rng=...)`` and ``step(targets, armed)`` return the TRUE
    :class:`~motion_envs.models.juggling.CascadeState`. qpos/qvel layout: right hand
    ``x, z``, left hand ``x, z``, then ``x, z`` of balls 0, 1, 2. The parameters are
    :class:`~motion_envs.envs.juggling.JugglingV1World`'s (the task constants, the release
    noise per toss); each hand is servoed as its hand is
    (:func:`~motion_envs.envs.juggling._v1_scene.servo_plan`).
    """

    def __init__(
        self, task: JugglingTask, release_speed_std: float = 0.0, release_angle_std: float = 0.0
    ) -> None:
        super().__init__(task, release_speed_std, release_angle_std)
        self.model = load_cascade_model(task)
        self.data = mujoco.MjData(self.model)
        m, geom = self.model, mujoco.mjtObj.mjOBJ_GEOM
        self.palm_geoms = [mujoco.mj_name2id(m, geom, f"palm_{h}") for h in _HANDS]
        self.ball_geoms = [mujoco.mj_name2id(m, geom, f"ball{i}") for i in range(CASCADE_BALLS)]
        self.floor_geom = mujoco.mj_name2id(m, geom, "floor")
        #: height of a palm's top face above its hand origin (``-ball_radius``)
        self.palm_top = float(
            m.geom_pos[self.palm_geoms[0], 2] + m.geom_size[self.palm_geoms[0], 2]
        )
        self._ref: list[tuple[float, float]] = [(0.0, 0.0)] * CASCADE_HANDS
        self._vref: list[tuple[float, float]] = [(0.0, 0.0)] * CASCADE_HANDS
        self._holder = [-1] * CASCADE_BALLS
        self._thrower = [-1] * CASCADE_BALLS
        self._left = [True] * CASCADE_BALLS
        self._dropped = [False] * CASCADE_BALLS
        #: each hand's height one control sample before the current one (the release rule's)
        self._z_before = [0.0] * CASCADE_HANDS
        self._k = 0
        self.state: CascadeState | None = None

    # -- setup ----------------------------------------------------------------------------
    def _set_contacts(self, ball: int, on: bool) -> None:
        g = self.ball_geoms[ball]
        self.model.geom_contype[g] = BALL_CONTYPE if on else 0
        self.model.geom_conaffinity[g] = BALL_CONAFFINITY if on else 0

    def reset(
        self,
        hand_pos: ArrayLike,
        *,
        flying: tuple[ArrayLike, ArrayLike] | None = None,
        rng: np.random.Generator | None = None,
    ) -> CascadeState:
        """Hands at rest at ``hand_pos`` ``(2, 2)``, ball 0 in the right hand, ball 1 in
        the left, ball 2 in flight at ``flying = (position, velocity)`` (required; thrown
        by the left hand). Time 0; the scene placed (camera and lights included) before
        any physics step."""
        hands = np.asarray(hand_pos, dtype=np.float64)
        if hands.shape != (CASCADE_HANDS, 2) or not np.isfinite(hands).all():
            raise ValueError(f"hand_pos must be a finite (2, 2) array; got {hand_pos!r}")
        if flying is None:
            raise ValueError("flying (position, velocity of ball 2) is required")
        bp = np.asarray(flying[0], dtype=np.float64)
        bv = np.asarray(flying[1], dtype=np.float64)
        if (
            bp.shape != (2,)
            or bv.shape != (2,)
            or not (np.isfinite(bp).all() and np.isfinite(bv).all())
        ):
            raise ValueError(f"flying must be two finite (x, z) pairs; got {flying!r}")
        self._rng = rng
        mujoco.mj_resetData(self.model, self.data)
        q = self.data.qpos
        q[0:4] = hands.ravel()
        q[4:6] = hands[0]
        q[6:8] = hands[1]
        q[8:10] = bp
        self.data.qvel[:] = 0.0
        self.data.qvel[8:10] = bv
        self._ref = [(float(x), float(z)) for x, z in hands]
        self._vref = [(0.0, 0.0)] * CASCADE_HANDS
        self._holder = [0, 1, -1]
        self._thrower = [-1, -1, 1]
        self._left = [False, False, True]
        self._dropped = [False] * CASCADE_BALLS
        self._z_before = [float(z) for _, z in hands]  # at rest before time 0
        self._k = 0
        for i in range(CASCADE_BALLS):
            self._set_contacts(i, self._holder[i] < 0)
        mujoco.mj_forward(self.model, self.data)
        self.state = self._make_state((-1, -1), (-1, -1))
        return self.state

    # -- one control period -----------------------------------------------------------------
    def _touching(self) -> set[tuple[int, int]]:
        d = self.data
        out = set()
        for i in range(d.ncon):
            c = d.contact[i]
            out.add((int(c.geom1), int(c.geom2)))
            out.add((int(c.geom2), int(c.geom1)))
        return out

    def step(self, targets: ArrayLike, armed: tuple[bool, bool]) -> CascadeState:
        """One control period: servo both hands toward ``targets`` ``(2, 2)`` (rate
        limited), grasp rule after every physics step, releases at the period's end."""
        if self.state is None:
            raise RuntimeError("call reset() before step()")
        tg = np.asarray(targets, dtype=np.float64)
        if tg.shape != (CASCADE_HANDS, 2):
            raise ValueError(f"targets must be a finite (2, 2) array; got {targets!r}")
        flat = tg.ravel().tolist()
        if not all(math.isfinite(x) for x in flat):
            raise ValueError(f"targets must be a finite (2, 2) array; got {targets!r}")
        task, dt = self.task, self.task.dt
        servo = []
        for h in range(CASCADE_HANDS):
            plan = servo_plan(self._ref[h], self._vref[h], flat[2 * h], flat[2 * h + 1], dt)
            self._ref[h] = (plan[0] + plan[2], plan[1] + plan[3])
            self._vref[h] = (plan[4], plan[5])
            servo.append(plan)
        m, d = self.model, self.data
        qpos, qvel, ctrl = d.qpos, d.qvel, d.ctrl
        z_prev, z_prev2 = [float(qpos[1]), float(qpos[3])], self._z_before
        h_step = m.opt.timestep
        radius, floor_z = task.ball_radius, task.floor_z
        holder, left, dropped = self._holder, self._left, self._dropped
        caught = [-1, -1]
        q, v = qpos.tolist(), qvel.tolist()
        forces = [0.0] * (2 * CASCADE_HANDS)
        for j in range(1, SUBSTEPS + 1):
            f = j / SUBSTEPS
            for h in range(CASCADE_HANDS):
                ax, az = servo_acceleration(
                    f, servo[h], q[2 * h], q[2 * h + 1], v[2 * h], v[2 * h + 1], h_step
                )
                forces[2 * h] = HAND_MASS * ax
                forces[2 * h + 1] = HAND_MASS * az
            ctrl[:] = forces
            mujoco.mj_step(m, d)
            q, v = qpos.tolist(), qvel.tolist()
            touching: set[tuple[int, int]] | None = None
            for i in range(CASCADE_BALLS):
                b = 4 + 2 * i
                h = holder[i]
                if h >= 0:  # held: follows its hand (written after the last physics step)
                    continue
                bx, bz = q[b], q[b + 1]
                if not left[i]:
                    t = self._thrower[i]
                    if math.hypot(bx - q[2 * t], bz - q[2 * t + 1]) > 2 * radius:
                        left[i] = True
                if dropped[i] or (not left[i] and bz - radius > floor_z):
                    continue
                if touching is None:
                    touching = self._touching()
                g = self.ball_geoms[i]
                if bz - radius <= floor_z or (g, self.floor_geom) in touching:
                    dropped[i] = True
                    continue
                if v[b + 1] >= 0.0 or not left[i]:
                    continue
                for h in range(CASCADE_HANDS):
                    if h in holder or bz < q[2 * h + 1] + self.palm_top:
                        continue
                    rel = math.hypot(v[b] - v[2 * h], v[b + 1] - v[2 * h + 1])
                    if rel < CAPTURE_SPEED and (g, self.palm_geoms[h]) in touching:
                        holder[i] = h
                        caught[h] = i
                        self._set_contacts(i, False)
                        break
        # held balls follow their hands (contacts off: their own flight in between
        # touches nothing, so writing them once per period is the same world)
        for i in range(CASCADE_BALLS):
            h = holder[i]
            if h >= 0:
                b = 4 + 2 * i
                q[b], q[b + 1], v[b], v[b + 1] = q[2 * h], q[2 * h + 1], v[2 * h], v[2 * h + 1]
        qpos[4:] = q[4:]
        qvel[4:] = v[4:]
        self._k += 1
        d.time = self._k * dt
        self._z_before = z_prev
        released = [-1, -1]
        for h in range(CASCADE_HANDS):
            if h not in holder or caught[h] >= 0 or not armed[h]:
                continue
            a_z = rules.hand_acceleration(float(qpos[2 * h + 1]), z_prev[h], z_prev2[h], dt)
            if rules.release_fires(True, a_z, task.toss_threshold):
                i = holder.index(h)
                v = perturb_release(
                    qvel[2 * h : 2 * h + 2].copy(),
                    self.release_speed_std,
                    self.release_angle_std,
                    self._rng,
                )
                b = 4 + 2 * i
                qvel[b], qvel[b + 1] = float(v[0]), float(v[1])
                holder[i] = -1
                self._thrower[i] = h
                left[i] = False
                released[h] = i
                self._set_contacts(i, True)
        self.state = self._make_state((released[0], released[1]), (caught[0], caught[1]))
        return self.state

    def launch(self, ball: int, position: ArrayLike, velocity: ArrayLike) -> CascadeState:
        """Put ``ball`` in flight at ``position`` with ``velocity`` (as if thrown long ago:
        it may be captured at once), the hands unchanged; for tests."""
        b = 4 + 2 * int(ball)
        self.data.qpos[b : b + 2] = np.asarray(position, dtype=np.float64)
        self.data.qvel[b : b + 2] = np.asarray(velocity, dtype=np.float64)
        self._holder[ball] = -1
        self._left[ball] = True
        self._set_contacts(ball, True)
        mujoco.mj_forward(self.model, self.data)
        self.state = self._make_state((-1, -1), (-1, -1))
        return self.state

    def sync(self) -> None:
        """Recompute the poses and the camera/lights (``mj_forward``) for drawing."""
        mujoco.mj_forward(self.model, self.data)

    def _make_state(self, released: tuple[int, int], caught: tuple[int, int]) -> CascadeState:
        q, v = self.data.qpos, self.data.qvel
        return CascadeState(
            time=float(self.data.time),
            hand_pos=np.array(q[0:4]).reshape(2, 2),
            hand_vel=np.array(v[0:4]).reshape(2, 2),
            ball_pos=np.array(q[4:10]).reshape(3, 2),
            ball_vel=np.array(v[4:10]).reshape(3, 2),
            holder=tuple(self._holder),
            released=released,
            caught=caught,
            dropped=tuple(self._dropped),
        )
