r"""Juggling-v2's levels and its reference controllers: the analytic juggler fed by a
flight estimator (:mod:`~motion_envs.models.juggling._camera`).

**Levels** (:data:`V2_LEVELS`): what varies per episode and how the ball is seen and
tossed. Every level's visuomotor delay is drawn per episode, uniformly, from a part of
the human range 100-250 ms (visual feedback delays of 100 ms and more, Franklin &
Wolpert 2011, *Computational mechanisms of sensorimotor control*, Neuron 72: 425-442;
the upper end is that of simple visual reaction times, about 200-250 ms); a camera at
100 Hz with frame drops, occlusion near the palm and millimetre noise; and a quadratic
air drag ``k = rho C_d A / (2 m)`` drawn per episode, uniformly, between a 130 g
juggling ball (``k = 0.009/m``) and, on the harder levels, a table-tennis ball
(``k = 0.14/m``; :mod:`~motion_envs.envs.juggling._world`, *Air drag*).

**The level ``drift``**: the juggler's parameters change WITHIN the episode, at every
catch (while the ball is in the hand, between flights), so that an estimate pooled over
the episode's past flights lags. Its camera and toss scatter are ``medium``'s.

* The delay starts uniform in the whole human range 100-250 ms and then follows a random
  walk, a normal step of std 20 ms per catch, reflected at 100 and 250 ms. A person's
  visuomotor latency is not a constant: reaction-time series fluctuate slowly, with
  serial correlation over many trials (1/f noise: Gilden, Thornton & Mallon 1995, *1/f
  noise in human cognition*, Science 267: 1837-1839), with attention and fatigue; a step
  of 20 ms per toss spreads about 60 ms over ten tosses (about 8 s of juggling), the
  order of a person's trial-to-trial spread of simple visual reaction times (tens of
  ms). The step is a reasoned choice, not a measurement, and not tuned against any row.
* The drag is drawn afresh at every catch, uniformly in 0.009-0.03 /m: a beanbag of a
  juggling ball's mass and size lands in a new shape each catch; its drag coefficient
  lies between a sphere's (``C_d = 0.47``, ``k = 0.009``) and a flat disc's face on
  (``C_d`` about 1.1-1.2, standard drag tables) with a frontal area up to about 1.3
  times the ball's when flattened: ``0.009 x 1.17 / 0.47 x 1.3 = 0.03``.

The oracle is told the current delay and drag after every change.

**The level ``gaze``**: the latency changes WITHIN a flight, frame by frame, so that no
single delay (estimated, tracked or constant) places every frame right. A juggler fixates
near the apex of the toss (Huys & Beek 2002, *The coupling between point-of-gaze and ball
movements in three-ball cascade juggling: the effects of expertise, pattern and tempo*,
J. Sports Sciences 20: 171-186), so the ball near the hand is seen in the periphery, and
visual reaction times rise with retinal eccentricity (Payne 1967, *Visual reaction times
on a circle about the fovea*, Science 155: 481-482). Each captured frame's latency is
``delay + slope * ecc + jitter``: ``delay`` the episode's as on every level, ``slope`` (s
per degree) drawn per episode uniformly from ``gaze_slope`` = 0.5-1.5 ms/deg and hidden (a
person's own), ``ecc`` the angle between the ball's true position and the apex predicted
ballistically at the release, seen from an eye 0.45 m above the hand's home and 0.40 m out
of the plane (:mod:`~motion_envs.models.juggling._camera`, *Gaze*; the slope and the eye
are reasoned choices, not measurements, and not tuned against any row). The per-frame
latency this produces, measured on the 2,817 frames received in 20 episodes (seeds 0-19,
at most 3 catches) of ``juggler_oracle_catch``: ``delay + slope * ecc`` 102 / 172 / 274 ms
(min / median / max), of which the gaze part 0.2 / 13.7 / 82.5 ms at eccentricities of
0.2 / 14.7 / 66.9 degrees (the ball near the palm is far in the periphery); with the
jitter and the control step, arrival minus capture 90 / 175 / 290 ms. Everything else is
``medium``'s: camera, drag, toss scatter, delay range. The oracle is told the delay and,
per frame, the gaze latency (not the jitter).

**Controllers** (:data:`V2_CONTROLLERS`): the analytic juggler of Juggling-v1 (eq. 9
toss, eq. 10 correction; the same fit) whose eq. 10 correction is fed the ball's state
from a :class:`~motion_envs.models.juggling.FlightEstimator`:

* ``"juggler"``: frames taken as the present (``"arrival"``);
* ``"juggler_mean_delay"``: frames shifted by the level's mean delay;
* ``"juggler_delay_estimator"``: the hand-written delay estimator (the delay found
  from the release, per episode; ``"release"``);
* ``"juggler_oracle"``: the episode's true (current) delay, on ``gaze`` each frame's true
  gaze latency, and the ball's true drag (an UPPER
  REFERENCE: it is given what the world hides; not the frames' jitter, which nothing
  observable tells). With drag the juggler's ballistic
  prediction is handed the equivalent ballistic state: the velocity whose ballistic
  flight reaches, at the plan's catch time, the point the drag flight reaches;
* ``"juggler_oracle_catch"``: the oracle's estimator with a catch planned for the
  capture rule (:mod:`~motion_envs.models.juggling._v2_catch`: the palm arrives early
  and meets the ball descending slower than it): the UPPER REFERENCE;
* ``"juggler_mean_delay_catch"``: the same catch plan on the level's mean delay (no
  hidden information: a competitor);
* ``"juggler_delay_estimator_catch"``: the same catch plan on the hand-written delay
  estimator's delay (``"release"``; the mean-delay plan, not re-tuned: the two
  hand-written fixes combined, a competitor);
* ``"juggler_gaze_estimator_catch"``: the same catch plan (the mean delay's, not
  re-tuned) on the hand-written gaze-aware estimator (``"gaze_release"``: the delay AND
  the gaze slope found from the releases, pooled over the episode's flights; written for
  the level ``gaze``, a competitor);
* ``"juggler_delay_tracker"``: the mean-delay catch plan whose delay is corrected after
  every catch from the catch's timing error (:mod:`~motion_envs.models.juggling._delay_tracker`;
  the env hands the error to :meth:`V2Controller.felt`; a competitor).

Without a state estimate (fewer than 3 frames of the flight) the juggler does not
correct; the controller never sees the true ball in flight.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from motion_envs.datasets.juggling import JugglingState
from motion_envs.models.juggling._camera import FlightEstimator
from motion_envs.models.juggling._juggler import AnalyticJuggler
from motion_envs.models.juggling._levels import JugglerController

__all__ = ["V2_CONTROLLERS", "V2_LEVELS", "V2Controller", "V2Level"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class V2Level:
    """What a Juggling-v2 level fixes.

    Attributes
    ----------
    delay:
        s, the range ``(low, high)`` the episode's visuomotor delay is drawn from.
    jitter_std:
        s, the std of each frame's extra latency.
    frame_rate:
        Hz, the camera's.
    drop_prob:
        The probability that a frame is lost.
    occlusion_radius:
        m; the ball is not seen this close to the hand's origin.
    position_std:
        m, the camera's noise per coordinate.
    drag:
        1/m, the range ``(low, high)`` the episode's drag ``k`` is drawn from.
    release_speed_std, release_angle_std:
        The toss's scatter (relative; degrees).
    capture_speed:
        m/s; a catch needs the palm to meet the ball slower than this.
    delay_walk:
        s; the std of the delay's step at every catch (a random walk reflected at the
        ends of ``delay``, :meth:`next_delay`); 0: one delay per episode.
    drag_per_toss:
        The drag is drawn afresh from ``drag`` at every catch (:meth:`next_drag`; a
        beanbag lands in a new shape); False: one drag per episode.
    gaze_slope:
        s per degree, the range ``(low, high)`` the episode's gaze slope is drawn from:
        each frame's latency grows by ``slope * ecc``, ``ecc`` its eccentricity from the
        fixated apex (module docstring); ``(0, 0)``: no gaze latency.
    """

    delay: tuple[float, float]
    jitter_std: float
    frame_rate: float
    drop_prob: float
    occlusion_radius: float
    position_std: float
    drag: tuple[float, float]
    release_speed_std: float
    release_angle_std: float
    capture_speed: float
    delay_walk: float = 0.0
    drag_per_toss: bool = False
    gaze_slope: tuple[float, float] = (0.0, 0.0)

    def __post_init__(self) -> None:
        low, high = self.gaze_slope
        if not (0.0 <= low <= high <= 0.01):  # also rejects NaN
            raise ValueError(
                f"gaze_slope must be (low, high) with 0 <= low <= high <= 0.01 s per degree; "
                f"got {self.gaze_slope!r}"
            )

    @property
    def drifts(self) -> bool:
        """True if the delay or the drag changes within the episode (at catches)."""
        return self.delay_walk > 0 or self.drag_per_toss

    def next_delay(self, delay: float, rng: np.random.Generator) -> float:
        """s; the delay after one more catch: ``delay + delay_walk N(0, 1)`` reflected
        into ``[low, high]`` of ``delay`` (unchanged, and no draw, when ``delay_walk`` is
        0)."""
        if self.delay_walk <= 0:
            return delay
        low, high = self.delay
        width = high - low
        y = (delay + self.delay_walk * float(rng.standard_normal()) - low) % (2 * width)
        return low + (2 * width - y if y > width else y)

    def next_drag(self, drag: float, rng: np.random.Generator) -> float:
        """1/m; the drag after one more catch: drawn afresh from ``drag`` when
        ``drag_per_toss`` (else unchanged, no draw)."""
        return float(rng.uniform(*self.drag)) if self.drag_per_toss else drag

    @property
    def mean_delay(self) -> float:
        """s, the mean of the episode's delay."""
        return 0.5 * (self.delay[0] + self.delay[1])


