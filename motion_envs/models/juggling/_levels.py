"""Juggling-v1's difficulty levels, its four reference controllers and its human-likeness.

**Levels** (:data:`LEVELS`): what a level fixes is how the ball is seen and tossed: the
sensor's latency and noise (:class:`~motion_envs.models.juggling.BallSensor`) and
the release noise (speed and angle, :func:`~motion_envs.models.juggling.perturb_release`).
The values were chosen by reasoning (people juggle with a 100-200 ms visuomotor delay) and
by running the analytic juggler on TRAINING seeds only (``SPLIT_SEEDS["train"]`` of
:mod:`motion_envs.datasets.juggling`); the env docstring has the table.

**Controllers**, all with the juggler's interface (``reset(state, rng)``,
``command(state) -> (target, armed)``, ``phase``, ``phase_time``, ``nominal_next()``,
``plan_end``, ``duration``):

* ``"juggler"``: the analytic juggler itself (eq. 9 toss, eq. 10 correction from the
  DELAYED measurement it is given, as in the paper);
* ``"juggler_latency_aware"``: the same juggler fed the measurement predicted forward by
  the known latency along the ballistic flight (the strong analytic reference);
* ``"fixed_point"``: the juggler's toss, go-down and return; the catch is a minimum-jerk
  reach to one fixed point (the training demonstrations' mean catch point) over the
  juggler's planned catch duration, blind to the ball;
* ``"commanded_intercept"``: the same, to the intercept predicted from the release
  velocity the juggler commanded (its efference copy), never corrected.

**Human-likeness** (:class:`HumanLikeness`): the distance (m) from the hand's state
``(x, z, tau vx, tau vz)`` (``tau = 0.1`` s) to the nearest sample of the same phase in a
set of demonstrations (a k-d tree per phase): 0 when the hand moves where and as a person
moved in that phase. Juggling-v1's reward uses the TRAINING demonstrations; the benchmark
reports it against the held-out ones.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, replace

import numpy as np
from scipy.spatial import cKDTree

from motion_envs._typing import FloatArray
from motion_envs.datasets.juggling import PHASES, JugglingDemos, JugglingState
from motion_envs.geometry.minimum_jerk import minimum_jerk
from motion_envs.models.juggling._controller import JugglingController
from motion_envs.models.juggling._fit import v1_fit
from motion_envs.models.juggling._juggler import AnalyticJuggler
from motion_envs.models.juggling._sensor import predict_forward

__all__ = [
    "CONTROLLERS",
    "LEVELS",
    "LIKENESS_TAU",
    "HumanLikeness",
    "JugglerController",
    "JugglingLevel",
    "make_controller",
    "v1_likeness",
]


@dataclass(frozen=True)
class JugglingLevel:
    """What a level fixes (every field can also be passed to the env on its own).

    Attributes
    ----------
    latency:
        s, the ball measurement's delay (rounded to control periods).
    position_std, velocity_std:
        Measurement noise of the ball, m and m/s.
    release_speed_std:
        Relative std of the release speed.
    release_angle_std:
        Std of the release direction, degrees.
    """

    latency: float
    position_std: float
    velocity_std: float
    release_speed_std: float
    release_angle_std: float


#: The levels (see the env docstring's table).
LEVELS: dict[str, JugglingLevel] = {
    "easy": JugglingLevel(0.0, 0.0, 0.0, 0.05, 4.0),
    "medium": JugglingLevel(0.10, 0.002, 0.02, 0.08, 6.0),
    "hard": JugglingLevel(0.11, 0.004, 0.05, 0.12, 12.0),
}

#: The reference controllers' names.
CONTROLLERS: tuple[str, ...] = (
    "juggler",
    "juggler_latency_aware",
    "fixed_point",
    "commanded_intercept",
)

#: s; weight of the velocity in the human-likeness distance.
LIKENESS_TAU = 0.1


class JugglerController:
    """The analytic juggler as a controller (``"juggler"``); the base of the others.

    ``latency``: s, the delay of the measurements the controller is given (used by the
    latency-aware variant only).
    """

    def __init__(self, juggler: AnalyticJuggler, latency: float = 0.0) -> None:
        self.juggler = juggler
        self.latency = float(latency)

    def reset(self, state: JugglingState, rng: np.random.Generator | None = None) -> None:
        """Start a toss from the (measured) state."""
        self.juggler.reset(state, rng)

    def command(self, state: JugglingState) -> tuple[FloatArray, bool]:
        """Next hand target and release arming from the measured state."""
        return self.juggler.command(state)

    @property
    def _episode(self) -> JugglingController:
        episode = self.juggler.episode
        if episode is None:
            raise RuntimeError("no episode; call reset() first")
        return episode

    @property
    def phase(self) -> str:
        """The current phase."""
        return str(self.juggler.phase)

    @property
    def phase_time(self) -> float:
        """s in the current phase."""
        return float(self.juggler.phase_time)

    @property
    def duration(self) -> float:
        """s, the current phase plan's duration."""
        return float(self._episode.duration)

    @property
    def plan_end(self) -> FloatArray:
        """The current phase plan's end point (in the catch phase: the planned catch point)."""
        return np.asarray(self._episode.end, dtype=np.float64)

    def nominal_next(self) -> FloatArray:
        """The next hand target the plan gives (without events)."""
        return self.juggler.nominal_next()


