"""The analytic juggler: Lippi et al.'s phase models chained by the task's online criteria.

One :class:`~motion_envs.models.sine_regression.SineSeriesRegression` per phase (toss,
go down, catch, return), fitted on demonstrations with conditions ``Q = [start, end]``
(hand positions) and ``N`` chosen by cross-validation on the training demonstrations
(:func:`~motion_envs.models.sine_regression.select_n_sines`). Generation, as in the
paper's section III-A:

* end points of toss, go-down and return are drawn from a Gaussian fitted to the
  training end points, durations uniformly over the training range;
* **toss**: the plan is constrained to zero vertical velocity at its end (eq. 9, on the
  regression hyperplane) and driven until the world releases the ball (vertical hand
  acceleration below ``-toss_threshold``);
* **go down**: reaches its end point (``PositionReached`` on the commanded position);
* **catch**: :func:`plan_catch` chooses the duration ``T`` in the training range whose
  intercept on the predicted flight is closest to the training catch end points, and
  sets the end point to the ball's predicted centre at ``t0 + T``. The flight is
  predicted from what the juggler commanded at the release (its own hand velocity, an
  efference copy); when the observed ball's flight predicts a different intercept
  (release noise), the eq. 10 correction (:meth:`SineSeriesRegression.correct`, position
  and velocity kept at ``tau_1``, new end point) re-plans the rest of the reach;
* **return**: back to a home point; then the next toss.

Each phase plan is evaluated once on the control grid ``t_start + k dt`` (the closed
form ``Y(t) = Phi(t / T) . P``), so one :meth:`AnalyticJuggler.command` costs an index.
The juggler sees only the state (observed hand, ball); it never imports Gymnasium.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from motion_envs.datasets.juggling_demos import JugglingDemos
from motion_envs.datasets.juggling_task import (
    PHASES,
    JugglingState,
    JugglingTask,
    ballistic_position,
)
from motion_envs.geometry import sine_series as ss
from motion_envs.models.sine_regression import SineSeriesRegression, select_n_sines

__all__ = [
    "AnalyticJuggler",
    "PhaseFit",
    "minimum_jerk",
    "phase_conditions",
    "plan_catch",
]

FloatArray = NDArray[np.float64]


def minimum_jerk(start: ArrayLike, end: ArrayLike, tau: ArrayLike) -> FloatArray:
    """Minimum-jerk movement between rest states: ``s + (e - s)(10 u^3 - 15 u^4 + 6 u^5)``.

    ``start``, ``end`` ``(D,)`` (or ``(m, D)``), ``tau`` ``(K,)`` normalised time; returns
    ``(K, D)`` (or ``(m, K, D)``).
    """
    s = np.asarray(start, dtype=np.float64)
    e = np.asarray(end, dtype=np.float64)
    u = np.asarray(tau, dtype=np.float64)
    shape = 10 * u**3 - 15 * u**4 + 6 * u**5
    return s[..., None, :] + (e - s)[..., None, :] * shape[:, None]


def phase_conditions(positions: list[FloatArray]) -> FloatArray:
    """Conditions ``Q_i = [start_x, start_z, end_x, end_z]`` of phase examples, ``(n, 4)``."""
    return np.stack([np.concatenate([y[0], y[-1]]) for y in positions])


def plan_catch(
    hand: ArrayLike,
    ball_pos: ArrayLike,
    ball_vel: ArrayLike,
    gravity: float,
    durations: tuple[float, float],
    preferred_end: ArrayLike,
    n_grid: int = 201,
) -> tuple[float, FloatArray]:
    """Catch duration ``T`` and end point from the ball's predicted flight.

    Candidates ``T`` span ``durations`` (``n_grid`` values); the intercept at ``T`` is the
    ball's centre ``ballistic_position(ball_pos, ball_vel, T)``; the chosen ``T`` puts it
    closest to ``preferred_end`` (the person's usual catch point). Returns ``(T, end)``;
    ``end`` is exactly on the predicted flight at ``T``.
    """
    lo, hi = float(durations[0]), float(durations[1])
    if not (np.isfinite(lo) and np.isfinite(hi)) or lo <= 0 or hi < lo:
        raise ValueError(f"durations must be 0 < lo <= hi; got {durations}")
    del hand  # the reach adapts to any start; kept for the signature's clarity
    ts = np.linspace(lo, hi, n_grid)
    points = ballistic_position(ball_pos, ball_vel, ts, gravity)
    best = int(np.argmin(np.linalg.norm(points - np.asarray(preferred_end), axis=1)))
    t_best = float(ts[best])
    return t_best, ballistic_position(ball_pos, ball_vel, t_best, gravity)


@dataclass
class PhaseFit:
    """One phase's fitted model and the training statistics generation draws from."""

    model: SineSeriesRegression
    cv_scores: FloatArray  # CV RMS error per candidate N
    duration_range: tuple[float, float]
    end_mean: FloatArray
    end_cov: FloatArray
    n_examples: int

    @property
    def end_chol(self) -> FloatArray:
        """A square root ``L`` of ``end_cov`` (``L L^T = end_cov``; eigen form, PSD-safe)."""
        if not hasattr(self, "_chol"):
            w, v = np.linalg.eigh(self.end_cov)
            self._chol = v * np.sqrt(np.maximum(w, 0.0))
        return self._chol


class AnalyticJuggler:
    """The analytic juggler (see the module docstring); the contract's controller.

    Parameters
    ----------
    task:
        The task constants (defaults :class:`JugglingTask`).
    n_sines:
        ``"auto"`` (cross-validation on the training examples, per phase) or an int.
    candidates:
        Values of ``N`` tried by the cross-validation.
    correction:
        Apply the eq. 10 correction in the catch phase.
    correction_tolerance:
        m; re-plan when the predicted intercept moves farther than this from the plan.
    n_folds:
        Folds of the ``N`` cross-validation.
    cv_tolerance:
        ``N`` is the smallest candidate whose CV error is within this relative margin of
        the best (the CV curve of smooth movements is flat past a few terms; the plain
        argmin then drifts to the largest candidate on differences of 0.1 %).
    reach_tolerance:
        m; go-down and return end when the commanded position is this close to their
        end point (the paper's "position reached").
    release_after:
        s; the release is armed only after this time in the toss (the toss accelerates
        first, so the threshold belongs to its decelerating part; a step of the observed
        start position under tracking noise must not release the ball).
    """

    def __init__(
        self,
        task: JugglingTask | None = None,
        n_sines: int | str = "auto",
        candidates: tuple[int, ...] = tuple(range(0, 13)),
        correction: bool = True,
        correction_tolerance: float = 1e-3,
        n_folds: int = 5,
        release_after: float = 0.25,
        reach_tolerance: float = 1e-3,
        cv_tolerance: float = 0.01,
    ) -> None:
        self.task = task or JugglingTask()
        self.n_sines = n_sines
        self.candidates = candidates
        self.correction = correction
        self.correction_tolerance = correction_tolerance
        self.n_folds = n_folds
        self.release_after = release_after
        self.reach_tolerance = reach_tolerance
        self.cv_tolerance = cv_tolerance

    # -- fitting --------------------------------------------------------------------
    def fit(
        self, demos: JugglingDemos, cycles: set[tuple[int, int]] | None = None
    ) -> AnalyticJuggler:
        """Fit every phase on ``demos`` (a :class:`JugglingDemos`), only ``cycles`` if given.

        ``cycles`` holds ``(recording, cycle)`` pairs (the training split).
        """
        segments = demos.segments(toss_to_top=True)
        self.phases_: dict[str, PhaseFit] = {}
        for phase in PHASES:
            segs = [
                s
                for s in segments
                if s.phase == phase and (cycles is None or (s.recording, s.cycle) in cycles)
            ]
            if len(segs) < 6:
                raise ValueError(
                    f"phase {phase!r} has {len(segs)} training examples; at least 6 are needed"
                )
            ys = [s.positions for s in segs]
            ts = [s.times for s in segs]
            q = phase_conditions(ys)
            if self.n_sines == "auto":
                folds = min(self.n_folds, len(segs))
                cands = sorted(self.candidates)
                _, scores = select_n_sines(ys, q, cands, ts, n_folds=folds)
                # parsimony: the smallest N within cv_tolerance of the best CV score
                ok = scores <= (1.0 + self.cv_tolerance) * scores.min()
                n = int(cands[int(np.argmax(ok))])
            else:
                n, scores = int(self.n_sines), np.full(1, np.nan)
            model = SineSeriesRegression(n_sines=n).fit(ys, q, ts)
            ends = q[:, 2:]
            self.phases_[phase] = PhaseFit(
                model=model,
                cv_scores=scores,
                duration_range=(float(model.durations_.min()), float(model.durations_.max())),
                end_mean=ends.mean(axis=0),
                end_cov=np.cov(ends.T),
                n_examples=len(segs),
            )
        self.home_ = self.phases_["toss"].model.conditions_[:, :2].mean(axis=0)
        return self

    def _fitted(self) -> None:
        if not hasattr(self, "phases_"):
            raise ValueError("this AnalyticJuggler is not fitted; call fit() first")

    # -- planning -------------------------------------------------------------------
    def _draw_end(self, phase: str) -> FloatArray:
        fit = self.phases_[phase]
        return fit.end_mean + fit.end_chol @ self._rng.standard_normal(2)

    def _draw_duration(self, phase: str) -> float:
        lo, hi = self.phases_[phase].duration_range
        return float(self._rng.uniform(lo, hi))

    def _start_phase(self, phase: str, t: float, start: FloatArray) -> None:
        fit = self.phases_[phase]
        model = fit.model
        if phase == "catch":
            duration, end = plan_catch(
                start,
                *self._belief_at(t),
                self.task.gravity,
                fit.duration_range,
                fit.end_mean,
            )
        else:
            duration, end = self._draw_duration(phase), self._draw_end(phase)
        q = np.concatenate([start, end])
        if phase == "toss":  # eq. 9: zero vertical velocity at the end, on the hyperplane
            p = model.plan(
                q, duration, start, end, final_velocity=np.zeros(2), axes=[1],
                mode="hyperplane", fix_end=False, max_end_shift=None,
            )  # fmt: skip
        else:
            p = model.plan(q, duration, start, end)
        self.phase = phase
        self.t_start = t
        self.duration = duration
        self.coefficients = p
        self.end = p[0] + p[1]
        self._grid_from(0)
        if phase in ("go_down", "return"):  # PositionReached(end, 1 mm) on the command
            near = np.linalg.norm(self._grid - self.end, axis=1) <= self.reach_tolerance
            self._end_k = int(np.argmax(near)) if near.any() else len(self._grid) - 1
        else:  # toss and catch end on the world's release and catch events
            self._end_k = -1
        self.plans.append((phase, t, duration, p.copy()))

    def _grid_from(self, k0: int) -> None:
        """Evaluate the current plan on steps ``k0 .. ceil(T / dt)`` of the phase."""
        dt = self.task.dt
        n = math.ceil(self.duration / dt - 1e-9)
        k = np.arange(k0, n + 1)
        tau = np.minimum(k * dt / self.duration, 1.0)
        grid = ss.evaluate(self.coefficients, tau)
        if k0 == 0:
            self._grid = grid
        else:
            self._grid = np.concatenate([self._grid[:k0], grid])

    def _belief_at(self, t: float) -> tuple[FloatArray, FloatArray]:
        """The ball's believed position and velocity at ``t`` (flight from the release)."""
        t_r, p_r, v_r = self._release_belief
        s = t - t_r
        pos = ballistic_position(p_r, v_r, s, self.task.gravity)
        return pos, v_r - np.array([0.0, self.task.gravity * s])

    # -- the controller interface ---------------------------------------------------
    def reset(self, state: JugglingState, rng: np.random.Generator | None = None) -> None:
        """Start a toss from the observed state (ball in hand)."""
        self._fitted()
        self._rng = rng if rng is not None else np.random.default_rng(0)
        self.plans: list[tuple[str, float, float, FloatArray]] = []
        self.corrections: list[tuple[float, float]] = []
        self._last = [np.asarray(state.hand_pos, dtype=np.float64)] * 2
        self._release_belief = (0.0, self._last[0], np.zeros(2))
        self._start_phase("toss", state.time, self._last[0].copy())
        self._k = 0

    @property
    def phase_time(self) -> float:
        """Time within the current phase, s."""
        return self._k * self.task.dt

    def nominal_next(self) -> FloatArray:
        """The nominal's next hand position (what :meth:`command` returns without events)."""
        return self._grid[min(self._k + 1, len(self._grid) - 1)].copy()

    def command(self, state: JugglingState) -> tuple[FloatArray, bool]:
        """Next hand target ``(2,)`` and whether the release is armed, given the state."""
        phase = self.phase
        if (
            (phase == "toss" and state.released)
            or (phase == "catch" and state.caught)
            or (self._end_k >= 0 and self._k >= self._end_k)
        ):
            if self.phase == "toss":
                dt = self.task.dt
                v = (self._last[1] - self._last[0]) / dt  # what the juggler commanded
                self._release_belief = (state.time, self._last[1].copy(), v)
            nxt = PHASES[(PHASES.index(self.phase) + 1) % len(PHASES)]
            self._start_phase(nxt, state.time, np.asarray(state.hand_pos, dtype=np.float64))
            self._k = 0
        elif phase == "catch" and self.correction and not state.held:
            self._correct(state)
        self._k += 1
        target = self._grid[min(self._k, len(self._grid) - 1)]
        self._last = [self._last[1], target]
        armed = self.phase == "toss" and self._k * self.task.dt >= self.release_after
        return target, armed

    def _correct(self, state: JugglingState) -> None:
        """Eq. 10 when the observed flight predicts another intercept than the plan's."""
        s = self.t_start + self.duration - state.time
        if s <= self.task.dt:
            return
        bx, bz = float(state.ball_pos[0]), float(state.ball_pos[1])
        vx, vz = float(state.ball_vel[0]), float(state.ball_vel[1])
        px, pz = bx + vx * s, bz + vz * s - 0.5 * self.task.gravity * s * s
        if math.hypot(px - self.end[0], pz - self.end[1]) <= self.correction_tolerance:
            return
        predicted = np.array([px, pz])
        tau1 = self._k * self.task.dt / self.duration
        velocity = ss.velocity(self.coefficients, np.array([tau1]), self.duration)[0]
        model = self.phases_["catch"].model
        self.coefficients = model.correct(
            self.coefficients,
            tau1,
            self._grid[self._k],
            predicted,
            self.duration,
            velocity=velocity,
            mode="free",
        )
        self.end = predicted
        self._grid_from(self._k + 1)
        self.corrections.append((state.time, tau1))
