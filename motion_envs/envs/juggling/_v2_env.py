"""``MotionEnvs/Juggling-v2``: juggle one ball seen through a delayed camera, in air."""

# ruff: noqa: E501  (the class docstring holds Gymnasium-style Markdown tables)

from __future__ import annotations

import math
from collections import deque
from collections.abc import Mapping, Sequence
from dataclasses import replace
from typing import Any

import gymnasium as gym
import numpy as np
from numpy.typing import NDArray

from motion_envs.datasets.juggling import JugglingState, JugglingTask
from motion_envs.envs._common import as_action, check_choice
from motion_envs.envs.juggling._cascade_v1_errors import HeldTaskErrors, check_observe_task_error
from motion_envs.envs.juggling._shared import (
    ESTIMATE_OFFSET,
    check_delay_offset,
    check_delay_rule,
    check_timing_scale,
    check_tracker_gain,
)
from motion_envs.envs.juggling._v1_batch import V1Batch
from motion_envs.envs.juggling._v1_env import OBS_HEAD, V1_CYCLE_TIME, OneBallEnv
from motion_envs.envs.juggling._v1_scene import JugglingV1World
from motion_envs.envs.juggling._world_spec import (
    AIR_DENSITY,
    IMPACT_CONTACT_DAMPING,
    WorldSpec,
)
from motion_envs.models.juggling import (
    ANCHOR_FRAMES,
    V2_CONTROLLERS,
    V2_LEVELS,
    CameraFrame,
    CameraSensor,
    CorrectionTracker,
    DelayRule,
    DelayTracker,
    DelayTrackerController,
    V2Controller,
    ballistic_apex,
    gaze_eye,
    make_v2_controller,
    v1_juggler,
    v1_likeness,
)

__all__ = ["AIR_DENSITY", "FRAMES", "V2_OBS_DIM", "JugglingV2Env", "V2Batch", "controller_view"]

#: Received camera frames in the observation (newest first).
FRAMES = 4
#: Observation size (see the class docstring).
V2_OBS_DIM = 16 + 4 * FRAMES


def controller_view(true: JugglingState) -> JugglingState:
    """What Juggling-v2's controller is given: the true hand and events; the ball's fields
    are the hand's (in flight it sees the ball only through its estimator)."""
    return replace(true, ball_pos=true.hand_pos, ball_vel=true.hand_vel)


class V2Batch(V1Batch):
    """Juggling-v2's batch: Juggling-v1's step (:class:`~motion_envs.envs.juggling._v1_batch.V1Batch`:
    the command with the residual, the world's period, the release scatter, the likeness,
    the reward, the episode's end, the observation's first 15 entries) with every command
    made by the controller in Python (it reads its camera's estimator), shown the hand
    in the ball's fields."""

    FAST = ()

    def shown(self, i: int) -> JugglingState:
        return controller_view(super().shown(i))


