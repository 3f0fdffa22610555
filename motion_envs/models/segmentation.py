"""Phases of a movement: online segmentation criteria and a phase state machine.

Lippi et al. model each *phase* of a task separately and chain the phases with a state
machine; the criteria that end a phase must be computable online (from the past only),
so the same criteria cut the training recordings and drive generation:

* :class:`PositionReached` — the position is within ``tolerance`` of a target;
* :class:`SpeedBelow` / :class:`SpeedAbove` — ``|v|`` crosses a threshold;
* :class:`AccelerationBelow` / :class:`AccelerationAbove` — one acceleration coordinate
  crosses a threshold (the juggling toss ends when the vertical acceleration drops below
  a negative threshold);
* :class:`EventOccurred` — an external event (e.g. ``"catch"``) was signalled;
* :class:`AnyOf` / :class:`AllOf` combine criteria.

Every criterion may require ``min_elapsed`` seconds since the phase began (a reach
starts at rest, so "speed below" would fire at once without it). Their parameters are
keyword-only (``SpeedAbove(threshold=0.05)``; ``SpeedAbove(0.05)`` is a ``TypeError``)
and a criterion that could never fire (``SpeedBelow(threshold=0)``, a non-finite
threshold, a negative tolerance or ``min_elapsed``, an empty event name) is refused
with a ``ValueError`` when it is built.

Derivatives of a recording (:func:`segment`) are Savitzky-Golay smoothed by default
(:func:`motion_envs.geometry.kinematics.smoothed_velocity`, window
``DEFAULT_WINDOW = 0.1`` s, cubic): raw differences of noisy samples fire speed
criteria on noise. The smoothing window is centred (it looks ``window / 2`` ahead), so
offline segments may start up to that much earlier than an online criterion would fire.
``window=None`` uses the causal backward differences of :func:`causal_derivatives`:
``v_k = (y_k - y_{k-1}) / (t_k - t_{k-1})``, ``a_k = (v_k - v_{k-1}) / (t_k - t_{k-1})``,
``v_0 = a_0 = a_1 = 0``.

:func:`segment` cuts a recording into consecutive phases; :class:`PhaseStateMachine`
generates a movement phase by phase: at each phase start it asks the phase's planner for
sine-series coefficients and a duration (typically ``SineSeriesRegression.plan``), then
follows ``Y(t) = Phi((t - t_start) / T) . P`` (held at ``tau = 1`` once reached) until the
phase's end criterion holds on the commanded state, and switches to the next phase.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike

from motion_envs._typing import FloatArray
from motion_envs.geometry import sine_series as ss
from motion_envs.geometry.kinematics import (
    DEFAULT_POLYORDER,
    DEFAULT_WINDOW,
    smoothed_acceleration,
    smoothed_velocity,
)

__all__ = [
    "AccelerationAbove",
    "AccelerationBelow",
    "AllOf",
    "AnyOf",
    "Criterion",
    "EventOccurred",
    "MotionState",
    "Phase",
    "PhaseStateMachine",
    "PositionReached",
    "Segment",
    "SpeedAbove",
    "SpeedBelow",
    "causal_derivatives",
    "segment",
]


@dataclass(frozen=True)
class MotionState:
    """What an online criterion may look at: the present and the phase's elapsed time."""

    t: float
    position: FloatArray
    velocity: FloatArray
    acceleration: FloatArray
    elapsed: float = 0.0
    events: frozenset[str] = frozenset()


class Criterion(Protocol):
    """A callable ``state -> bool`` ending a phase."""

    def __call__(self, state: MotionState) -> bool: ...


