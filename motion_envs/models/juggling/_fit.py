"""THE default fit: the juggler as ``motion-bench juggling`` fits it, which
``MotionEnvs/Juggling-v0`` acts on top of, with its constants in one place.

:func:`load_demonstrations` gives the SIMULATED demonstrations (or the users' juggling
CSV, segmented by the online criteria), :func:`fit_juggler` splits them by demonstration
and fits the juggler on the training cycles only; :func:`default_fit` is both with the
defaults, once per process, data and task.
"""

from __future__ import annotations

import copy
import functools
import math
import os
from dataclasses import dataclass

from motion_envs.datasets.juggling import (
    JugglingDemos,
    JugglingTask,
    split_cycles,
)
from motion_envs.datasets.registry import data_file, load_builtin
from motion_envs.models.juggling._juggler import AnalyticJuggler
from motion_envs.models.juggling._segmentation import load_juggling_csv

__all__ = [
    "DEMO_CYCLES",
    "FIT_SEED",
    "FIT_TEST_FRACTION",
    "PAPER_GRAVITY",
    "TRACKING_NOISE",
    "V1_N_SINES",
    "DefaultFit",
    "default_fit",
    "fit_juggler",
    "juggler_demonstrations",
    "load_demonstrations",
    "load_juggler",
    "v1_fit",
    "v1_juggler",
]

#: Tracking noise (m) that comes with a release-noise level, as in ``motion-bench juggling
#: --noise LEVEL`` (its ``--tracking`` default) and ``Juggling-v0``'s ``noise=LEVEL``.
TRACKING_NOISE = 0.0005

#: Seed (of the demonstrations and the split) and held-out share with which
#: ``motion-bench juggling`` (default ``--seed 0``) generates, splits and fits;
#: Juggling-v0 fits the same juggler.
FIT_SEED = 0
FIT_TEST_FRACTION = 0.25

#: m/s^2, the paper's slow virtual world (``JugglingTask``'s default gravity).
PAPER_GRAVITY = 1.0

#: Sines per phase of Juggling-v1's juggler (:func:`v1_fit`).
V1_N_SINES = 4

#: Cycles per simulated person of the default demonstrations (the paper's 50 per phase).
DEMO_CYCLES = 50


def load_demonstrations(
    data: str | os.PathLike[str] | None = None,
    task: JugglingTask | None = None,
    seed: int = FIT_SEED,
    n_cycles: int = DEMO_CYCLES,
    n_persons: int = 1,
) -> JugglingDemos:
    """A built-in juggling dataset by name (:mod:`motion_envs.datasets.registry`; ``data``
    None: ``"simulated"``, the SIMULATED demonstrations, seeded by ``seed``) or the users'
    juggling CSV at ``data`` (:func:`~motion_envs.models.juggling.load_juggling_csv`)."""
    name = "simulated" if data is None else data
    options = {"task": task, "seed": seed, "n_cycles": n_cycles, "n_persons": n_persons}
    builtin: JugglingDemos | None = load_builtin(name, "juggling", **options)
    if builtin is not None:
        return builtin
    return load_juggling_csv(data_file(name, "juggling", "a path to a juggling CSV"), task=task)


def fit_juggler(
    demos: JugglingDemos,
    seed: int = FIT_SEED,
    test_fraction: float = FIT_TEST_FRACTION,
    **kwargs: object,
) -> tuple[AnalyticJuggler, set[tuple[int, int]], set[tuple[int, int]]]:
    """The juggler as ``motion-bench juggling --seed seed`` fits it, and the split.

    ``demos`` (a :class:`~motion_envs.datasets.juggling.JugglingDemos`) is split by
    demonstration (:func:`~motion_envs.datasets.juggling.split_cycles`); the juggler
    (``AnalyticJuggler(task=demos.task, **kwargs)``) is fitted on the training cycles only.
    Returns ``(juggler, train, test)``.
    """
    train, test = split_cycles(demos, test_fraction, seed)
    juggler = AnalyticJuggler(task=demos.task, **kwargs).fit(demos, train)  # type: ignore[arg-type]
    return juggler, train, test


@dataclass(frozen=True)
class DefaultFit:
    """The default fit: the demonstrations, their split and the fitted juggler."""

    demos: JugglingDemos
    train: frozenset[tuple[int, int]]
    test: frozenset[tuple[int, int]]
    juggler: AnalyticJuggler


@functools.lru_cache(maxsize=8)
def _cached_fit(data: str | None, task: JugglingTask) -> DefaultFit:
    demos = load_demonstrations(data, task)  # SIMULATED when data is None
    juggler, train, test = fit_juggler(demos)
    return DefaultFit(demos, frozenset(train), frozenset(test), juggler)


def default_fit(data: str | os.PathLike[str] | None, task: JugglingTask) -> DefaultFit:
    """The default fit of ``data`` (None: the built-in SIMULATED demonstrations) under
    ``task``: seed ``FIT_SEED``, held-out share ``FIT_TEST_FRACTION``; computed once per
    process, data and task (a few seconds). Do not change the returned juggler: take
    :func:`load_juggler`'s copy."""
    return _cached_fit(None if data is None else os.fspath(data), task)


def juggler_demonstrations(
    data: str | os.PathLike[str] | None, task: JugglingTask
) -> tuple[JugglingDemos, frozenset[tuple[int, int]], frozenset[tuple[int, int]]]:
    """The demonstrations the default juggler is fitted on and their split: ``(demos,
    train, test)`` with ``train``/``test`` sets of ``(recording, cycle)``; the juggler saw
    the ``train`` cycles only (``motion-bench juggling``'s split, seed ``FIT_SEED``)."""
    fit = default_fit(data, task)
    return fit.demos, fit.train, fit.test


def load_juggler(data: str | os.PathLike[str] | None, task: JugglingTask) -> AnalyticJuggler:
    """A fresh copy of the analytic juggler fitted as ``motion-bench juggling`` fits it:
    on the training cycles of the built-in SIMULATED demonstrations (``data`` None) or of
    the users' juggling CSV (:func:`default_fit`)."""
    return copy.deepcopy(default_fit(data, task).juggler)


@functools.lru_cache(maxsize=4)
def v1_fit(gravity: float) -> DefaultFit:
    """Juggling-v1's fit at ``gravity``: the built-in SIMULATED demonstrations generated
    at that gravity (seed ``FIT_SEED``), the default split, the juggler fitted on the
    training cycles. Differences from :func:`default_fit`: the release is armed after
    ``0.25 sqrt(PAPER_GRAVITY / g)`` s (it scales with the toss's time scale; 0.25 s at the
    paper's gravity) and every phase has ``V1_N_SINES`` sines (the cross-validated N gives
    a toss faster than the demonstrations'; ``docs/models.md``). Computed once per
    process and gravity; do not change the returned juggler (:func:`v1_juggler` copies)."""
    task = JugglingTask(gravity=float(gravity))
    demos = load_demonstrations(None, task)  # SIMULATED
    juggler, train, test = fit_juggler(
        demos, n_sines=V1_N_SINES, release_after=0.25 * math.sqrt(PAPER_GRAVITY / task.gravity)
    )
    return DefaultFit(demos, frozenset(train), frozenset(test), juggler)


def v1_juggler(gravity: float) -> AnalyticJuggler:
    """A fresh copy of Juggling-v1's analytic juggler at ``gravity`` (:func:`v1_fit`)."""
    return copy.deepcopy(v1_fit(float(gravity)).juggler)