class _LatencyAware(JugglerController):
    def command(self, state: JugglingState) -> tuple[FloatArray, bool]:
        if state.held or self.latency <= 0:
            return self.juggler.command(state)
        p, v = predict_forward(
            state.ball_pos, state.ball_vel, self.latency, self.juggler.task.gravity
        )
        return self.juggler.command(replace(state, ball_pos=p, ball_vel=v))


class _MinimumJerkCatch(JugglerController):
    """Toss, go-down and return of the juggler (no eq. 10); the catch is a minimum-jerk
    reach from the catch start to :meth:`_catch_point` over the planned duration."""

    def __init__(self, juggler: AnalyticJuggler, latency: float = 0.0) -> None:
        super().__init__(juggler.variant(correction=False), latency)
        self._catch: tuple[FloatArray, FloatArray, float] | None = None

    def _catch_point(self) -> FloatArray:
        raise NotImplementedError

    def reset(self, state: JugglingState, rng: np.random.Generator | None = None) -> None:
        super().reset(state, rng)
        self._catch = None

    def command(self, state: JugglingState) -> tuple[FloatArray, bool]:
        target, armed = self.juggler.command(state)
        if self.juggler.phase != "catch":
            self._catch = None
            return target, armed
        if self._catch is None:
            start = np.asarray(state.hand_pos, dtype=np.float64)
            self._catch = (start, self._catch_point(), float(self._episode.duration))
        start, end, duration = self._catch
        tau = min(self.juggler.phase_time / duration, 1.0)
        return minimum_jerk(start, end, np.array([tau]))[0], armed

    @property
    def plan_end(self) -> FloatArray:
        if self._catch is not None:
            return self._catch[1].copy()
        return super().plan_end

    def nominal_next(self) -> FloatArray:
        if self._catch is None:
            return super().nominal_next()
        start, end, duration = self._catch
        dt = self.juggler.task.dt
        tau = min(self.juggler.phase_time / duration + dt / duration, 1.0)
        return minimum_jerk(start, end, np.array([tau]))[0]


class _FixedPoint(_MinimumJerkCatch):
    def _catch_point(self) -> FloatArray:
        return np.asarray(self.juggler.phases_["catch"].end_mean, dtype=np.float64).copy()


class _CommandedIntercept(_MinimumJerkCatch):
    def _catch_point(self) -> FloatArray:
        return np.asarray(self._episode.end, dtype=np.float64).copy()


def make_controller(name: str, juggler: AnalyticJuggler, latency: float = 0.0) -> JugglerController:
    """The controller ``name`` (one of :data:`CONTROLLERS`) around ``juggler``'s fitted
    model (a :meth:`~AnalyticJuggler.variant`: the controller's episodes never touch
    ``juggler``)."""
    classes: dict[str, type[JugglerController]] = {
        "juggler": JugglerController,
        "juggler_latency_aware": _LatencyAware,
        "fixed_point": _FixedPoint,
        "commanded_intercept": _CommandedIntercept,
    }
    if name not in classes:
        raise ValueError(f"controller must be one of {list(CONTROLLERS)}; got {name!r}")
    return classes[name](juggler.variant(), latency)


