r"""The MuJoCo juggling world: a kinematic hand, a ball under gravity, explicit hold and release.

:class:`JugglingScene` has the interface and the semantics of the pure-model
``BallisticWorld`` (:mod:`motion_envs.models.juggling`; both satisfy its ``JugglingWorld``
protocol): ``reset(hand_pos)`` puts the ball in the hand, ``step(hand_target,
release_armed)`` advances one control period ``dt``. The scene is ``juggling.xml`` (beside
this module, SI units, its values the defaults of ``JugglingTask``; tested) with the
constants of the task it is given written into the compiled model (timestep ``dt``,
gravity ``(0, 0, -g)``, ball radius and mass, catch radius, floor height).

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
  ``g dt t / 2`` (2.5 mm after 1 s at the default g = 1 m/s^2, 25 mm at 9.81).
* **Holding is a state copy, not a weld.** While held, the ball's ``qpos``/``qvel`` are
  set to the hand's position and finite-difference velocity after each step, so the ball
  follows the hand exactly (a weld equality is a soft constraint and would not). A toss
  sets the ball's velocity to the hand's times ``1 + release noise``; a catch (the ball,
  once it has left the hand, back within ``catch_radius`` of it) snaps it into the hand.
  Contacts are disabled: nothing collides, so ``data.warning`` stays empty whatever the
  hand does.

Step order: exactly ``BallisticWorld``'s, with the same rule functions
(:mod:`motion_envs.datasets.juggling.rules`: ``hand_velocity``, ``hand_acceleration``,
``release_fires``, ``release_velocity``, ``catch_fires``, ``has_left``, ``drop_fires``;
the flight is MuJoCo's) and the same noise draws
(:func:`~motion_envs.models.juggling.draw_episode_noise`, at reset), so that for the same
hand targets and generator both give the same states to round-off (tested to 1e-9):

1. ``h_k = hand_target``; ``v_k = (h_k - h_{k-1}) / dt``,
   ``a_k = (h_k - 2 h_{k-1} + h_{k-2}) / dt^2`` (the hand rests at the reset position);
   one ``mj_step`` if the ball is flying (it moves along its parabola; a held ball is a
   copy of the hand, nothing to integrate, so the step is skipped); time ``k dt``.
2. Held ball: released (``released``) at ``h_k`` with velocity ``v_k * f`` if
   ``release_armed`` and ``a_k[z] < -toss_threshold`` (``f = 1 + release * N(0, 1)`` per
   component, drawn at reset); else it stays at ``h_k`` with velocity ``v_k``.
3. Flying ball: once it has been farther than ``catch_radius`` from the hand, a closest
   approach over the period (``rules.swept_distance``) ``<= catch_radius`` is a catch
   (``caught``; held again, its state copied from the hand); a flying ball whose centre
   is below ``floor_z`` is ``dropped`` (sticky until reset; a dropped ball is not caught).

The state's ``hand_pos`` is what the controller observes: the hand plus the episode's
tracking noise (``JugglingNoise.tracking``); ``hand_vel`` is the true hand's.
"""

from __future__ import annotations

import math
from importlib import resources
from typing import Any

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray

from motion_envs.datasets.juggling import JugglingNoise, JugglingState, JugglingTask, rules
from motion_envs.models.juggling import draw_episode_noise, tracked_hand

__all__ = ["SCENE_XML", "JugglingScene", "check_task", "load_juggling_model"]

#: The scene's MJCF (package data, beside this module).
SCENE_XML = "juggling.xml"


def check_task(task: Any) -> JugglingTask:
    """``task`` if it is a :class:`JugglingTask` (which checks its own constants)."""
    if not isinstance(task, JugglingTask):
        raise ValueError(f"task must be a JugglingTask; got {type(task).__name__}")
    return task


