"""``MotionEnvs/Cascade-v0``: a juggling pattern (the three-ball cascade by default,
``pattern=``) with two actuated hands, seeing the balls late."""

# ruff: noqa: E501  (the class docstring holds Gymnasium-style Markdown tables)

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import gymnasium as gym
import numpy as np
from numpy.typing import NDArray

from motion_envs.datasets.juggling import CASCADE_BALLS, CASCADE_HANDS, JugglingTask
from motion_envs.envs._common import SideCameraMixin, as_action, check_integer, check_number
from motion_envs.envs._kernels import numba_available
from motion_envs.envs.juggling._cascade_batch import CascadeBatch
from motion_envs.envs.juggling._cascade_scene import CascadeWorld
from motion_envs.envs.juggling._cascade_step import OUT_COLUMNS
from motion_envs.envs.juggling._shared import LevelsEnvMixin
from motion_envs.envs.juggling._world_spec import HAND_SPEED_LIMIT
from motion_envs.models.juggling import (
    CASCADE_CONTROLLERS,
    CascadeController,
    CascadeSensor,
    CascadeState,
    CascadeTunables,
    SiteswapController,
    SiteswapStyle,
    pattern_controller,
    pattern_likeness,
    pattern_spec,
)

__all__ = [
    "CASCADE_HISTORY",
    "CASCADE_OBS_DIM",
    "CASCADE_TIME_PER_CATCH",
    "DEFAULT_CASCADE_REWARD_WEIGHTS",
    "CascadeEnv",
    "cascade_obs_dim",
]

#: Default reward weights (see the class docstring, section Rewards).
DEFAULT_CASCADE_REWARD_WEIGHTS: Mapping[str, float] = {
    "catch": 10.0,
    "drop": 10.0,
    "likeness": 0.01,
    "action": 0.01,
}
#: Delayed measurements of each ball in the observation (newest first).
CASCADE_HISTORY = 4
_PER_HAND = 15


def cascade_obs_dim(balls: int) -> int:
    """The observation's size with ``balls`` balls (see the class docstring)."""
    return CASCADE_HANDS * _PER_HAND + 2 * balls + 4 * balls * CASCADE_HISTORY


#: Observation size of the three-ball cascade (see the class docstring).
CASCADE_OBS_DIM = cascade_obs_dim(CASCADE_BALLS)
#: s of simulated time per catch (at 9.81 m/s^2; times ``sqrt(9.81 / g)``) after which an
#: episode is truncated anyway; the pattern catches a ball every ~0.4 s.
CASCADE_TIME_PER_CATCH = 2.0
_TIME, _CATCHES, _TOSSES = (OUT_COLUMNS.index(k) for k in ("time", "catches", "tosses"))
_TERMINATED, _TRUNCATED = OUT_COLUMNS.index("terminated"), OUT_COLUMNS.index("truncated")
#: Most control periods per step (as Juggling-v0's ``frame_skip``).
MAX_FRAME_SKIP = 10_000
_POS_MARGIN = 10.0
_SPEED_BOUND = 30.0


