"""``MotionEnvs/Juggling-v1``: juggle one ball with an actuated hand, seeing the ball late."""

# ruff: noqa: E501  (the class docstring holds Gymnasium-style Markdown tables)

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import replace
from typing import Any

import gymnasium as gym
import numpy as np
from numpy.typing import NDArray

from motion_envs.datasets.juggling import JugglingState, JugglingTask
from motion_envs.envs._common import SideCameraMixin, as_action
from motion_envs.envs._kernels import numba_available
from motion_envs.envs.juggling._shared import LevelsEnvMixin
from motion_envs.envs.juggling._v1_batch import V1Batch, v1_info
from motion_envs.envs.juggling._v1_scene import JugglingV1World
from motion_envs.envs.juggling._world_spec import HAND_SPEED_LIMIT
from motion_envs.models.juggling import (
    CONTROLLERS,
    BallSensor,
    JugglerController,
    make_controller,
    v1_juggler,
    v1_likeness,
)

__all__ = [
    "DEFAULT_V1_REWARD_WEIGHTS",
    "HISTORY",
    "OBS_HEAD",
    "V1_CYCLE_TIME",
    "V1_OBS_DIM",
    "JugglingV1Env",
    "OneBallEnv",
]

#: Default reward weights (see the class docstring, section Rewards).
DEFAULT_V1_REWARD_WEIGHTS: Mapping[str, float] = {
    "catch": 10.0,
    "drop": 10.0,
    "likeness": 0.01,
    "action": 0.01,
}
#: Delayed ball measurements in the observation (newest first).
HISTORY = 4
#: Observation size (see the class docstring).
V1_OBS_DIM = 15 + 4 * HISTORY
#: s of simulated time per catch (at 9.81 m/s^2; times ``sqrt(9.81 / g)``) after which an
#: episode is truncated anyway; a cycle of the juggler lasts about 1.1 s at 9.81 m/s^2.
V1_CYCLE_TIME = 4.0
_POS_MARGIN = 10.0
#: The kinds (``OneBallEnv._OBS_KINDS``) of the observation's first 15 entries, the
#: batch's: hand position and velocity, held, the phase one-hot, the phase's time and
#: duration, the next target, the plan's end.
OBS_HEAD = ("x", "z", "v", "v", "1", "1", "1", "1", "1", "t", "t", "x", "z", "x", "z")
_SPEED_BOUND = 30.0