#: Juggling-v2's levels (the env docstring has the table).
V2_LEVELS: dict[str, V2Level] = {
    "easy": V2Level((0.10, 0.15), 0.005, 100.0, 0.02, 0.10, 0.001, (0.009, 0.02), 0.05, 4.0, 5.0),
    "medium": V2Level((0.10, 0.20), 0.01, 100.0, 0.05, 0.10, 0.002, (0.009, 0.07), 0.08, 6.0, 5.0),
    "hard": V2Level((0.15, 0.25), 0.015, 100.0, 0.10, 0.10, 0.003, (0.009, 0.14), 0.12, 12.0, 5.0),
    "drift": V2Level(
        (0.10, 0.25),
        0.01,
        100.0,
        0.05,
        0.10,
        0.002,
        (0.009, 0.03),
        0.08,
        6.0,
        5.0,
        delay_walk=0.02,
        drag_per_toss=True,
    ),
    "gaze": V2Level(
        (0.10, 0.20),
        0.01,
        100.0,
        0.05,
        0.10,
        0.002,
        (0.009, 0.07),
        0.08,
        6.0,
        5.0,
        gaze_slope=(0.0005, 0.0015),
    ),
}

#: The controllers' names and their estimators.
V2_CONTROLLERS: dict[str, str] = {
    "juggler": "arrival",
    "juggler_mean_delay": "mean_delay",
    "juggler_delay_estimator": "release",
    "juggler_oracle": "oracle",
    "juggler_oracle_catch": "oracle",
    "juggler_mean_delay_catch": "mean_delay",
    "juggler_delay_tracker": "mean_delay",
    "juggler_delay_estimator_catch": "release",
    "juggler_gaze_estimator_catch": "gaze_release",
    "juggler_estimator_tracker_catch": "release",
}


