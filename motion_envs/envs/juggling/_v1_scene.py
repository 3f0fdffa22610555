r"""The Juggling-v1 world: one actuated hand and one ball, the one juggling world's
(:class:`~motion_envs.envs.juggling._world.HandsWorld`) batch of one with
``WorldSpec.of(task, hands=1, balls=1)``.

In the style of dm_control's ``ball_in_cup``: the physics lives in the model
(:func:`~motion_envs.envs.juggling._world_mjcf.world_mjcf`: joints, motors with force limits,
contacts), the control period in :mod:`~motion_envs.envs.juggling._period` (the servo
within a human hand's limits, the grasp rule), and :class:`JugglingV1World` is the thin
task on top: it returns the world's TRUE state as a
:class:`~motion_envs.datasets.juggling.JugglingState`.

**The servo.** Every 5 ms control period the controller gives a target ``h_k``; during
the period's physics steps the motor force is ``m a`` with the computed-torque servo

.. math:: a = a_{ref} + k_p (p_{ref} - p) + k_d (v_{ref} - v)

(``p_ref`` moving linearly from ``h_{k-1}`` to ``h_k``, ``v_ref = (h_k - h_{k-1}) / dt``,
``a_ref`` its backward difference; ``k_p = w^2``, ``k_d = 2 w``, ``w = servo_omega``),
clipped so that ``|a| <= accel_limit`` and the hand's speed after the physics step stays
``<= speed_limit``; the command itself is rate limited (a step longer than
``speed_limit dt`` is shortened), so a target 1 m away is approached at the speed limit.

**The grasp rule** (the fingers): a held ball rides in the hand (its contacts off). The
controller arms the release; the ball is released when the hand's vertical acceleration
is below ``-toss_threshold`` (``3 g``), measured as the demonstrations measure it: the
second backward difference of the hand's height at the control samples
(:func:`~motion_envs.datasets.juggling.rules.hand_acceleration`; before time 0 the hand
moves at its reset velocity), with the hand's velocity perturbed in speed and angle
(:func:`~motion_envs.models.juggling.perturb_release`). A flying ball is **captured**
under the rule of :mod:`~motion_envs.envs.juggling._world` (falling, touching the palm
above its top face, slower than ``capture_speed`` relative to the hand at a physics
step; it must have left the palm once since the release). **A drop** is any contact of
the ball with the floor (or its lowest point at or below it).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from motion_envs.datasets.juggling import JugglingState, JugglingTask
from motion_envs.envs.juggling._world import HandsWorld
from motion_envs.envs.juggling._world_spec import WorldSpec
from motion_envs.models.juggling import xz_pair

__all__ = ["JugglingV1World"]


class JugglingV1World(HandsWorld):
    """One hand, one ball (see the module docstring).

    ``reset(hand_pos, rng=...)`` and ``step(hand_target, release_armed)`` return the TRUE
    :class:`~motion_envs.datasets.juggling.JugglingState` (what a controller sees goes
    through :class:`~motion_envs.models.juggling.BallSensor`).

    Parameters
    ----------
    task:
        The task constants (gravity, dt, ball, floor, toss threshold).
    release_speed_std, release_angle_std:
        Release noise: relative speed error and direction error (rad), per toss.
    spec:
        The world (one hand, one ball, ``task``'s constants); None: ``WorldSpec.of(task)``
        (Juggling-v2 passes its own: air and the capture at impact).
    """

    def __init__(
        self,
        task: JugglingTask,
        release_speed_std: float = 0.0,
        release_angle_std: float = 0.0,
        spec: WorldSpec | None = None,
    ) -> None:
        spec = WorldSpec.of(task, hands=1, balls=1) if spec is None else spec
        if (spec.hands, spec.balls) != (1, 1):
            raise ValueError(f"spec must have one hand and one ball; got {spec!r}")
        super().__init__(spec, release_speed_std, release_angle_std)
        self.task = task
        self._reset = False

    def reset(
        self,
        hand_pos: ArrayLike,
        *,
        rng: np.random.Generator | None = None,
        hand_vel: ArrayLike = (0.0, 0.0),
    ) -> JugglingState:
        """Hand at ``hand_pos`` moving at ``hand_vel`` (default at rest), ball held in it,
        time 0; the scene placed (camera and lights included) before any physics step."""
        pos = np.array([xz_pair(hand_pos, "hand_pos")])
        vel = np.array([xz_pair(hand_vel, "hand_vel")])
        self._rng = rng
        self.reset_state(pos, vel, (0,), (-1,), pos, vel)
        self.caught[0, 0] = self.released[0, 0] = -1
        self._reset = True
        return self._make_state(False, False)

    def step(self, hand_target: ArrayLike, release_armed: bool) -> JugglingState:
        """One control period: servo the hand toward ``hand_target`` (rate limited), grasp
        rule after every physics step, release decision at the period's end."""
        if not self._reset:
            raise RuntimeError("call reset() before step()")
        tx, tz = xz_pair(hand_target, "hand_target")
        return self.advance(tx, tz, release_armed)

    def advance(self, tx: float, tz: float, release_armed: bool) -> JugglingState:
        """:meth:`step` toward the finite floats ``(tx, tz)``, unchecked (the env's hot
        path; the episode must have been reset)."""
        self.period(((tx, tz),), (release_armed,))
        return self._make_state(bool(self.released[0, 0] >= 0), bool(self.caught[0, 0] >= 0))

    def launch(self, ball_pos: ArrayLike, ball_vel: ArrayLike) -> JugglingState:
        """Put the ball in flight at ``ball_pos`` with ``ball_vel`` (as if tossed long ago:
        it may be captured at once), the hand unchanged; for tests and demonstrations."""
        self.launch_ball(0, xz_pair(ball_pos, "ball_pos"), xz_pair(ball_vel, "ball_vel"))
        self.caught[0, 0] = self.released[0, 0] = -1
        return self._make_state(False, False)

    @property
    def state(self) -> JugglingState | None:
        """The TRUE state now (None before the first reset): after a control period,
        whether it caught or released the ball (the period's, also when the
        environment's batch of one stepped it)."""
        if not self._reset:
            return None
        return self._make_state(bool(self.released[0, 0] >= 0), bool(self.caught[0, 0] >= 0))

    @property
    def held(self) -> bool:
        """Whether the ball is in the hand."""
        return bool(self.holder[0, 0] >= 0)

    def _make_state(self, released: bool, caught: bool) -> JugglingState:
        q, v = self.data.qpos, self.data.qvel
        return JugglingState(
            time=float(self.data.time),
            hand_pos=q[0:2].copy(),
            hand_vel=v[0:2].copy(),
            ball_pos=q[2:4].copy(),
            ball_vel=v[2:4].copy(),
            held=self.held,
            released=released,
            caught=caught,
            dropped=bool(self.dropped[0, 0]),
        )