class OneBallEnv(SideCameraMixin, LevelsEnvMixin, gym.Env):
    """What the one-hand, one-ball environments (Juggling-v1, Juggling-v2) share: their
    episode is the batch of one of :attr:`_BATCH` (:class:`V1Batch`: the command with the
    residual, the world's period, the likeness, the reward, the episode's end, the
    observation's first 15 entries), its spaces, its reset's info, its step and its
    nominal episode.

    A subclass sets :attr:`_OBS_KINDS`; in ``__init__`` ``task``, ``home``, ``world``,
    ``controller``, ``likeness`` and the arguments, then calls :meth:`_init_spaces`; its
    ``reset`` ends with :meth:`_start`."""

    metadata: dict[str, Any] = {"render_modes": ["rgb_array"], "render_fps": 200}  # noqa: RUF012
    _DEFAULT_WEIGHTS = DEFAULT_V1_REWARD_WEIGHTS
    #: The batch class stepping the episodes.
    _BATCH: type[V1Batch] = V1Batch
    #: The kind of each observation entry, which gives its bounds: ``x``, ``z`` a
    #: position within ``_POS_MARGIN`` of the home (``z`` down to the floor's margin),
    #: ``v`` a speed within ``_SPEED_BOUND``, ``t`` a time within the time limit, ``1`` a
    #: flag; the batch's first 15 entries are :data:`OBS_HEAD`.
    _OBS_KINDS: tuple[str, ...]
    task: JugglingTask
    home: NDArray[np.float64]
    world: JugglingV1World
    controller: JugglerController

    def _init_spaces(self, time_limit: float) -> None:
        """The MuJoCo handles, the time limit, the spaces and the episode's bookkeeping."""
        self.model, self.data = self.world.model, self.world.data
        self.metadata = {**self.metadata, "render_fps": round(1.0 / self.task.dt)}
        self._time_limit = time_limit
        self.action_space = gym.spaces.Box(-1.0, 1.0, (2,), dtype=np.float32)
        low, high = self._bounds()
        self.observation_space = gym.spaces.Box(low, high, dtype=np.float32)
        self._low, self._high = low, high
        self._renderer: Any = None
        self._done = True
        #: the state the controller was shown at the reset (the batch's starting point)
        self._state: JugglingState | None = None
        #: the batch stepping this episode and its row (:meth:`_batch_row`)
        self._batch: V1Batch | None = None
        self._rows = np.zeros(1, dtype=np.int64)

    def _bounds(self) -> tuple[NDArray[np.float32], NDArray[np.float32]]:
        """The observation's bounds, entry by entry from its kind (:data:`_OBS_KINDS`)."""
        (hx, hz), m, v = self.home, _POS_MARGIN, _SPEED_BOUND
        fz, t = self.task.floor_z, self._time_limit
        ranges = {"x": (hx - m, hx + m), "z": (fz - m, hz + m), "v": (-v, v), "t": (0, t)}
        ranges["1"] = (0, 1)
        low, high = zip(*(ranges[kind] for kind in self._OBS_KINDS), strict=True)
        return np.array(low, dtype=np.float32), np.array(high, dtype=np.float32)

    @property
    def dt(self) -> float:
        """s of simulated time per step (one control period)."""
        return self.task.dt

    def _batch_row(self) -> tuple[V1Batch, NDArray[np.int64]]:
        """The batch this episode is stepped in and its row: the native vector
        environment's (set by it) or this environment's own batch of one."""
        if self._batch is None:
            backend = "numba" if numba_available() else "python"
            self._batch, self._rows = self._BATCH([self], backend), np.zeros(1, dtype=np.int64)
        return self._batch, self._rows

    def _start(
        self, true: JugglingState, state: JugglingState, seed: int
    ) -> tuple[NDArray[np.float32], dict[str, Any]]:
        """The end of a reset (the world, the sensors and the controller reset; ``state``
        what the controller was shown): the batch's row loaded, the observation and the
        reset's info."""
        batch, rows = self._batch_row()
        i = int(rows[0])
        self._state = state
        batch.load(i)
        self._done = False
        info = {
            "phase": self.controller.phase,
            "time": true.time,
            "hand": true.hand_pos.copy(),
            "ball": true.ball_pos.copy(),
            "seed": seed,
        }
        return batch.observation(i), info

    def step(self, action: Any) -> tuple[NDArray[np.float32], float, bool, bool, dict[str, Any]]:
        if self._done or self._state is None:
            raise RuntimeError("the episode has ended (or never started); call reset() first")
        obs, out = self._step_batch(as_action(action, (2,)))
        term, trunc = bool(out[0, 17] > 0.0), bool(out[0, 18] > 0.0)
        self._done = term or trunc
        info = v1_info(out)
        self._add_info(info, term)
        return obs, float(out[0, 0]), term, trunc, info

    def _step_batch(
        self, action: NDArray[np.float64]
    ) -> tuple[NDArray[np.float32], NDArray[np.float64]]:
        """One step of the batch with ``action (2,)``: the observation and the row."""
        batch, rows = self._batch_row()
        obs, out = batch.step(rows, action[None])
        return obs[0], out

    def _add_info(self, info: dict[str, Any], terminated: bool) -> None:
        """A subclass's own entries of a step's ``info`` (none here)."""

    def nominal_episode(self, seed: int) -> dict[str, Any]:
        """``reset(seed=seed)``, then the zero action until the episode ends (the
        controller alone; what the benchmarks score).

        Returns ``time (n,)``, ``hand (n, 2)`` and ``phase`` (n labels) at the reset and
        after every step (the values of the infos ``time``, ``hand`` and ``phase``), and the
        episode's ``tosses``, ``catches`` and ``dropped`` (it ended by a drop)."""
        _, info = self.reset(seed=seed)
        times = [float(info["time"])]
        hands = [info["hand"].tolist()]
        phases = [str(info["phase"])]
        zero = np.zeros(self.action_space.shape or (2,))  # Juggling-v2: with its timing entry
        terminated = truncated = False
        while not (terminated or truncated):
            _, _, terminated, truncated, info = self.step(zero)
            times.append(info["time"])
            hands.append(info["hand"].tolist())
            phases.append(info["phase"])
        return {
            "time": np.array(times, dtype=np.float64),
            "hand": np.array(hands, dtype=np.float64),
            "phase": phases,
            "tosses": info["tosses"],
            "catches": info["catches"],
            "dropped": terminated,
        }

    # -- rendering (SideCameraMixin.render) ----------------------------------------------
    def _sync_scene(self) -> None:
        self.world.sync()


