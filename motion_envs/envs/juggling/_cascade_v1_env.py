"""``MotionEnvs/Cascade-v1``: a juggling pattern with two hands at Juggling-v2's human
levels (a hidden delay, a position-only camera per ball, air drag, the capture at impact)."""

# ruff: noqa: E501  (the class docstring holds Gymnasium-style Markdown tables)

from __future__ import annotations

import math
from collections import deque
from collections.abc import Mapping, Sequence
from typing import Any

import gymnasium as gym
import numpy as np
from numpy.typing import NDArray

from motion_envs.datasets.juggling import CASCADE_HANDS, PHASES, JugglingTask
from motion_envs.envs._common import SideCameraMixin, as_action, check_choice
from motion_envs.envs.juggling._cascade_env import (
    CASCADE_TIME_PER_CATCH,
    DEFAULT_CASCADE_REWARD_WEIGHTS,
)
from motion_envs.envs.juggling._cascade_scene import CascadeWorld
from motion_envs.envs.juggling._cascade_v1_errors import (
    HeldTaskErrors,
    MissTracker,
    catch_errors,
    check_observe_task_error,
)
from motion_envs.envs.juggling._likeness import LikenessQuery
from motion_envs.envs.juggling._shared import (
    LevelsEnvMixin,
    check_anchor_start,
    check_delay_offset,
    check_delay_rule,
    check_timing_scale,
    check_tracker_gain,
)
from motion_envs.envs.juggling._world_spec import (
    AIR_DENSITY,
    IMPACT_CONTACT_DAMPING,
    WorldSpec,
)
from motion_envs.models.juggling import (
    ANCHOR_FRAMES,
    CASCADE_V1_CONTROLLERS,
    CASCADE_V1_LEVELS,
    V2_LEVELS,
    CameraFrame,
    CameraSensor,
    CascadeBallView,
    CascadeController,
    CascadeState,
    CorrectionTracker,
    DelayRule,
    DelayTracker,
    SiteswapController,
    catch_height,
    catch_plan,
    nearest_palm,
    pattern_controller,
    pattern_likeness,
    pattern_spec,
    planned_catch,
)

__all__ = ["CASCADE_V1_FRAMES", "CascadeV1Env", "cascade_v1_obs_dim"]

#: Received camera frames per ball in the observation (newest first).
CASCADE_V1_FRAMES = 4
_PER_HAND = 16
_ONE_HOT = {name: tuple(float(i == j) for j in range(len(PHASES))) for i, name in enumerate(PHASES)}
_POS_MARGIN = 10.0
_SPEED_BOUND = 30.0


def cascade_v1_obs_dim(balls: int) -> int:
    """The observation's size with ``balls`` balls (see the class docstring)."""
    return CASCADE_HANDS * _PER_HAND + 2 * balls + 4 * CASCADE_V1_FRAMES * balls


