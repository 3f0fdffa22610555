r"""The Cascade-v0 world: two actuated hands and the pattern's balls (3 by default), the
one juggling world's (:class:`~motion_envs.envs.juggling._world.HandsWorld`) batch of one
with ``WorldSpec.of(task, hands=2, balls=balls)``.

Each hand is servoed and each ball caught, held and released under the rules of
:mod:`~motion_envs.envs.juggling._period`, per hand:

* a hand holds at most one ball; a held ball follows the hand origin with its contacts
  off (in the fingers);
* a held ball is released at the end of a control period when its hand's release is
  armed and the hand's vertical acceleration is below ``-toss_threshold``, measured as
  the demonstrations and Juggling-v1 measure it (the second backward difference of the
  hand's height at the control samples; the hands rest before time 0); it leaves with the
  hand's velocity scattered in speed and angle
  (:func:`~motion_envs.models.juggling.perturb_release`);
* a flying ball that has left its thrower (farther than two radii from it) is captured by
  an EMPTY hand when it falls, touches that hand's palm and is slower than
  ``capture_speed`` relative to the hand; otherwise it bounces off the palm;
* a ball touching the floor (or its lowest point at or below ``floor_z``) is dropped
  (sticky).

Balls do not collide with each other, palms neither with each other nor with the floor.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from motion_envs.datasets.juggling import CASCADE_BALLS, CASCADE_HANDS, JugglingTask
from motion_envs.envs.juggling._world import HandsWorld
from motion_envs.envs.juggling._world_spec import WorldSpec
from motion_envs.models.juggling import CascadeStart, CascadeState

__all__ = ["CascadeWorld"]


class CascadeWorld(HandsWorld):
    """The cascade task on MuJoCo (see the module docstring).

    ``reset(hand_pos, start=..., rng=...)`` and ``step(targets, armed)`` return the TRUE
    :class:`~motion_envs.models.juggling.CascadeState`. qpos/qvel layout: right hand
    ``x, z``, left hand ``x, z``, then ``x, z`` of balls 0, 1, ..., ``balls - 1``. The
    parameters are :class:`~motion_envs.envs.juggling.JugglingV1World`'s (the task
    constants, the release noise per toss, ``spec``: None for ``WorldSpec.of(task,
    hands=2, balls=balls)``; Cascade-v1 passes air and the capture at impact) and the
    number of balls.
    """

    def __init__(
        self,
        task: JugglingTask,
        release_speed_std: float = 0.0,
        release_angle_std: float = 0.0,
        balls: int = CASCADE_BALLS,
        spec: WorldSpec | None = None,
    ) -> None:
        spec = WorldSpec.of(task, hands=CASCADE_HANDS, balls=balls) if spec is None else spec
        if (spec.hands, spec.balls) != (CASCADE_HANDS, balls):
            raise ValueError(f"spec must have 2 hands and {balls} balls; got {spec!r}")
        super().__init__(spec, release_speed_std, release_angle_std)
        self.task = task
        self.state: CascadeState | None = None

    def reset(
        self,
        hand_pos: ArrayLike,
        *,
        start: CascadeStart | None = None,
        rng: np.random.Generator | None = None,
    ) -> CascadeState:
        """Hands at rest at ``hand_pos`` ``(2, 2)``, the balls as ``start`` says (required:
        :meth:`~motion_envs.models.juggling.CascadeController.start`; a held ball in its
        hand, a flying one at its position and velocity). Time 0; the scene placed
        (camera and lights included) before any physics step."""
        hands = np.asarray(hand_pos, dtype=np.float64)
        if hands.shape != (CASCADE_HANDS, 2) or not np.isfinite(hands).all():
            raise ValueError(f"hand_pos must be a finite (2, 2) array; got {hand_pos!r}")
        if start is None:
            raise ValueError("start (the balls at t = 0) is required")
        n = self.spec.balls
        bp = np.asarray(start.ball_pos, dtype=np.float64)
        bv = np.asarray(start.ball_vel, dtype=np.float64)
        if (
            bp.shape != (n, 2)
            or bv.shape != (n, 2)
            or len(start.holder) != n
            or len(start.thrower) != n
            or not (np.isfinite(bp).all() and np.isfinite(bv).all())
        ):
            raise ValueError(f"start must hold {n} balls' finite (x, z) rows; got {start!r}")
        self._rng = rng
        self.reset_state(hands, np.zeros((2, 2)), start.holder, start.thrower, bp, bv)
        self.state = self._make_state((-1, -1), (-1, -1))
        return self.state

    def step(self, targets: ArrayLike, armed: tuple[bool, bool]) -> CascadeState:
        """One control period: servo both hands toward ``targets`` ``(2, 2)`` (rate
        limited), grasp rule after every physics step, releases at the period's end."""
        if self.state is None:
            raise RuntimeError("call reset() before step()")
        tg = np.asarray(targets, dtype=np.float64)
        if tg.shape != (CASCADE_HANDS, 2) or not all(math.isfinite(x) for x in tg.ravel().tolist()):
            raise ValueError(f"targets must be a finite (2, 2) array; got {targets!r}")
        self.period(tg, armed)
        released, caught = self.released[0].tolist(), self.caught[0].tolist()
        self.state = self._make_state((released[0], released[1]), (caught[0], caught[1]))
        return self.state

    def launch(self, ball: int, position: ArrayLike, velocity: ArrayLike) -> CascadeState:
        """Put ``ball`` in flight at ``position`` with ``velocity`` (as if thrown long ago:
        it may be captured at once), the hands unchanged; for tests."""
        self.launch_ball(ball, position, velocity)
        self.state = self._make_state((-1, -1), (-1, -1))
        return self.state

    def _make_state(self, released: tuple[int, int], caught: tuple[int, int]) -> CascadeState:
        q, v = self.data.qpos, self.data.qvel
        end = 4 + 2 * self.spec.balls
        return CascadeState(
            time=float(self.data.time),
            hand_pos=np.array(q[0:4]).reshape(2, 2),
            hand_vel=np.array(v[0:4]).reshape(2, 2),
            ball_pos=np.array(q[4:end]).reshape(-1, 2),
            ball_vel=np.array(v[4:end]).reshape(-1, 2),
            holder=tuple(self.holder[0].tolist()),
            released=released,
            caught=caught,
            dropped=tuple(bool(d) for d in self.dropped[0].tolist()),
        )