def _finite(value: float, name: str, owner: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise TypeError(f"{owner}: {name} must be a number; got {value!r}")
    if not np.isfinite(value):
        raise ValueError(f"{owner}: {name} must be finite (it could never fire); got {value}")
    return float(value)


@dataclass(frozen=True, kw_only=True)
class _Timed:
    min_elapsed: float = 0.0

    def __post_init__(self) -> None:
        if _finite(self.min_elapsed, "min_elapsed", type(self).__name__) < 0:
            raise ValueError(f"{type(self).__name__}: min_elapsed must be >= 0 s")

    def _early(self, state: MotionState) -> bool:
        return state.elapsed < self.min_elapsed


@dataclass(frozen=True, kw_only=True)
class PositionReached(_Timed):
    """``|position[axes] - target[axes]| <= tolerance`` (Euclidean; default all axes).

    Keyword-only: ``PositionReached(target=(x, y, z), tolerance=1e-3, axes=None,
    min_elapsed=0.0)``.
    """

    target: tuple[float, ...]
    tolerance: float = 1e-3
    axes: tuple[int, ...] | None = None

    def __post_init__(self) -> None:
        super().__post_init__()
        name = type(self).__name__
        target = np.asarray(self.target, dtype=np.float64)
        if target.ndim != 1 or target.size == 0 or not np.all(np.isfinite(target)):
            raise ValueError(f"{name}: target must be a non-empty finite vector; got {self.target}")
        if _finite(self.tolerance, "tolerance", name) < 0:
            raise ValueError(f"{name}: tolerance must be >= 0 (it could never fire)")
        if self.axes is not None and len(self.axes) != target.size:
            raise ValueError(f"{name}: axes {self.axes} must name one axis per target value")

    def __call__(self, state: MotionState) -> bool:
        if self._early(state):
            return False
        target = np.asarray(self.target, dtype=np.float64)
        axes = slice(None) if self.axes is None else list(self.axes)
        return bool(np.linalg.norm(state.position[axes] - target) <= self.tolerance)


@dataclass(frozen=True, kw_only=True)
class SpeedBelow(_Timed):
    """``|velocity| < threshold`` (keyword-only; ``threshold > 0``, else it never fires)."""

    threshold: float

    def __post_init__(self) -> None:
        super().__post_init__()
        if _finite(self.threshold, "threshold", "SpeedBelow") <= 0:
            raise ValueError(
                f"SpeedBelow: threshold must be > 0 (|v| < {self.threshold} never holds)"
            )

    def __call__(self, state: MotionState) -> bool:
        return not self._early(state) and bool(np.linalg.norm(state.velocity) < self.threshold)


@dataclass(frozen=True, kw_only=True)
class SpeedAbove(_Timed):
    """``|velocity| > threshold`` (keyword-only; ``threshold >= 0``)."""

    threshold: float

    def __post_init__(self) -> None:
        super().__post_init__()
        if _finite(self.threshold, "threshold", "SpeedAbove") < 0:
            raise ValueError(
                f"SpeedAbove: threshold must be >= 0 (|v| > {self.threshold} always holds)"
            )

    def __call__(self, state: MotionState) -> bool:
        return not self._early(state) and bool(np.linalg.norm(state.velocity) > self.threshold)


@dataclass(frozen=True, kw_only=True)
class _AxisThreshold(_Timed):
    axis: int
    threshold: float

    def __post_init__(self) -> None:
        super().__post_init__()
        name = type(self).__name__
        _finite(self.threshold, "threshold", name)
        if isinstance(self.axis, bool) or not isinstance(self.axis, (int, np.integer)):
            raise TypeError(f"{name}: axis must be an integer; got {self.axis!r}")


@dataclass(frozen=True, kw_only=True)
class AccelerationBelow(_AxisThreshold):
    """``acceleration[axis] < threshold`` (keyword-only: ``axis=``, ``threshold=``)."""

    def __call__(self, state: MotionState) -> bool:
        return not self._early(state) and bool(state.acceleration[self.axis] < self.threshold)


@dataclass(frozen=True, kw_only=True)
class AccelerationAbove(_AxisThreshold):
    """``acceleration[axis] > threshold`` (keyword-only: ``axis=``, ``threshold=``)."""

    def __call__(self, state: MotionState) -> bool:
        return not self._early(state) and bool(state.acceleration[self.axis] > self.threshold)


@dataclass(frozen=True, kw_only=True)
class EventOccurred(_Timed):
    """The external event ``name`` (non-empty, keyword-only) is among the state's events."""

    name: str

    def __post_init__(self) -> None:
        super().__post_init__()
        if not isinstance(self.name, str) or not self.name:
            raise ValueError(f"EventOccurred: name must be a non-empty string; got {self.name!r}")

    def __call__(self, state: MotionState) -> bool:
        return not self._early(state) and self.name in state.events


@dataclass(frozen=True)
class AnyOf:
    """True when any of ``criteria`` is."""

    criteria: tuple[Criterion, ...]

    def __call__(self, state: MotionState) -> bool:
        return any(c(state) for c in self.criteria)


@dataclass(frozen=True)
class AllOf:
    """True when all of ``criteria`` are."""

    criteria: tuple[Criterion, ...]

    def __call__(self, state: MotionState) -> bool:
        return all(c(state) for c in self.criteria)


def causal_derivatives(times: ArrayLike, positions: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Backward-difference velocities and accelerations ``(K, D)`` (past samples only)."""
    t = np.asarray(times, dtype=np.float64)
    y = np.asarray(positions, dtype=np.float64)
    if y.ndim != 2 or t.shape != (y.shape[0],):
        raise ValueError(f"times must be (K,) and positions (K, D); got {t.shape}, {y.shape}")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(y))):
        raise ValueError("times or positions contains NaN or infinite values")
    if np.any(np.diff(t) <= 0):
        raise ValueError("times must be strictly increasing")
    v = np.zeros_like(y)
    a = np.zeros_like(y)
    dt = np.diff(t)[:, None]
    v[1:] = np.diff(y, axis=0) / dt
    a[2:] = np.diff(v[1:], axis=0) / dt[1:]
    return v, a


@dataclass(frozen=True)
class Segment:
    """Phase ``name`` spans samples ``start .. stop`` inclusive (``stop`` starts the next)."""

    name: str
    start: int
    stop: int


def segment(
    times: ArrayLike,
    positions: ArrayLike,
    phases: Sequence[tuple[str, Criterion]],
    events: Mapping[int, Iterable[str]] | None = None,
    cycle: bool = True,
    *,
    window: float | None = DEFAULT_WINDOW,
    polyorder: int = DEFAULT_POLYORDER,
) -> list[Segment]:
    """Cut a recording into phases ``(name, end criterion)`` taken in order.

    The criterion of the current phase is evaluated at every sample after the phase's
    first (with the velocity, acceleration and ``events[k]``, the events at sample
    ``k``); the sample where it first holds ends the phase and starts the next. With
    ``cycle`` the phase list repeats. A last phase whose criterion never holds is not
    returned.

    Velocities and accelerations are Savitzky-Golay derivatives over ``window`` seconds
    with polynomials of degree ``polyorder`` (default 0.1 s, cubic; ``times`` must then
    be uniform, see :func:`motion_envs.geometry.kinematics.smoothed_derivative`);
    ``window=None`` uses raw causal backward differences (:func:`causal_derivatives`).
    """
    if not phases:
        raise ValueError("phases must contain at least one (name, criterion) pair")
    t = np.asarray(times, dtype=np.float64)
    y = np.asarray(positions, dtype=np.float64)
    v, a = causal_derivatives(t, y)
    if window is not None:
        v = smoothed_velocity(y, times=t, window=window, polyorder=polyorder)
        a = smoothed_acceleration(y, times=t, window=window, polyorder=polyorder)
    events = events or {}
    out: list[Segment] = []
    p, start = 0, 0
    for k in range(1, len(t)):
        name, criterion = phases[p]
        state = MotionState(
            t=float(t[k]),
            position=y[k],
            velocity=v[k],
            acceleration=a[k],
            elapsed=float(t[k] - t[start]),
            events=frozenset(events.get(k, ())),
        )
        if criterion(state):
            out.append(Segment(name, start, k))
            start = k
            p += 1
            if p == len(phases):
                if not cycle:
                    break
                p = 0
    return out


Planner = Callable[[MotionState], tuple[ArrayLike, float]]


@dataclass
class Phase:
    """One phase: a planner ``state -> (coefficients (N + 2, D), duration)`` and an end.

    ``end`` is an online criterion evaluated on the commanded state; ``None`` ends the
    phase at ``tau = 1``. ``next`` names the following phase (default: the next in the
    list, cyclically).
    """

    name: str
    planner: Planner
    end: Criterion | None = None
    next: str | None = None


@dataclass
class PhaseStateMachine:
    """Drives generation phase by phase (see the module docstring).

    ``reset(t, position)`` starts the initial phase; ``step(t, events)`` returns the
    commanded position at time ``t`` (non-decreasing) and switches phase when the
    current phase's end criterion holds. ``transitions`` records ``(t, from, to)``.
    """

    phases: Sequence[Phase]
    initial: str | None = None
    transitions: list[tuple[float, str, str]] = field(default_factory=list)

    def __post_init__(self) -> None:
        if not self.phases:
            raise ValueError("phases must contain at least one Phase")
        self._by_name = {p.name: i for i, p in enumerate(self.phases)}
        if len(self._by_name) != len(self.phases):
            raise ValueError("phase names must be unique")
        for p in self.phases:
            if p.next is not None and p.next not in self._by_name:
                raise ValueError(f"phase {p.name!r}: next phase {p.next!r} does not exist")
        if self.initial is not None and self.initial not in self._by_name:
            raise ValueError(f"initial phase {self.initial!r} does not exist")

    @property
    def phase(self) -> Phase:
        """The current phase."""
        return self.phases[self._current]

    def _start_phase(self, index: int, state: MotionState) -> None:
        self._current = index
        coefficients, duration = self.phase.planner(state)
        p = np.asarray(coefficients, dtype=np.float64)
        if p.ndim != 2 or p.shape[1] != state.position.shape[0] or not np.all(np.isfinite(p)):
            raise ValueError(
                f"phase {self.phase.name!r}: planner must return finite (N + 2, "
                f"{state.position.shape[0]}) coefficients; got shape {p.shape}"
            )
        if not np.isfinite(duration) or duration <= 0:
            raise ValueError(f"phase {self.phase.name!r}: planner duration must be > 0")
        self.coefficients = p
        self.duration = float(duration)
        self.t_start = state.t

    def reset(self, t: float, position: ArrayLike, velocity: ArrayLike | None = None) -> None:
        """Start the initial phase at time ``t`` from ``position`` (and ``velocity``)."""
        y = np.asarray(position, dtype=np.float64)
        v = np.zeros_like(y) if velocity is None else np.asarray(velocity, dtype=np.float64)
        self.transitions = []
        index = 0 if self.initial is None else self._by_name[self.initial]
        self._start_phase(index, MotionState(float(t), y, v, np.zeros_like(y)))

    def state(self, t: float, events: Iterable[str] = ()) -> MotionState:
        """The commanded state of the current phase at time ``t``."""
        tau = min(max((t - self.t_start) / self.duration, 0.0), 1.0)
        n = self.coefficients.shape[0] - 2
        moving = tau < 1.0
        v = (ss.basis_derivative(tau, n) @ self.coefficients) / self.duration
        a = (ss.basis_second_derivative(tau, n) @ self.coefficients) / self.duration**2
        return MotionState(
            t=float(t),
            position=ss.basis(tau, n) @ self.coefficients,
            velocity=v if moving else np.zeros_like(v),
            acceleration=a if moving else np.zeros_like(a),
            elapsed=float(t - self.t_start),
            events=frozenset(events),
        )

    def step(self, t: float, events: Iterable[str] = ()) -> FloatArray:
        """Commanded position at ``t``; switches to the next phase when this one ends."""
        if not hasattr(self, "coefficients"):
            raise ValueError("call reset() before step()")
        state = self.state(t, events)
        end = self.phase.end
        done = (t - self.t_start) >= self.duration if end is None else end(state)
        if done:
            old = self.phase
            nxt = (
                self._by_name[old.next]
                if old.next is not None
                else (self._current + 1) % len(self.phases)
            )
            self._start_phase(nxt, state)
            self.transitions.append((float(t), old.name, self.phase.name))
        return state.position