class CascadeV1Env(SideCameraMixin, LevelsEnvMixin, gym.Env):
    r"""Juggle a pattern with two hands that see the balls through a delayed camera, in air.

    ## Description
    Cascade-v0's pattern and juggler (two actuated hands within human limits, the
    pattern's balls, MuJoCo contacts; the fitted cascade juggler for ``"3"``, the
    siteswap juggler for the others; :class:`~motion_envs.envs.juggling.CascadeEnv`),
    with Juggling-v2's human levels (:class:`~motion_envs.envs.juggling.JugglingV2Env`),
    drawn per episode:

    * **a visuomotor delay** from the level's part of the human range (100-250 ms; one
      per episode, the same for every ball), hidden from the observation, plus a jitter
      per frame;
    * **a camera per ball** that reports its POSITION only, at 100 Hz, with frame drops,
      no frame within 10 cm of EITHER palm, and millimetre noise
      (:class:`~motion_envs.models.juggling.CameraSensor`);
    * **quadratic air drag** in MuJoCo's fluid model with a coefficient per BALL, drawn
      uniformly from the level's range (``k`` from a juggling ball's 0.009/m up to a
      table-tennis ball's 0.14/m on `hard`), unknown to the juggler;
    * **the capture at impact**: a falling ball is caught only at the physics step its
      contact with an empty palm begins, slower than the level's `capture_speed`; a
      faster ball bounces.

    The juggler is told each ball through its own flight estimator
    (:class:`~motion_envs.models.juggling.CascadeBallView`): a held ball exactly, a
    flying ball as the flight fitted to its newest frames (``controller="juggler"``:
    the frames taken as the present, as Juggling-v2's juggler does), before 3 frames of
    its flight its thrower's release state flown ballistically. Reference controllers
    (:data:`~motion_envs.models.juggling.CASCADE_V1_CONTROLLERS`):
    ``juggler_mean_delay`` (frames shifted by the level's mean delay plus
    `delay_offset`), ``juggler_delay_estimator`` (the hand-written delay estimator: the
    delay found from each release, pooled over the episode's releases of every ball;
    :class:`~motion_envs.models.juggling.PooledReleaseEstimator`), ``juggler_oracle``
    (the true delay and each ball's true drag; a reference, labelled as upper only where
    measured above the others) and
    ``fixed_point`` (catches at the nominal point and time, never looking: trivial),
    and Juggling-v2's catch planned for the capture rule (``juggler_oracle_catch``,
    ``juggler_mean_delay_catch``; fitted juggler: each ball told ``lead`` ahead, so the
    reach ends early and the hand waits; siteswap juggler: the oracle's own reach
    ending ``lead`` early, :class:`~motion_envs.models.juggling.SiteswapCatchController`,
    the mean delay's none; :data:`~motion_envs.models.juggling.CASCADE_CATCH_PLANS`),
    and ``juggler_delay_tracker``: the mean-delay catch plan whose one delay (one
    person) is corrected after every catch from that catch's timing error,
    ``D <- clip(D - k (e - delay_offset))`` over the level's delay range, told ``D +
    delay_offset`` (:mod:`~motion_envs.models.juggling._delay_tracker`; ``k`` is
    ``tracker_gain``; the env hands the view each catch's timing error, never the delay),
    and ``juggler_delay_estimator_catch``: the two hand-written fixes together, the
    delay estimator's pooled delay with the mean-delay catch plan (declared, not
    re-tuned; with `delay_offset` the frames are placed by the pooled delay plus the
    offset, before the first estimate by the level's mean plus it: a correction of the
    estimate's bias, which may be negative), and ``juggler_estimator_tracker_catch``:
    that controller whose pooled estimate (and prior) is told with a correction ``C +
    delay_offset``, ``C <- clip(C - k (e - delay_offset), -0.05, 0.05)`` after every
    catch by either hand from 0, each flight fitted with the correction told at its
    ball's release (``k`` is ``tracker_gain``;
    :class:`~motion_envs.models.juggling.CorrectionTracker`; a competitor). The agent
    adds a residual to each hand's command.

    Levels (Juggling-v2's; :data:`~motion_envs.models.juggling.V2_LEVELS`):

    | level    | delay (ms) | jitter (ms) | frame drops | noise (mm) | drag `k` (1/m) per ball | release speed / angle std | `capture_speed` (m/s) |
    |----------|------------|-------------|-------------|------------|-------------------------|---------------------------|------------------------|
    | `easy`   | 100-150    | 5           | 2 %         | 1          | 0.009-0.02              | 0.05 / 4 deg              | 5                      |
    | `medium` | 100-200    | 10          | 5 %         | 2          | 0.009-0.07              | 0.08 / 6 deg              | 5                      |
    | `hard`   | 150-250    | 15          | 10 %        | 3          | 0.009-0.14              | 0.12 / 12 deg             | 5                      |

    The true delay and drags are the attributes ``delay`` (s) and ``drags`` ``(N,)``
    (1/m), for evaluation; never in the observation or the info.

    ## Action Space
    ``Box(-1, 1, (4,), float32)``: the residuals ``(dx, dz)`` of the right hand, then the
    left hand, added to the controller's next hand targets, times `residual_scale` (m);
    with `residual_phases` a hand's residual acts only in those phases. Entries outside
    ``[-1, 1]`` are clipped, NaN counts as 0 (``info["action_invalid"]``); a wrong shape
    raises ``ValueError``.

    With ``timing_scale > 0`` (controllers ``juggler_delay_tracker`` and
    ``juggler_delay_estimator_catch`` only) ``Box(-1, 1, (5,), float32)``: the
    residuals, then a **timing** entry ``u``: the delay the juggler is told is the
    tracker's plus ``timing_scale * u`` s (at least 0), or for the delay estimator the
    pooled estimate plus an offset of ``delay_offset + timing_scale * u`` s (before the
    first estimate the level's mean plus it; at least 0), and each ball released in a
    step is fitted with the delay told in that step (every flight keeps the delay, or
    the offset, of its release; the balls in the air at the reset are told ``u = 0``),
    so the agent RE-TIMES the catches instead of moving the hands. ``u = 0`` is the
    controller alone (the tracker, or the estimator told `delay_offset`). The action
    cost ``|a|^2`` is the residuals'.

    ## Observation Space
    ``Box(low, high, (32 + 18 N,), float32)`` (86 for three balls, 122 for five; 8 more
    at the end with ``observe_task_error=True``);
    positions within 10 m of the right hand's home, speeds within 30 m/s, times within
    the time limit; world frame:

    | index            | observation                                                              | unit           |
    |------------------|--------------------------------------------------------------------------|----------------|
    | 0, 1             | right hand position ``x, z`` (proprioception, exact)                     | position (m)   |
    | 2, 3             | right hand velocity                                                      | velocity (m/s) |
    | 4                | 1 if the right hand holds a ball, else 0 (touch)                         | unitless       |
    | 5..8             | the right hand's phase one-hot: toss, go_down, catch, return             | unitless       |
    | 9                | time within the phase                                                    | time (s)       |
    | 10               | duration of the current phase plan                                       | time (s)       |
    | 11, 12           | the controller's next target for the right hand (no residual)            | position (m)   |
    | 13, 14           | the right hand's plan end point (in the catch phase: the planned catch)  | position (m)   |
    | 15               | time since the right hand last released a ball (0 before its first)      | time (s)       |
    | 16..31           | the same for the left hand                                               |                |
    | 32..32 + 2N      | per ball: 1 if held by the right hand, 1 if held by the left hand        | unitless       |
    | then 16 per ball | the ball's last 4 received frames ``x, z, age, valid``, newest first: its measured position, the time since the frame ARRIVED, 1 if the slot holds a frame | m, s |
    | then 4 per hand  | only with ``observe_task_error=True``, right hand then left: the hand's LAST catch's ``info["task_error"]`` row, ``offset`` (within 10 m) and ``timing`` (within the time limit; 0 when NaN), 1 if the timing is known, the hand's catches so far (at most `max_catches`); held until its next catch, all 0 before its first | m, s, unitless, count |

    **Task error** (``observe_task_error=True``): Juggling-v2's, per hand: the haptic
    feedback of where and when a ball landed in that palm, from the step of its catch
    until the hand's next; the delay and the drags stay hidden.

    **Memory.** As Juggling-v2's: the delay can be inferred only by relating a ball's
    frames to its release over a flight; an agent needs memory (a frame stack or a
    recurrent policy).

    ## Rewards
    Cascade-v0's: ``w_catch * catches - w_drop * dropped - w_likeness * likeness -
    w_action * |a|^2`` per step (default weights ``catch: 10, drop: 10, likeness: 0.01,
    action: 0.01``; ``likeness`` the mean over the hands of the distance of the hand's
    state to the TRAINING demonstrations' of the same phase, SIMULATED). `info` holds
    each weighted term, ``likeness``, the step's catches ``caught``, ``catches`` and
    ``tosses`` (``cycles``) so far, ``phase`` (the right hand's) and ``phases``, ``held``
    per hand, ``time``, the true ``hands`` ``(2, 2)``, ``balls`` ``(N, 2)`` and ``hand``,
    and ``action_invalid``; at a step with a catch also the task-error vector per hand,
    ``task_error`` ``(2, 2)``: where the ball met the palm relative to its centre (m,
    along ``x``, world frame) and the catch time minus the hand's planned catch time (s;
    with a catch plan its planned meeting, the plan's end plus ``lead``),
    and ``catch_speed`` ``(2,)`` (m/s, the speed at which the palm met the ball); NaN for
    a hand that did not catch, and the timing NaN for a catch outside the hand's catch
    phase (no planned catch time; Juggling-v2's vector, per hand). At the step of a
    drop, the dropped ball's miss: ``miss_error`` ``(offset, timing)``, ``miss_speed``
    and ``miss_hand`` at its closest approach (sampled every period since its release,
    while it falls) to the origin of a hand in its catch phase (absent when it fell past
    none; :class:`~motion_envs.envs.juggling._cascade_v1_errors.MissTracker`).

    ## Starting State
    Cascade-v0's: the hands at their homes, ball 0 in the right hand, ball 1 in the left,
    the others in flight as the pattern's earlier throws put them (scattered by the
    level's release noise for the siteswap juggler); time 0. `reset(seed=S)` seeds six
    independent streams ``SeedSequence(S).spawn(6)``: the world (release noise), the
    controller, the start's scatter, the episode's delay, the balls' drags, and the
    cameras (spawned once more, one stream per ball).

    ## Episode End
    ### Termination
    A ball touches the floor (a drop): the score is the catches before it.

    ### Truncation
    After `max_catches` catches, or ``max_catches * 2 s`` of simulated time.

    ## Arguments
    ```python
    import gymnasium as gym
    import motion_envs
    env = gym.make("MotionEnvs/Cascade-v1", level="medium", pattern="5")
    ```

    | Parameter         | Type      | Default     | Description |
    |-------------------|-----------|-------------|-------------|
    | `level`           | **str**   | `"medium"`  | `"easy"`, `"medium"` or `"hard"` (table above) |
    | `pattern`         | **str**   | `"3"`       | a registered pattern's name (as Cascade-v0's: `"3"`, `"3-human"`, `"4"`, `"5"`, `"441"`, `"531"`, `"423"`, `"51"`) |
    | `controller`      | **str**   | `"juggler"` | `juggler`, `juggler_mean_delay`, `juggler_oracle`, `fixed_point`, `juggler_oracle_catch`, `juggler_mean_delay_catch`, `juggler_delay_estimator`, `juggler_delay_tracker`, `juggler_delay_estimator_catch`, `juggler_estimator_tracker_catch` |
    | `delay_offset`    | **float** | `0.0`       | s added to the mean delay `juggler_mean_delay` and `juggler_delay_tracker` assume (0-0.25; a later meeting), or to `juggler_delay_estimator_catch`'s pooled estimate and its prior, the level's mean (-0.05-0.25; a correction of the estimate, may be negative; the timing entry's `timing_scale * u` added per flight), or `juggler_estimator_tracker_catch`'s offset (0-0.25, added to its estimate's correction and the timing error it steers to) |
    | `tracker_gain`    | **float** | `0.0`       | `juggler_delay_tracker`'s gain `k` (0-1.5; 0: the mean-delay catch plan), or `juggler_estimator_tracker_catch`'s (0: `juggler_delay_estimator_catch` told `delay_offset`) |
    | `delay_rule`      | **callable** | `None`   | how the pooled estimate is made from the episode's anchored flights of every ball, `(flights, gravity) -> delay` (:class:`~motion_envs.models.juggling.DelayRule`; None: each flight's least-residual delay, averaged); `juggler_delay_estimator`, `juggler_delay_estimator_catch`, `juggler_estimator_tracker_catch` only |
    | `anchor_frames`   | **int**   | `8`         | the frames after each release the estimate is made from (>= 3); the same controllers only |
    | `anchor_start`    | **bool**  | `False`     | each ball in flight at the start also anchored on the throw it left its thrower's hand with before `t = 0` (its time and point, the juggler's own; the velocity fitted), so the pooled estimate can come before the episode's first release is seen; the same controllers only |
    | `max_catches`     | **int**   | `30`        | catches after which the episode is truncated |
    | `residual_scale`  | **float** | `0.05`      | m of residual for an action of 1 |
    | `residual_phases` | **tuple** | `None`      | phases in which a hand's residual acts; None: all |
    | `observe_task_error` | **bool** | `False`  | 8 last entries: each hand's last catch's task error (table above) |
    | `reward_weights`  | **dict**  | `None`      | keys `catch`, `drop`, `likeness`, `action` |
    | `timing_scale`    | **float** | `0.0`       | s of told delay per unit of the action's timing entry (0-0.15; 0: no timing entry; `juggler_delay_tracker` and `juggler_delay_estimator_catch` only) |
    | `render_mode`     | **str**   | `None`      | `None` or `"rgb_array"` (camera `side`) |
    | `width`           | **int**   | `480`       | frame width in pixels |
    | `height`          | **int**   | `480`       | frame height in pixels |

    ## Version History
    * v1: Juggling-v2's human levels (a hidden per-episode delay with jitter, a
      position-only camera per ball with drops and occlusion near either palm, drag per
      ball, the capture at impact; ``observe_task_error`` added later, its default,
      False, leaves every rollout unchanged; ``timing_scale`` later still, its default
      0 likewise; the controller ``juggler_delay_estimator_catch`` later, every other
      controller's rollout unchanged; its ``delay_offset`` later still, the default 0
      leaving its rollouts unchanged, and then its timing entry, ``timing_scale`` 0 by
      default; the controller ``juggler_estimator_tracker_catch`` added 2026-12-07, every
      other controller's rollout unchanged; ``delay_rule`` and ``anchor_frames`` added
      2026-12-07, their defaults leaving every rollout unchanged; ``anchor_start`` added
      2026-12-07, False by default, every rollout unchanged).
    * v0: the pattern on Juggling-v1's physics, sensor and levels.
    """

    metadata: dict[str, Any] = {"render_modes": ["rgb_array"], "render_fps": 200}  # noqa: RUF012
    _DEFAULT_WEIGHTS = DEFAULT_CASCADE_REWARD_WEIGHTS

    def __init__(
        self,
        level: str = "medium",
        pattern: str = "3",
        controller: str = "juggler",
        delay_offset: float = 0.0,
        max_catches: int = 30,
        residual_scale: float = 0.05,
        residual_phases: Sequence[str] | None = None,
        reward_weights: Mapping[str, float] | None = None,
        render_mode: str | None = None,
        width: int = 480,
        height: int = 480,
        observe_task_error: bool = False,
        tracker_gain: float = 0.0,
        timing_scale: float = 0.0,
        delay_rule: DelayRule | None = None,
        anchor_frames: int = ANCHOR_FRAMES,
        anchor_start: bool = False,
    ) -> None:
        self.level = check_choice(level, "level", CASCADE_V1_LEVELS)
        #: Whether the observation ends with each hand's last catch's task error.
        self.observe_task_error = check_observe_task_error(observe_task_error)
        self.controller_name = check_choice(controller, "controller", tuple(CASCADE_V1_CONTROLLERS))
        self.delay_offset = check_delay_offset(delay_offset, self.controller_name)
        self.tracker_gain = check_tracker_gain(tracker_gain, self.controller_name)
        #: s of told delay per unit of the action's timing entry (0: no timing entry)
        self.timing_scale = check_timing_scale(timing_scale, self.controller_name)
        rule, anchors = check_delay_rule(delay_rule, anchor_frames, self.controller_name)
        #: whether the balls in flight at the start are anchored on their throws
        self.anchor_start = check_anchor_start(anchor_start, self.controller_name)
        self._init_episode_arguments(
            (max_catches, residual_scale, residual_phases, reward_weights),
            (render_mode, width, height),
        )
        lv = self.spec_level = V2_LEVELS[self.level]
        #: The registered pattern played (:class:`~motion_envs.models.juggling.PatternSpec`).
        self.pattern = pattern_spec(pattern)
        self.balls = self.pattern.balls
        self.gravity = 9.81
        self.task = JugglingTask(gravity=self.gravity)
        variant, mode = CASCADE_V1_CONTROLLERS[self.controller_name]
        #: the controller's catch plan (``*_catch`` controllers), else None
        plan = self.catch_plan = catch_plan(self.controller_name, self.pattern.fitted)
        own = None if self.pattern.fitted else plan  # the siteswap juggler's own catch
        self.controller: CascadeController | SiteswapController = pattern_controller(
            self.pattern, variant, self.gravity, catch=own
        )
        self.home = self.controller.home
        lead = plan.lead if plan is not None and own is None else 0.0  # told ahead
        tracker: DelayTracker | None = None
        if self.controller_name == "juggler_delay_tracker":
            tracker = DelayTracker(self.tracker_gain, self.delay_offset, lv.delay)
        elif self.controller_name == "juggler_estimator_tracker_catch":  # offset: the tracker's
            tracker = CorrectionTracker(self.tracker_gain, self.delay_offset)
        told = isinstance(tracker, CorrectionTracker)
        # on the pooled estimate (the correction tracker's offset: in its correction told)
        estimate = self.delay_offset if mode == "release" and not told else 0.0
        self.view = CascadeBallView(
            self.balls, mode, self.gravity, lv.mean_delay + (0.0 if told else self.delay_offset),
            catch_height(self.controller), lead, tracker, estimate, rule, anchors,
            self.anchor_start,
        )  # fmt: skip
        if self.timing_scale and tracker is None:  # the estimator's timing entry
            self.view.adjust = 0.0
        self.likeness = pattern_likeness(self.pattern, self.gravity)
        self._likeness = LikenessQuery(self.likeness)
        spec = WorldSpec.of(
            self.task,
            hands=CASCADE_HANDS,
            balls=self.balls,
            capture_speed=lv.capture_speed,
            air_density=AIR_DENSITY,
            impact_capture=True,
            contact_damping=IMPACT_CONTACT_DAMPING,
        )
        self.world = CascadeWorld(
            self.task,
            lv.release_speed_std,
            math.radians(lv.release_angle_std),
            self.balls,
            spec=spec,
        )
        self.cameras = [
            CameraSensor(
                self.task.dt,
                lv.frame_rate,
                lv.jitter_std,
                lv.drop_prob,
                lv.occlusion_radius,
                lv.position_std,
            )
            for _ in range(self.balls)
        ]
        self.model, self.data = self.world.model, self.world.data
        self.metadata = {**self.metadata, "render_fps": round(1.0 / self.task.dt)}
        self._time_limit = self.max_catches * CASCADE_TIME_PER_CATCH
        timing = 1 if self.timing_scale else 0
        self.action_space = gym.spaces.Box(
            -1.0, 1.0, (2 * CASCADE_HANDS + timing,), dtype=np.float32
        )
        self._held = HeldTaskErrors(CASCADE_HANDS, self.max_catches)
        low, high = self._bounds()
        self.observation_space = gym.spaces.Box(low, high, dtype=np.float32)
        self._low, self._high = low, high
        self._renderer: Any = None
        self._done = True
        self._state: CascadeState | None = None
        self._frames: list[deque[CameraFrame]] = [
            deque(maxlen=CASCADE_V1_FRAMES) for _ in range(self.balls)
        ]
        self._catches = self._tosses = 0
        self._release_time = [math.nan, math.nan]
        self._errors = (np.full((2, 2), np.nan), np.full(2, np.nan))
        self._misses = MissTracker(self.balls)
        #: s and 1/m ``(N,)``: the episode's true delay and the balls' drags (hidden)
        self.delay = math.nan
        self.drags = np.full(self.balls, np.nan)

    def _bounds(self) -> tuple[NDArray[np.float32], NDArray[np.float32]]:
        hx, hz = self.home[0]
        m, v = _POS_MARGIN, _SPEED_BOUND
        fz, t = self.task.floor_z, self._time_limit
        low: list[float] = []
        high: list[float] = []
        for _ in range(CASCADE_HANDS):
            low += [hx - m, fz - m, -v, -v, 0, 0, 0, 0, 0, 0, 0, hx - m, fz - m, hx - m, fz - m, 0]
            high += [hx + m, hz + m, v, v, 1, 1, 1, 1, 1, t, t, hx + m, hz + m, hx + m, hz + m, t]
        low += [0.0] * (2 * self.balls)
        high += [1.0] * (2 * self.balls)
        low += [hx - m, fz - m, 0, 0] * (self.balls * CASCADE_V1_FRAMES)
        high += [hx + m, hz + m, t, 1] * (self.balls * CASCADE_V1_FRAMES)
        if self.observe_task_error:
            low, high = (a + b for a, b in zip((low, high), self._held.bounds(t), strict=True))
        return np.array(low, dtype=np.float32), np.array(high, dtype=np.float32)

    @property
    def dt(self) -> float:
        """s of simulated time per step (one control period)."""
        return self.task.dt

    # -- episode ------------------------------------------------------------------------
    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[NDArray[np.float32], dict[str, Any]]:
        super().reset(seed=seed)
        base = int(seed) if seed is not None else int(self.np_random.integers(2**63))
        world_ss, controller_ss, start_ss, delay_ss, drag_ss, camera_ss = np.random.SeedSequence(
            base
        ).spawn(6)
        lv = self.spec_level
        self.delay = float(np.random.default_rng(delay_ss).uniform(*lv.delay))
        self.drags = np.random.default_rng(drag_ss).uniform(*lv.drag, size=self.balls)
        scatter = (lv.release_speed_std, math.radians(lv.release_angle_std))
        start = self.controller.start(scatter, np.random.default_rng(start_ss))
        true = self.world.reset(self.home, start=start, rng=np.random.default_rng(world_ss))
        for i, drag in enumerate(self.drags.tolist()):
            self.world.set_drag(i, drag)
        for camera, ss in zip(self.cameras, camera_ss.spawn(self.balls), strict=True):
            camera.reset(self.delay, np.random.default_rng(ss))
        self.view.reset(self.controller.start(), self.drags, self.delay)
        state = self.view.view(true)
        self.controller.reset(state, np.random.default_rng(controller_ss))
        self._state = state
        for frames in self._frames:
            frames.clear()
        self._done = False
        self._catches = self._tosses = 0
        self._release_time = [math.nan, math.nan]
        self._misses.reset()
        self._held.reset()
        return self._observation(true), self._info(true, seed=base)

    def _info(self, true: CascadeState, **extra: Any) -> dict[str, Any]:
        c = self.controller
        return {
            "phase": c.phase(0),
            "phases": (c.phase(0), c.phase(1)),
            "held": tuple(h in true.holder for h in range(CASCADE_HANDS)),
            "time": true.time,
            "hand": true.hand_pos[0].copy(),
            "hands": true.hand_pos.copy(),
            "balls": true.ball_pos.copy(),
            **extra,
        }

    def step(self, action: Any) -> tuple[NDArray[np.float32], float, bool, bool, dict[str, Any]]:
        if self._done or self._state is None:
            raise RuntimeError("the episode has ended (or never started); call reset() first")
        a = as_action(action, self.action_space.shape or ())
        invalid = not bool(np.isfinite(a).all())
        a = np.clip(np.nan_to_num(a, nan=0.0), -1.0, 1.0)
        if self.timing_scale:  # told from this step's releases on (CascadeBallView.record)
            adjust = self.timing_scale * float(a[-1])
            if self.view.tracker is not None:
                self.view.tracker.adjust = adjust
            else:  # the release estimator's offset
                self.view.adjust = adjust
            a = a[: 2 * CASCADE_HANDS]
        true = self._advance(self.residual_scale * a.reshape(2, 2))
        caught = sum(int(c >= 0) for c in true.caught)
        events: dict[str, Any] = {}
        if caught:
            events = {"task_error": self._errors[0], "catch_speed": self._errors[1]}
        like = 0.0
        for h in range(CASCADE_HANDS):
            sign = (1.0 if h == 0 else -1.0, 1.0)
            phase = self.controller.phase(h)
            like += self._likeness.distance(phase, true.hand_pos[h] * sign, true.hand_vel[h] * sign)
        reward, terms = self._rewards(caught, true.any_dropped, like / CASCADE_HANDS, float(a @ a))
        terminated, truncated = self._episode_end(true.any_dropped, true.time)
        if terminated:
            events.update(self._misses.miss(true))
        info = self._info(
            true,
            **terms,
            caught=caught,
            catches=self._catches,
            tosses=self._tosses,
            cycles=self._tosses,
            action_invalid=invalid,
            **events,
        )
        return self._observation(true), reward, terminated, truncated, info

    def _advance(self, residual: NDArray[np.float64]) -> CascadeState:
        """One control period with the hands' residuals ``(2, 2)`` (m): the controller's
        command on the view of the balls (masked by `residual_phases`), the world, each
        ball's camera and estimator, the counts. Returns the true state."""
        state = self._state
        assert state is not None
        c = self.controller
        targets, armed = c.command(state)
        if self.residual_phases is not None:
            acts = self.residual_acts[[PHASES.index(c.phase(h)) for h in range(CASCADE_HANDS)]]
            residual = np.where(acts[:, None], residual, 0.0)
        planned = [planned_catch(c, h) + self.view.lead for h in range(CASCADE_HANDS)]
        phases = [c.phase(h) for h in range(CASCADE_HANDS)]
        before = self.data.qpos.copy(), self.data.qvel.copy()
        true = self.world.step(targets + residual, armed)
        if any(b >= 0 for b in true.caught):
            self._errors = catch_errors(before, true, planned, self.task.dt)
            self._held.record(self._errors[0])
            self.view.felt(self._errors[0][:, 1])  # what the palms felt (the tracker's)
        self._misses.update(true, phases, planned)
        k = int(self.world.k[0])
        frames = []
        for i, camera in enumerate(self.cameras):
            ball = true.ball_pos[i]
            palm = nearest_palm(true.hand_pos, ball)
            new = camera.record(k, (float(ball[0]), float(ball[1])), palm, true.holder[i] >= 0)
            self._frames[i].extendleft(new)
            frames.append(new)
        self.view.record(true, frames)
        for h, b in enumerate(true.released):
            if b >= 0:
                self._release_time[h] = true.time
        self._state = self.view.view(true)
        self._catches += sum(int(x >= 0) for x in true.caught)
        self._tosses += sum(int(x >= 0) for x in true.released)
        return true

    def play(self, seed: int) -> tuple[int, int, bool, float]:
        """The zero-action episode reset with ``seed`` (the controller alone; the same
        periods as ``reset(seed=seed)`` then ``step(0)`` until the episode ends, without
        the observations and rewards): ``(catches, tosses, dropped, time)``."""
        self.reset(seed=seed)
        zero = np.zeros((CASCADE_HANDS, 2))
        while True:
            true = self._advance(zero)
            terminated, truncated = self._episode_end(true.any_dropped, true.time)
            if terminated or truncated:
                return self._catches, self._tosses, terminated, true.time

    def _observation(self, true: CascadeState) -> NDArray[np.float32]:
        c = self.controller
        row: list[float] = []
        for h in range(CASCADE_HANDS):
            row += [*true.hand_pos[h].tolist(), *true.hand_vel[h].tolist()]
            row.append(float(h in true.holder))
            row += _ONE_HOT[c.phase(h)]
            row += [c.phase_time(h), c.duration(h)]
            row += [*c.nominal_next(h).tolist(), *c.plan_end(h).tolist()]
            since = true.time - self._release_time[h]
            row.append(0.0 if math.isnan(since) else since)
        for i in range(self.balls):
            row += [float(true.holder[i] == 0), float(true.holder[i] == 1)]
        home = self.home[0].tolist()
        for frames in self._frames:
            for j in range(CASCADE_V1_FRAMES):
                if j < len(frames):
                    f = frames[j]
                    row += (f.x, f.z, true.time - f.arrival, 1.0)
                else:
                    row += (*home, 0.0, 0.0)
        if self.observe_task_error:
            row += self._held.entries()
        obs = np.array(row, dtype=np.float32)
        np.minimum(obs, self._high, out=obs)
        return np.maximum(obs, self._low, out=obs)

    # -- rendering (SideCameraMixin.render) ----------------------------------------------
    def _sync_scene(self) -> None:
        self.world.sync()
