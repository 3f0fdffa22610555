"""``MotionEnvs/Juggling-v0``: act on top of the analytic juggler in the MuJoCo scene."""

# ruff: noqa: E501  (the class docstring holds Gymnasium-style Markdown tables)

from __future__ import annotations

import dataclasses
import math
import os
from collections.abc import Mapping
from typing import Any

import gymnasium as gym
import numpy as np
from numpy.typing import NDArray

from motion_envs.datasets.juggling import PHASES, JugglingNoise, JugglingState, JugglingTask
from motion_envs.envs._common import (
    MAX_FRAME_SIZE,
    SideCameraMixin,
    check_integer,
    check_number,
    check_reward_weights,
    check_scale,
    clipped_pair,
    has_render_mode,
)
from motion_envs.envs.juggling._scene import JugglingScene
from motion_envs.envs.rendering import (
    JugglingSketch,
    new_mujoco_renderer,
    warn_matplotlib_fallback,
)
from motion_envs.models.juggling import (
    TRACKING_NOISE,
    cycle_rng,
    load_juggler,
)

__all__ = [
    "CYCLE_TIME_LIMIT",
    "DEFAULT_JUGGLING_REWARD_WEIGHTS",
    "GRAVITY_RANGE",
    "HAND_SPEED_MARGIN",
    "MAX_CYCLE_INDEX",
    "MAX_RELEASE_NOISE",
    "MAX_RESIDUAL_SCALE",
    "MAX_TRACKING_NOISE",
    "OBS_DIM",
    "POSITION_MARGIN",
    "JugglingEnv",
]

#: Default reward weights (see the class docstring, section Rewards).
DEFAULT_JUGGLING_REWARD_WEIGHTS: Mapping[str, float] = {
    "catch": 10.0,
    "drop": 10.0,
    "deviation": 1.0,
    "action": 0.01,
}

#: Simulated seconds per cycle after which an episode is truncated anyway (a hand that
#: never tosses); a cycle of the analytic juggler lasts 3 to 4 s at the default gravity.
CYCLE_TIME_LIMIT = 20.0

#: Half-width (m) of the box of observed positions around the task's start/floor: a
#: human arm reaches < 1 m and a toss of 4.5 m/s under the default gravity peaks 10 m up.
POSITION_MARGIN = 10.0
#: Speed (m/s) a human hand (peak 3-5 m/s) or a tossed ball stays under, times a margin of 2;
#: the velocity bound adds the largest jump of the offset, ``3 residual_scale / dt``.
HAND_SPEED_MARGIN = 10.0

#: Accepted ``gravity`` (m/s^2): from a hundredth of the default slow world to ten times
#: Earth's; beyond, a toss takes hours or a millisecond (and the flight arithmetic overflows).
GRAVITY_RANGE = (0.01, 100.0)
#: Largest accepted ``residual_scale`` (m): an arm's reach.
MAX_RESIDUAL_SCALE = 1.0
#: Largest accepted release-velocity noise (relative std: 1 = 100 %).
MAX_RELEASE_NOISE = 1.0
#: Largest accepted tracking noise (std, m: a tracker off by 10 cm is no tracker).
MAX_TRACKING_NOISE = 0.1

#: Largest ``options["cycle"]`` of ``reset`` (any cycle is O(1); the bound is a seed's).
MAX_CYCLE_INDEX = 2**63 - 1

#: Observation size: hand (4), ball (4), held (1), phase one-hot (4), phase time (1),
#: the nominal's next hand position (2).
OBS_DIM = 16
_ONE_HOT = {name: tuple(float(i == j) for j in range(len(PHASES))) for i, name in enumerate(PHASES)}


