"""The fitted juggler: one sine-series regression per phase and the statistics generation
draws from (scikit-learn style: parameters in ``__init__``, fitted attributes ``phases_``
and ``home_`` set by :meth:`JugglerModel.fit` and never changed afterwards).

One :class:`~motion_envs.models.sine_regression.SineSeriesRegression` per phase (toss,
go down, catch, return), fitted on demonstrations with conditions ``Q = [start, end]``
(hand positions) and ``N`` chosen by cross-validation on the training demonstrations
(:func:`~motion_envs.models.sine_regression.select_n_sines`). The per-episode controller
(:class:`motion_envs.models.juggling.JugglingController`) reads it.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from motion_envs._typing import FloatArray
from motion_envs.datasets.juggling import (
    PHASES,
    JugglingDemos,
    JugglingTask,
    ballistic_position,
)
from motion_envs.models.sine_regression import SineSeriesRegression, select_n_sines

__all__ = ["JugglerModel", "PhaseFit", "phase_conditions", "plan_catch"]


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


@dataclass(frozen=True)
class PhaseFit:
    """One phase's fitted model and the training statistics generation draws from.

    ``end_chol`` is a square root ``L`` of ``end_cov`` (``L L^T = end_cov``; eigen form,
    PSD-safe), computed at construction.
    """

    model: SineSeriesRegression
    cv_scores: FloatArray  # CV RMS error per candidate N
    duration_range: tuple[float, float]
    end_mean: FloatArray
    end_cov: FloatArray
    n_examples: int
    end_chol: FloatArray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        w, v = np.linalg.eigh(self.end_cov)
        object.__setattr__(self, "end_chol", v * np.sqrt(np.maximum(w, 0.0)))


class JugglerModel:
    """The fitted phase models of the analytic juggler (see the module docstring).

    Parameters
    ----------
    task:
        The task constants (defaults :class:`JugglingTask`).
    n_sines:
        ``"auto"`` (cross-validation on the training examples, per phase) or an int.
    candidates:
        Values of ``N`` tried by the cross-validation.
    n_folds:
        Folds of the ``N`` cross-validation.
    cv_tolerance:
        ``N`` is the smallest candidate whose CV error is within this relative margin of
        the best (the CV curve of smooth movements is flat past a few terms; the plain
        argmin then drifts to the largest candidate on differences of 0.1 %).
    """

    def __init__(
        self,
        task: JugglingTask | None = None,
        n_sines: int | str = "auto",
        candidates: tuple[int, ...] = tuple(range(0, 13)),
        n_folds: int = 5,
        cv_tolerance: float = 0.01,
    ) -> None:
        self.task = task or JugglingTask()
        self.n_sines = n_sines
        self.candidates = candidates
        self.n_folds = n_folds
        self.cv_tolerance = cv_tolerance

    @property
    def fitted(self) -> bool:
        """Whether :meth:`fit` has run."""
        return hasattr(self, "phases_")

    def check_fitted(self) -> None:
        """Raise ``ValueError`` unless :meth:`fit` has run."""
        if not self.fitted:
            raise ValueError("this AnalyticJuggler is not fitted; call fit() first")

    def fit(self, demos: JugglingDemos, cycles: set[tuple[int, int]] | None = None) -> JugglerModel:
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
            model = SineSeriesRegression(n_sines=n).fit(q, ys, ts)
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
