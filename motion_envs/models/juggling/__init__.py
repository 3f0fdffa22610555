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
* ``_sensor``: how Juggling-v1 sees the ball (:class:`BallSensor`: delay and noise) and
  scatters a toss (:func:`perturb_release`);
* ``_camera``: how Juggling-v2 sees the ball (:class:`CameraSensor`: positions at a
  camera rate, a hidden delay with jitter, drops, occlusion) and the flight estimators
  fed from it (:class:`FlightEstimator`, :func:`drag_flight`; the gaze latency,
  :func:`eccentricity`); ``_pooled_delay``: the release-anchored delay fitted to all of an
  episode's flights at once (:func:`pooled_flight_delay`, a :class:`DelayRule`);
  ``_v2_levels``:
  Juggling-v2's levels (:data:`V2_LEVELS`) and controllers (:class:`V2Controller`);
  ``_cascade_v1``: Cascade-v1's view of the balls through those cameras and estimators
  (:class:`CascadeBallView`, :data:`CASCADE_V1_CONTROLLERS`; the delay estimator
  pooled over the balls, :class:`PooledReleaseEstimator`) and its catch plans
  (:data:`CASCADE_CATCH_PLANS`; :func:`catch_plan`: also the controllers carrying the
  mean delay's, the delay tracker and the delay estimator with the catch plan);
  ``_v2_catch``: the catch planned for Juggling-v2's capture rule (:class:`CatchPlan`)
  and every Juggling-v2 controller by name (:func:`make_v2_controller`);
  ``_delay_tracker``: the online delay tracker driven by each catch's timing error
  (:class:`DelayTracker`; Juggling-v2's :class:`DelayTrackerController`, Cascade-v1's
  through :meth:`CascadeBallView.felt`) and the tracked correction of the
  release-anchored estimate (:class:`CorrectionTracker`; Juggling-v2's
  :class:`EstimatorTrackerController`, Cascade-v1's through the view likewise);
* ``_levels``: Juggling-v1's levels (:data:`LEVELS`), its reference controllers
  (:func:`make_controller`) and :class:`HumanLikeness`;
* ``_flights``: ball flights in recordings (:func:`detect_flights`: free-flight segments
  of unlabelled, gappy markers, fitted gravity, apex, releases and catches where the
  ball leaves and joins a hand's carry);
* ``_pattern``: the pattern of those flights (:func:`pattern_summary`: the across-body
  axis, hands, beat, dwell, throw values, siteswap, balls by Shannon's juggling theorem
  and by the concurrent count);
* ``_cascade``: the odd-cascade juggler's fit (:func:`cascade_fit`, 3 or 5 balls), its
  state and sensor; ``_cascade_hand``: one hand (:class:`CascadeHand`) and the
  controller's tunables (:class:`CascadeTunables`); ``_cascade_control``: the juggler (two
  hands of the one-ball juggler scheduled by Shannon's theorem,
  :class:`CascadeController`), its start and reference controllers
  (:func:`make_cascade_controller`);
* ``_cascade_siteswap``: the siteswap juggler's plan (any vanilla siteswap of 2 to 5
  balls: each throw value's flight and landing hand, quintic movements within the hand's
  limits, the tempo, :func:`choose_beat`) and its SIMULATED demonstrations
  (:func:`siteswap_demonstrations`); ``_cascade_siteswap_control``: the siteswap juggler
  (:class:`SiteswapController`) and its reference variants;
* ``_patterns``: the registered patterns (:class:`PatternSpec`, :func:`register_pattern`),
  which juggler plays which and why a siteswap is refused (:func:`pattern_reasons`,
  :func:`check_pattern`), a pattern's controller and likeness reference
  (:func:`pattern_controller`, :func:`pattern_likeness`);
* ``_gravity``: the gravities Juggling-v1 and Cascade-v0 can be built at, from the
  task's timing (:func:`check_gravity`);
* ``_fit``: THE default fit (``motion-bench juggling``'s, which ``Juggling-v0`` uses) and
  its constants; Juggling-v1's fit (:func:`v1_fit`).
"""

from motion_envs.models.juggling._camera import (
    ANCHOR_FRAMES,
    DELAY_GRID,
    ESTIMATORS,
    GAZE_EYE,
    SLOPE_GRID,
    AnchoredFlight,
    CameraFrame,
    CameraSensor,
    DelayRule,
    FlightEstimator,
    ballistic_apex,
    drag_flight,
    eccentricities,
    eccentricity,
    gaze_eye,
    mean_flight_delay,
    release_residuals,
)
from motion_envs.models.juggling._cascade import (
    CascadeFit,
    CascadePattern,
    CascadeSensor,
    CascadeState,
    cascade_fit,
    cascade_likeness,
)
from motion_envs.models.juggling._cascade_control import (
    CASCADE_CONTROLLERS,
    CascadeController,
    CascadeStart,
    make_cascade_controller,
)
from motion_envs.models.juggling._cascade_hand import (
    DEFAULT_TUNABLES,
    CascadeHand,
    CascadeTunables,
)
from motion_envs.models.juggling._cascade_siteswap import (
    SiteswapPlan,
    SiteswapStyle,
    SiteswapTiming,
    choose_beat,
    siteswap_demonstrations,
    siteswap_reasons,
)
from motion_envs.models.juggling._cascade_siteswap_catch import SiteswapCatchController
from motion_envs.models.juggling._cascade_siteswap_control import SiteswapController
from motion_envs.models.juggling._cascade_v1 import (
    CASCADE_CATCH_PLANS,
    CASCADE_V1_CONTROLLERS,
    CASCADE_V1_LEVELS,
    CascadeBallView,
    PooledReleaseEstimator,
    catch_height,
    catch_plan,
    equivalent_ballistic,
    nearest_palm,
    planned_catch,
)
from motion_envs.models.juggling._controller import (
    ControlOptions,
    Eq10Rows,
    JugglingController,
    eq10_many,
    eq10_rows,
    replan_many,
)
from motion_envs.models.juggling._delay_tracker import (
    CORRECTION_BOUND,
    TRACKER_MAX_GAIN,
    CorrectionTracker,
    DelayTracker,
)
from motion_envs.models.juggling._fit import (
    DEMO_CYCLES,
    FIT_SEED,
    FIT_TEST_FRACTION,
    PAPER_GRAVITY,
    TRACKING_NOISE,
    V1_N_SINES,
    DefaultFit,
    default_fit,
    fit_juggler,
    juggler_demonstrations,
    load_demonstrations,
    load_juggler,
    v1_fit,
    v1_juggler,
)
from motion_envs.models.juggling._flights import (
    Flight,
    FlightAnalysis,
    FlightOptions,
    detect_flights,
    estimate_noise,
)
from motion_envs.models.juggling._gravity import (
    MAX_DEMO_SAMPLES,
    MIN_PHASE_SAMPLES,
    TIMING_AT_PAPER_GRAVITY,
    check_gravity,
    gravity_range,
)
from motion_envs.models.juggling._juggler import AnalyticJuggler
from motion_envs.models.juggling._levels import (
    CONTROLLERS,
    LEVELS,
    LIKENESS_TAU,
    HumanLikeness,
    JugglerController,
    JugglingLevel,
    make_controller,
    v1_likeness,
)
from motion_envs.models.juggling._model import (
    JugglerModel,
    PhaseFit,
    phase_conditions,
    plan_catch,
)
from motion_envs.models.juggling._pattern import (
    PatternSummary,
    ThrowEvent,
    across_axis,
    pattern_summary,
)
from motion_envs.models.juggling._patterns import (
    PATTERNS,
    PatternCheck,
    PatternSpec,
    ThrowNeed,
    cascade_reasons,
    check_pattern,
    pattern_controller,
    pattern_likeness,
    pattern_plan,
    pattern_reasons,
    pattern_spec,
    pattern_tempo,
    register_pattern,
)
from motion_envs.models.juggling._pooled_delay import (
    parabolic_minimum,
    pooled_flight_delay,
    pooled_residuals,
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
from motion_envs.models.juggling._sensor import (
    BallMeasurement,
    BallSensor,
    perturb_release,
    predict_forward,
)
from motion_envs.models.juggling._v2_catch import (
    CATCH_PLANS,
    CatchPlan,
    CatchPlanController,
    DelayTrackerController,
    EstimatorTrackerController,
    make_v2_controller,
)
from motion_envs.models.juggling._v2_levels import (
    V2_CONTROLLERS,
    V2_LEVELS,
    V2Controller,
    V2Level,
)
from motion_envs.models.juggling._world import (
    TRACKING_ROWS,
    BallisticWorld,
    JugglingWorld,
    draw_episode_noise,
    tracked_hand,
    xz_pair,
)

__all__ = [
    "ANCHOR_FRAMES",
    "CASCADE_CATCH_PLANS",
    "CASCADE_CONTROLLERS",
    "CASCADE_V1_CONTROLLERS",
    "CASCADE_V1_LEVELS",
    "CATCH_PLANS",
    "CONTROLLERS",
    "CORRECTION_BOUND",
    "DEFAULT_TUNABLES",
    "DELAY_GRID",
    "DEMO_CYCLES",
    "ESTIMATORS",
    "FIT_SEED",
    "FIT_TEST_FRACTION",
    "GAZE_EYE",
    "LEVELS",
    "LIKENESS_TAU",
    "MAX_DEMO_SAMPLES",
    "MIN_PHASE_SAMPLES",
    "PAPER_GRAVITY",
    "PATTERNS",
    "SLOPE_GRID",
    "TIMING_AT_PAPER_GRAVITY",
    "TRACKER_MAX_GAIN",
    "TRACKING_NOISE",
    "TRACKING_ROWS",
    "V1_N_SINES",
    "V2_CONTROLLERS",
    "V2_LEVELS",
    "AnalyticJuggler",
    "AnchoredFlight",
    "BallMeasurement",
    "BallSensor",
    "BallisticWorld",
    "CameraFrame",
    "CameraSensor",
    "CascadeBallView",
    "CascadeController",
    "CascadeFit",
    "CascadeHand",
    "CascadePattern",
    "CascadeSensor",
    "CascadeStart",
    "CascadeState",
    "CascadeTunables",
    "CatchPlan",
    "CatchPlanController",
    "ControlOptions",
    "CorrectionTracker",
    "CycleResult",
    "DefaultFit",
    "DelayRule",
    "DelayTracker",
    "DelayTrackerController",
    "Eq10Rows",
    "EstimatorTrackerController",
    "Flight",
    "FlightAnalysis",
    "FlightEstimator",
    "FlightOptions",
    "HumanLikeness",
    "JugglerController",
    "JugglerModel",
    "JugglingController",
    "JugglingLevel",
    "JugglingWorld",
    "PatternCheck",
    "PatternSpec",
    "PatternSummary",
    "PhaseFit",
    "PooledReleaseEstimator",
    "SiteswapCatchController",
    "SiteswapController",
    "SiteswapPlan",
    "SiteswapStyle",
    "SiteswapTiming",
    "ThrowEvent",
    "ThrowNeed",
    "V2Controller",
    "V2Level",
    "across_axis",
    "ballistic_apex",
    "cascade_fit",
    "cascade_likeness",
    "cascade_reasons",
    "catch_height",
    "catch_plan",
    "check_gravity",
    "check_pattern",
    "choose_beat",
    "cycle_rng",
    "cycle_rngs",
    "default_fit",
    "detect_flights",
    "drag_flight",
    "draw_episode_noise",
    "eccentricities",
    "eccentricity",
    "eq10_many",
    "eq10_rows",
    "equivalent_ballistic",
    "estimate_noise",
    "fit_juggler",
    "gaze_eye",
    "gravity_range",
    "juggler_demonstrations",
    "load_demonstrations",
    "load_juggler",
    "load_juggling_csv",
    "make_cascade_controller",
    "make_controller",
    "make_v2_controller",
    "mean_flight_delay",
    "nearest_palm",
    "parabolic_minimum",
    "pattern_controller",
    "pattern_likeness",
    "pattern_plan",
    "pattern_reasons",
    "pattern_spec",
    "pattern_summary",
    "pattern_tempo",
    "perturb_release",
    "phase_conditions",
    "plan_catch",
    "planned_catch",
    "pooled_flight_delay",
    "pooled_residuals",
    "predict_forward",
    "register_pattern",
    "release_residuals",
    "replan_many",
    "run_cycle",
    "run_cycles",
    "run_cycles_fast",
    "segment_demos",
    "segment_juggling",
    "siteswap_demonstrations",
    "siteswap_reasons",
    "tracked_hand",
    "v1_fit",
    "v1_juggler",
    "v1_likeness",
    "xz_pair",
]
