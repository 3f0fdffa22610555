"""The analytic juggler as one object: a fitted :class:`JugglerModel`, the
:class:`ControlOptions` it runs with and, after :meth:`AnalyticJuggler.reset`, the current
episode's :class:`JugglingController`.

The fitted model is never changed after ``fit``: :meth:`AnalyticJuggler.variant` makes a
juggler with other options that shares it (``juggler.variant(correction=False)``), and
:meth:`AnalyticJuggler.controller` a fresh controller for one episode, so that runs of
variants, or many episodes at once, never switch a flag on a shared object and back.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from motion_envs._typing import FloatArray
from motion_envs.datasets.juggling import JugglingDemos, JugglingState, JugglingTask
from motion_envs.models.juggling._controller import ControlOptions, JugglingController
from motion_envs.models.juggling._model import JugglerModel, PhaseFit

__all__ = ["AnalyticJuggler"]


class AnalyticJuggler:
    """The analytic juggler: fitted phase models plus a controller per episode.

    Parameters
    ----------
    task, n_sines, candidates, n_folds, cv_tolerance:
        The fit's (:class:`JugglerModel`).
    correction, correction_tolerance, release_after, reach_tolerance:
        The controller's (:class:`ControlOptions`).

    Attributes ``model`` (the :class:`JugglerModel`), ``options`` (the
    :class:`ControlOptions`) and ``episode`` (the current :class:`JugglingController`,
    None before the first ``reset``; its current plan: ``episode.t_start``,
    ``episode.duration``, ``episode.coefficients``, ``episode.end``); ``phases_`` and
    ``home_`` are the model's; ``reset``, ``command``, ``nominal_next``, ``phase``,
    ``phase_time``, ``plans`` and ``corrections`` the current episode's.
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
        self.model = JugglerModel(task, n_sines, candidates, n_folds, cv_tolerance)
        self.options = ControlOptions(
            correction, correction_tolerance, release_after, reach_tolerance
        )
        self.episode: JugglingController | None = None

    # -- the fitted model ---------------------------------------------------------------
    def fit(
        self, demos: JugglingDemos, cycles: set[tuple[int, int]] | None = None
    ) -> AnalyticJuggler:
        """Fit every phase on ``demos``, only ``cycles`` if given (:meth:`JugglerModel.fit`)."""
        self.model.fit(demos, cycles)
        return self

    @property
    def task(self) -> JugglingTask:
        """The task constants."""
        return self.model.task

    @property
    def phases_(self) -> dict[str, PhaseFit]:
        """Per phase, the fitted model and its training statistics."""
        self.model.check_fitted()
        return self.model.phases_

    @property
    def home_(self) -> FloatArray:
        """The mean start of the training tosses: where a cycle starts."""
        self.model.check_fitted()
        return self.model.home_

    # -- options and variants -----------------------------------------------------------
    @property
    def correction(self) -> bool:
        """Whether the catch applies the eq. 10 correction (``options.correction``)."""
        return self.options.correction

    @correction.setter
    def correction(self, value: bool) -> None:
        self.options = replace(self.options, correction=bool(value))

    @property
    def correction_tolerance(self) -> float:
        """``options.correction_tolerance`` (m)."""
        return self.options.correction_tolerance

    @property
    def release_after(self) -> float:
        """``options.release_after`` (s)."""
        return self.options.release_after

    @property
    def reach_tolerance(self) -> float:
        """``options.reach_tolerance`` (m)."""
        return self.options.reach_tolerance

    def variant(self, **options: Any) -> AnalyticJuggler:
        """A juggler sharing this one's fitted model, with ``options`` (fields of
        :class:`ControlOptions`) replaced; this juggler is unchanged."""
        out = AnalyticJuggler.__new__(AnalyticJuggler)
        out.model = self.model
        out.options = replace(self.options, **options)
        out.episode = None
        return out

    def controller(self) -> JugglingController:
        """A new controller for one episode (the model fitted, the options of this juggler)."""
        return JugglingController(self.model, self.options)

    # -- the current episode ------------------------------------------------------------
    def reset(self, state: JugglingState, rng: np.random.Generator | None = None) -> None:
        """Start an episode: a new controller, a toss from the observed state."""
        self.episode = self.controller()
        self.episode.reset(state, rng)

    def command(self, state: JugglingState) -> tuple[FloatArray, bool]:
        """Next hand target ``(2,)`` and whether the release is armed, given the state."""
        return self._current().command(state)

    def nominal_next(self) -> FloatArray:
        """The nominal's next hand position (what :meth:`command` returns without events)."""
        return self._current().nominal_next()

    @property
    def phase(self) -> str:
        """The current phase."""
        return self._current().phase

    @property
    def phase_time(self) -> float:
        """Time within the current phase, s."""
        return self._current().phase_time

    @property
    def plans(self) -> list[tuple[str, float, float, FloatArray]]:
        """The episode's phase plans ``(phase, t_start, duration, coefficients)``."""
        return self._current().plans

    @property
    def corrections(self) -> list[tuple[float, float]]:
        """The episode's eq. 10 corrections ``(time, tau_1)``."""
        return self._current().corrections

    def _current(self) -> JugglingController:
        if self.episode is None:
            raise RuntimeError("no episode; call reset() first")
        return self.episode
