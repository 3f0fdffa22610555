r"""The juggling world, one for every pattern: a spec, its MJCF, and the world on MuJoCo.

:class:`WorldSpec` says what a world is: how many hands (1 or 2) and balls (1 to 5), the
task's gravity, control period, ball and floor, and the human limits of the hands (mass,
speed, acceleration, servo bandwidth) and of the catch (``capture_speed``). Everything
about the physics comes from it: :func:`~motion_envs.envs.juggling._world_mjcf.world_mjcf`
writes the one MJCF of any spec
(bodies, joints, motors and their force range ``hand_mass x accel_limit``, contacts,
contact sensors), and :class:`HandsWorld` steps it with the one control period of
:mod:`~motion_envs.envs.juggling._period` (compiled by numba when it is installed; the
single world is the batch of one through the same function as the native vector
environments).

**The hand** is a ``hand_mass`` body on two slide joints (``x``, ``z``), gravity
compensated (the arm holds its own weight), driven by two motors whose force range is
``hand_mass x accel_limit`` per axis, and stopped at the floor by a joint limit (its palm
cannot pass below the floor). Human limits (defaults ``speed_limit = 6 m/s``,
``accel_limit = 120 m/s^2``): ISO 13855:2010 takes 2.0 m/s as the approach speed of a
person's hand/arm for safety distances (a typical fast reach, not a maximum); fast
ballistic arm movements go far beyond (hand speeds in overarm throwing exceed 15 m/s,
e.g. Atwater, Exerc. Sport Sci. Rev. 7, 1979); the SIMULATED demonstrations at
9.81 m/s^2 peak at 5.1 m/s and 91 m/s^2: the limits are those peaks with a 20-30 % margin.

**The palm** is a box under the hand origin (a held ball's centre sits at the origin);
palms collide with balls only. **Balls** are spheres on two slide joints each; they
collide with the palms and the floor, not with each other (in a real pattern they fly in
slightly different planes). **The floor** is a plane at ``floor_z``; a ball touching it is
a drop.

**The capture rule as it behaves** (tested by a sweep of closing speeds and offsets): a
falling ball that touches an empty hand's palm, its centre above the palm's top face, is
caught when its speed relative to the hand is below ``capture_speed`` *at a physics step
at which the contact is active*. The soft contact (``solref`` 4 ms) slows a fast ball
within a step or two of touching, so a ball hitting a still palm much faster than
``capture_speed`` is usually caught too, on the step after the contact has slowed it;
only a ball that the contact throws back up (or off the palm's edge) before it is slow
enough bounces off. ``capture_speed`` is therefore a limit on the relative speed at which
the fingers close, not on the speed of the impact.

**Capture at impact** (``impact_capture=True``, Juggling-v2's world): the rule in the
hand's frame. A ball is caught only at the physics step at which its contact with an
empty palm BEGINS (the contact sensor reports it, and did not at the step before), when
the ball's velocity relative to the hand just before that step (before the contact's
force acted) points at the palm (relative ``v_z < 0``) and its magnitude, the speed at
which the palm meets the ball, is below ``capture_speed``; its centre must be above the
palm's top face and it must have left its thrower. A ball that meets the palm faster
bounces off (the contact computes the bounce) and cannot be caught during that contact;
it may be caught at a later contact that begins slowly enough.

**Air drag** (``air_density > 0``): MuJoCo's fluid model (``option density``; every ball
geom and palm with ``fluidshape="ellipsoid"``, every coefficient 0 but a ball's blunt
drag; the air at rest, no viscosity). On a sphere of radius ``r`` moving at ``v`` it is
the quadratic drag ``F = -rho C_b pi r^2 |v| v``, MuJoCo's blunt-drag coefficient ``C_b``
being half the textbook drag coefficient (``F = 1/2 rho C_d A v^2``, ``A = pi r^2``;
checked against ``mj_forward``). :meth:`HandsWorld.set_drag` sets a ball's drag per
episode as ``k = rho C_d A / (2 m)`` (1/m, the deceleration per squared speed, the
only number of the drag that the flight depends on): the world's ball keeps its mass and
radius and flies as a ball with that ``k`` (a table-tennis ball, 2.7 g, 40 mm, ``C_d``
0.5: ``k = 0.14/m``; a 130 g 70 mm juggling ball, ``C_d`` 0.47: ``0.009/m``). The palms
carry zero coefficients (a body with an ellipsoid geom gets no inertia-box drag; the
hands feel no air) and the balls slide without rotating (no Magnus lift; the added-mass
terms vanish without rotation).
"""

from __future__ import annotations

import math
from typing import Any

import mujoco
import numpy as np
from numpy.typing import NDArray