def load_juggling_model(task: JugglingTask | None = None) -> mujoco.MjModel:
    """Compile ``juggling.xml`` with the constants of ``task`` (default task)."""
    task = check_task(JugglingTask() if task is None else task)
    xml = resources.files("motion_envs.envs.juggling").joinpath(SCENE_XML).read_text()
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
    world's time); ``state`` the last :class:`JugglingState`; ``release_factor`` and
    ``tracking_noise`` the episode's noise (as ``BallisticWorld``'s).
    """

    def __init__(self, task: JugglingTask | None = None) -> None:
        self.task = check_task(JugglingTask() if task is None else task)
        self.model = load_juggling_model(self.task)
        self.data = mujoco.MjData(self.model)
        self._bind()
        self.noise = JugglingNoise()
        self.release_factor = (1.0, 1.0)
        self.tracking_noise: NDArray[np.float64] | None = None
        self._k = 0
        self._hand = (0.0, 0.0)
        self._prev = (0.0, 0.0)
        self._held = True
        self._left = False
        self._dropped = False
        self.state: JugglingState | None = None
        #: the last state's tracked hand, hand velocity, ball and ball velocity (8 floats)
        self.values: tuple[float, ...] = ()

    def _bind(self) -> None:
        self._mocap = self.data.mocap_pos[0]
        self._qpos = self.data.qpos
        self._qvel = self.data.qvel

    # -- interface ----------------------------------------------------------------------
    def reset(
        self,
        hand_pos: ArrayLike,
        *,
        noise: JugglingNoise | None = None,
        rng: np.random.Generator | None = None,
    ) -> JugglingState:
        """Hand at rest at ``hand_pos``, ball held in it, time 0; draws the episode's noise."""
        p = _vec2(hand_pos, "hand_pos")
        noise = JugglingNoise() if noise is None else noise
        if not isinstance(noise, JugglingNoise):
            raise ValueError(f"noise must be a JugglingNoise; got {type(noise).__name__}")
        self.noise = noise
        self.redraw_noise(rng)
        mujoco.mj_resetData(self.model, self.data)
        x, z = float(p[0]), float(p[1])
        self._hand = self._prev = (x, z)
        self._k = 0
        self._held, self._left, self._dropped = True, False, False
        self._mocap[0], self._mocap[2] = x, z
        self._qpos[0], self._qpos[1] = x, z
        mujoco.mj_kinematics(self.model, self.data)
        self.state = self._make_state(False, False)
        return self.state

    def step(self, hand_target: ArrayLike, release_armed: bool) -> JugglingState:
        """Move the hand to ``hand_target`` over one ``dt``; hold, release, catch or drop."""
        if self.state is None:
            raise RuntimeError("call reset() before step()")
        x, z = float(hand_target[0]), float(hand_target[1])  # type: ignore[index, arg-type]
        if not (math.isfinite(x) and math.isfinite(z)):
            raise ValueError(f"hand_target must be finite; got {[x, z]}")
        task = self.task
        dt = task.dt
        prev2 = self._prev
        prev = self._prev = self._hand
        self._hand = (x, z)
        self._k += 1
        vx, vz = rules.hand_velocity(x, prev[0], dt), rules.hand_velocity(z, prev[1], dt)
        az = rules.hand_acceleration(z, prev[1], prev2[1], dt)
        self._mocap[0], self._mocap[2] = x, z
        ball0 = (float(self._qpos[0]), float(self._qpos[1]))
        if not self._held:  # a held ball is a copy of the hand: nothing to integrate
            mujoco.mj_step(self.model, self.data)
        self.data.time = self._k * dt  # k dt exactly, as BallisticWorld (no summed round-off)
        qpos, qvel = self._qpos, self._qvel
        released = caught = False
        if self._held:
            if rules.release_fires(release_armed, az, task.toss_threshold):
                self._held = self._left = False
                released = True
                f = self.release_factor
                qvel[0], qvel[1] = rules.release_velocity(vx, vz, f[0], f[1])
            else:
                qvel[0], qvel[1] = vx, vz
            qpos[0], qpos[1] = x, z
        else:
            dist = math.hypot(x - float(qpos[0]), z - float(qpos[1]))
            swept = float(
                rules.swept_distance(
                    prev[0] - ball0[0], prev[1] - ball0[1], x - float(qpos[0]), z - float(qpos[1])
                )
            )
            caught = bool(rules.catch_fires(swept, self._left, self._dropped, task.catch_radius))
            self._left = bool(rules.has_left(dist, self._left, caught, task.catch_radius))
            if caught:
                self._held = True
                qpos[0], qpos[1] = x, z
                qvel[0], qvel[1] = vx, vz
            self._dropped = self._dropped or bool(
                rules.drop_fires(float(qpos[1]), self._held, task.floor_z)
            )
        self.state = self._make_state(released, caught)
        return self.state

    def redraw_noise(self, rng: np.random.Generator | None) -> None:
        """Draw a new release factor and tracking noise (as ``reset`` does), keeping the
        state: a new cycle of a continuous run. Not part of ``BallisticWorld``."""
        factor, self.tracking_noise = draw_episode_noise(self.noise, rng)
        self.release_factor = (float(factor[0]), float(factor[1]))

    # -- helpers ------------------------------------------------------------------------
    @property
    def held(self) -> bool:
        """Whether the ball is in the hand."""
        return self._held

    @property
    def hand_true(self) -> NDArray[np.float64]:
        """The hand's true position (without tracking noise)."""
        return np.array(self._hand)

    def sync(self) -> None:
        """Recompute the bodies' poses (``data.xpos``) after the state copies, and place the
        cameras and lights, for drawing (a held ball is never integrated, so no ``mj_step``
        places them before the first release)."""
        mujoco.mj_kinematics(self.model, self.data)
        mujoco.mj_camlight(self.model, self.data)

    def _make_state(self, released: bool, caught: bool) -> JugglingState:
        dt = self.task.dt
        hx, hz = self._hand
        px, pz = self._prev
        obs = tracked_hand(np.array(self._hand), self.tracking_noise, self._k)
        ball_pos, ball_vel = self._qpos[:2].copy(), self._qvel[:2].copy()
        hand_vel = (rules.hand_velocity(hx, px, dt), rules.hand_velocity(hz, pz, dt))
        self.values = (*obs.tolist(), *hand_vel, *ball_pos.tolist(), *ball_vel.tolist())
        return JugglingState(
            time=float(self.data.time),
            hand_pos=obs,
            hand_vel=np.array(hand_vel),
            ball_pos=ball_pos,
            ball_vel=ball_vel,
            held=self._held,
            released=released,
            caught=caught,
            dropped=self._dropped,
        )

    def __getstate__(self) -> dict[str, Any]:
        state = self.__dict__.copy()
        for key in ("_mocap", "_qpos", "_qvel"):
            del state[key]
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self._bind()