class JugglingV2Env(OneBallEnv):
    r"""Toss and catch one ball seen through a camera with a hidden human delay, in air.

    ## Description
    Juggling-v1's world and analytic juggler (one actuated hand within human limits, one
    ball, MuJoCo contacts, the juggler of Lippi et al. fitted on the **SIMULATED**
    demonstrations; :class:`~motion_envs.envs.juggling.JugglingV1Env`), with what a
    person faces and the juggler does not model, drawn per episode:

    * **a visuomotor delay** drawn from the level's part of the human range (100-250
      ms), hidden from the observation, plus a per-frame jitter;
    * **a camera** that reports ball POSITIONS only, at 100 Hz, with frame drops,
      occlusion near the palm and millimetre noise
      (:class:`~motion_envs.models.juggling.CameraSensor`);
    * **quadratic air drag** ``F = 1/2 rho C_d A v^2`` in MuJoCo's fluid model, with a
      per-episode coefficient ``k = rho C_d A / (2 m)`` between a juggling ball
      (0.009/m) and a table-tennis ball (0.14/m), unknown to the juggler
      (:mod:`~motion_envs.envs.juggling._world`, *Air drag*);
    * **the capture rule in the hand's frame**: a catch needs the palm to meet the
      ball slower than ``capture_speed`` (5 m/s) at the first physics step of their
      contact; a faster ball bounces off (*Capture at impact*).

    The analytic juggler's eq. 10 correction is fed the ball's state fitted to the
    frames it has received, taking them as the present (``controller="juggler"``); the
    agent adds a residual to each of its commands. Reference controllers
    (:data:`~motion_envs.models.juggling.V2_CONTROLLERS`): ``juggler_mean_delay``
    (frames shifted by the level's mean delay), ``juggler_delay_estimator`` (the
    delay estimated from the release, a hand-written fix) and ``juggler_oracle`` (given
    the episode's true delay and drag, on `gaze` each frame's gaze latency, not the
    frames' jitter; not a competitor). With a
    catch planned for the capture rule (the palm arrives early and meets the ball
    descending slower than it; :mod:`~motion_envs.models.juggling._v2_catch`):
    ``juggler_oracle_catch`` (the oracle's information, the UPPER REFERENCE) and
    ``juggler_mean_delay_catch`` (the level's mean delay, a competitor),
    ``juggler_delay_estimator_catch`` (the hand-written delay estimator's delay with the
    mean delay's plan: the two hand-written fixes together, a competitor; with
    `delay_offset` the frames are placed by the estimate plus the offset, a correction
    of the estimate's bias that may be negative), and
    ``juggler_gaze_estimator_catch`` (that catch plan on a hand-written gaze-aware
    estimator written for `gaze`: the delay and the gaze slope found from the releases,
    pooled over the episode; a competitor), and
    ``juggler_delay_tracker``: that catch plan with its delay corrected after every
    catch from the catch's timing error, ``D <- clip(D - k (e - delay_offset))`` over
    the level's delay range, told ``D + delay_offset``
    (:mod:`~motion_envs.models.juggling._delay_tracker`; the gain ``k`` is
    ``tracker_gain``; the env hands the controller the catch's task error, never the
    delay), and ``juggler_estimator_tracker_catch``: the two put together,
    ``juggler_delay_estimator_catch`` whose frames are placed by the release-anchored
    estimate plus a correction ``C + delay_offset``, ``C <- clip(C - k (e -
    delay_offset), -0.05, 0.05)`` after every catch from 0 (``k`` is ``tracker_gain``;
    :class:`~motion_envs.models.juggling.CorrectionTracker`; a competitor).

    A step is Juggling-v1's, in its batch of one (``V2Batch``, a
    :class:`~motion_envs.envs.juggling._v1_batch.V1Batch`: the command with the
    residual, the world's period, the release scatter, the human-likeness, the reward,
    the episode's end, observation entries 0-14), the controller given the hand in the
    ball's fields; the camera, the estimator and entries 15-31 are this environment's.

    Levels (the delay and the drag are drawn uniformly per episode):

    | level    | delay (ms) | jitter (ms) | frame drops | noise (mm) | drag `k` (1/m) | release speed / angle std | `capture_speed` (m/s) |
    |----------|------------|-------------|-------------|------------|----------------|---------------------------|------------------------|
    | `easy`   | 100-150    | 5           | 2 %         | 1          | 0.009-0.02     | 0.05 / 4 deg              | 5                      |
    | `medium` | 100-200    | 10          | 5 %         | 2          | 0.009-0.07     | 0.08 / 6 deg              | 5                      |
    | `hard`   | 150-250    | 15          | 10 %        | 3          | 0.009-0.14     | 0.12 / 12 deg             | 5                      |
    | `drift`  | 100-250, a walk | 10     | 5 %         | 2          | 0.009-0.03, per catch | 0.08 / 6 deg       | 5                      |
    | `gaze`   | 100-200, + 0.5-1.5 ms/deg of eccentricity per frame | 10 | 5 % | 2 | 0.009-0.07   | 0.08 / 6 deg              | 5                      |

    Every level's camera runs at 100 Hz and loses the ball within 10 cm of the hand's
    origin. On `drift` the delay and the drag change WITHIN the episode, at every catch
    (between flights): the delay takes a normal step of std 20 ms reflected at 100 and
    250 ms, the drag (a beanbag landing in a new shape) is drawn afresh; the oracle is
    told the new values (:mod:`~motion_envs.models.juggling._v2_levels` has the
    reasoning). On `gaze` the latency changes WITHIN a flight, frame by frame: each
    frame's latency is ``delay + slope * ecc + jitter``, ``ecc`` the angle (degrees),
    seen from an eye 0.45 m above the hand's home and 0.40 m out of the plane, between
    the ball and the fixation point, the apex of the flight predicted ballistically at
    its release (jugglers fixate near the apex; reaction times grow with eccentricity),
    ``slope`` drawn per episode from 0.5-1.5 ms per degree (measured: frames up to 83 ms
    later near the palm than at the apex, 14 ms at the median); the rest is `medium`'s
    (:mod:`~motion_envs.models.juggling._v2_levels` and
    :mod:`~motion_envs.models.juggling._camera` have the reasoning); the oracle is told
    each frame's gaze latency too. The true current delay, drag and gaze slope are the
    attributes ``delay``, ``drag`` and ``slope`` (0 but on `gaze`; for evaluation; never
    in the observation or the info).

    ## Action Space
    ``Box(-1, 1, (2,), float32)``: the residual ``(dx, dz)`` added to the controller's
    next hand target, times `residual_scale` (m), in the phases of `residual_phases`.

    With ``timing_scale > 0`` (controllers ``juggler_delay_tracker`` and
    ``juggler_delay_estimator_catch`` only) ``Box(-1, 1, (3,), float32)``: the residual,
    then a **timing** entry ``u``: the delay the juggler is told is the tracker's plus
    ``timing_scale * u`` s (at least 0), or for the delay estimator its estimate plus an
    offset of ``delay_offset + timing_scale * u`` s (the sum at least 0); the flight
    released in a step is fitted with the delay told in that step (the offset latched at
    its release), so the agent RE-TIMES the catch (a later told delay, a later meeting,
    the hand waiting lower) instead of moving the hand. ``u = 0`` is the controller
    alone (the tracker, or the estimator told `delay_offset`). The action cost ``|a|^2``
    is the residual's; a non-finite ``u`` counts as 0 and sets ``action_invalid``.

    ## Observation Space
    ``Box(low, high, (32,), float32)``, ``(36,)`` with ``observe_task_error=True``
    (positions within 10 m of the home, speeds within 30 m/s):

    | index   | observation                                                              | unit           |
    |---------|--------------------------------------------------------------------------|----------------|
    | 0, 1    | hand position ``x, z`` (proprioception, exact)                           | position (m)   |
    | 2, 3    | hand velocity                                                            | velocity (m/s) |
    | 4       | 1 if the ball is held, else 0 (touch)                                    | unitless       |
    | 5..8    | phase one-hot: toss, go_down, catch, return                              | unitless       |
    | 9       | time within the phase                                                    | time (s)       |
    | 10      | duration of the current phase plan                                       | time (s)       |
    | 11, 12  | the controller's next hand target (its plan, no residual)                | position (m)   |
    | 13, 14  | the plan's end point (in the catch phase: the planned catch point)       | position (m)   |
    | 15      | time since the hand last released the ball (0 before the first toss)     | time (s)       |
    | 16..31  | the last 4 received frames ``x, z, age, valid``, newest first: the ball's measured position, the time since the frame ARRIVED (s; its capture time is hidden), 1 if the slot holds a frame | m, s |
    | 32, 33  | only with ``observe_task_error=True``: the LAST catch's task error ``info["task_error"]``, ``offset`` (within 10 m) and ``timing`` (within the time limit; 0 when NaN), held until the next catch, 0 before the first | m, s |
    | 34      | only with ``observe_task_error=True``: 1 if entry 33 holds a timing (the catch had a planned time), else 0 | unitless |
    | 35      | only with ``observe_task_error=True``: the catches so far (0: no error yet; at most `max_catches`) | count |

    **Task error** (``observe_task_error=True``): the haptic feedback a juggler has in
    the palm, where and when the ball landed, entries 32-35 from the step of a catch
    (the observation that step returns) until the next; the delay and the drag stay
    hidden (:class:`~motion_envs.envs.juggling._cascade_v1_errors.HeldTaskErrors`).

    **Memory.** The observation is the present only: the delay is a property of the
    episode, and a policy can infer it only by relating the frames' arrivals to its
    own release (entry 15) over a flight (about 0.4 s, 80 steps): an agent needs memory
    over a flight, a recurrent policy (sb3-contrib's ``RecurrentPPO``) or a frame stack
    long enough to span one (Gymnasium's ``FrameStackObservation``; 4 frames of 5 ms
    see only the last 20 ms). Every entry is a plain number in a fixed slot, so frames
    stack.

    ## Rewards
    Juggling-v1's: ``w_catch * caught - w_drop * dropped - w_likeness * likeness -
    w_action * |a|^2`` (default weights ``catch: 10, drop: 10, likeness: 0.01, action:
    0.01``; ``likeness`` against the TRAINING demonstrations). `info` holds each
    weighted term, ``likeness``, ``catches``, ``tosses`` (``cycles``), ``phase``,
    ``held``, ``time``, the true ``hand`` and ``ball`` positions and
    ``action_invalid``; at a step with a catch also the task-error vector
    ``task_error = (offset, timing)``: where the ball met the palm relative to its
    centre (m, along ``x``) and the catch time minus the plan's catch time (s), and
    ``catch_speed`` (m/s), the speed at which the palm met the ball. At the step of a
    drop, the same vector of the miss, ``miss_error = (offset, timing)``, and
    ``miss_speed``: at the closest approach (sampled every 5 ms) of the falling ball's
    centre to the hand's origin in the last catch phase, the ``x`` offset, the time
    minus the plan's catch time, and the relative speed (absent when the ball fell
    before a catch phase). The offset and the meeting time are interpolated within
    the control period from its start (relative motion linear over 5 ms).

    ## Starting State
    The hand rests at the juggler's home with the ball in it, time 0, toss phase.
    `reset(seed=S)` seeds six independent streams ``SeedSequence(S).spawn(6)``: the
    world (release noise), the camera, the controller, the episode's delay, the
    episode's drag (on `drift` their streams also draw every catch's step and drag) and
    the gaze slope (drawn on `gaze` only; the first five are ``spawn(5)``'s, as before
    the level existed).

    ## Episode End
    ### Termination
    The ball touches the floor (a drop).

    ### Truncation
    After `max_catches` catches, or ``max_catches * 4 s`` of simulated time.

    ## Arguments
    ```python
    import gymnasium as gym
    import motion_envs
    env = gym.make("MotionEnvs/Juggling-v2", level="medium")
    ```

    | Parameter         | Type      | Default     | Description |
    |-------------------|-----------|-------------|-------------|
    | `level`           | **str**   | `"medium"`  | `"easy"`, `"medium"`, `"hard"`, `"drift"` or `"gaze"` (table above) |
    | `controller`      | **str**   | `"juggler"` | `juggler`, `juggler_mean_delay`, `juggler_delay_estimator`, `juggler_oracle`, `juggler_oracle_catch`, `juggler_mean_delay_catch`, `juggler_delay_estimator_catch`, `juggler_delay_tracker`, `juggler_gaze_estimator_catch`, `juggler_estimator_tracker_catch` |
    | `delay_offset`    | **float** | `0.0`       | s added to the mean delay `juggler_mean_delay` and `juggler_delay_tracker` assume (0-0.25; a later meeting), or to `juggler_delay_estimator_catch`'s estimated delay (-0.05-0.25; a correction of the estimate, may be negative; the timing entry's `timing_scale * u` added per flight), or `juggler_estimator_tracker_catch`'s offset (0-0.25, added to its estimate's correction and the timing error it steers to) |
    | `tracker_gain`    | **float** | `0.0`       | `juggler_delay_tracker`'s gain `k` (0-1.5; 0: the mean-delay catch plan), or `juggler_estimator_tracker_catch`'s (0: `juggler_delay_estimator_catch` told `delay_offset`) |
    | `timing_scale`    | **float** | `0.0`       | s of told delay per unit of the action's timing entry (0-0.15; 0: no timing entry; `juggler_delay_tracker` and `juggler_delay_estimator_catch` only) |
    | `delay_rule`      | **callable** | `None`   | how the release-anchored estimate is made from the episode's anchored flights, `(flights, gravity) -> delay` (:class:`~motion_envs.models.juggling.DelayRule`; None: each flight's least-residual delay, averaged); `juggler_delay_estimator`, `juggler_delay_estimator_catch`, `juggler_estimator_tracker_catch` only |
    | `anchor_frames`   | **int**   | `8`         | the frames after each release the estimate is made from (>= 3); the same controllers only |
    | `max_catches`     | **int**   | `10`        | catches after which the episode is truncated |
    | `residual_scale`  | **float** | `0.05`      | m of residual for an action of 1 |
    | `residual_phases` | **tuple** | `None`      | phases in which the residual acts; None: all |
    | `observe_task_error` | **bool** | `False`  | entries 32-35: the last catch's task error (table above) |
    | `reward_weights`  | **dict**  | `None`      | keys `catch`, `drop`, `likeness`, `action` |
    | `render_mode`     | **str**   | `None`      | `None` or `"rgb_array"` (camera `side`) |
    | `width`           | **int**   | `480`       | frame width in pixels |
    | `height`          | **int**   | `480`       | frame height in pixels |

    ## Version History
    * v2: a hidden per-episode human delay with jitter, a position-only camera with
      drops and occlusion, air drag, the capture at impact, the task-error vector
      (``observe_task_error`` added later; its default, False, leaves every rollout
      unchanged; ``timing_scale`` later still, its default 0 likewise; the controller
      ``juggler_delay_estimator_catch`` added 2026-12-07, the others' rollouts unchanged;
      its ``delay_offset`` later, the default 0 leaving its rollouts unchanged; its
      timing entry later still, ``timing_scale`` 0 by default; the level `gaze`
      added 2026-12-07, every other level's rollouts unchanged; the controller
      ``juggler_gaze_estimator_catch`` with it; the controller
      ``juggler_estimator_tracker_catch`` added 2026-12-07, the others' rollouts
      unchanged; ``delay_rule`` and ``anchor_frames`` added 2026-12-07, their defaults
      leaving every rollout unchanged).
    * v1: MuJoCo contacts and an actuated hand with human limits, a delayed noisy ball
      sensor with a fixed latency per level.
    * v0: the paper's setting (kinematic hand, exact ball state).
    """

    _OBS_KINDS = (*OBS_HEAD, "t", *("x", "z", "t", "1") * FRAMES)
    _BATCH = V2Batch
    #: Juggling-v1's ball sensor, which this world does not have (its camera runs in
    #: Python, beside the batch): no delay, no noise, no measurement in the batch's
    #: observation; the batch's measured ball is never shown to the controller.
    delay_steps, position_std, velocity_std, history = 0, 0.0, 0.0, 0
    controller: V2Controller

    def __init__(
        self,
        level: str = "medium",
        controller: str = "juggler",
        delay_offset: float = 0.0,
        max_catches: int = 10,
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
    ) -> None:
        self.level = check_choice(level, "level", tuple(V2_LEVELS))
        #: Whether the observation holds the last catch's task error (entries 32-35).
        self.observe_task_error = check_observe_task_error(observe_task_error)
        self.controller_name = check_choice(controller, "controller", tuple(V2_CONTROLLERS))
        self.delay_offset = check_delay_offset(delay_offset, self.controller_name)
        self.tracker_gain = check_tracker_gain(tracker_gain, self.controller_name)
        #: s of told delay per unit of the action's timing entry (0: no timing entry)
        self.timing_scale = check_timing_scale(timing_scale, self.controller_name)
        rule, anchors = check_delay_rule(delay_rule, anchor_frames, self.controller_name)
        self._init_episode_arguments(
            (max_catches, residual_scale, residual_phases, reward_weights),
            (render_mode, width, height),
        )
        lv = self.spec_level = V2_LEVELS[self.level]
        self.gravity = 9.81
        self.task = JugglingTask(gravity=self.gravity)
        juggler = v1_juggler(self.gravity)
        self.home = np.asarray(juggler.home_, dtype=np.float64)
        tracker: DelayTracker | None = None
        if self.controller_name == "juggler_delay_tracker":
            tracker = DelayTracker(self.tracker_gain, self.delay_offset, lv.delay)
        elif self.controller_name == "juggler_estimator_tracker_catch":  # offset: the tracker's
            tracker = CorrectionTracker(self.tracker_gain, self.delay_offset)
        estimate = self.controller_name == ESTIMATE_OFFSET[0]  # its offset: on the estimate
        told = isinstance(tracker, CorrectionTracker)
        self.controller = make_v2_controller(
            self.controller_name, juggler, self.gravity,
            lv.mean_delay + (0.0 if estimate or told else self.delay_offset), tracker,
            self.delay_offset if estimate else 0.0, rule, anchors,
        )  # fmt: skip
        self._eye = gaze_eye((float(self.home[0]), float(self.home[1])))
        self.controller.estimator.eye = self._eye  # the gaze-aware estimator's eye
        self.likeness = v1_likeness(self.gravity, "train")
        spec = WorldSpec.of(
            self.task,
            capture_speed=lv.capture_speed,
            air_density=AIR_DENSITY,
            impact_capture=True,
            contact_damping=IMPACT_CONTACT_DAMPING,
        )
        self.world = JugglingV1World(
            self.task, lv.release_speed_std, math.radians(lv.release_angle_std), spec=spec
        )
        self.camera = CameraSensor(
            self.task.dt,
            lv.frame_rate,
            lv.jitter_std,
            lv.drop_prob,
            lv.occlusion_radius,
            lv.position_std,
        )
        self._held = HeldTaskErrors(1, self.max_catches)
        #: s, the timing entry's ``timing_scale * u`` of the last step, told the estimator
        #: of ``juggler_delay_estimator_catch`` at the next release (the tracker keeps its
        #: own, ``DelayTracker.adjust``)
        self._adjust = 0.0
        self._init_spaces(self.max_catches * V1_CYCLE_TIME)
        if self.timing_scale:
            self.action_space = gym.spaces.Box(-1.0, 1.0, (3,), dtype=np.float32)
        self._frames: deque[CameraFrame] = deque(maxlen=FRAMES)
        #: this step's catch: its task error and meeting speed (None: no catch)
        self._caught: tuple[NDArray[np.float64], float] | None = None
        #: the episode's catches' task errors
        self._task_errors: list[NDArray[np.float64]] = []
        self._release_time = math.nan
        #: the falling ball's closest approach to the hand in this catch phase:
        #: ``(distance, x offset, time - planned catch time, relative speed)``
        self._closest: tuple[float, float, float, float] | None = None
        #: s and 1/m: the episode's true (current) delay and drag (hidden from the policy)
        self.delay = self.drag = math.nan
        #: s per degree: the episode's true gaze slope (level ``gaze``; 0 elsewhere;
        #: hidden from the policy)
        self.slope = math.nan
        self._drift_rngs: tuple[np.random.Generator, np.random.Generator] | None = None

    # -- episode ------------------------------------------------------------------------
    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[NDArray[np.float32], dict[str, Any]]:
        super().reset(seed=seed)
        base = int(seed) if seed is not None else int(self.np_random.integers(2**63))
        # spawn(6)'s first five children are spawn(5)'s: the sixth (the gaze slope's)
        # leaves every other stream, and every level without gaze, as before
        streams = np.random.SeedSequence(base).spawn(6)
        world_rng, camera_rng, controller_rng, delay_rng, drag_rng, slope_rng = (
            np.random.default_rng(s) for s in streams
        )
        lv = self.spec_level
        self.delay = float(delay_rng.uniform(*lv.delay))
        self.drag = float(drag_rng.uniform(*lv.drag))
        self.slope = float(slope_rng.uniform(*lv.gaze_slope)) if lv.gaze_slope[1] else 0.0
        self._drift_rngs = (delay_rng, drag_rng)  # drawn from again at catches (drift)
        true = self.world.reset(self.home, rng=world_rng)
        self.world.set_drag(0, self.drag)
        self.camera.reset(self.delay, camera_rng, self.slope, self._eye)
        self.controller.estimator.reset(self.drag, self.delay)
        state = controller_view(true)
        self.controller.reset(state, controller_rng)
        if self.timing_scale:  # no adjustment before the first action
            self._adjust = 0.0
            self._retell()
        self._frames.clear()
        self._release_time = math.nan
        self._closest = None
        self._caught = None
        self._task_errors.clear()
        self._held.reset()
        obs, info = self._start(true, state, base)
        self._observe_frames(obs, true.time)
        return obs, info

    def step(self, action: Any) -> tuple[NDArray[np.float32], float, bool, bool, dict[str, Any]]:
        if not self.timing_scale:
            return super().step(action)
        a = as_action(action, (3,))
        u = float(a[2])
        finite = math.isfinite(u)
        adjust = self.timing_scale * (min(max(u, -1.0), 1.0) if finite else 0.0)
        controller = self.controller
        if isinstance(controller, DelayTrackerController):
            controller.tracker.adjust = adjust
        else:  # the estimator's offset: latched at this step's release, if any (_retell)
            self._adjust = adjust
        obs, reward, terminated, truncated, info = super().step(a[:2])
        if not finite:
            info["action_invalid"] = True
        return obs, reward, terminated, truncated, info

    def _step_batch(
        self, action: NDArray[np.float64]
    ) -> tuple[NDArray[np.float32], NDArray[np.float64]]:
        """The batch's step (Juggling-v1's command, period, reward and episode end), then
        the camera and the estimator, the catch's task error, the closest approach in a
        catch phase, the drift, the observation's entries from 15 on."""
        before = self.data.qpos[:4].copy(), self.data.qvel[:4].copy()
        obs, out = super()._step_batch(action)
        true = self.world.state
        assert true is not None
        controller = self.controller
        planned = math.nan
        if controller.phase == "catch":  # the phase after the step's command
            episode = controller._episode
            planned = episode.t_start + episode.duration
        self._caught = None
        if true.caught:
            self._caught = self._task_error(before, true.time - self.task.dt, planned)
            self._task_errors.append(self._caught[0])
            self._held.record(self._caught[0])
            controller.felt(self._caught[0])  # what the palm felt (the delay tracker's)
        hand = (float(true.hand_pos[0]), float(true.hand_pos[1]))
        ball = (float(true.ball_pos[0]), float(true.ball_pos[1]))
        if true.released and self.slope:  # the gaze fixates the new flight's apex
            vel = (float(true.ball_vel[0]), float(true.ball_vel[1]))
            self.camera.fixate(ballistic_apex(ball, vel, self.gravity))
        frames = self.camera.record(int(self.world.k[0]), ball, hand, true.held)
        if true.released:
            hand_vel = (float(true.hand_vel[0]), float(true.hand_vel[1]))
            controller.estimator.released(true.time, *hand, hand_vel)
            if self.timing_scale:  # the new flight fitted with the delay told now
                self._retell()
            self._release_time = true.time
            self._closest = None
        elif not true.held and controller.phase == "catch" and true.ball_vel[1] < 0:
            rel = true.ball_pos - true.hand_pos
            dist = math.hypot(float(rel[0]), float(rel[1]))
            if self._closest is None or dist < self._closest[0]:
                rv = true.ball_vel - true.hand_vel
                self._closest = (dist, float(rel[0]), true.time - planned,
                                 math.hypot(float(rv[0]), float(rv[1])))  # fmt: skip
        controller.estimator.add(frames)
        self._frames.extendleft(frames)
        if true.caught and self.spec_level.drifts:
            self._drift()
        self._observe_frames(obs, true.time)
        return obs, out

    def _retell(self) -> None:
        """With a timing entry, at a release and at a reset: the delay told from now on,
        so the flight released now is fitted with it until the next release: the
        tracker's told delay (:meth:`DelayTrackerController.retell`, its ``adjust`` set
        in :meth:`step`), or the release-anchored estimator's ``offset``, `delay_offset`
        plus the timing entry's ``timing_scale * u`` (``_adjust``, 0 at a reset)."""
        controller = self.controller
        if isinstance(controller, DelayTrackerController):
            controller.retell()
        else:
            controller.estimator.tell(offset=self.delay_offset + self._adjust)

    def _add_info(self, info: dict[str, Any], terminated: bool) -> None:
        """At a catch its ``task_error`` and ``catch_speed``; at a drop its ``miss_error``
        and ``miss_speed``."""
        if self._caught is not None:
            info["task_error"], info["catch_speed"] = self._caught
        elif terminated and self._closest is not None:  # the drop's miss
            _, offset, timing, rel_speed = self._closest
            info["miss_error"] = np.array([offset, timing])
            info["miss_speed"] = rel_speed

    def _drift(self) -> None:
        """Level ``drift``: at a catch the delay takes its next step and the drag is
        drawn afresh (``V2Level.next_delay``/``next_drag``, from the episode's delay and
        drag streams); the camera's frames captured from now on carry the new delay, the
        ball flies with the new drag, the oracle is told both."""
        lv = self.spec_level
        assert self._drift_rngs is not None
        delay_rng, drag_rng = self._drift_rngs
        self.delay = lv.next_delay(self.delay, delay_rng)
        self.drag = lv.next_drag(self.drag, drag_rng)
        self.camera.delay = self.delay
        self.world.set_drag(0, self.drag)
        self.controller.estimator.retell(self.drag, self.delay)

    def _task_error(
        self, before: tuple[NDArray[np.float64], NDArray[np.float64]], t0: float, planned: float
    ) -> tuple[NDArray[np.float64], float]:
        """The catch's ``(offset, timing)`` and meeting speed from the state at the
        period's start: the relative motion, linear over the period, meets the palm's
        top (the ball's centre level with the hand's origin) at ``s`` in ``[0, dt]``."""
        q, v = before
        rx, rz = q[2] - q[0], q[3] - q[1]
        vx, vz = v[2] - v[0], v[3] - v[1]
        dt = self.task.dt
        s = min(max(-rz / vz, 0.0), dt) if vz < 0 else 0.0
        return np.array([rx + vx * s, t0 + s - planned]), math.hypot(vx, vz)

    def _bounds(self) -> tuple[NDArray[np.float32], NDArray[np.float32]]:
        """Juggling-v1's bounds by kind (:meth:`OneBallEnv._bounds`), then with
        ``observe_task_error`` the task error's (:meth:`HeldTaskErrors.bounds`)."""
        low, high = super()._bounds()
        if not self.observe_task_error:
            return low, high
        lo, hi = self._held.bounds(self._time_limit)
        f32 = np.float32
        return np.append(low, np.array(lo, f32)), np.append(high, np.array(hi, f32))

    def nominal_episode(self, seed: int) -> dict[str, Any]:
        """Juggling-v1's (:meth:`OneBallEnv.nominal_episode`) and the catches'
        ``task_errors (n, 2)``."""
        episode = super().nominal_episode(seed)
        episode["task_errors"] = np.array(self._task_errors, dtype=np.float64).reshape(-1, 2)
        return episode

    def _observe_frames(self, obs: NDArray[np.float32], time: float) -> None:
        """Entries 15.. of the observation ``obs`` (the batch wrote Juggling-v1's first
        15, the same entries): the time since the release, the received frames and with
        ``observe_task_error`` the last catch's task error."""
        since = time - self._release_time
        row = [0.0 if math.isnan(since) else since]
        for i in range(FRAMES):
            if i < len(self._frames):
                f = self._frames[i]
                row += (f.x, f.z, time - f.arrival, 1.0)
            else:
                row += (float(self.home[0]), float(self.home[1]), 0.0, 0.0)
        if self.observe_task_error:
            row += self._held.entries()
        tail = np.array(row, dtype=np.float32)
        np.minimum(tail, self._high[15:], out=tail)
        obs[15:] = np.maximum(tail, self._low[15:], out=tail)
