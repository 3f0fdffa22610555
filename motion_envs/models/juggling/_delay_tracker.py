r"""An online delay tracker driven by the task error: the juggler corrects the delay it
assumes from what it feels at each catch.

The mean-delay catch plan (``juggler_mean_delay_catch``,
:mod:`~motion_envs.models.juggling._v2_catch`) places every camera frame at its arrival
minus one fixed delay, the level's mean. When the assumed delay ``\hat d`` exceeds the
episode's true delay ``d`` by ``\delta = \hat d - d``, a frame is believed captured
``\delta`` earlier than it was, the fitted flight runs ``\delta`` ahead of the ball, and
the ball passes the planned meeting point ``\delta`` LATE: the catch's timing error
(the catch time minus the planned meeting, ``info["task_error"][1]``) is about
``s \delta`` with ``s = d timing / d \hat d`` near 1 where the palm waits at the meeting
point. Measured on the first catches of ``juggler_mean_delay_catch`` on TRAINING episodes (seeds
from 1000; 2026-12-06): Juggling-v2 medium ``s = 0.92``, hard ``0.99`` (40 episodes),
residual std 8 and 12 ms; Cascade-v1 three balls medium ``s = 0.85`` (13 ms), five balls
medium ``s = 2.3`` with a residual std of 93 ms (15 episodes, every catch; the siteswap
juggler's timing tells its delay poorly; measured on the plain siteswap juggler, before
``juggler_mean_delay_catch`` got its catch plan on five balls, not re-measured since).

**The tracker** (:class:`DelayTracker`): an estimate ``D`` of the delay, starting at the
level's mean, and a declared ``offset`` (the late meeting's: the delay told is ``D +
offset``, so the ball is planned to arrive ``offset`` late, the hand waiting lower on its
path). After every catch with a timing error ``e`` (relative to the planned meeting),

.. math:: D \leftarrow \mathrm{clip}(D - k\,(e - \mathrm{offset}),\ d_{low},\ d_{high})

with one gain ``k`` and the level's delay range ``[d_low, d_high]``; a catch without a
timing (NaN) leaves ``D``. The next flight is fitted with ``D + offset``. Under the
linear model ``e - offset = s (D - d)`` (a catch ``offset`` late when ``D = d``) the
estimate's error shrinks geometrically,

.. math:: D_{n} - d = (1 - k s)^n (D_0 - d),

inside the range (the clip only stops it at the ends); ``k = 0`` is the base controller
(the mean-delay catch plan told ``offset``) exactly. The gain and the offset are chosen
on VALIDATION seeds from declared grids by the benches (``delay_tracker`` rows).

**An agent's timing action** (the envs' ``timing_scale``): :attr:`DelayTracker.adjust`
is added to the told delay, ``D + offset + adjust`` (at least 0), and the envs set it
from the action's last entry; a flight is fitted with the delay told at its release, so
an agent re-times a catch by the delay it tells at the ball's release (a later told
delay plans a later meeting, the hand waiting lower). ``adjust = 0`` is the tracker.

**A tracked correction of another estimate** (:class:`CorrectionTracker`, the controllers
``juggler_estimator_tracker_catch``): the same step on a correction ``C`` added to the
release-anchored delay estimate ``\hat d_r`` (the delay told is ``\hat d_r + C +
offset``), starting at ``C = 0`` and clipped to ``[-bound, bound]``; ``e - offset =
s (\hat d_r + C - d)`` gives ``C_n + \hat d_r - d = (1 - k s)^n (\hat d_r - d)`` for a
fixed estimate, so the per-episode error of the estimate is removed by the catches;
``k = 0`` is ``juggler_delay_estimator_catch`` told ``offset``.

**What it reads**: only the catch's timing error, which the env hands the controller
(the palm feels when the ball landed); never the hidden delay (the estimators'
``reset``/``retell`` tell only the oracle; the tracker is reset with nothing but its
prior).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

__all__ = ["CORRECTION_BOUND", "TRACKER_MAX_GAIN", "CorrectionTracker", "DelayTracker"]

#: The largest gain accepted (``k s < 2`` keeps the update stable for ``s`` up to 1.3).
TRACKER_MAX_GAIN = 1.5
#: s, the largest correction :class:`CorrectionTracker` reaches either way: 50 ms, the
#: lower end of the estimate's offset range (``ESTIMATE_OFFSET``), far beyond the
#: estimate's measured per-episode error (bias 6-7 ms, sd 5-7 ms on Cascade-v1 three balls).
CORRECTION_BOUND = 0.05


@dataclass
class DelayTracker:
    """The online delay tracker (module docstring).

    Attributes
    ----------
    gain:
        ``k`` (0 to :data:`TRACKER_MAX_GAIN`); 0: the estimate never moves.
    offset:
        s (0-0.25), added to the estimate in the delay told to the estimator, and the
        timing error the tracker steers to.
    delay_range:
        s, ``(low, high)``: the level's delay range; the estimate is clipped to it and
        starts at its middle.
    estimate:
        s, the current estimate ``D`` (set by :meth:`reset`).
    """

    gain: float
    offset: float
    delay_range: tuple[float, float]
    estimate: float = field(init=False)
    #: s, added to the told delay by an agent's timing action (the envs' ``timing_scale``;
    #: 0 at every reset, the tracker alone).
    adjust: float = field(init=False)

    def __post_init__(self) -> None:
        if not (math.isfinite(self.gain) and 0.0 <= self.gain <= TRACKER_MAX_GAIN):
            raise ValueError(f"gain must be in [0, {TRACKER_MAX_GAIN}]; got {self.gain!r}")
        if not (math.isfinite(self.offset) and 0.0 <= self.offset <= 0.25):
            raise ValueError(f"offset must be in [0, 0.25] s; got {self.offset!r}")
        low, high = (float(v) for v in self.delay_range)
        if not (math.isfinite(low) and math.isfinite(high) and self._range_ok(low, high)):
            raise ValueError(
                f"delay_range must be finite with {self._RANGE_RULE}; got {self.delay_range!r}"
            )
        self.delay_range = (low, high)
        self.reset()

    #: the rule a range must keep (the error's words) and its check
    _RANGE_RULE = "0 <= low <= high"

    @staticmethod
    def _range_ok(low: float, high: float) -> bool:
        return 0.0 <= low <= high

    @property
    def prior(self) -> float:
        """s, the estimate at an episode's start: the middle of the range (the level's
        mean delay)."""
        return 0.5 * (self.delay_range[0] + self.delay_range[1])

    @property
    def told(self) -> float:
        """s, the delay told to the estimator: ``estimate + offset + adjust`` (at least 0)."""
        return max(self.estimate + self.offset + self.adjust, 0.0)

    def reset(self) -> None:
        """A new episode: the estimate back to the prior, no adjustment."""
        self.estimate = self.prior
        self.adjust = 0.0

    def update(self, timing: float) -> float:
        """One catch's timing error ``timing`` (s, the catch time minus the planned
        meeting; NaN: no timing, no change): the module docstring's step. Returns the
        new estimate."""
        if math.isfinite(timing):
            low, high = self.delay_range
            step = self.estimate - self.gain * (timing - self.offset)
            self.estimate = min(max(step, low), high)
        return self.estimate


class CorrectionTracker(DelayTracker):
    """A tracked correction ``C`` of another delay estimate (module docstring): the
    :class:`DelayTracker` step on ``C``, which starts at 0 and is clipped to
    ``delay_range``, a range around 0 (default ``[-CORRECTION_BOUND, CORRECTION_BOUND]``);
    :attr:`told` is the correction told, ``C + offset + adjust``, which may be negative
    (the estimator adds it to its estimate and keeps the sum at least 0)."""

    def __init__(
        self, gain: float, offset: float,
        delay_range: tuple[float, float] = (-CORRECTION_BOUND, CORRECTION_BOUND),
    ) -> None:  # fmt: skip
        super().__init__(gain, offset, delay_range)

    _RANGE_RULE = "low <= 0 <= high"

    @staticmethod
    def _range_ok(low: float, high: float) -> bool:
        return low <= 0.0 <= high

    @property
    def prior(self) -> float:
        """s, the correction at an episode's start: 0 (the estimate as it is)."""
        return 0.0

    @property
    def told(self) -> float:
        """s, the correction told: ``estimate + offset + adjust`` (may be negative)."""
        return self.estimate + self.offset + self.adjust