def _check_noise(noise: Any) -> JugglingNoise:
    if isinstance(noise, JugglingNoise):
        return noise
    if isinstance(noise, Mapping):
        unknown = set(noise) - {"release", "tracking"}
        if unknown:
            raise ValueError(
                f"noise has unknown key(s) {sorted(unknown)}; expected 'release', 'tracking'"
            )
        values = dict(noise)
    elif isinstance(noise, (int, float, np.integer, np.floating)) and not isinstance(noise, bool):
        level = check_number(noise, "noise", 0.0, MAX_RELEASE_NOISE)
        values = {"release": level, "tracking": TRACKING_NOISE if level > 0 else 0.0}
    else:
        raise ValueError(
            "noise must be a number (release-velocity std, relative), a mapping with keys "
            f"'release'/'tracking', or a JugglingNoise; got {noise!r}"
        )
    highs = {"release": MAX_RELEASE_NOISE, "tracking": MAX_TRACKING_NOISE}
    checked = {k: check_number(v, f"noise[{k!r}]", 0.0, highs[k]) for k, v in values.items()}
    return JugglingNoise(**checked)


def _check_int(value: Any, name: str, low: int, high: int = 10_000) -> int:
    return check_integer(value, name, low, high)


class JugglingEnv(SideCameraMixin, gym.Env):
    r"""Toss and catch one ball; the agent corrects the analytic juggler's hand.

    ## Description
    The juggling task of Lippi, Avizzano & Ruffaldi (2011, section III-A): one ball, one
    (right) hand, the vertical plane (``x`` horizontal, ``z`` up, metres). A cycle has four
    phases: **toss** (the hand accelerates up and decelerates; the ball is released when
    the hand's vertical acceleration falls below ``-toss_threshold`` and leaves with the
    hand's velocity), **go down** (to a point at the bottom), **catch** (a dynamic reach
    that meets the falling ball; the ball is caught when it comes within ``catch_radius``
    of the hand) and **return** (to the start). The *analytic juggler*
    (``motion_envs.models``: one sine-series regression per phase fitted on demonstrations,
    chained by the paper's phase criteria, the toss planned with zero final vertical speed,
    the catch planned from the ball's predicted flight and corrected online) commands the
    hand every 5 ms; the agent adds a bounded offset to each command. The world is the
    MuJoCo scene :class:`~motion_envs.envs.juggling.JugglingScene` (a mocap hand, a
    ball under gravity; see its docstring). The built-in demonstrations are **simulated**
    (a seeded generator of a person doing the paper's task): the paper's recordings are not
    public.

    The zero action reproduces the analytic juggler exactly: the first cycle of the episode
    after ``reset(seed=S, options={"cycle": i})`` is cycle ``i`` of the analytic juggler's
    seeded runner (``motion_envs.models.juggling.run_cycle``) with seed ``S``, the runner
    ``motion-bench juggling`` uses: same release, same catch or drop at the same control
    step, same hand path to 1e-9 (tested against the pure-model runner and the same runner
    in the MuJoCo scene; and ``motion-bench juggling --seed 0 --noise LEVEL``'s catch rates
    over its first cycles equal the zero-action episodes' with ``noise=LEVEL``, seed 0).
    The episode then goes on juggling (return, next toss) as the juggler does.

    ## Action Space
    The action space is a `Box(-1, 1, (2,), float32)`: the offset of the hand from the
    juggler's command in units of `residual_scale` (metres), held for the `frame_skip`
    control periods of a step: ``hand = target + residual_scale * a``. Entries outside
    ``[-1, 1]`` are clipped, NaN counts as 0 (no offset); ``info["action_invalid"]`` is
    True when the action had a non-finite entry. A wrong shape raises `ValueError`.

    | Num | Action                                  | Control Min | Control Max | Type (Unit)               |
    |-----|-----------------------------------------|-------------|-------------|---------------------------|
    | 0   | horizontal offset of the hand (``x``)   | -1          | 1           | position (residual_scale m) |
    | 1   | vertical offset of the hand (``z``)     | -1          | 1           | position (residual_scale m) |

    ## Observation Space
    The observation space is a `Box(low, high, (16,), float32)` whose bounds depend only
    on the task's constants and `residual_scale` (no data, no seed): positions within
    ``POSITION_MARGIN = 10`` m of the start ``(x0, z0) = JugglingTask.home`` horizontally
    and between ``floor_z - 10`` and ``z0 + 10`` m vertically (an arm reaches less than
    1 m; a toss at 4.5 m/s under the default gravity peaks 10 m up); speeds below
    ``V = 10 + 3 residual_scale / dt`` m/s (a hand peaks at 3-5 m/s, times 2, plus the
    largest jump of the offset between two steps; 40 m/s by default); the phase time below
    ``max_cycles * CYCLE_TIME_LIMIT``. Values beyond the bounds (only absurd commands
    reach them) are clipped.

    | Num    | Observation                                                         | Min              | Max          | Type (Unit)    |
    |--------|---------------------------------------------------------------------|------------------|--------------|----------------|
    | 0, 1   | hand position ``x, z`` as tracked (with the tracking noise)         | x0-10, floor_z-10 | x0+10, z0+10 | position (m)   |
    | 2, 3   | hand velocity (backward difference over 5 ms)                        | -V               | V            | velocity (m/s) |
    | 4, 5   | ball position ``x, z``                                              | x0-10, floor_z-10 | x0+10, z0+10 | position (m)   |
    | 6, 7   | ball velocity                                                       | -V               | V            | velocity (m/s) |
    | 8      | 1 if the ball is held, else 0                                       | 0                | 1            | unitless       |
    | 9..12  | phase one-hot: toss, go_down, catch, return                         | 0                | 1            | unitless       |
    | 13     | time within the phase                                               | 0                | 20 max_cycles | time (s)      |
    | 14, 15 | the nominal's next hand position (the juggler's plan, no offset)     | x0-10, floor_z-10 | x0+10, z0+10 | position (m)   |

    ## Rewards
    ``reward = w_catch * catches - w_drop * dropped - w_deviation * deviation
    - w_action * |a|^2`` with the weights of `reward_weights` (default ``catch: 10,
    drop: 10, deviation: 1, action: 0.01``): ``catches`` the number of catches during the
    step, ``dropped`` 1 on the step the ball falls below the floor, ``deviation`` the mean
    over the step's control periods of the hand's distance (m) from the juggler's command,
    the nominal (human-style) hand path (``residual_scale |a|``: the hand is kinematic),
    and ``|a|^2`` the squared norm of the (clipped) action. `info` holds each weighted
    term (``reward_catch``, ``reward_drop``, ``reward_deviation``, ``reward_action``;
    ``reward`` is their sum), ``deviation``, ``catches`` and ``cycles`` (so far),
    ``phase``, ``held``, ``time``, ``hand`` (the hand's true position ``(x, z)`` in m at
    the end of the step, without the observation's tracking noise), ``hand_observed``
    (the tracked hand, as observed) and ``action_invalid``.

    ## Starting State
    The hand rests at the juggler's home (the mean start of the training tosses) with the
    ball in it, at time 0, in the toss phase. `reset(seed=S, options={"cycle": i})` (``i``
    default 0) draws the episode's perturbation exactly as ``motion-bench juggling --seed
    S`` draws its cycle ``i``: two generators ``SeedSequence(S).spawn(i + 1)[i].spawn(2)``,
    one for the world (the release-velocity factor ``1 + release * N(0, 1)`` per component
    and the tracking noise of every control period,
    ``motion_envs.models.juggling.draw_episode_noise``), one for the juggler (its
    random phase end points and durations); so the zero-action episode's first cycle *is*
    that cycle. Any ``i`` up to ``2**63 - 1`` costs the same (the cycle's generators come from
    its spawn key, ``models.juggling.cycle_rng``). Without a seed, ``S`` is drawn from the environment's generator. Each
    later toss of the episode redraws the world's noise from the world generator.

    ## Episode End
    ### Termination
    The episode terminates on a drop: the free ball's centre falls below the floor
    (``floor_z``), or the ball is lost otherwise: held below the floor, or the (true) hand
    outside the box of observed positions (10 m around the start and the floor, see the
    observation space). Both count as a drop (``reward_drop``).

    ### Truncation
    The episode is truncated at the `max_cycles`-th catch, or after
    ``max_cycles * CYCLE_TIME_LIMIT`` (20 s) of simulated time without it.

    ## Arguments
    ```python
    import gymnasium as gym
    import motion_envs
    env = gym.make("MotionEnvs/Juggling-v0", noise=0.05, max_cycles=5)
    ```

    | Parameter        | Type          | Default | Description |
    |------------------|---------------|---------|-------------|
    | `noise`          | **float/dict** | `0.0`  | a level as `motion-bench juggling --noise LEVEL`: release-velocity std relative to the hand's velocity (0.05 = 5 %) plus 0.5 mm hand tracking noise (none at 0); or a dict with keys `release`, `tracking` (std of the tracked hand position, m); release at most 1, tracking at most 0.1 m |
    | `max_cycles`     | **int**       | `10`    | catches after which the episode is truncated (at most 10,000) |
    | `residual_scale` | **float**     | `0.05`  | offset (m) of the hand for an action of 1, in (0, 1] (an arm's reach) |
    | `reward_weights` | **dict**      | `None`  | weights of the reward terms, keys `catch`, `drop`, `deviation`, `action` (None: 10, 10, 1, 0.01) |
    | `frame_skip`     | **int**       | `1`     | control periods (5 ms, one MuJoCo step each) per environment step; the action is held over them (at most 10,000) |
    | `data`           | **str**       | `None`  | None: the built-in simulated demonstrations; or a path to the users' juggling CSV (`t, x, z[, ball_x, ball_z][, phase]`) |
    | `gravity`        | **float**     | `None`  | None: the task's default (the paper's slow virtual world, see `JugglingTask`); 9.81 for real gravity; in [0.01, 100] m/s^2 |
    | `render_mode`    | **str**       | `None`  | `None` or `"rgb_array"` (MuJoCo, camera `side`; without a usable OpenGL backend a matplotlib drawing of floor, hand and ball, with one warning) |
    | `width`          | **int**       | `480`   | frame width in pixels |
    | `height`         | **int**       | `480`   | frame height in pixels |

    ## Version History
    * v0: Initial version (``info["hand"]`` added later; observations, rewards and
      dynamics unchanged).
    * v0, hardened (rollouts change on purpose; the id stays v0, the paper's setting is
      unchanged, its defects are mended): the catch is tested between samples (closest
      approach over the control period, ``rules.swept_distance``: no pass-through; also
      in ``BallisticWorld`` and the vectorised runner, so the zero action still equals
      ``run_cycle``); a ball held below the floor or a hand outside the observation box
      ends the episode as a drop (before, the juggler could carry it for the whole time
      limit); the juggler sees its own hand (the tracked hand minus the agent's last
      offset), so the offset is added once at a phase start (it was added twice: a
      constant action jumped the hand by ``residual_scale``); ``info["hand"]`` is the
      true hand (it carried the tracking noise; the tracked hand is
      ``info["hand_observed"]``); ``reset(options={"cycle": N})`` costs O(1) (same
      generators as before).
    """

    metadata: dict[str, Any] = {"render_modes": ["rgb_array"], "render_fps": 200}  # noqa: RUF012

    def __init__(
        self,
        noise: float | Mapping[str, float] = 0.0,
        max_cycles: int = 10,
        residual_scale: float = 0.05,
        reward_weights: Mapping[str, float] | None = None,
        frame_skip: int = 1,
        data: str | os.PathLike[str] | None = None,
        gravity: float | None = None,
        render_mode: str | None = None,
        width: int = 480,
        height: int = 480,
    ) -> None:
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(
                f"render_mode must be None or one of {self.metadata['render_modes']}; "
                f"got {render_mode!r}"
            )
        for name, value in (("width", width), ("height", height)):
            _check_int(value, name, 16, MAX_FRAME_SIZE)
        self.noise = _check_noise(noise)
        self.max_cycles = _check_int(max_cycles, "max_cycles", 1)
        self.residual_scale = check_scale(residual_scale, MAX_RESIDUAL_SCALE)
        self.reward_weights = check_reward_weights(reward_weights, DEFAULT_JUGGLING_REWARD_WEIGHTS)
        self.frame_skip = _check_int(frame_skip, "frame_skip", 1)
        if data is not None and not isinstance(data, (str, os.PathLike)):
            raise ValueError(f"data must be None or a path to a juggling CSV; got {data!r}")
        if gravity is None:
            task = JugglingTask()
        else:
            task = JugglingTask(gravity=check_number(gravity, "gravity", *GRAVITY_RANGE))
        self.task = task
        self.data_path = data
        self.juggler = load_juggler(data, task)
        self.scene = JugglingScene(task)
        self.model, self.data = self.scene.model, self.scene.data
        self.render_mode = render_mode
        self.width, self.height = int(width), int(height)
        self.metadata = {**self.metadata, "render_fps": round(1.0 / self.dt)}
        self.action_space = gym.spaces.Box(-1.0, 1.0, (2,), dtype=np.float32)
        self._time_limit = self.max_cycles * CYCLE_TIME_LIMIT
        low, high = self._bounds()
        self.observation_space = gym.spaces.Box(low, high, dtype=np.float32)
        self._low, self._high = low, high
        self._renderer: Any = None
        self._state: JugglingState | None = None
        self._done = True
        self._catches = 0
        self._cycles = 0
        self._applied = (0.0, 0.0)

    def _bounds(self) -> tuple[NDArray[np.float32], NDArray[np.float32]]:
        """The observation bounds of the docstring (task constants and arguments only)."""
        (hx, hz), m = self.task.home, POSITION_MARGIN
        v = HAND_SPEED_MARGIN + 3.0 * self.residual_scale / self.task.dt
        pos_low, pos_high = [hx - m, self.task.floor_z - m], [hx + m, hz + m]
        low = np.array(
            [*pos_low, -v, -v, *pos_low, -v, -v, 0, 0, 0, 0, 0, 0, *pos_low], dtype=np.float32
        )
        high = np.array(
            [*pos_high, v, v, *pos_high, v, v, 1, 1, 1, 1, 1, self._time_limit, *pos_high],
            dtype=np.float32,
        )
        return low, high

    @property
    def dt(self) -> float:
        """Seconds of simulated time per environment step (``frame_skip`` control periods)."""
        return self.task.dt * self.frame_skip

    # -- episode ------------------------------------------------------------------------
    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[NDArray[np.float32], dict[str, Any]]:
        super().reset(seed=seed)
        cycle = 0
        if options is not None and options.get("cycle") is not None:
            cycle = check_integer(options["cycle"], "options['cycle']", 0, MAX_CYCLE_INDEX)
        base = int(seed) if seed is not None else int(self.np_random.integers(2**63))
        self._world_rng, juggler_rng = cycle_rng(base, cycle)
        home = np.asarray(getattr(self.juggler, "home_", self.task.home), dtype=np.float64)
        state = self.scene.reset(home, noise=self.noise, rng=self._world_rng)
        self.juggler.reset(state, juggler_rng)
        self._state = state
        self._phase = self.juggler.phase
        self._done = False
        self._catches = 0
        self._cycles = 0
        self._applied = (0.0, 0.0)
        info = {
            "phase": self._phase,
            "time": state.time,
            "hand": self.scene.hand_true,
            "hand_observed": np.array(state.hand_pos, dtype=np.float64),
            "seed": base,
            "cycle": cycle,
        }
        return self._observation(state), info

    def step(self, action: Any) -> tuple[NDArray[np.float32], float, bool, bool, dict[str, Any]]:
        if self._done or self._state is None:
            raise RuntimeError("the episode has ended (or never started); call reset() first")
        ax, az, invalid = clipped_pair(action)
        rx, rz = self.residual_scale * ax, self.residual_scale * az
        offset = math.hypot(rx, rz)
        state = self._state
        juggler, scene = self.juggler, self.scene
        catches = 0
        periods = 0
        for _ in range(self.frame_skip):
            # the juggler sees its own hand: the tracked hand minus the offset the agent
            # added in the last period (else a phase planned from the hand would start
            # at the offset hand and the offset be added twice)
            ox, oz = self._applied
            seen = state
            if ox != 0.0 or oz != 0.0:
                seen = dataclasses.replace(state, hand_pos=state.hand_pos - (ox, oz))
            target, armed = juggler.command(seen)
            phase = juggler.phase
            if phase != self._phase:
                if phase == "toss":  # a new cycle: its own release and tracking noise
                    scene.redraw_noise(self._world_rng)
                self._phase = phase
            state = scene.step((float(target[0]) + rx, float(target[1]) + rz), armed)
            self._applied = (rx, rz)
            periods += 1
            if state.released:
                self._cycles += 1
            if state.caught:
                catches += 1
            if state.dropped or self._lost(state):
                break
        self._state = state
        self._catches += catches
        w = self.reward_weights
        dropped = state.dropped or self._lost(state)
        r_catch = w["catch"] * catches
        r_drop = -w["drop"] * float(dropped)
        r_dev = -w["deviation"] * offset
        r_act = -w["action"] * (ax * ax + az * az)
        reward = r_catch + r_drop + r_dev + r_act
        terminated = dropped
        truncated = not terminated and (
            self._catches >= self.max_cycles or state.time >= self._time_limit
        )
        self._done = terminated or truncated
        info = {
            "reward_catch": r_catch,
            "reward_drop": r_drop,
            "reward_deviation": r_dev,
            "reward_action": r_act,
            "deviation": offset,
            "catches": self._catches,
            "cycles": self._cycles,
            "phase": juggler.phase,
            "held": state.held,
            "time": state.time,
            "hand": scene.hand_true,
            "hand_observed": np.array(state.hand_pos, dtype=np.float64),
            "action_invalid": invalid,
        }
        return self._observation(state), reward, terminated, truncated, info

    def _lost(self, state: JugglingState) -> bool:
        """The ball is lost (a drop): held below the floor, or the hand outside the box
        of observed positions (``POSITION_MARGIN`` around the start and floor)."""
        hx, hz = self.scene.hand_true.tolist()
        low, high = self._low, self._high
        outside = not (low[0] <= hx <= high[0] and low[1] <= hz <= high[1])
        return outside or (state.held and float(state.ball_pos[1]) < self.task.floor_z)

    def _observation(self, state: JugglingState) -> NDArray[np.float32]:
        juggler = self.juggler
        onehot = _ONE_HOT[juggler.phase]
        nx, nz = juggler.nominal_next().tolist()
        obs = np.array(
            (*self.scene.values, float(state.held), *onehot, juggler.phase_time, nx, nz),
            dtype=np.float32,
        )
        np.minimum(obs, self._high, out=obs)
        return np.maximum(obs, self._low, out=obs)

    # -- rendering ----------------------------------------------------------------------
    def _sync_scene(self) -> None:
        self.scene.sync()

    def render(self) -> NDArray[np.uint8] | None:
        """As :class:`SideCameraMixin`'s, drawn with matplotlib when OpenGL is unusable."""
        if not has_render_mode(self.render_mode):
            return None
        if self._state is None:
            raise RuntimeError("call reset() before render()")
        if self._renderer is None:
            self._renderer = self._new_renderer()
        if isinstance(self._renderer, JugglingSketch):
            st = self._state
            title = f"{self.juggler.phase}  t = {st.time:.2f} s  catches {self._catches}"
            return self._renderer.render(self.scene.hand_true, st.ball_pos, title)
        self.scene.sync()
        self._renderer.update_scene(self.data, camera="side")
        frame: NDArray[np.uint8] = self._renderer.render()
        return frame

    def _new_renderer(self) -> Any:
        """MuJoCo's renderer, or without a usable OpenGL backend the matplotlib sketch
        (one warning says why)."""
        try:
            self.model.vis.global_.offwidth = max(self.model.vis.global_.offwidth, self.width)
            self.model.vis.global_.offheight = max(self.model.vis.global_.offheight, self.height)
            return new_mujoco_renderer(self.model, self.height, self.width)
        except RuntimeError as exc:
            warn_matplotlib_fallback("juggling frames", str(exc))
        (hx, hz), task = self.task.home, self.task
        limits = (hx - 1.5, hx + 1.5, task.floor_z - 0.2, hz + 2.8)
        return JugglingSketch(
            self.width, self.height, limits, task.floor_z, task.catch_radius, task.ball_radius
        )
