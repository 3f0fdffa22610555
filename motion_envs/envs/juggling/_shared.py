"""What Juggling-v1's and Cascade-v0's environments share: their arguments (a level and
the values that override it, the world's gravity, the controller, the episode's length,
the residual's scale and the phases it acts in, the reward's weights, the rendering) and a
step's bookkeeping (the weighted reward terms, termination at a drop, truncation after
``max_catches`` catches or the time limit)."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from motion_envs.datasets.juggling import PHASES, JugglingState
from motion_envs.envs._common import (
    check_choice,
    check_integer,
    check_number,
    check_reward_weights,
    check_scale,
)
from motion_envs.models.juggling import (
    ANCHOR_FRAMES,
    LEVELS,
    TRACKER_MAX_GAIN,
    DelayRule,
    check_gravity,
)

__all__ = [
    "ESTIMATE_OFFSET",
    "MAX_TIMING_SCALE",
    "OFFSET_CONTROLLERS",
    "RULE_CONTROLLERS",
    "TIMING_CONTROLLERS",
    "TRACKER_CONTROLLERS",
    "LevelsEnvMixin",
    "check_anchor_start",
    "check_delay_offset",
    "check_delay_rule",
    "check_phases",
    "check_timing_scale",
    "check_tracker_gain",
]


#: The controllers told a ``delay_offset``: a later delay than the level's mean
#: (``juggler_mean_delay``, ``juggler_delay_tracker``), or a correction of the
#: release-anchored estimate (``juggler_delay_estimator_catch``, :data:`ESTIMATE_OFFSET`),
#: or the offset of the estimate's tracked correction (``juggler_estimator_tracker_catch``,
#: a later meeting as the tracker's, >= 0).
OFFSET_CONTROLLERS = (
    "juggler_mean_delay",
    "juggler_delay_tracker",
    "juggler_delay_estimator_catch",
    "juggler_estimator_tracker_catch",
)
#: The controllers with a tracker, whose gain ``tracker_gain`` is: the delay tracker and
#: the release-anchored estimate with its tracked correction.
TRACKER_CONTROLLERS = ("juggler_delay_tracker", "juggler_estimator_tracker_catch")
#: The controller whose ``delay_offset`` corrects an ESTIMATE, so may be negative, and
#: its range (s). The estimate's measured bias has either sign (Cascade-v1, the pooled
#: estimate minus the true delay: -7.0 to +2.2 ms mean by level and pattern, sd up to
#: 15 ms; docs/models.md), so a correction must reach below 0; 50 ms is half the
#: lowest human delay, far beyond any measured bias. The mean delay's offset stays >= 0
#: (a later meeting; the tracker's clip assumes it).
ESTIMATE_OFFSET: tuple[str, tuple[float, float]] = ("juggler_delay_estimator_catch", (-0.05, 0.25))


def _real(value: Any, lo: float, hi: float) -> float:
    """``value`` as a float if it is a real number in ``[lo, hi]``, else NaN."""
    real = isinstance(value, (int, float, np.integer, np.floating))
    try:  # bools, None, text, an int beyond float64's range: refused as out of range
        out = float(value) if real and not isinstance(value, bool) else math.nan
    except OverflowError:
        out = math.nan
    return out if lo <= out <= hi else math.nan  # also rejects NaN


def check_delay_offset(delay_offset: float, controller: str) -> float:
    """``delay_offset`` (s) as a float in [0, 0.25] ([-0.05, 0.25] for the estimate's
    controller, :data:`ESTIMATE_OFFSET`), nonzero only for the :data:`OFFSET_CONTROLLERS`
    (the delay they are told); else one-line ValueError naming the argument."""
    name, (low, high) = ESTIMATE_OFFSET
    if controller != name:
        low = 0.0
    offset = _real(delay_offset, low, high)
    if math.isnan(offset):
        extra = "" if controller == name else f"; [{ESTIMATE_OFFSET[1][0]}, {high}] s for {name!r}"
        raise ValueError(
            f"delay_offset must be in [{low:g}, {high}] s for controller={controller!r}{extra}; "
            f"got {delay_offset!r:.80}"
        )
    if offset and controller not in OFFSET_CONTROLLERS:
        raise ValueError(
            f"delay_offset is for controller={' or '.join(map(repr, OFFSET_CONTROLLERS))}; "
            f"got {controller!r}"
        )
    return offset


def _tracker_argument(
    name: str,
    value: float,
    high: float,
    controller: str,
    unit: str = "",
    controllers: tuple[str, ...] = ("juggler_delay_tracker",),
) -> float:
    """The argument ``name``'s ``value`` as a float in ``[0, high]``, nonzero only with one
    of ``controllers`` (the tracker's by default); else one-line ValueError naming the
    argument."""
    out = _real(value, 0.0, high)
    if math.isnan(out):
        raise ValueError(f"{name} must be in [0, {high}]{unit}; got {value!r:.80}")
    if out and controller not in controllers:
        raise ValueError(
            f"{name} is for controller={' or '.join(map(repr, controllers))}; got {controller!r}"
        )
    return out


def check_tracker_gain(tracker_gain: float, controller: str) -> float:
    """``tracker_gain`` (the tracker's gain ``k``) in ``[0, TRACKER_MAX_GAIN]``, nonzero
    only for the :data:`TRACKER_CONTROLLERS` (:func:`_tracker_argument`)."""
    return _tracker_argument(
        "tracker_gain", tracker_gain, TRACKER_MAX_GAIN, controller, "", TRACKER_CONTROLLERS
    )


#: s, the largest ``timing_scale`` accepted (the human delay range's width, 150 ms).
MAX_TIMING_SCALE = 0.15
#: The controllers with an agent's timing entry (``timing_scale``): the delay tracker
#: (its told delay, :class:`~motion_envs.models.juggling.DelayTracker`'s ``adjust``) and
#: the delay estimator with the catch plan (its estimate's offset, ``delay_offset``
#: plus the entry's), each latched per flight at its release.
TIMING_CONTROLLERS = ("juggler_delay_tracker", ESTIMATE_OFFSET[0])


def check_timing_scale(timing_scale: float, controller: str) -> float:
    """``timing_scale`` (s told later per unit of the action's timing entry) in ``[0,
    MAX_TIMING_SCALE]``, nonzero only for the :data:`TIMING_CONTROLLERS` whose told delay
    it adjusts (:func:`_tracker_argument`)."""
    return _tracker_argument(
        "timing_scale", timing_scale, MAX_TIMING_SCALE, controller, " s", TIMING_CONTROLLERS
    )


#: The controllers whose estimators anchor on the release (mode ``"release"``), so take a
#: ``delay_rule`` and ``anchor_frames``.
RULE_CONTROLLERS = (
    "juggler_delay_estimator",
    "juggler_delay_estimator_catch",
    "juggler_estimator_tracker_catch",
)


def check_delay_rule(
    delay_rule: DelayRule | None, anchor_frames: int, controller: str
) -> tuple[DelayRule | None, int]:
    """``delay_rule`` (a callable, or None) and ``anchor_frames`` (an integer >= 3), other
    than their defaults only for the :data:`RULE_CONTROLLERS`; else one-line ValueError
    naming the argument."""
    if delay_rule is not None and not callable(delay_rule):
        raise ValueError(f"delay_rule must be a callable (flights, gravity) -> delay or None; "
                         f"got {delay_rule!r}")  # fmt: skip
    if (
        isinstance(anchor_frames, bool)
        or not isinstance(anchor_frames, (int, np.integer))
        or (anchor_frames < 3)
    ):
        raise ValueError(f"anchor_frames must be an integer >= 3; got {anchor_frames!r}")
    if (delay_rule is not None or anchor_frames != ANCHOR_FRAMES) and (
        controller not in RULE_CONTROLLERS
    ):
        raise ValueError(f"delay_rule and anchor_frames are for the controllers "
                         f"{list(RULE_CONTROLLERS)}; got controller={controller!r}")  # fmt: skip
    return delay_rule, int(anchor_frames)


def check_anchor_start(anchor_start: bool, controller: str) -> bool:
    """``anchor_start`` (a bool), True only for the :data:`RULE_CONTROLLERS`; else one-line
    ValueError naming the argument."""
    if not isinstance(anchor_start, (bool, np.bool_)):
        raise ValueError(f"anchor_start must be True or False; got {anchor_start!r}")
    if anchor_start and controller not in RULE_CONTROLLERS:
        raise ValueError(f"anchor_start is for the controllers {list(RULE_CONTROLLERS)}; "
                         f"got controller={controller!r}")  # fmt: skip
    return bool(anchor_start)


def check_phases(phases: Sequence[str] | None) -> tuple[str, ...] | None:
    """``residual_phases`` (a list or tuple of distinct phase names) as a tuple (None
    stays None); else ``ValueError`` naming the argument."""
    if phases is None:
        return None
    if not isinstance(phases, (list, tuple)) or not all(isinstance(p, str) for p in phases):
        raise ValueError(f"residual_phases must be a list of phase names; got {phases!r}")
    names = tuple(phases)
    for p in names:
        check_choice(p, "residual_phases entry", PHASES)
    if not names or len(set(names)) != len(names):
        raise ValueError(f"residual_phases must name distinct phases; got {list(names)}")
    return names


class LevelsEnvMixin:
    """The shared arguments and step bookkeeping of the juggling environments with levels.

    A subclass sets ``_CONTROLLERS`` (the controller names) and ``_DEFAULT_WEIGHTS`` (the
    reward weights), calls :meth:`_init_arguments` first in ``__init__`` and sets
    ``_time_limit`` (s), ``_catches`` and ``_done``."""

    _CONTROLLERS: tuple[str, ...]
    _DEFAULT_WEIGHTS: Mapping[str, float]
    metadata: dict[str, Any]
    level: str
    latency: float
    position_std: float
    velocity_std: float
    release_speed_std: float
    release_angle_std: float
    gravity: float
    controller_name: str
    #: The world's name for :func:`~motion_envs.models.juggling.check_gravity`.
    _WORLD = "Juggling-v1"
    max_catches: int
    residual_scale: float
    residual_phases: tuple[str, ...] | None
    residual_acts: NDArray[np.bool_]
    reward_weights: dict[str, float]
    render_mode: str | None
    width: int
    height: int
    _time_limit: float
    _catches: int
    _tosses: int
    _done: bool

    def _init_arguments(
        self,
        level: tuple[str, float | None, float | None, float | None, float | None, float | None],
        world: tuple[float, str, int, float, Sequence[str] | None, Mapping[str, float] | None],
        rendering: tuple[str | None, int, int],
    ) -> None:
        """Check and set the arguments: ``level`` is ``(level, latency, position_std,
        velocity_std, release_speed_std, release_angle_std)`` (None: the level's value),
        ``world`` ``(gravity, controller, max_catches, residual_scale, residual_phases,
        reward_weights)``, ``rendering`` ``(render_mode, width, height)``.

        ``residual_phases`` (:func:`check_phases`) also gives ``residual_acts``, the
        ``(len(PHASES),)`` bool mask of the phases in which a hand's residual acts (all
        with None): a hand whose controller is in phase ``PHASES[i]`` after its command
        gets the residual only where ``residual_acts[i]``."""
        name, latency, position_std, velocity_std, release_speed_std, release_angle_std = level
        self.level = check_choice(name, "level", tuple(LEVELS))
        base = LEVELS[self.level]

        def pick(value: float | None, name: str, default: float, high: float) -> float:
            return default if value is None else check_number(value, name, 0.0, high)

        self.latency = pick(latency, "latency", base.latency, 1.0)
        self.position_std = pick(position_std, "position_std", base.position_std, 1.0)
        self.velocity_std = pick(velocity_std, "velocity_std", base.velocity_std, 10.0)
        self.release_speed_std = pick(
            release_speed_std, "release_speed_std", base.release_speed_std, 1.0
        )
        self.release_angle_std = pick(
            release_angle_std, "release_angle_std", base.release_angle_std, 90.0
        )
        gravity, controller, max_catches, residual_scale, residual_phases, reward_weights = world
        self.gravity = check_number(gravity, "gravity", 0.0, 100.0, low_open=True)
        check_gravity(self.gravity, self._WORLD)  # what the demonstrations' timing allows
        self.controller_name = check_choice(controller, "controller", self._CONTROLLERS)
        self._init_episode_arguments(
            (max_catches, residual_scale, residual_phases, reward_weights), rendering
        )

    def _init_episode_arguments(
        self,
        episode: tuple[int, float, Sequence[str] | None, Mapping[str, float] | None],
        rendering: tuple[str | None, int, int],
    ) -> None:
        """Check and set ``episode = (max_catches, residual_scale, residual_phases,
        reward_weights)`` and ``rendering = (render_mode, width, height)`` (every
        juggling env with levels has them; :meth:`_init_arguments` ends with this)."""
        render_mode, width, height = rendering
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(
                f"render_mode must be None or one of {self.metadata['render_modes']}; "
                f"got {render_mode!r}"
            )
        max_catches, residual_scale, residual_phases, reward_weights = episode
        self.max_catches = check_integer(max_catches, "max_catches", 1, 10**6)
        self.residual_scale = check_scale(residual_scale, 1.0)
        #: Phases in which a hand's residual acts (None: all).
        self.residual_phases = check_phases(residual_phases)
        #: ``(len(PHASES),)`` bool: whether a hand's residual acts in each phase.
        self.residual_acts = np.array(
            [self.residual_phases is None or p in self.residual_phases for p in PHASES]
        )
        self.reward_weights = check_reward_weights(reward_weights, self._DEFAULT_WEIGHTS)
        for key, value in (("width", width), ("height", height)):
            check_integer(value, key, 16, 8192)
        self.render_mode = render_mode
        self.width, self.height = int(width), int(height)

    def _rewards(
        self, caught: int, dropped: bool, likeness: float, action_sq: float
    ) -> tuple[float, dict[str, float]]:
        """The reward and its info terms: ``caught`` catches and ``dropped`` this step, the
        hand's ``likeness`` cost (m) and the action's squared norm ``action_sq``."""
        w = self.reward_weights
        r_catch = w["catch"] * caught
        r_drop = -w["drop"] * float(dropped)
        r_like = -w["likeness"] * likeness
        r_act = -w["action"] * action_sq
        reward = r_catch + r_drop + r_like + r_act
        terms = {
            "reward_catch": r_catch,
            "reward_drop": r_drop,
            "reward_likeness": r_like,
            "reward_action": r_act,
            "likeness": likeness,
        }
        return float(reward), terms

    def _step_info(
        self, terms: dict[str, float], true: JugglingState, phase: str, invalid: bool
    ) -> dict[str, Any]:
        """A step's ``info`` (the one-ball envs'): the reward's ``terms``, the event and
        the counts, the phase, the true hand and ball, ``action_invalid``."""
        return {
            **terms,
            "caught": bool(true.caught),
            "catches": self._catches,
            "tosses": self._tosses,
            "cycles": self._tosses,
            "phase": phase,
            "held": true.held,
            "time": true.time,
            "hand": true.hand_pos.copy(),
            "ball": true.ball_pos.copy(),
            "action_invalid": invalid,
        }

    def _episode_end(self, dropped: bool, time: float) -> tuple[bool, bool]:
        """``(terminated, truncated)`` after a step ending at ``time`` (s): terminated by a
        drop, truncated after ``max_catches`` catches or at the time limit."""
        terminated = bool(dropped)
        truncated = not terminated and (
            self._catches >= self.max_catches or time >= self._time_limit
        )
        self._done = terminated or truncated
        return terminated, truncated