class CascadeEnv(SideCameraMixin, LevelsEnvMixin, gym.Env):
    r"""Juggle a pattern (the three-ball cascade by default) with two actuated hands that
    see the balls late.

    ## Description
    The three-ball cascade in Juggling-v1's physical world: two hands, three balls, the
    vertical plane (``x`` horizontal with the body's midline at 0 and the right hand at
    ``x > 0``, ``z`` up, metres), 9.81 m/s^2 by default. MuJoCo does the physics with
    contacts on (:class:`~motion_envs.envs.juggling.CascadeWorld`, the one world's MJCF): each
    hand is Juggling-v1's actuated hand (0.5 kg on two slide joints, motors within
    ``hand_speed_limit`` = 6 m/s and 120 m/s^2), a falling ball touching an EMPTY hand's
    palm slower than 5 m/s relative to it is captured (a hand holds one ball), a ball
    touching the floor is a drop. Balls collide with palms and the floor, not with each
    other (``contype``/``conaffinity``: crossing balls pass). Each ball is seen through
    Juggling-v1's sensor with the level's latency and noise; each toss is scattered in
    speed and angle.

    The analytic cascade juggler (:class:`~motion_envs.models.juggling.CascadeController`)
    commands both hands every 5 ms: each hand runs the one-ball juggler's per-phase
    sine-series models (eq. 9 toss, catch on the predicted flight with the eq. 10
    correction; the left hand mirrored), fitted on the training cycles of the built-in
    **SIMULATED** two-hand demonstrations; the hands throw in turn on the beat of
    Shannon's theorem ``(F + D) H = (V + D) N`` (``H = 2``, ``N`` the pattern's balls,
    dwell ratio ``D / (V + D)`` = `dwell_ratio` or the pattern's); a hand catches the other
    hand's ball, planned on the thrower's efference copy and corrected from the delayed
    measurement. The agent adds a residual to each hand's command. The pattern starts
    with ball 0 in the right hand, ball 1 in the left and balls 2 .. N - 1 in flight
    (ball ``L`` landing on beat ``L``, beat 0 the right hand's first release; for the
    three-ball cascade ball 2 flies towards the right hand).

    `pattern` names a registered pattern
    (:data:`~motion_envs.models.juggling.PATTERNS`: a vanilla siteswap and its dwell
    ratio; :func:`~motion_envs.models.juggling.register_pattern` adds one); every size
    below that counts balls is for ``N`` balls (the table: ``N = 3``, the default). The
    juggler above plays ``"3"`` and ``"3-human"``; ``"5"``, ``"4"``, ``"441"``, ``"531"``,
    ``"423"`` and ``"51"`` are played by the siteswap juggler
    (:class:`~motion_envs.models.juggling.SiteswapController`: each throw value on its own
    flight and landing hand, a 2 held, a 1 a short pass, quintic movements within the
    hand's limits; its start's flying balls carry the level's release scatter; docs/models.md
    section 5).

    Levels: Juggling-v1's (every value can also be passed on its own):

    | level    | `latency` (s) | `position_std` (m) | `velocity_std` (m/s) | `release_speed_std` | `release_angle_std` (deg) |
    |----------|---------------|--------------------|----------------------|---------------------|---------------------------|
    | `easy`   | 0.0           | 0.0                | 0.0                  | 0.05                | 4.0                       |
    | `medium` | 0.10          | 0.002              | 0.02                 | 0.08                | 6.0                       |
    | `hard`   | 0.11          | 0.004              | 0.05                 | 0.12                | 12.0                      |

    The zero action reproduces the reference controller exactly (the same world, sensor
    and seeds; tested against an independent loop). A step runs the environment's batch
    of one (:class:`~motion_envs.envs.juggling._cascade_batch.CascadeBatch`: the step
    written once, compiled with numba when installed), the same code that steps the
    native vector environment's ``N`` episodes; between its hands' events the batch
    steps the controller's plans in arrays (:meth:`CascadeEnv.synced_controller` gives
    the controller its hands' step counts).

    ## Action Space
    `Box(-1, 1, (4,), float32)`: the residuals added to the controller's hand targets, in
    units of `residual_scale` metres, held over the step's `frame_skip` control periods
    (5 ms each; one by default). With `residual_phases`, a hand's residual acts only while
    that hand is in one of those phases (the phase whose plan gave the period's target);
    in the others the hand follows the controller alone.
    Entries outside ``[-1, 1]`` are clipped; NaN counts as 0 (``info["action_invalid"]``).
    A wrong shape raises `ValueError`.

    | Num | Action                                   | Control Min | Control Max | Type (Unit)                 |
    |-----|------------------------------------------|-------------|-------------|-----------------------------|
    | 0   | right hand: horizontal residual          | -1          | 1           | position (residual_scale m) |
    | 1   | right hand: vertical residual            | -1          | 1           | position (residual_scale m) |
    | 2   | left hand: horizontal residual           | -1          | 1           | position (residual_scale m) |
    | 3   | left hand: vertical residual             | -1          | 1           | position (residual_scale m) |

    ## Observation Space
    `Box(low, high, (30 + 18 N,), float32)` (84 for three balls); positions within 10 m of the right hand's home,
    speeds within 30 m/s (values beyond are clipped); world frame.

    | Num     | Observation                                                                  | Type (Unit)    |
    |---------|------------------------------------------------------------------------------|----------------|
    | 0, 1    | right hand position ``x, z`` (proprioception, exact)                         | position (m)   |
    | 2, 3    | right hand velocity                                                          | velocity (m/s) |
    | 4       | 1 if the right hand holds a ball, else 0                                     | unitless       |
    | 5..8    | the right hand's phase one-hot: toss, go_down, catch, return                 | unitless       |
    | 9       | time within the phase                                                        | time (s)       |
    | 10      | duration of the current phase plan                                           | time (s)       |
    | 11, 12  | the controller's next target for the right hand (no residual)                | position (m)   |
    | 13, 14  | the right hand's plan end point (in the catch phase: the planned catch)      | position (m)   |
    | 15..29  | the same for the left hand                                                   |                |
    | 30..35  | per ball 0 .. N - 1: 1 if held by the right hand, 1 if held by the left hand | unitless       |
    | 36..83  | per ball, its measurements ``x, z, vx, vz`` of the last 4 periods, newest first | m, m/s       |

    ## Rewards
    ``reward = w_catch * catches - w_drop * dropped - w_likeness * likeness - w_action * |a|^2``
    per control period (default weights ``catch: 10, drop: 10, likeness: 0.01, action:
    0.01``): ``catches`` counts the catches of the period (both hands), ``dropped`` is 1 at
    the period a ball touches the floor, ``likeness`` the mean over the hands of the
    distance (m) of the hand's state ``(x, z, 0.1 s * v)`` (own frame) to the nearest state
    of the same phase in the TRAINING demonstrations (never the controller's own plan);
    ``|a|^2`` is the whole (clipped) action's, also where `residual_phases` keeps a hand's
    residual from acting (as in Juggling-v1).
    A step's reward is the sum over its `frame_skip` periods (the periods played: the
    step stops at the period that ends the episode), so a held action earns the same
    return whatever `frame_skip`. `info` holds each weighted term (``reward_catch``,
    ``reward_drop``, ``reward_likeness``, ``reward_action``), ``likeness`` and the
    step's catches ``caught`` (all summed over the step's periods), ``catches`` and
    ``tosses`` so far (``cycles``: the same as ``tosses``), and at the end of the step's
    last period ``phase`` (the right hand's) and ``phases`` (both), ``held`` (per hand),
    ``time``, the true ``hands`` ``(2, 2)`` and ``balls`` ``(N, 2)`` positions, ``hand``
    (the right hand's position); ``action_invalid``.

    ## Starting State
    The hands at their homes (the training tosses' mean start, the left mirrored), ball 0
    in the right hand, ball 1 in the left, ball 2 in flight towards the right hand as if
    thrown by the left hand's nominal toss one beat earlier; time 0; the right hand starts
    its toss. `reset(seed=S)` seeds three independent streams
    ``SeedSequence(S).spawn(3)``: the world (release noise), the sensor (measurement
    noise) and the controller (its random phase end points and durations).

    ## Episode End
    ### Termination
    A ball touches the floor (a drop).

    ### Truncation
    After `max_catches` catches, or ``max_catches * 2 s * sqrt(9.81 / g)`` of simulated time.

    Both are tested after every control period: with `frame_skip` > 1 the step ends at the
    period that ends the episode (the step's remaining periods are not played).

    ## Arguments
    ```python
    import gymnasium as gym
    import motion_envs
    env = gym.make("MotionEnvs/Cascade-v0", level="medium")
    ```

    | Parameter           | Type      | Default     | Description |
    |---------------------|-----------|-------------|-------------|
    | `level`             | **str**   | `"medium"`  | `"easy"`, `"medium"` or `"hard"` (table above) |
    | `latency`           | **float** | `None`      | s, the ball measurements' delay (rounded to 5 ms); None: the level's |
    | `position_std`      | **float** | `None`      | m, measurement noise of the ball positions; None: the level's |
    | `velocity_std`      | **float** | `None`      | m/s, measurement noise of the ball velocities; None: the level's |
    | `release_speed_std` | **float** | `None`      | relative std of the release speed; None: the level's |
    | `release_angle_std` | **float** | `None`      | degrees, std of the release direction; None: the level's |
    | `pattern`           | **str**   | `"3"`       | a registered pattern's name (`PATTERNS`: `"3"`, `"3-human"` at dwell ratio 2/3 (the fitted cascade juggler); `"5"`, `"4"`, `"441"`, `"531"`, `"423"`, `"51"` (the siteswap juggler)); anything else is refused with the reason |
    | `dwell_ratio`       | **float** | `None`      | ``D / (V + D)`` in (0.2, 0.8); None: the pattern's (for `"3"` the demonstrations' median, ~0.56) |
    | `tunables`          | **CascadeTunables** or **SiteswapStyle** | `None` | the controller's tunables (the pattern's juggler's kind); None: the pattern's |
    | `gravity`           | **float** | `9.81`      | m/s^2 (the demonstrations are generated at this gravity) |
    | `controller`        | **str**   | `"juggler"` | `juggler`, `juggler_latency_aware`, `fixed_point`, `commanded_intercept` |
    | `max_catches`       | **int**   | `30`        | catches after which the episode is truncated |
    | `residual_scale`    | **float** | `0.05`      | m of residual for an action of 1 |
    | `residual_phases`   | **tuple** | `None`      | phases (`toss`, `go_down`, `catch`, `return`) in which a hand's residual acts; None: all |
    | `reward_weights`    | **dict**  | `None`      | keys `catch`, `drop`, `likeness`, `action` |
    | `frame_skip`        | **int**   | `1`         | control periods (5 ms, one MuJoCo step each) per environment step; the action is held over them (at most 10,000) |
    | `render_mode`       | **str**   | `None`      | `None` or `"rgb_array"` (camera `side`) |
    | `width`             | **int**   | `480`       | frame width in pixels |
    | `height`            | **int**   | `480`       | frame height in pixels |

    ## Version History
    * v0: the three-ball cascade on Juggling-v1's physics, sensor and levels
      (``frame_skip`` and ``residual_phases`` added later; their defaults, 1 and None,
      leave every rollout unchanged).
    """

    metadata: dict[str, Any] = {"render_modes": ["rgb_array"], "render_fps": 200}  # noqa: RUF012
    _CONTROLLERS = CASCADE_CONTROLLERS
    _WORLD = "Cascade-v0"
    _DEFAULT_WEIGHTS = DEFAULT_CASCADE_REWARD_WEIGHTS
    #: Delayed measurements of each ball in the observation.
    history = CASCADE_HISTORY

    def __init__(
        self,
        level: str = "medium",
        latency: float | None = None,
        position_std: float | None = None,
        velocity_std: float | None = None,
        release_speed_std: float | None = None,
        release_angle_std: float | None = None,
        dwell_ratio: float | None = None,
        gravity: float = 9.81,
        controller: str = "juggler",
        max_catches: int = 30,
        residual_scale: float = 0.05,
        reward_weights: Mapping[str, float] | None = None,
        frame_skip: int = 1,
        residual_phases: Sequence[str] | None = None,
        render_mode: str | None = None,
        width: int = 480,
        height: int = 480,
        pattern: str = "3",
        tunables: CascadeTunables | None = None,
    ) -> None:
        self._init_arguments(
            (level, latency, position_std, velocity_std, release_speed_std, release_angle_std),
            (gravity, controller, max_catches, residual_scale, residual_phases, reward_weights),
            (render_mode, width, height),
        )
        #: Control periods (5 ms each) per step; the action is held over them.
        self.frame_skip = check_integer(frame_skip, "frame_skip", 1, MAX_FRAME_SKIP)
        #: The registered pattern played (:class:`~motion_envs.models.juggling.PatternSpec`).
        self.pattern = pattern_spec(pattern)
        #: Balls of the pattern.
        self.balls = self.pattern.balls
        self.dwell_ratio = (
            self.pattern.dwell_ratio
            if dwell_ratio is None
            else check_number(dwell_ratio, "dwell_ratio", 0.2, 0.8)
        )
        if tunables is not None and not isinstance(tunables, (CascadeTunables, SiteswapStyle)):
            raise ValueError(
                f"tunables must be a CascadeTunables or SiteswapStyle; got {tunables!r}"
            )
        self.tunables = self.pattern.tunables if tunables is None else tunables
        self.task = JugglingTask(gravity=self.gravity)
        self.delay_steps = round(self.latency / self.task.dt)
        self.controller: CascadeController | SiteswapController = pattern_controller(
            self.pattern,
            self.controller_name,
            self.gravity,
            self.delay_steps * self.task.dt,
            self.dwell_ratio,
            self.tunables,
        )
        self.home = self.controller.home
        self.likeness = pattern_likeness(self.pattern, self.gravity)
        self.world = CascadeWorld(
            self.task, self.release_speed_std, math.radians(self.release_angle_std), self.balls
        )
        self.sensor = CascadeSensor(
            self.delay_steps, self.position_std, self.velocity_std, self.task.dt, self.balls
        )
        self.model, self.data = self.world.model, self.world.data
        #: m/s, each hand's speed limit.
        self.hand_speed_limit = HAND_SPEED_LIMIT
        self.metadata = {**self.metadata, "render_fps": round(1.0 / self.dt)}
        self._time_limit = (
            self.max_catches * CASCADE_TIME_PER_CATCH * math.sqrt(9.81 / self.gravity)
        )
        self.action_space = gym.spaces.Box(-1.0, 1.0, (2 * CASCADE_HANDS,), dtype=np.float32)
        low, high = self._bounds()
        self.observation_space = gym.spaces.Box(low, high, dtype=np.float32)
        self._low, self._high = low, high
        self._renderer: Any = None
        self._done = True
        #: the measured state at the reset (the batch's starting point)
        self._state: CascadeState | None = None
        #: the batch stepping this episode and its row (:meth:`_batch_row`)
        self._batch: CascadeBatch | None = None
        self._rows = np.zeros(1, dtype=np.int64)

    def _bounds(self) -> tuple[NDArray[np.float32], NDArray[np.float32]]:
        hx, hz = self.home[0]
        m, v = _POS_MARGIN, _SPEED_BOUND
        fz = self.task.floor_z
        t = self._time_limit
        low: list[float] = []
        high: list[float] = []
        for _ in range(CASCADE_HANDS):
            low += [hx - m, fz - m, -v, -v, 0, 0, 0, 0, 0, 0, 0, hx - m, fz - m, hx - m, fz - m]
            high += [hx + m, hz + m, v, v, 1, 1, 1, 1, 1, t, t, hx + m, hz + m, hx + m, hz + m]
        low += [0.0] * (2 * self.balls)
        high += [1.0] * (2 * self.balls)
        low += [hx - m, fz - m, -v, -v] * (self.balls * CASCADE_HISTORY)
        high += [hx + m, hz + m, v, v] * (self.balls * CASCADE_HISTORY)
        return np.array(low, dtype=np.float32), np.array(high, dtype=np.float32)

    @property
    def dt(self) -> float:
        """s of simulated time per step (``frame_skip`` control periods)."""
        return self.task.dt * self.frame_skip

    # -- episode ------------------------------------------------------------------------
    def _batch_row(self) -> tuple[CascadeBatch, NDArray[np.int64]]:
        """The batch this episode is stepped in and its row: the native vector
        environment's (set by it) or this environment's own batch of one."""
        if self._batch is None:
            backend = "numba" if numba_available() else "python"
            self._batch, self._rows = CascadeBatch([self], backend), np.zeros(1, dtype=np.int64)
        return self._batch, self._rows

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[NDArray[np.float32], dict[str, Any]]:
        super().reset(seed=seed)
        base = int(seed) if seed is not None else int(self.np_random.integers(2**63))
        world_ss, sensor_ss, controller_ss, start_ss = np.random.SeedSequence(base).spawn(4)
        batch, rows = self._batch_row()
        i = int(rows[0])
        start = self.controller.start(
            (self.release_speed_std, math.radians(self.release_angle_std)),
            np.random.default_rng(start_ss),
        )
        true = self.world.reset(self.home, start=start, rng=np.random.default_rng(world_ss))
        state = self.sensor.reset(true, np.random.default_rng(sensor_ss), self.task.gravity)
        self.controller.reset(state, np.random.default_rng(controller_ss))
        self._state = state
        batch.load(i, state)
        self._done = False
        c = self.controller
        info = {
            "phase": c.phase(0),
            "phases": (c.phase(0), c.phase(1)),
            "held": tuple(h in true.holder for h in range(CASCADE_HANDS)),
            "time": true.time,
            "hand": true.hand_pos[0].copy(),
            "hands": true.hand_pos.copy(),
            "balls": true.ball_pos.copy(),
            "seed": base,
        }
        return batch.observation(i), info

    def step(self, action: Any) -> tuple[NDArray[np.float32], float, bool, bool, dict[str, Any]]:
        if self._done or self._state is None:
            raise RuntimeError("the episode has ended (or never started); call reset() first")
        a = as_action(action, (2 * CASCADE_HANDS,))
        batch, rows = self._batch_row()
        obs, out = batch.step(rows, a[None])
        info = batch.info(out[0])
        terminated, truncated = bool(out[0, _TERMINATED] > 0.0), bool(out[0, _TRUNCATED] > 0.0)
        self._done = terminated or truncated
        return obs[0], float(out[0, 0]), terminated, truncated, info

    def synced_controller(self) -> CascadeController | SiteswapController:
        """:attr:`controller` as of the last step: between its hands' events the batch
        steps their plans in arrays and gives the hands their step counts at the next
        event; this gives them now (for reading ``phase_time`` and the plans)."""
        if self._state is not None:
            batch, rows = self._batch_row()
            batch.sync(int(rows[0]))
        return self.controller

    def play(
        self, seed: int, on_period: Callable[[CascadeState], None] | None = None
    ) -> tuple[int, int, bool, float]:
        """The zero-action episode reset with ``seed`` (the controller alone; the same
        periods as ``reset(seed=seed)`` then ``step(0)`` until the episode ends):
        ``(catches, tosses, dropped, time)``. ``on_period(true_state)`` is called after
        every period."""
        self.reset(seed=seed)
        batch, rows = self._batch_row()
        zero = np.zeros((1, 2 * CASCADE_HANDS))
        while True:
            _, out = batch.period(rows, zero)
            if on_period is not None:
                on_period(batch.true_state(int(rows[0])))
            r = out[0].tolist()
            if r[_TERMINATED] > 0.0 or r[_TRUNCATED] > 0.0:
                self._done = True
                return int(r[_CATCHES]), int(r[_TOSSES]), r[_TERMINATED] > 0.0, r[_TIME]

    # -- rendering (SideCameraMixin.render) ----------------------------------------------
    def _sync_scene(self) -> None:
        self.world.sync()
