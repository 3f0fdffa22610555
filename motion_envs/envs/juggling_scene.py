r"""The MuJoCo juggling world: a kinematic hand, a ball under gravity, explicit hold and release.

:class:`JugglingScene` has the interface and the semantics of the pure-model
``BallisticWorld`` (``motion_envs.models``; notes/JUGGLING-CONTRACT.md): ``reset(hand_pos)``
puts the ball in the hand, ``step(hand_target, release_armed)`` advances one control period
``dt``. The scene is ``assets/juggling.xml`` (SI units) with the task's constants written
into the compiled model (timestep ``dt``, gravity ``(0, 0, -g)``, ball radius and mass,
catch radius, floor height).

Choices, and why:

* **The hand is a mocap body.** The paper's hand is a tracker reading: a position, set
  every 5 ms, that nothing in the virtual world pushes back. A mocap body is exactly that:
  it is at ``hand_target`` after the step, so hand velocity and acceleration are the finite
  differences of the targets, as in the pure model, and the scene equals ``BallisticWorld``
  to round-off. The alternative, slide joints driven by position actuators, lags its
  target. Measured on a 0.4 kg hand following a 200 Hz minimum-jerk toss (0.3 m in 0.4 s,
  peak 1.4 m/s; ``tests/test_juggling_scene.py``): ``kp = 10^4 N/m``, critical damping,
  one step per 5 ms: 10.7 mm tracking error and 0.08 m/s velocity error (the release
  velocity would be the actuator's, not the plan's); ``kp = 10^5`` or ``10^6`` diverge at
  5 ms (MuJoCo's "simulation is unstable" warning) and with 10 substeps still leave
  2.2 mm / 0.6 mm and velocity errors of 0.6 / 3.3 m/s (the stiff servo rings on the
  staircase of targets), at 10 times the cost. Nothing is bought for a hand the task
  commands kinematically.
* **The ball has two slide joints (x, z)** and the RK4 integrator. Its flight is the
  constant-acceleration ODE, which RK4 integrates exactly (the closed form

  .. math:: x(t) = x_0 + v_x t, \qquad z(t) = z_0 + v_z t - g t^2 / 2

  to round-off, tested to 1e-6 m over seconds); semi-implicit Euler would be off by
  ``g dt t / 2`` (5 mm after 1 s at g = 2).
* **Holding is a state copy, not a weld.** While held, the ball's ``qpos``/``qvel`` are
  set to the hand's position and finite-difference velocity after each step, so the ball
  follows the hand exactly (a weld equality is a soft constraint and would not). A toss
  sets the ball's velocity to the hand's times ``1 + release noise``; a catch (ball falling,
  centre within ``catch_radius`` of the hand's) snaps it back into the hand. Contacts are
  disabled: nothing collides, so ``data.warning`` stays empty whatever the hand does.

Step order (identical in ``BallisticWorld``; state before the step: hand ``p0, v0``,
``v0 = 0`` at reset):

1. ``p1 = hand_target``, ``v1 = (p1 - p0) / dt``, ``a1 = (v1 - v0) / dt``; one ``mj_step``
   (time ``+= dt``; a flying ball moves along its parabola).
2. If the ball was held: if ``release_armed`` and ``a1_z < -toss_threshold`` it is released
   (``released``) at ``p1`` with velocity ``v1 * (1 + release * N(0, 1))`` per component,
   drawn from the generator given to ``reset``; else it stays at ``p1`` with velocity ``v1``.
3. If it was flying: caught (``caught``, held again at ``p1`` with ``v1``) when its vertical
   velocity is negative and ``|p1 - ball| <= catch_radius``; else ``dropped`` while its
   centre is below ``floor_z``.
"""

from __future__ import annotations

import math
from importlib import resources
from typing import Any

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray

from motion_envs.models.juggling_task import JugglingNoise, JugglingState, JugglingTask

__all__ = ["SCENE_XML", "JugglingScene", "check_task", "load_juggling_model"]

#: The scene's MJCF (package data).
SCENE_XML = "juggling.xml"


def check_task(task: Any) -> JugglingTask:
    """``task`` if it is a :class:`JugglingTask` with finite, positive constants."""
    if not isinstance(task, JugglingTask):
        raise ValueError(f"task must be a JugglingTask; got {type(task).__name__}")
    for name in ("gravity", "dt", "ball_radius", "ball_mass", "catch_radius", "toss_threshold"):
        value = getattr(task, name)
        if not math.isfinite(value) or value <= 0:
            raise ValueError(f"task.{name} must be finite and > 0; got {value!r}")
    if not math.isfinite(task.floor_z):
        raise ValueError(f"task.floor_z must be finite; got {task.floor_z!r}")
    return task


def load_juggling_model(task: JugglingTask | None = None) -> mujoco.MjModel:
    """Compile ``assets/juggling.xml`` with the constants of ``task`` (default task)."""
    task = check_task(JugglingTask() if task is None else task)
    xml = resources.files("motion_envs.envs").joinpath("assets", SCENE_XML).read_text()
    model = mujoco.MjModel.from_xml_string(xml)
    model.opt.timestep = task.dt
    model.opt.gravity[:] = (0.0, 0.0, -task.gravity)
    ball = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "ball")
    hand = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "hand")
    floor = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "floor")
    model.geom_size[ball, 0] = task.ball_radius
    model.geom_size[hand, 0] = task.catch_radius
    model.geom_pos[floor, 2] = task.floor_z
    model.body_mass[model.geom_bodyid[ball]] = task.ball_mass
    model.body_inertia[model.geom_bodyid[ball]] = 0.4 * task.ball_mass * task.ball_radius**2
    return model