class JugglingV1Env(OneBallEnv):
    r"""Toss and catch one ball with an actuated hand that sees the ball late.

    ## Description
    The juggling task of Lippi, Avizzano & Ruffaldi (2011, section III-A) in a physical
    world: one ball, one hand, the vertical plane (``x`` horizontal, ``z`` up, metres),
    real gravity (9.81 m/s^2) by default. MuJoCo does the physics with contacts on
    (:class:`~motion_envs.envs.juggling.JugglingV1World`): the hand is a 0.5 kg body on two slide
    joints driven by motors within a human hand's limits (``hand_speed_limit`` = 6 m/s,
    120 m/s^2; sources in that module), the ball lands on a palm and is captured only when
    falling, touching the palm and slower than 5 m/s relative to the hand (else it
    bounces off), and a ball touching the floor is a drop. The ball is seen through a
    sensor with the level's latency and noise (:class:`~motion_envs.models.juggling.BallSensor`);
    each toss is scattered in speed and angle. The analytic juggler (Juggling-v0's, eq. 9
    toss, eq. 10 catch correction, fitted on the training cycles of the built-in
    **SIMULATED** demonstrations at the env's gravity) commands the hand every 5 ms from the
    same delayed measurements; the agent adds a residual to each command. At ``level="easy"``
    the juggler catches almost every ball; at ``"medium"`` and ``"hard"`` the delay makes it
    drop (the latency-aware reference, ``controller="juggler_latency_aware"``, shows what
    predicting the delay buys).

    Levels (every value can also be passed on its own and then overrides the level's):

    | level    | `latency` (s) | `position_std` (m) | `velocity_std` (m/s) | `release_speed_std` | `release_angle_std` (deg) |
    |----------|---------------|--------------------|----------------------|---------------------|---------------------------|
    | `easy`   | 0.0           | 0.0                | 0.0                  | 0.05                | 4.0                       |
    | `medium` | 0.10          | 0.002              | 0.02                 | 0.08                | 6.0                       |
    | `hard`   | 0.11          | 0.004              | 0.05                 | 0.12                | 12.0                      |

    The zero action reproduces the reference controller exactly (the same world, sensor and
    seeds; tested against an independent loop).

    ## Action Space
    `Box(-1, 1, (2,), float32)`: the residual added to the controller's hand target, in
    units of `residual_scale` metres (``target + residual_scale * a``), applied once per
    step (one 5 ms control period). With `residual_phases`, the residual acts only while
    the hand is in one of those phases (the phase whose plan gave the period's target, as
    in Cascade-v0); in the others the hand follows the controller alone. Entries outside
    ``[-1, 1]`` are clipped; NaN counts as 0 (``info["action_invalid"]``). A wrong shape
    raises `ValueError`.

    | Num | Action                              | Control Min | Control Max | Type (Unit)                  |
    |-----|-------------------------------------|-------------|-------------|------------------------------|
    | 0   | horizontal residual of the target   | -1          | 1           | position (residual_scale m)  |
    | 1   | vertical residual of the target     | -1          | 1           | position (residual_scale m)  |

    ## Observation Space
    `Box(low, high, (31,), float32)`; positions within 10 m of the home point, speeds
    within 30 m/s (values beyond are clipped). Everything the controller's plan depends on
    is in it, and the last `HISTORY = 4` ball measurements (the sensor's delayed, noisy
    view, newest first; exact while the ball is held).

    | Num     | Observation                                                                 | Type (Unit)    |
    |---------|-----------------------------------------------------------------------------|----------------|
    | 0, 1    | hand position ``x, z`` (proprioception, exact)                              | position (m)   |
    | 2, 3    | hand velocity                                                               | velocity (m/s) |
    | 4       | 1 if the ball is held, else 0                                               | unitless       |
    | 5..8    | phase one-hot: toss, go_down, catch, return                                 | unitless       |
    | 9       | time within the phase                                                       | time (s)       |
    | 10      | duration of the current phase plan                                          | time (s)       |
    | 11, 12  | the controller's next hand target (its plan, no residual)                   | position (m)   |
    | 13, 14  | the plan's end point (in the catch phase: the planned catch point)          | position (m)   |
    | 15..30  | ball measurements ``x, z, vx, vz`` of the last 4 steps, newest first         | m, m/s         |

    ## Rewards
    ``reward = w_catch * caught - w_drop * dropped - w_likeness * likeness - w_action * |a|^2``
    (default weights ``catch: 10, drop: 10, likeness: 0.01, action: 0.01``; the likeness
    weight keeps an episode's summed likeness cost, ~0.1 m per step over ~800 steps, well
    under the drop's: with weight 1 a drop that ends the episode early paid off, and PPO
    learned to drop): ``likeness`` is
    the distance (m) of the hand's state ``(x, z, 0.1 s * v)`` to the nearest state of the
    same phase in the TRAINING demonstrations (:class:`~motion_envs.models.juggling.HumanLikeness`;
    never the controller's own plan, so the zero action is not its optimum); ``|a|^2`` is
    the whole (clipped) action's, also where `residual_phases` keeps the residual from
    acting (as in Cascade-v0). `info` holds
    each weighted term (``reward_catch``, ``reward_drop``, ``reward_likeness``,
    ``reward_action``), ``likeness``, ``catches`` and ``tosses`` so far (``cycles``:
    the same, Juggling-v0's name), ``phase``,
    ``held``, ``time``, the true ``hand`` and ``ball`` positions ``(x, z)`` (m) and
    ``action_invalid``.

    ## Starting State
    The hand rests at the juggler's home with the ball in it, time 0, toss phase.
    `reset(seed=S)` seeds three independent streams ``SeedSequence(S).spawn(3)``: the
    world (release noise), the sensor (measurement noise) and the controller (its random
    phase end points and durations).

    ## Episode End
    ### Termination
    The ball touches the floor (a drop).

    ### Truncation
    After `max_catches` catches, or ``max_catches * 4 s * sqrt(9.81 / g)`` of simulated time.

    ## Arguments
    ```python
    import gymnasium as gym
    import motion_envs
    env = gym.make("MotionEnvs/Juggling-v1", level="medium")
    ```

    | Parameter           | Type      | Default     | Description |
    |---------------------|-----------|-------------|-------------|
    | `level`             | **str**   | `"medium"`  | `"easy"`, `"medium"` or `"hard"` (table above) |
    | `latency`           | **float** | `None`      | s, the ball measurement's delay (rounded to 5 ms); None: the level's |
    | `position_std`      | **float** | `None`      | m, measurement noise of the ball position; None: the level's |
    | `velocity_std`      | **float** | `None`      | m/s, measurement noise of the ball velocity; None: the level's |
    | `release_speed_std` | **float** | `None`      | relative std of the release speed; None: the level's |
    | `release_angle_std` | **float** | `None`      | degrees, std of the release direction; None: the level's |
    | `gravity`           | **float** | `9.81`      | m/s^2; `1.0` is the paper's slow virtual world (`PAPER_GRAVITY`) |
    | `controller`        | **str**   | `"juggler"` | the controller the residual acts on: `juggler`, `juggler_latency_aware`, `fixed_point`, `commanded_intercept` |
    | `max_catches`       | **int**   | `10`        | catches after which the episode is truncated |
    | `residual_scale`    | **float** | `0.05`      | m of residual for an action of 1 |
    | `residual_phases`   | **tuple** | `None`      | phases (`toss`, `go_down`, `catch`, `return`) in which the hand's residual acts; None: all |
    | `reward_weights`    | **dict**  | `None`      | keys `catch`, `drop`, `likeness`, `action` |
    | `render_mode`       | **str**   | `None`      | `None` or `"rgb_array"` (camera `side`) |
    | `width`             | **int**   | `480`       | frame width in pixels |
    | `height`            | **int**   | `480`       | frame height in pixels |

    ## Version History
    * v1: MuJoCo contacts and an actuated hand with human limits, real gravity, a delayed
      noisy ball sensor shared by agent and juggler, difficulty levels, speed-and-angle
      release noise, a Markov observation, human-likeness against the training
      demonstrations (``residual_phases`` added later; its default, None, leaves every
      rollout unchanged).
    * v0: the paper's setting (kinematic hand, exact ball state).
    """

    #: Ball measurements in the observation.
    history = HISTORY
    _OBS_KINDS = (*OBS_HEAD, *("x", "z", "v", "v") * HISTORY)
    _CONTROLLERS = CONTROLLERS

    def __init__(
        self,
        level: str = "medium",
        latency: float | None = None,
        position_std: float | None = None,
        velocity_std: float | None = None,
        release_speed_std: float | None = None,
        release_angle_std: float | None = None,
        gravity: float = 9.81,
        controller: str = "juggler",
        max_catches: int = 10,
        residual_scale: float = 0.05,
        residual_phases: Sequence[str] | None = None,
        reward_weights: Mapping[str, float] | None = None,
        render_mode: str | None = None,
        width: int = 480,
        height: int = 480,
    ) -> None:
        self._init_arguments(
            (level, latency, position_std, velocity_std, release_speed_std, release_angle_std),
            (gravity, controller, max_catches, residual_scale, residual_phases, reward_weights),
            (render_mode, width, height),
        )
        self.task = JugglingTask(gravity=self.gravity)
        juggler = v1_juggler(self.gravity)
        self.home = np.asarray(juggler.home_, dtype=np.float64)
        self.delay_steps = round(self.latency / self.task.dt)
        self.controller: JugglerController = make_controller(
            self.controller_name, juggler, self.delay_steps * self.task.dt
        )
        self.likeness = v1_likeness(self.gravity, "train")
        self.world = JugglingV1World(
            self.task, self.release_speed_std, math.radians(self.release_angle_std)
        )
        self.sensor = BallSensor(self.delay_steps, self.position_std, self.velocity_std)
        #: m/s, the hand's speed limit.
        self.hand_speed_limit = HAND_SPEED_LIMIT
        self._init_spaces(self.max_catches * V1_CYCLE_TIME * math.sqrt(9.81 / self.gravity))

    # -- episode ------------------------------------------------------------------------
    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[NDArray[np.float32], dict[str, Any]]:
        super().reset(seed=seed)
        base = int(seed) if seed is not None else int(self.np_random.integers(2**63))
        world_ss, sensor_ss, controller_ss = np.random.SeedSequence(base).spawn(3)
        batch, rows = self._batch_row()
        i = int(rows[0])
        if not self._done:
            batch.sync(i)  # the ending episode's controller complete
        true = self.world.reset(self.home, rng=np.random.default_rng(world_ss))
        meas = self.sensor.reset(true.ball_pos, true.ball_vel, np.random.default_rng(sensor_ss))
        state = self._measured(true, meas.position, meas.velocity)
        self.controller.reset(state, np.random.default_rng(controller_ss))
        return self._start(true, state, base)

    @staticmethod
    def _measured(true: JugglingState, ball_pos: Any, ball_vel: Any) -> JugglingState:
        return replace(true, ball_pos=ball_pos, ball_vel=ball_vel)

    def synced_controller(self) -> JugglerController:
        """:attr:`controller` as of the last step: between its plan's events the batch
        steps the plan in arrays and gives the controller its step count and corrections
        at the next event; this gives them now (for reading ``phase_time`` and the plan)."""
        if self._state is not None:
            batch, rows = self._batch_row()
            batch.sync(int(rows[0]))
        return self.controller