class HumanLikeness:
    """Distance of a hand state to the nearest demonstrated state of the same phase.

    Built from the ``cycles`` (``(recording, cycle)`` pairs) of ``demos``; the hand's
    velocity is the backward difference of the recorded positions.
    """

    def __init__(
        self, demos: JugglingDemos, cycles: set[tuple[int, int]] | frozenset[tuple[int, int]]
    ) -> None:
        points: dict[str, list[FloatArray]] = {p: [] for p in PHASES}
        for s in demos.segments():
            if (s.recording, s.cycle) not in cycles:
                continue
            v = np.diff(s.positions, axis=0) / np.diff(s.times)[:, None]
            points[s.phase].append(np.hstack([s.positions[1:], LIKENESS_TAU * v]))
        self.trees = {p: cKDTree(np.vstack(points[p])) for p in PHASES if points[p]}
        if len(self.trees) != len(PHASES):
            raise ValueError("human-likeness needs demonstrations of every phase")
        self._sorted = {p: _SortedSamples(tree) for p, tree in self.trees.items()}

    def distance(self, phase: str, hand_pos: FloatArray, hand_vel: FloatArray) -> float:
        """m; the distance of ``(x, z, tau vx, tau vz)`` to the phase's nearest sample.

        The same number as the phase's k-d tree query (``trees[phase].query``, the
        squared differences summed in coordinate order, then the square root), found by
        :class:`_SortedSamples` at a fraction of the tree query's call overhead."""
        q = (
            float(hand_pos[0]),
            float(hand_pos[1]),
            LIKENESS_TAU * float(hand_vel[0]),
            LIKENESS_TAU * float(hand_vel[1]),
        )
        d = self._sorted[phase].nearest(q)
        return d if math.isfinite(d) else math.inf


class _SortedSamples:
    """Exact nearest-neighbour distance among ``points (M, 4)`` for one query at a time.

    The samples are sorted along their widest coordinate ``c``. A query's distance to
    the previous query's nearest sample bounds its nearest distance ``U`` from above, so
    the nearest sample lies in the slab ``|p_c - q_c| <= U`` (widened by a relative
    1e-9 against rounding): two binary searches find it, and the distances to the
    samples in it are computed in the k-d tree's order (``((d0^2 + d1^2) + d2^2) +
    d3^2``, then the square root), so the result is the tree query's bit for bit. The
    previous nearest sample only speeds the search up; any start gives the same value
    (a query far from all samples searches a slab of most of them, which costs less than
    the tree query's call).
    """

    def __init__(self, tree: cKDTree) -> None:
        pts = np.asarray(tree.data, dtype=np.float64)
        self.tree = tree
        self.axis = int(np.argmax(np.ptp(pts, axis=0)))
        order = np.argsort(pts[:, self.axis], kind="stable")
        pts = pts[order]
        #: the sorted samples, one row per coordinate ``(4, M)``
        self.columns = np.ascontiguousarray(pts.T)
        self.rows = pts.tolist()
        self.key = self.columns[self.axis]
        self._last = 0

    def nearest(self, q: tuple[float, float, float, float]) -> float:
        """The distance of ``q`` to the nearest sample (NaN for a NaN query)."""
        q0, q1, q2, q3 = q
        p0, p1, p2, p3 = self.rows[self._last]
        d0, d1, d2, d3 = p0 - q0, p1 - q1, p2 - q2, p3 - q3
        bound = math.sqrt(((d0 * d0 + d1 * d1) + d2 * d2) + d3 * d3)
        if not math.isfinite(bound):
            return math.nan
        width = bound * (1.0 + 1e-9) + 1e-12
        qc = q[self.axis]
        key = self.key
        lo = int(key.searchsorted(qc - width, "left"))
        hi = int(key.searchsorted(qc + width, "right"))
        e = self.columns[:, lo:hi] - np.array(q)[:, None]
        e *= e
        s = e[0] + e[1]  # the four terms added in order, as the tree does
        s += e[2]
        s += e[3]
        j = int(s.argmin())
        self._last = lo + j
        return math.sqrt(float(s[j]))


@functools.lru_cache(maxsize=8)
def v1_likeness(gravity: float, split: str) -> HumanLikeness:
    """Human-likeness against Juggling-v1's demonstrations at ``gravity``
    (:func:`~motion_envs.models.juggling.v1_fit`): the ``"train"`` cycles (the reward's) or
    the held-out ``"test"`` ones (the benchmark's)."""
    if split not in ("train", "test"):
        raise ValueError(f"split must be 'train' or 'test'; got {split!r}")
    fit = v1_fit(float(gravity))
    return HumanLikeness(fit.demos, fit.train if split == "train" else fit.test)