def _vec2(value: ArrayLike, name: str) -> NDArray[np.float64]:
    arr = np.asarray(value, dtype=np.float64)
    if arr.shape != (2,):
        raise ValueError(f"{name} must have shape (2,) (x, z); got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite; got {arr.tolist()}")
    return arr


class JugglingScene:
    """The juggling world in MuJoCo (see the module docstring for the semantics).

    Attributes ``model`` and ``data`` are the MuJoCo structures (``data.time`` is the
    world's time); ``state`` the last :class:`JugglingState`.
    """

    def __init__(self, task: JugglingTask | None = None) -> None:
        self.task = check_task(JugglingTask() if task is None else task)
        self.model = load_juggling_model(self.task)
        self.data = mujoco.MjData(self.model)
        self._mocap = self.data.mocap_pos[0]
        self._qpos = self.data.qpos
        self._qvel = self.data.qvel
        self._noise = JugglingNoise()
        self._rng = np.random.default_rng(0)
        self._hand = (0.0, 0.0)
        self._hand_vel = (0.0, 0.0)
        self._held = True
        self.state: JugglingState | None = None

    # -- interface ----------------------------------------------------------------------
    def reset(
        self,
        hand_pos: ArrayLike,
        *,
        noise: JugglingNoise = JugglingNoise(),  # noqa: B008  (frozen dataclass)
        rng: np.random.Generator | None = None,
    ) -> JugglingState:
        """Hand at rest at ``hand_pos``, ball held in it, time 0."""
        p = _vec2(hand_pos, "hand_pos")
        if not isinstance(noise, JugglingNoise):
            raise ValueError(f"noise must be a JugglingNoise; got {type(noise).__name__}")
        self._noise = noise
        self._rng = np.random.default_rng() if rng is None else rng
        mujoco.mj_resetData(self.model, self.data)
        x, z = float(p[0]), float(p[1])
        self._hand = (x, z)
        self._hand_vel = (0.0, 0.0)
        self._held = True
        self._mocap[0], self._mocap[2] = x, z
        self._qpos[0], self._qpos[1] = x, z
        mujoco.mj_kinematics(self.model, self.data)
        self.state = self._make_state(False, False, False)
        return self.state

    def step(self, hand_target: ArrayLike, release_armed: bool) -> JugglingState:
        """Move the hand to ``hand_target`` over one ``dt``; hold, release, catch or drop."""
        if self.state is None:
            raise RuntimeError("call reset() before step()")
        tx, tz = hand_target[0], hand_target[1]  # type: ignore[index]
        x, z = float(tx), float(tz)
        if not (math.isfinite(x) and math.isfinite(z)):
            raise ValueError(f"hand_target must be finite; got {[x, z]}")
        task = self.task
        dt = task.dt
        x0, z0 = self._hand
        vx, vz = (x - x0) / dt, (z - z0) / dt
        az = (vz - self._hand_vel[1]) / dt
        self._hand = (x, z)
        self._hand_vel = (vx, vz)
        self._mocap[0], self._mocap[2] = x, z
        mujoco.mj_step(self.model, self.data)
        qpos, qvel = self._qpos, self._qvel
        released = caught = dropped = False
        if self._held:
            if release_armed and az < -task.toss_threshold:
                self._held = False
                released = True
                r = self._noise.release
                if r != 0.0:
                    e = self._rng.standard_normal(2)
                    qvel[0], qvel[1] = vx * (1.0 + r * e[0]), vz * (1.0 + r * e[1])
                else:
                    qvel[0], qvel[1] = vx, vz
            else:
                qvel[0], qvel[1] = vx, vz
            qpos[0], qpos[1] = x, z
        else:
            bx, bz = float(qpos[0]), float(qpos[1])
            if float(qvel[1]) < 0.0 and math.hypot(x - bx, z - bz) <= task.catch_radius:
                self._held = caught = True
                qpos[0], qpos[1] = x, z
                qvel[0], qvel[1] = vx, vz
            elif bz < task.floor_z:
                dropped = True
        self.state = self._make_state(released, caught, dropped)
        return self.state

    # -- helpers ------------------------------------------------------------------------
    @property
    def held(self) -> bool:
        """Whether the ball is in the hand."""
        return self._held

    def sync(self) -> None:
        """Recompute the bodies' poses (``data.xpos``) after the state copies, for drawing."""
        mujoco.mj_kinematics(self.model, self.data)

    def _make_state(self, released: bool, caught: bool, dropped: bool) -> JugglingState:
        return JugglingState(
            time=float(self.data.time),
            hand_pos=np.array(self._hand),
            hand_vel=np.array(self._hand_vel),
            ball_pos=self._qpos[:2].copy(),
            ball_vel=self._qvel[:2].copy(),
            held=self._held,
            released=released,
            caught=caught,
            dropped=dropped,
        )

    def __getstate__(self) -> dict[str, Any]:
        state = self.__dict__.copy()
        for key in ("_mocap", "_qpos", "_qvel"):
            del state[key]
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self._mocap = self.data.mocap_pos[0]
        self._qpos = self.data.qpos
        self._qvel = self.data.qvel
