"""The juggling task's models (Lippi, Avizzano & Ruffaldi, section III-A).

The public names of small private modules, one concern each:

* ``_world``: the pure-model world (:class:`BallisticWorld`), the :class:`JugglingWorld`
  protocol every world satisfies, the episode's noise (:func:`draw_episode_noise`,
  :func:`tracked_hand`); the rules themselves are in :mod:`motion_envs.datasets.juggling`,
  the lowest layer that every user of them can import;
* ``_model``: the fitted phase models (:class:`JugglerModel`, scikit-learn style), the
  catch planner (:func:`plan_catch`);
* ``_controller``: one episode of the juggler (:class:`JugglingController`,
  :class:`ControlOptions`);
* ``_juggler``: :class:`AnalyticJuggler`, the model, its options and the current episode
  in one object;
* ``_run``: seeded cycles, step by step in any world or vectorised in the pure model;
* ``_segmentation``: recordings cut into phases by the online criteria;
* ``_fit``: THE default fit (``motion-bench juggling``'s, which ``Juggling-v0`` uses) and
  its constants.
"""

from motion_envs.models.juggling._controller import ControlOptions, JugglingController
from motion_envs.models.juggling._fit import (
    DEMO_CYCLES,
    FIT_SEED,
    FIT_TEST_FRACTION,
    TRACKING_NOISE,
    DefaultFit,
    default_fit,
    fit_juggler,
    juggler_demonstrations,
    load_demonstrations,
    load_juggler,
)
from motion_envs.models.juggling._juggler import AnalyticJuggler
from motion_envs.models.juggling._model import (
    JugglerModel,
    PhaseFit,
    phase_conditions,
    plan_catch,
)
from motion_envs.models.juggling._run import (
    CycleResult,
    cycle_rng,
    cycle_rngs,
    run_cycle,
    run_cycles,
    run_cycles_fast,
)
from motion_envs.models.juggling._segmentation import (
    load_juggling_csv,
    segment_demos,
    segment_juggling,
)
from motion_envs.models.juggling._world import (
    TRACKING_ROWS,
    BallisticWorld,
    JugglingWorld,
    draw_episode_noise,
    tracked_hand,
)

__all__ = [
    "DEMO_CYCLES",
    "FIT_SEED",
    "FIT_TEST_FRACTION",
    "TRACKING_NOISE",
    "TRACKING_ROWS",
    "AnalyticJuggler",
    "BallisticWorld",
    "ControlOptions",
    "CycleResult",
    "DefaultFit",
    "JugglerModel",
    "JugglingController",
    "JugglingWorld",
    "PhaseFit",
    "cycle_rng",
    "cycle_rngs",
    "default_fit",
    "draw_episode_noise",
    "fit_juggler",
    "juggler_demonstrations",
    "load_demonstrations",
    "load_juggler",
    "load_juggling_csv",
    "phase_conditions",
    "plan_catch",
    "run_cycle",
    "run_cycles",
    "run_cycles_fast",
    "segment_demos",
    "segment_juggling",
    "tracked_hand",
]
