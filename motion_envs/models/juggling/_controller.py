"""The analytic juggler's per-episode controller: Lippi et al.'s phase models chained by
the task's online criteria (section III-A).

A :class:`JugglingController` reads a fitted :class:`~motion_envs.models.juggling.JugglerModel`
(never changes it) and holds one episode's state: its generator, the current phase plan,
the ball's believed flight. Generation:

* end points of toss, go-down and return are drawn from a Gaussian fitted to the
  training end points, durations uniformly over the training range;
* **toss**: the plan is constrained to zero vertical velocity at its end (eq. 9, on the
  regression hyperplane) and driven until the world releases the ball (vertical hand
  acceleration below ``-toss_threshold``);
* **go down**: reaches its end point (``PositionReached`` on the commanded position);
* **catch**: :func:`~motion_envs.models.juggling.plan_catch` chooses the duration ``T`` in
  the training range whose intercept on the predicted flight is closest to the training
  catch end points, and sets the end point to the ball's predicted centre at ``t0 + T``.
  The flight is predicted from what the juggler commanded at the release (its own hand
  velocity, an efference copy); when the observed ball's flight predicts a different
  intercept (release noise), the eq. 10 correction
  (:meth:`SineSeriesRegression.correct`, position and velocity kept at ``tau_1``, new end
  point) re-plans the rest of the reach (``ControlOptions.correction``);
* **return**: back to a home point; then the next toss.

Each phase plan is evaluated once on the control grid ``t_start + k dt`` (the closed
form ``Y(t) = Phi(t / T) . P``), so one :meth:`JugglingController.command` costs an index.
The controller sees only the state (observed hand, ball); it never imports Gymnasium.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from motion_envs._typing import FloatArray
from motion_envs.datasets.juggling import PHASES, JugglingState, ballistic_position, rules
from motion_envs.geometry import sine_series as ss
from motion_envs.models.juggling._model import JugglerModel, plan_catch

__all__ = [
    "ControlOptions",
    "Eq10Rows",
    "JugglingController",
    "eq10_many",
    "eq10_rows",
    "replan_many",
]


@dataclass(frozen=True)
class ControlOptions:
    """How the controller runs a fitted model (a variant is ``dataclasses.replace``).

    Attributes
    ----------
    correction:
        Apply the eq. 10 correction in the catch phase.
    correction_tolerance:
        m; re-plan when the predicted intercept moves farther than this from the plan.
    release_after:
        s; the release is armed only after this time in the toss (the toss accelerates
        first, so the threshold belongs to its decelerating part; a step of the observed
        start position under tracking noise must not release the ball).
    reach_tolerance:
        m; go-down and return end when the commanded position is this close to their
        end point (the paper's "position reached").
    """

    correction: bool = True
    correction_tolerance: float = 1e-3
    release_after: float = 0.25
    reach_tolerance: float = 1e-3


class JugglingController:
    """One episode of the analytic juggler (see the module docstring).

    Public state (read by the vectorised runner): ``phase``, ``t_start``, ``duration``,
    ``coefficients``, ``end`` (the current plan), ``grid`` (the plan on the control grid),
    ``end_k`` (the grid step that ends go-down and return; -1 for toss and catch, which end
    on the world's events), ``k`` (steps into the phase), ``plans`` and ``corrections``
    (the episode's history).
    """

    def __init__(self, model: JugglerModel, options: ControlOptions | None = None) -> None:
        model.check_fitted()
        self.model = model
        self.options = ControlOptions() if options is None else options
        self.task = model.task
        #: the ball's believed release ``(time, position, velocity)``
        self.release_belief: tuple[float, FloatArray, FloatArray] = (0.0, np.zeros(2), np.zeros(2))

    # -- planning -------------------------------------------------------------------
    def _draw_end(self, phase: str) -> FloatArray:
        fit = self.model.phases_[phase]
        out: FloatArray = fit.end_mean + fit.end_chol @ self._rng.standard_normal(2)
        return out

    def _draw_duration(self, phase: str) -> float:
        lo, hi = self.model.phases_[phase].duration_range
        return float(self._rng.uniform(lo, hi))

    def start_phase(self, phase: str, t: float, start: FloatArray) -> None:
        """Plan ``phase`` from the hand position ``start`` at time ``t``; ``k = 0``."""
        fit = self.model.phases_[phase]
        model = fit.model
        if phase == "catch":
            duration, end = plan_catch(
                start,
                *self.belief_at(t),
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
            near = np.linalg.norm(self.grid - self.end, axis=1) <= self.options.reach_tolerance
            self.end_k = int(np.argmax(near)) if near.any() else len(self.grid) - 1
        else:  # toss and catch end on the world's release and catch events
            self.end_k = -1
        self.plans.append((phase, t, duration, p.copy()))
        self.k = 0

    def _grid_from(self, k0: int) -> None:
        """Evaluate the current plan on steps ``k0 .. ceil(T / dt)`` of the phase.

        The basis on the phase's grid is computed once, at ``k0 = 0`` (the duration is
        fixed within a phase; eq. 10 changes only the coefficients)."""
        if k0 == 0:
            dt = self.task.dt
            n = math.ceil(self.duration / dt - 1e-9)
            k = np.arange(0, n + 1)
            tau = np.minimum(k * dt / self.duration, 1.0)
            self._tau = tau
            self._basis = ss.basis(tau, self.coefficients.shape[0] - 2)
            self._eq10: Eq10Rows | None = None
            self.grid = self._basis @ self.coefficients
        else:  # the rows before k0 were executed: keep them
            self.grid[k0:] = self._basis[k0:] @ self.coefficients

    def belief_at(self, t: float) -> tuple[FloatArray, FloatArray]:
        """The ball's believed position and velocity at ``t`` (flight from the release)."""
        t_r, p_r, v_r = self.release_belief
        s = t - t_r
        pos = ballistic_position(p_r, v_r, s, self.task.gravity)
        return pos, v_r - np.array([0.0, self.task.gravity * s])

    def next_phase(
        self, time: float, hand: FloatArray, last_commands: tuple[FloatArray, FloatArray]
    ) -> None:
        """End the current phase at ``time`` (observed hand ``hand``) and start the next.

        Ending the toss sets the release belief: the last command and the velocity of the
        last two commands ``last_commands`` (what the juggler commanded, an efference copy).
        """
        if self.phase == "toss":
            v = (last_commands[1] - last_commands[0]) / self.task.dt
            self.release_belief = (time, last_commands[1].copy(), v)
        nxt = PHASES[(PHASES.index(self.phase) + 1) % len(PHASES)]
        self.start_phase(nxt, time, hand)

    # -- the controller interface ---------------------------------------------------
    def reset(self, state: JugglingState, rng: np.random.Generator | None = None) -> None:
        """Start a toss from the observed state (ball in hand)."""
        self._rng = rng if rng is not None else np.random.default_rng(0)
        self.plans: list[tuple[str, float, float, FloatArray]] = []
        self.corrections: list[tuple[float, float]] = []
        self._last = [np.asarray(state.hand_pos, dtype=np.float64)] * 2
        self.release_belief = (0.0, self._last[0], np.zeros(2))
        self.start_phase("toss", state.time, self._last[0].copy())

    @property
    def phase_time(self) -> float:
        """Time within the current phase, s."""
        return self.k * self.task.dt

    def nominal_next(self) -> FloatArray:
        """The nominal's next hand position (what :meth:`command` returns without events)."""
        out: FloatArray = self.grid[min(self.k + 1, len(self.grid) - 1)].copy()
        return out

    def command(self, state: JugglingState) -> tuple[FloatArray, bool]:
        """Next hand target ``(2,)`` and whether the release is armed, given the state."""
        phase = self.phase
        if (
            (phase == "toss" and state.released)
            or (phase == "catch" and state.caught)
            or (self.end_k >= 0 and self.k >= self.end_k)
        ):
            hand = np.asarray(state.hand_pos, dtype=np.float64)
            self.next_phase(state.time, hand, (self._last[0], self._last[1]))
        elif phase == "catch" and self.options.correction and not state.held:
            self.correct(state.time, state.ball_pos, state.ball_vel)
        self.k += 1
        target: FloatArray = self.grid[min(self.k, len(self.grid) - 1)]
        self._last = [self._last[1], target]
        armed = self.phase == "toss" and self.k * self.task.dt >= self.options.release_after
        return target, armed

    def correct(self, time: float, ball_pos: FloatArray, ball_vel: FloatArray) -> bool:
        """Eq. 10 at step ``k`` of the catch when the ball observed at ``time`` flies to
        another intercept than the plan's (farther than ``correction_tolerance``); returns
        whether the plan changed."""
        s = self.t_start + self.duration - time
        if s <= self.task.dt:
            return False
        bx, bz = float(ball_pos[0]), float(ball_pos[1])
        vx, vz = float(ball_vel[0]), float(ball_vel[1])
        px, pz, _, _ = rules.flight((0.0, bx, bz, vx, vz), s, self.task.gravity)
        if math.hypot(px - self.end[0], pz - self.end[1]) <= self.options.correction_tolerance:
            return False
        self.replan(time, np.array([px, pz]))
        return True

    def _rows(self) -> Eq10Rows | None:
        """The eq. 10 rows for step ``k`` (:func:`eq10_rows`, looked up at the phase's
        first correction), or None when ``k`` is past them or ``tau_1 >= 1`` (then
        :meth:`replan` corrects with the model's own ``correct``)."""
        k, duration = self.k, self.duration
        rows = self._eq10
        if rows is None:
            rows = self._eq10 = eq10_rows(self._tau, self._basis, duration, self.task.dt)
        tau1 = k * self.task.dt / duration
        return rows if tau1 < 1.0 and k < rows.end else None

    def _replanned(self, time: float, predicted: FloatArray, coefficients: FloatArray) -> None:
        """Take the corrected ``coefficients``: the plan now ends at ``predicted``."""
        self.coefficients = coefficients
        self.end = predicted
        self._grid_from(self.k + 1)
        self.corrections.append((time, self.k * self.task.dt / self.duration))

    def replan(self, time: float, predicted: FloatArray) -> None:
        """Eq. 10 at step ``k`` of the catch: the rest of the plan re-planned to end at
        ``predicted`` (what :meth:`correct` does once its test asks for it)."""
        k, duration = self.k, self.duration
        rows = self._rows()
        if rows is not None:  # eq. 10 on the cached rows: correct_online's numbers
            coefficients = rows.correct(k, self.coefficients, self.grid[k], predicted)
        else:
            tau1 = k * self.task.dt / duration
            velocity = ss.velocity(self.coefficients, np.array([tau1]), duration)[0]
            model = self.model.phases_["catch"].model
            coefficients = model.correct(
                self.coefficients,
                tau1,
                self.grid[k],
                predicted,
                duration,
                velocity=velocity,
                mode="free",
            )
        self._replanned(time, predicted, coefficients)


def replan_many(
    episodes: Sequence[JugglingController], times: Sequence[float], predicted: FloatArray
) -> None:
    """:meth:`JugglingController.replan` of each episode ``j`` at ``times[j]`` toward
    ``predicted[j]`` (``(n, 2)``), the eq. 10 products of all of them computed together:
    numpy's ``matmul`` over a stack calls the same BLAS routine per matrix as the
    single products do, so every episode gets its own numbers bit for bit (tested
    against :meth:`~JugglingController.replan`). The native vector environment's
    corrections."""
    batch: list[tuple[int, JugglingController, Eq10Rows]] = []
    for j, ep in enumerate(episodes):
        rows = ep._rows()
        if rows is None:
            ep.replan(times[j], predicted[j])
        else:
            batch.append((j, ep, rows))
    if not batch:
        return
    at = [(rows, ep.k - rows.k0) for _, ep, rows in batch]
    derivative = np.stack([rows.derivative[i : i + 1] for rows, i in at])
    a1 = np.stack([rows.a[i] for rows, i in at])
    pinv = np.stack([rows.pinv[i] for rows, i in at])
    c = np.stack([ep.coefficients for _, ep, _ in batch])
    duration = np.array([rows.duration for _, _, rows in batch])
    position = np.stack([ep.grid[ep.k] for _, ep, _ in batch])
    target = predicted[[j for j, _, _ in batch]]
    out = eq10_many(derivative, a1, pinv, c, duration, position, target)
    for m, (j, ep, _) in enumerate(batch):
        ep._replanned(times[j], target[m].copy(), out[m])


class Eq10Rows:
    """The eq. 10 correction of one catch plan (free mode, position, end and velocity
    conditions) at steps ``k0 ..`` of its grid, with the conditions' rows and their
    pseudo-inverses computed once (they depend only on ``tau_1 = k dt / T``, ``T`` and
    the number of sines), so that :meth:`correct` does what
    :func:`~motion_envs.models.sine_regression.correct_online` does, with the same numbers
    (same rows, same ``pinv``, same products), for the plan's velocity at ``tau_1`` too
    (:func:`~motion_envs.geometry.sine_series.velocity`). Read-only (shared through
    :func:`eq10_rows`)."""

    def __init__(self, tau: FloatArray, basis: FloatArray, k0: int, duration: float) -> None:
        n_grid, n_basis = basis.shape
        n = n_basis - 2
        self.k0, self.end, self.duration = k0, n_grid, duration
        self.derivative = ss.basis_derivative(tau[k0:], n)
        a = np.empty((n_grid - k0, 3, n_basis))
        a[:, 0] = basis[k0:]
        a[:, 1] = ss.basis(1.0, n)
        a[:, 2] = self.derivative / duration
        self.a = a
        self.pinv = np.linalg.pinv(a)
        for array in (self.derivative, self.a, self.pinv):
            array.flags.writeable = False

    def correct(
        self, k: int, coefficients: FloatArray, position: FloatArray, target: FloatArray
    ) -> FloatArray:
        """The corrected coefficients at step ``k``: the plan restarts from ``position``
        with its own velocity there and ends at ``target``."""
        i = k - self.k0
        out = eq10_many(
            self.derivative[None, i : i + 1],
            self.a[None, i],
            self.pinv[None, i],
            coefficients[None],
            np.array([self.duration]),
            np.asarray(position, dtype=np.float64)[None],
            np.asarray(target, dtype=np.float64)[None],
        )
        return out[0]


#: :func:`eq10_rows`'s rows by catch duration, control step and basis size.
_EQ10_ROWS: dict[tuple[float, float, int], Eq10Rows] = {}
#: Entries :data:`_EQ10_ROWS` holds at most (emptied when full; a fitted catch model has
#: ``plan_catch``'s 201 candidate durations).
_EQ10_ROWS_MAX = 1024


def eq10_rows(tau: FloatArray, basis: FloatArray, duration: float, dt: float) -> Eq10Rows:
    """The eq. 10 rows of a catch plan of ``duration`` on the control grid ``tau`` (``k dt
    / T``, clipped at 1) with its ``basis`` (``ss.basis(tau, n)``), for every step
    (``k0 = 0``), shared by every plan of the same duration, step and basis size.

    A catch's duration is one of
    :func:`~motion_envs.models.juggling.plan_catch`'s candidates, so the catches of
    later cycles and episodes find their rows (above all the pseudo-inverses) computed.
    The numbers at step ``k`` are those of rows computed from any ``k0 <= k``: the
    rows are elementwise in ``tau``, and ``np.linalg.pinv`` of a stack decomposes and
    multiplies each matrix on its own (tested)."""
    key = (duration, dt, basis.shape[1])
    rows = _EQ10_ROWS.get(key)
    if rows is None:
        if len(_EQ10_ROWS) >= _EQ10_ROWS_MAX:
            _EQ10_ROWS.clear()
        rows = _EQ10_ROWS[key] = Eq10Rows(tau, basis, 0, duration)
    return rows


def eq10_many(
    derivative: FloatArray,
    a1: FloatArray,
    pinv: FloatArray,
    c: FloatArray,
    duration: FloatArray,
    position: FloatArray,
    target: FloatArray,
) -> FloatArray:
    """Eq. 10 (free mode) for ``n`` plans at once: coefficients ``c (n, nb, 2)``, the
    rows at their steps (``derivative (n, 1, nb)``, conditions ``a1 (n, 3, nb)`` and
    their pseudo-inverses ``pinv (n, nb, 3)``), durations ``(n,)``, positions and end
    targets ``(n, 2)``; returns the corrected coefficients. Stacked products: numpy's
    ``matmul`` calls the same BLAS routine for each matrix of a stack, so a plan's
    numbers do not depend on the others (tested)."""
    n = c.shape[0]
    r = np.empty((n, 3, 2))
    r[:, 0], r[:, 1] = position, target
    r[:, 2] = (derivative @ c / duration[:, None, None])[:, 0]  # the plan's velocity
    r -= a1 @ c
    dp = pinv @ r
    miss = np.abs(a1 @ dp - r).reshape(n, 6).max(axis=1)
    scale = np.abs(r).reshape(n, 6).max(axis=1)
    if (miss > 1e-9 * np.maximum(scale, 1.0)).any():
        raise ValueError(
            "correct_online: the free correction cannot meet the conditions "
            f"(residual {float(miss.max()):.3g})"
        )
    out: FloatArray = c + dp
    return out