class V2Controller(JugglerController):
    """The analytic juggler fed by ``estimator`` (module docstring)."""

    def __init__(self, juggler: AnalyticJuggler, estimator: FlightEstimator) -> None:
        super().__init__(juggler)
        self.estimator = estimator

    def reset(self, state: JugglingState, rng: np.random.Generator | None = None) -> None:
        """Start a toss from the state (ball in hand); the estimator keeps its drag (set
        by :meth:`FlightEstimator.reset` before)."""
        super().reset(state, rng)

    def felt(self, task_error: FloatArray) -> None:
        """A catch's task error ``(offset, timing)`` (the env's ``info["task_error"]``:
        what the palm feels); ignored here (the delay tracker uses it)."""

    def command(self, state: JugglingState) -> tuple[FloatArray, bool]:
        """Next hand target and release arming; in the catch phase the state's ball is
        the estimator's (``state``'s own ball fields are never read in flight)."""
        if self.phase != "catch" or state.held or state.caught:
            return self.juggler.command(state)
        est = self.estimator.estimate(state.time)
        if est is None:  # nothing to correct from: the juggler's "held" skips eq. 10
            return self.juggler.command(replace(state, held=True))
        p, v = est
        drag = self.estimator.drag
        if drag > 0:
            episode = self._episode
            s = episode.t_start + episode.duration - state.time
            end = self.estimator.position_at(episode.t_start + episode.duration)
            if s > self.juggler.task.dt and end is not None:
                g = self.juggler.task.gravity
                x, z = end
                v = np.array([(x - p[0]) / s, (z - p[1] + 0.5 * g * s * s) / s])
        return self.juggler.command(replace(state, ball_pos=p, ball_vel=v))