from motion_envs.envs._kernels import numba_available
from motion_envs.envs.juggling import _period
from motion_envs.envs.juggling._world_mjcf import load_world_model, palm_name
from motion_envs.envs.juggling._world_spec import BALL_CONAFFINITY, BALL_CONTYPE, WorldSpec
from motion_envs.models.juggling import perturb_release

__all__ = ["HandsWorld"]


class HandsWorld:
    """A world of ``spec.hands`` actuated hands and ``spec.balls`` balls on MuJoCo.

    Its state is the batch of one that :func:`~motion_envs.envs.juggling._period.world_periods`
    steps (arrays with a leading axis of 1): ``ref, vref (1, H, 2)``, ``z_before (1, H)``,
    ``holder, thrower (1, B)``, ``left, dropped (1, B)``, ``k (1,)``; the native vector
    environments copy these rows into their own batch at a reset.

    Parameters
    ----------
    spec:
        The world.
    release_speed_std, release_angle_std:
        Release scatter per toss: relative speed error and direction error (rad).
    backend:
        ``"auto"`` (numba when installed), ``"numba"`` or ``"python"``: which path runs
        the period (bit-identical).
    """

    def __init__(
        self,
        spec: WorldSpec,
        release_speed_std: float = 0.0,
        release_angle_std: float = 0.0,
        backend: str = "auto",
    ) -> None:
        if backend not in ("auto", "numba", "python"):
            raise ValueError(f"backend must be 'auto', 'numba' or 'python'; got {backend!r}")
        if backend == "numba" and not numba_available():
            raise ValueError("backend='numba' needs numba (pip install 'motion-envs[fast]')")
        self.backend = (
            ("numba" if numba_available() else "python") if backend == "auto" else backend
        )
        self.spec = spec
        self.release_speed_std = float(release_speed_std)
        self.release_angle_std = float(release_angle_std)
        self._rng: np.random.Generator | None = None
        self.model = load_world_model(spec)
        self.data = mujoco.MjData(self.model)
        geom = mujoco.mjtObj.mjOBJ_GEOM
        self.palm_geoms = [
            mujoco.mj_name2id(self.model, geom, palm_name(h)) for h in spec.hand_names
        ]
        self.ball_geoms = np.array(
            [mujoco.mj_name2id(self.model, geom, b) for b in spec.ball_names], dtype=np.int64
        )
        self.floor_geom = mujoco.mj_name2id(self.model, geom, "floor")
        self.palm_top = spec.palm_top
        self.constants = spec.constants()
        h, b = spec.hands, spec.balls
        self.ref = np.zeros((1, h, 2))
        self.vref = np.zeros((1, h, 2))
        self.z_before = np.zeros((1, h))
        self.holder = np.full((1, b), -1, dtype=np.int64)
        self.thrower = np.full((1, b), -1, dtype=np.int64)
        self.left = np.ones((1, b), dtype=np.bool_)
        self.dropped = np.zeros((1, b), dtype=np.bool_)
        self.k = np.zeros(1, dtype=np.int64)
        self.caught = np.full((1, h), -1, dtype=np.int64)
        self.released = np.full((1, h), -1, dtype=np.int64)
        self._target = np.zeros((1, h, 2))
        self._armed = np.zeros((1, h), dtype=np.bool_)
        self._link()

    # -- the period's links to this world (made again after unpickling) ---------------------
    def _link(self) -> None:
        m, d = self.model, self.data
        self._one = np.zeros(1, dtype=np.int64)
        if self.backend == "numba":
            from motion_envs.envs.juggling import _compiled

            # the batch of one: each array a (1, n) view of the world's own buffer (a
            # typed list, as the vector environments pass, costs ~50 µs to unbox per call)
            self._links: tuple[Any, ...] = (
                np.array([m._address], dtype=np.uint64),
                np.array([d._address], dtype=np.uint64),
                d.qpos[None], d.qvel[None], d.ctrl[None], d.sensordata[None],
                m.geom_contype[None], m.geom_conaffinity[None],
            )  # fmt: skip
            self._periods = _compiled.entry_point(
                _compiled.world_periods, *self._period_args(self._one)
            )
        else:
            self._links = (
                [m._address],  # ints: what ctypes takes
                [d._address],
                [d.qpos], [d.qvel], [d.ctrl], [d.sensordata],
                [m.geom_contype], [m.geom_conaffinity],
            )  # fmt: skip
            self._periods = _period.world_periods

    def _period_args(self, envs: NDArray[np.int64]) -> tuple[Any, ...]:
        return (
            envs, self._links, self.ball_geoms, self._target, self._armed, self.ref,
            self.vref, self.z_before, self.holder, self.thrower, self.left, self.dropped,
            self.k, self.constants, self.caught, self.released,
        )  # fmt: skip

    def __getstate__(self) -> dict[str, Any]:
        state = self.__dict__.copy()
        for key in ("_links", "_periods"):
            state.pop(key, None)
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self._link()

    # -- setup ----------------------------------------------------------------------------
    def set_drag(self, ball: int, drag: float) -> None:
        """Give ``ball`` the quadratic air drag ``drag`` = ``k = rho C_d A / (2 m)`` (1/m;
        module docstring, *Air drag*): MuJoCo's blunt-drag coefficient of its geom becomes
        ``k m / (rho pi r^2)``. Needs a spec with air (``air_density > 0``)."""
        spec = self.spec
        if spec.air_density <= 0:
            raise ValueError("set_drag needs a world with air (WorldSpec.air_density > 0)")
        if not (math.isfinite(drag) and drag >= 0):
            raise ValueError(f"drag must be a finite number >= 0 (1/m); got {drag!r}")
        area = math.pi * spec.ball_radius**2
        g = int(self.ball_geoms[ball])
        self.model.geom_fluid[g, 1] = drag * spec.ball_mass / (spec.air_density * area)

    def set_contacts(self, ball: int, on: bool) -> None:
        """Switch ``ball``'s contacts on (flying) or off (held in the fingers)."""
        g = int(self.ball_geoms[ball])
        self.model.geom_contype[g] = BALL_CONTYPE if on else 0
        self.model.geom_conaffinity[g] = BALL_CONAFFINITY if on else 0

    def reset_state(
        self,
        hand_pos: NDArray[np.float64],
        hand_vel: NDArray[np.float64],
        holder: tuple[int, ...],
        thrower: tuple[int, ...],
        ball_pos: NDArray[np.float64],
        ball_vel: NDArray[np.float64],
    ) -> None:
        """Time 0: hands at ``hand_pos (H, 2)`` moving at ``hand_vel``; ball ``b`` held by
        ``holder[b]`` (at its hand, with its velocity) or flying from ``ball_pos[b]`` at
        ``ball_vel[b]``, thrown by ``thrower[b]`` (-1: long ago, it has left); the scene
        placed (camera and lights included) before any physics step."""
        spec = self.spec
        mujoco.mj_resetData(self.model, self.data)
        q, v = self.data.qpos, self.data.qvel
        nh = 2 * spec.hands
        q[:nh] = hand_pos.ravel()
        v[:nh] = hand_vel.ravel()
        for b in range(spec.balls):
            h, c = holder[b], nh + 2 * b
            q[c : c + 2] = hand_pos[h] if h >= 0 else ball_pos[b]
            v[c : c + 2] = hand_vel[h] if h >= 0 else ball_vel[b]
            self.set_contacts(b, h < 0)
        self.ref[0] = hand_pos
        self.vref[0] = hand_vel
        self.z_before[0] = hand_pos[:, 1] - hand_vel[:, 1] * spec.dt
        self.holder[0] = holder
        self.thrower[0] = thrower
        self.left[0] = [h < 0 for h in holder]  # a ball flying at time 0 has left
        self.dropped[0] = False
        self.k[0] = 0
        mujoco.mj_forward(self.model, self.data)

    def launch_ball(self, ball: int, position: Any, velocity: Any) -> None:
        """Put ``ball`` in flight at ``position`` with ``velocity`` (as if thrown long ago:
        it may be captured at once), the hands unchanged; for tests and demonstrations."""
        c = 2 * self.spec.hands + 2 * int(ball)
        self.data.qpos[c : c + 2] = np.asarray(position, dtype=np.float64)
        self.data.qvel[c : c + 2] = np.asarray(velocity, dtype=np.float64)
        self.holder[0, ball] = -1
        self.left[0, ball] = True
        self.set_contacts(ball, True)
        mujoco.mj_forward(self.model, self.data)

    # -- one control period -----------------------------------------------------------------
    def period(self, targets: Any, armed: Any) -> None:
        """One control period toward ``targets (H, 2)`` (finite; unchecked) with the
        releases ``armed (H,)``; :attr:`caught` and :attr:`released` say what happened
        (``[0, h]``: a ball or -1). A released ball leaves with its hand's velocity,
        scattered by the world's generator."""
        self._target[0] = targets
        self._armed[0] = armed
        self._periods(*self._period_args(self._one))
        self.data.time = int(self.k[0]) * self.spec.dt
        nh = 2 * self.spec.hands
        for h, b in enumerate(self.released[0].tolist()):
            if b >= 0:
                qvel = self.data.qvel
                vel = perturb_release(
                    qvel[2 * h : 2 * h + 2].copy(),
                    self.release_speed_std,
                    self.release_angle_std,
                    self._rng,
                )
                qvel[nh + 2 * b], qvel[nh + 2 * b + 1] = float(vel[0]), float(vel[1])

    def sync(self) -> None:
        """Recompute the poses and the camera/lights (``mj_forward``) for drawing."""
        mujoco.mj_forward(self.model, self.data)
