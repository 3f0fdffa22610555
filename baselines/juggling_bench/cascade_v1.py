"""``motion-bench juggling --version v2 --pattern P``: Cascade-v1's reference rows (a
pattern at Juggling-v2's human levels), scored by catches before the first drop.

For each level (``easy``, ``medium``, ``hard``;
:data:`motion_envs.models.juggling.CASCADE_V1_LEVELS`) the rows (:data:`ROWS`) are played
in ``MotionEnvs/Cascade-v1`` with ``pattern=P`` (the residual, where a row acts, in the
env's own action space, :data:`RESIDUAL_SCALE` m per unit action):

* ``juggler``: the analytic juggler told each ball through the flight fitted to its
  frames taken as the present (the zero action);
* ``oracle``: the juggler given the episode's true delay and each ball's true drag
  (``juggler_oracle``): a reference, never a competitor and never chosen;
* ``oracle_catch``: the oracle with Juggling-v2's catch planned for the capture rule
  (``juggler_oracle_catch``: each flying ball told ``lead`` s ahead, so the hand ends its
  reach early at the meeting point and waits; the lead chosen per juggler on TRAINING
  seeds, :data:`motion_envs.models.juggling.CASCADE_CATCH_PLANS`): the reference the
  room is measured against (:data:`UPPER_REFERENCE`), called the UPPER reference only
  where measured at or above every row (``upper_is_upper``: its paired difference from
  every other row, in mean catches, is >= 0; the report names the rows with an interval
  wholly above it);
* ``best_constant``: the constant residual, from Juggling-v2's grid
  (:data:`CONSTANT_GRID`, :data:`baselines.juggling_bench.v2.CONSTANT_GRID`, declared
  before any run: each coordinate -0.5, 0 or 0.5, up to 5 cm at this scale) in each
  hand's own frame (``x`` mirrored for the left hand, as the pattern mirrors it), the one
  with the most mean catches before the first drop on VALIDATION episodes;
* ``velocity_x_mean_delay``: Juggling-v2's two-line residual
  (:class:`CascadeVelocityTimesDelay`): per hand in its catch phase, the velocity of the
  ball it is about to catch (read from the observation's frames:
  :func:`baselines.juggling_bench.v2.frame_velocity`) times the level's mean delay;
* ``juggler_mean_delay``: the frames shifted by the level's mean delay;
* ``late_meeting``: the same told the mean delay plus an offset from
  :data:`LATE_OFFSETS` (declared here before any run), the offset with the most mean
  catches before the first drop on VALIDATION episodes;
* ``mean_delay_catch``: the same catch plan on the level's mean delay
  (``juggler_mean_delay_catch``, its lead chosen on TRAINING seeds; no hidden
  information: a competitor). Without drag in its estimate, telling a ball ``lead``
  ahead is what ``late_meeting``'s offset does (a later placed fit, predicted further);
  the rows differ in the seeds the number is chosen on (one lead for all levels) and in
  the flight told before a ball's first three frames (advanced by the lead only). On
  the siteswap juggler (pattern ``"5"``) it, as ``oracle_catch``, is the juggler's own
  catch (:class:`~motion_envs.models.juggling.SiteswapCatchController`, the palm
  arriving ``lead`` early and waiting; the plan chosen on TRAINING seeds);
* ``delay_estimator``: the hand-written delay estimator (``juggler_delay_estimator``:
  Juggling-v2's release-anchored estimator, the delay found from each release, where
  the hand knows when and where it let go, and pooled over the episode's releases of
  every ball; :class:`~motion_envs.models.juggling.PooledReleaseEstimator`);
* ``delay_estimator_catch``: the two hand-written fixes together
  (``juggler_delay_estimator_catch``): the delay estimator's pooled delay with
  ``mean_delay_catch``'s catch plan on either juggler (the same plan, declared, not
  re-tuned; no hidden information: a competitor, the strongest simple fix a reviewer
  would write in a few lines);
* ``estimator_offset_catch``: the same told the pooled estimate plus an offset (the
  env's ``delay_offset`` on that controller, a correction of the estimate's bias, which
  may be negative; before the first estimate the level's mean plus it) from
  Juggling-v2's :data:`~baselines.juggling_bench.v2.ESTIMATOR_OFFSETS` (declared before
  any run), the offset with the most mean catches before the first drop on VALIDATION
  episodes (:func:`choose_estimator_offset`; offset 0 is ``delay_estimator_catch``);
* ``delay_tracker``: the online delay tracker (``juggler_delay_tracker``: the mean-delay
  catch plan whose one delay ``D`` starts at the level's mean and, after every catch by
  either hand, moves by that catch's timing error ``e`` relative to the planned meeting,
  ``D <- clip(D - k (e - offset))`` over the level's delay range, each flight fitted
  with the ``D + offset`` told at its release;
  :mod:`motion_envs.models.juggling._delay_tracker`), its gain and offset the pair of
  Juggling-v2's :data:`~baselines.juggling_bench.v2.TRACKER_GRID` with the most mean
  catches before the first drop on VALIDATION episodes (:func:`choose_tracker`);
* ``estimator_tracker_catch``: the two corrections together
  (``juggler_estimator_tracker_catch``: ``delay_estimator_catch`` whose pooled estimate,
  and prior, is told with a correction ``C + offset``, ``C`` starting at 0 and moving
  after every catch by either hand, ``C <- clip(C - k (e - offset), -50 ms, +50 ms)``,
  each flight fitted with the correction told at its ball's release;
  :class:`~motion_envs.models.juggling.CorrectionTracker`), its gain and offset the pair
  of Juggling-v2's :data:`~baselines.juggling_bench.v2.ESTIMATOR_TRACKER_GRID` with the
  most mean catches before the first drop on VALIDATION episodes
  (:func:`choose_estimator_tracker`; ``(0, 0)`` is ``delay_estimator_catch``); a
  competitor;
* ``pooled_estimator_catch``: ``delay_estimator_catch`` whose pooled delay is fitted to
  all the episode's anchored flights of every ball at once (the env's ``delay_rule``
  :func:`~motion_envs.models.juggling.pooled_flight_delay`: one least-squares delay,
  refined below the 5 ms grid, instead of the mean of each flight's grid delay), each
  flight anchored on its first ``anchor_frames`` frames, and the balls in flight at the
  start either telling no delay or anchored on the throws the juggler made before ``t =
  0`` (the env's ``anchor_start``): the pair of :data:`POOLED_GRID` (Juggling-v2's
  :data:`~baselines.juggling_bench.v2.POOLED_ANCHOR_FRAMES`, without then with the start
  anchor; declared before any run) with the most mean catches before the first drop on
  VALIDATION episodes (:func:`choose_pooled_anchor`); no offset; a competitor;
* ``fixed_point``: the juggler that catches at the nominal point and time, never
  looking (trivial);
* ``random``: uniform random actions on the juggler (trivial; each episode's generator
  seeded by its seed);
* ``task_error_ilc``: Juggling-v2's residual learner from the task-error vector, per
  hand (:class:`~baselines.juggling_bench.cascade_v1_ilc.CascadeTaskErrorILC`:
  iterative learning control of ``r = c + d v`` in the catch phase from each catch's
  ``info["task_error"]``, not RL; starting as ``velocity_x_mean_delay``), trained on a
  budget of ``ilc_iterations x ilc_episodes`` TRAINING episodes (default 6 x 10) and
  then scored on validation like every other row (``ilc=False``: not played).

Every choice is made on VALIDATION episodes (``SPLIT_SEEDS["val"]`` onward) before any
test seed is played, by mean catches before the first drop (ties: the first in grid or
row order): the grids' (the constant, the late offset, the tracker's pair, the
estimate's offset, the estimate's tracker's pair, the pooled estimate's anchor frames
and start anchor) on the first ``val_episodes`` (30), then the best non-oracle row and
the tracker's rival on the first ``pick_episodes`` (200), every row played with the
parameter its grid chose (the grids' plays reused when ``pick_episodes ==
val_episodes``; the pick's means are ``val_mean_catches``, its seeds ``seeds["pick"]``;
on 30 episodes three balls medium's pick was late meeting, 1.30 [0.57, 2.00] mean
catches below the pooled estimate on 200, BENCHMARKS); the rows are then played on
``episodes`` TEST episodes. An
episode ends at the first drop or after ``max_catches`` catches (censored). Reported per
row (:func:`baselines.juggling_bench.cascade.summary`, 95 % bootstrap intervals resampling
episodes): the median and the mean catches before the first drop, the catch rate, the
median time to the first drop, and the hand deviation from HELD-OUT demonstrations
(``deviation_m``, the likeness criterion; :mod:`baselines.agents.cascade_score`: each
hand in its own frame, per phase segment the distance to the nearest segment of the
same phase of the SIMULATED cascade demonstrations of the pattern's ball count held out
of the juggler's fit, after the departure from the segment's line; the median over the
segments of both hands, its interval resampling test episodes; per hand and per phase
too; recorded on the TEST episodes only, the choices read catches alone; the patterns
without such demonstrations, all but ``3``, ``3-human`` and ``5``, report none); per
level the ROOM, the paired difference of mean catches of ``oracle_catch`` and of the
best non-oracle row, ``oracle_catch`` minus every other row (paired), and the old
``oracle`` minus the best row; ``room_catch_rate``, the same room in catch rate, and
``target_room``, whether it can decide the agents' target (+0.05 catch rate above the
best row; :func:`baselines.agents.against_rows.room_for_target`).
:func:`write_cascade_v1` writes ``results.json`` and ``cascade_v1_rows.png`` (mean
catches and catch rate against the deviation, a point per row with its intervals, a
panel per level). The demonstrations (the likeness reward,
the siteswap juggler's style, the deviation's) are SIMULATED.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from baselines import options
from baselines.agents.against_rows import room_for_target
from baselines.agents.juggling_score import catch_rate_difference
from baselines.juggling_bench import v2
from baselines.juggling_bench.cascade import CascadeEpisodes, summary
from baselines.juggling_bench.cascade_v1_view import FRESH_FRAME, catching_velocities
from baselines.juggling_bench.grid_choice import best_on_grid
from motion_envs.datasets.juggling import SIMULATED_LABEL, SPLIT_SEEDS, episode_seeds
from motion_envs.models.juggling import ANCHOR_FRAMES, CASCADE_V1_LEVELS, V2_LEVELS, pattern_spec

__all__ = [
    "CASCADE_V1_ENV_ID",
    "CONSTANT_GRID",
    "FRESH_FRAME",
    "LATE_OFFSETS",
    "POOLED_GRID",
    "REFERENCES",
    "RESIDUAL_SCALE",
    "ROWS",
    "UPPER_REFERENCE",
    "CascadeV1Config",
    "CascadeVelocityTimesDelay",
    "cascade_v1_episodes",
    "catching_velocities",
    "check_cascade_v1_config",
    "choose_constant",
    "choose_estimator_offset",
    "choose_estimator_tracker",
    "choose_late_offset",
    "choose_pooled_anchor",
    "choose_tracker",
    "deviation_note",
    "plot_cascade_v1",
    "pooled_key",
    "report_cascade_v1",
    "row_styles",
    "row_summary",
    "run_cascade_v1",
    "write_cascade_v1",
]

CASCADE_V1_ENV_ID = "MotionEnvs/Cascade-v1"
#: m of residual per unit action (the random row's; the agent block's scale).
RESIDUAL_SCALE = 0.1
#: s added to the level's mean delay by ``late_meeting`` (the env's ``delay_offset``);
#: Juggling-v2's grid (0-80 ms, its best at the largest on medium and hard) widened to
#: 120 ms before any Cascade-v1 run.
LATE_OFFSETS: tuple[float, ...] = (0.0, 0.02, 0.04, 0.06, 0.08, 0.10, 0.12)
#: The constant residuals tried by ``best_constant`` (Juggling-v2's grid, in action units;
#: ``(x, z)`` in each hand's own frame).
CONSTANT_GRID: tuple[tuple[float, float], ...] = v2.CONSTANT_GRID
#: The rows, in the report's order.
ROWS = (
    "juggler",
    "oracle",
    "oracle_catch",
    "best_constant",
    "velocity_x_mean_delay",
    "juggler_mean_delay",
    "late_meeting",
    "mean_delay_catch",
    "delay_estimator",
    "delay_estimator_catch",
    "estimator_offset_catch",
    "fixed_point",
    "random",
    "task_error_ilc",
    "delay_tracker",
    "estimator_tracker_catch",
    "pooled_estimator_catch",
)
#: The references (given what the world hides): never a competitor, never chosen.
REFERENCES = ("oracle", "oracle_catch")
#: The reference the room is measured against.
UPPER_REFERENCE = "oracle_catch"
_LABELS = {"oracle": "oracle (true delay, drag)", "oracle_catch": "oracle+catch plan"}
#: A row's policy: None (the zero action), ``"random"`` or a function of the observation.
Policy = str | Callable[[NDArray[np.float32]], NDArray[np.float64]] | None
Play = Callable[[Policy, dict[str, Any], str, int], CascadeEpisodes]


@dataclass(frozen=True)
class CascadeV1Config:
    """What ``motion-bench juggling --version v2 --pattern P`` runs."""

    pattern: str = "3"
    levels: tuple[str, ...] = CASCADE_V1_LEVELS
    episodes: int = 100
    val_episodes: int = 30
    #: the validation episodes the best non-oracle row is picked on (>= ``val_episodes``)
    pick_episodes: int = 200
    max_catches: int = 30
    ilc: bool = True
    ilc_iterations: int = 6
    ilc_episodes: int = 10


def check_cascade_v1_config(config: CascadeV1Config) -> None:
    """Raise :class:`baselines.options.ConfigError` naming the first bad field."""
    try:
        pattern_spec(config.pattern)
    except ValueError as exc:
        raise options.ConfigError("pattern", str(exc)) from None
    if not config.levels or any(lv not in CASCADE_V1_LEVELS for lv in config.levels):
        raise options.ConfigError(
            "levels", f"must be among {list(CASCADE_V1_LEVELS)}; got {list(config.levels)}"
        )
    for name in ("episodes", "val_episodes", "ilc_iterations", "ilc_episodes"):
        if getattr(config, name) < 2:
            raise options.ConfigError(name, f"must be >= 2; got {getattr(config, name)}")
    v2.check_pick_episodes(config.pick_episodes, config.val_episodes)
    if config.max_catches < 1:
        raise options.ConfigError("max_catches", f"must be >= 1; got {config.max_catches}")


def cascade_v1_episodes(
    policy: Policy, kwargs: dict[str, Any], split: str, n: int
) -> CascadeEpisodes:
    """``n`` episodes of Cascade-v1 made with ``kwargs``, reset with the seeds of
    ``split``: the zero action (``policy`` None; the env's :meth:`play`), uniform random
    actions (``"random"``, a generator per episode seeded with its seed) or the action
    ``policy(obs)``. On the TEST split (the scores) the hands' paths are recorded and
    scored against the HELD-OUT demonstrations (``deviations``,
    :class:`~baselines.agents.cascade_score.CascadeDeviations`; None for a pattern
    without demonstrations): the zero action is then stepped, ``env.step(0)`` until the
    end, the same episode as :meth:`play` (tested)."""
    from baselines.agents.cascade_score import record_hand_paths
    from motion_envs.envs.juggling import CascadeV1Env

    env = CascadeV1Env(**kwargs)
    seeds = episode_seeds(split, n)
    recorder = record_hand_paths(env, env.pattern.name) if split == "test" else None
    stepped = env if recorder is None else recorder
    rows = []
    for seed in seeds.tolist():
        if policy is None and recorder is None:
            rows.append(env.play(seed))
            continue
        rng = np.random.default_rng(seed)
        obs, _ = stepped.reset(seed=seed)
        terminated = truncated = False
        while not (terminated or truncated):
            if policy is None:
                a = np.zeros(4)
            else:
                a = rng.uniform(-1.0, 1.0, 4) if isinstance(policy, str) else policy(obs)
            obs, _, terminated, truncated, info = stepped.step(a)
        rows.append((info["catches"], info["tosses"], terminated, info["time"]))
    devs = None if recorder is None else recorder.deviations(split)
    return CascadeEpisodes.from_rows(seeds, rows, devs)


def _kwargs(
    level: str, config: CascadeV1Config, controller: str, offset: float = 0.0,
    gain: float = 0.0, extra: dict[str, Any] | None = None,
) -> dict[str, Any]:  # fmt: skip
    """The env keywords of a row: ``offset`` its ``delay_offset``, ``gain`` its
    ``tracker_gain`` (each left out at 0), ``extra`` any others (the pooled row's
    ``delay_rule`` and ``anchor_frames``)."""
    out: dict[str, Any] = {
        "level": level,
        "pattern": config.pattern,
        "controller": controller,
        "max_catches": config.max_catches,
        "residual_scale": RESIDUAL_SCALE,
    }
    if offset:
        out["delay_offset"] = offset
    if gain:
        out["tracker_gain"] = gain
    out.update(extra or {})
    return out


def _val_mean(
    play: Play,
    policy: Policy,
    kwargs: dict[str, Any],
    config: CascadeV1Config,
    episodes: int | None = None,
) -> float:
    """The mean catches before the first drop of the first ``episodes`` (default
    ``config.val_episodes``) VALIDATION episodes played with ``kwargs``."""
    n = config.val_episodes if episodes is None else episodes
    return float(play(policy, kwargs, "val", n).catches.mean())


def choose_late_offset(
    level: str, config: CascadeV1Config, play: Play = cascade_v1_episodes
) -> tuple[float, dict[str, float]]:
    """The offset of :data:`LATE_OFFSETS` with the most mean catches before the first
    drop on ``config.val_episodes`` VALIDATION episodes (ties: the smallest), and every
    candidate's validation mean (:func:`~baselines.juggling_bench.grid_choice.best_on_grid`)."""

    def mean(offset: float) -> float:
        return _val_mean(play, None, _kwargs(level, config, "juggler_mean_delay", offset), config)

    offset, means = best_on_grid(LATE_OFFSETS, mean, v2.offset_key)
    return float(offset), means


def choose_estimator_offset(
    level: str, config: CascadeV1Config, play: Play = cascade_v1_episodes
) -> tuple[float, dict[str, float]]:
    """The offset of :data:`~baselines.juggling_bench.v2.ESTIMATOR_OFFSETS` (s added to
    the pooled delay estimate by ``juggler_delay_estimator_catch``) with the most mean
    catches before the first drop on ``config.val_episodes`` VALIDATION episodes (ties:
    the first, the smallest correction), and every candidate's validation mean
    (:func:`~baselines.juggling_bench.grid_choice.best_on_grid`)."""

    def mean(offset: float) -> float:
        kw = _kwargs(level, config, v2.ESTIMATOR_CONTROLLER, offset)
        return _val_mean(play, None, kw, config)

    offset, means = best_on_grid(v2.ESTIMATOR_OFFSETS, mean, v2.offset_key)
    return float(offset), means


def choose_tracker(
    level: str, config: CascadeV1Config, play: Play = cascade_v1_episodes
) -> tuple[tuple[float, float], dict[str, float]]:
    """The ``(gain, offset)`` of :data:`~baselines.juggling_bench.v2.TRACKER_GRID` with
    the most mean catches before the first drop on ``config.val_episodes`` VALIDATION
    episodes (ties: the first), and every candidate's validation mean
    (:func:`~baselines.juggling_bench.grid_choice.best_on_grid`)."""

    def mean(choice: tuple[float, float]) -> float:
        kw = _kwargs(level, config, "juggler_delay_tracker", choice[1], choice[0])
        return _val_mean(play, None, kw, config)

    choice, means = best_on_grid(v2.TRACKER_GRID, mean, v2.tracker_key)
    return (float(choice[0]), float(choice[1])), means


def choose_estimator_tracker(
    level: str, config: CascadeV1Config, play: Play = cascade_v1_episodes
) -> tuple[tuple[float, float], dict[str, float]]:
    """The ``(gain, offset)`` of :data:`~baselines.juggling_bench.v2.ESTIMATOR_TRACKER_GRID`
    for ``juggler_estimator_tracker_catch`` with the most mean catches before the first
    drop on ``config.val_episodes`` VALIDATION episodes (ties: the first), and every
    candidate's validation mean (:func:`~baselines.juggling_bench.grid_choice.best_on_grid`)."""

    def mean(choice: tuple[float, float]) -> float:
        kw = _kwargs(level, config, v2.ESTIMATOR_TRACKER_CONTROLLER, choice[1], choice[0])
        return _val_mean(play, None, kw, config)

    choice, means = best_on_grid(v2.ESTIMATOR_TRACKER_GRID, mean, v2.tracker_key)
    return (float(choice[0]), float(choice[1])), means


#: ``pooled_estimator_catch``'s candidates ``(anchor frames, start anchored)``: Juggling-v2's
#: :data:`~baselines.juggling_bench.v2.POOLED_ANCHOR_FRAMES`, without the start anchor,
#: then with it (ties: the first: no start anchor, the fewest frames).
POOLED_GRID: tuple[tuple[int, bool], ...] = tuple(
    (frames, start) for start in (False, True) for frames in v2.POOLED_ANCHOR_FRAMES
)


def pooled_key(choice: tuple[int, bool]) -> str:
    """A :data:`POOLED_GRID` pair's key in the validation tables (``"16 frames"``,
    ``"16 frames, start anchored"``)."""
    frames, start = choice
    return v2.anchor_key(frames) + (", start anchored" if start else "")


def pooled_extra(choice: tuple[int, bool]) -> dict[str, Any]:
    """The env keywords of ``pooled_estimator_catch`` with a :data:`POOLED_GRID` pair."""
    frames, start = choice
    return {**v2.pooled_kwargs(frames), **({"anchor_start": True} if start else {})}


def choose_pooled_anchor(
    level: str, config: CascadeV1Config, play: Play = cascade_v1_episodes
) -> tuple[tuple[int, bool], dict[str, float]]:
    """The pair ``(anchor frames, start anchored)`` of :data:`POOLED_GRID` for
    ``pooled_estimator_catch`` (``juggler_delay_estimator_catch`` with the pooled delay
    rule) with the most mean catches before the first drop on ``config.val_episodes``
    VALIDATION episodes (ties: the first), and every candidate's validation mean
    (:func:`~baselines.juggling_bench.grid_choice.best_on_grid`)."""

    def mean(choice: tuple[int, bool]) -> float:
        kw = _kwargs(level, config, v2.ESTIMATOR_CONTROLLER, extra=pooled_extra(choice))
        return _val_mean(play, None, kw, config)

    (frames, start), means = best_on_grid(POOLED_GRID, mean, pooled_key)
    return (int(frames), bool(start)), means


@dataclass(frozen=True)
class _Constant:
    """The constant action ``(x, z)`` for each hand in its own frame (``x`` mirrored for
    the left hand); equal constants are equal policies (a replay finds the same play)."""

    xz: tuple[float, float]

    @property
    def action(self) -> NDArray[np.float64]:
        x, z = self.xz
        return np.array([x, z, -x, z], dtype=np.float64)

    def __call__(self, obs: NDArray[np.float32]) -> NDArray[np.float64]:
        return self.action


def _constant_policy(action: tuple[float, float]) -> Policy:
    return None if action == (0.0, 0.0) else _Constant(action)


def choose_constant(
    level: str, config: CascadeV1Config, play: Play = cascade_v1_episodes
) -> tuple[tuple[float, float], dict[str, float]]:
    """The constant of :data:`CONSTANT_GRID` with the most mean catches before the first
    drop on ``config.val_episodes`` VALIDATION episodes (ties: the first), and every
    candidate's validation mean (:func:`~baselines.juggling_bench.grid_choice.best_on_grid`)."""

    def mean(action: tuple[float, float]) -> float:
        return _val_mean(play, _constant_policy(action), _kwargs(level, config, "juggler"), config)

    action, means = best_on_grid(CONSTANT_GRID, mean, v2.grid_key)
    return (float(action[0]), float(action[1])), means


@dataclass(frozen=True)
class CascadeVelocityTimesDelay:
    """Juggling-v2's two-line residual per hand (module docstring): in a hand's catch
    phase, ``v delay / scale`` (clipped to the action box) with ``v`` the velocity of the
    ball it is about to catch (:func:`catching_velocities`); 0 without one. Stateless:
    equal arguments are equal policies.

    Parameters
    ----------
    balls:
        Balls of the pattern.
    delay:
        s, the level's mean delay.
    scale:
        m of residual per unit action.
    """

    balls: int
    delay: float
    scale: float

    def __call__(self, obs: NDArray[np.float32]) -> NDArray[np.float64]:
        out = np.zeros(4)
        for h, v in enumerate(catching_velocities(obs, self.balls)):
            if v is not None:
                out[2 * h : 2 * h + 2] = v * self.delay / self.scale
        return np.clip(out, -1.0, 1.0)


def _players(
    level: str,
    config: CascadeV1Config,
    offset: float,
    constant: tuple[float, float],
    tracker: tuple[float, float] = (0.0, 0.0),
    estimator_offset: float = 0.0,
    estimator_tracker: tuple[float, float] = (0.0, 0.0),
    pooled_anchor: tuple[int, bool] = (ANCHOR_FRAMES, False),
) -> dict[str, tuple[str, Policy, float, float, dict[str, Any]]]:
    """Each row's controller, policy, delay offset, tracker gain and other env keywords
    (``offset`` late meeting's, ``estimator_offset`` the estimate's, ``tracker`` and
    ``estimator_tracker`` the ``(gain, offset)`` pairs of the delay tracker and of the
    estimate's tracker, ``pooled_anchor`` the pooled estimate's :data:`POOLED_GRID`
    pair)."""
    delay = V2_LEVELS[level].mean_delay
    velocity = CascadeVelocityTimesDelay(pattern_spec(config.pattern).balls, delay, RESIDUAL_SCALE)
    return {
        "juggler": ("juggler", None, 0.0, 0.0, {}),
        "oracle": ("juggler_oracle", None, 0.0, 0.0, {}),
        "oracle_catch": ("juggler_oracle_catch", None, 0.0, 0.0, {}),
        "best_constant": ("juggler", _constant_policy(constant), 0.0, 0.0, {}),
        "velocity_x_mean_delay": ("juggler", velocity, 0.0, 0.0, {}),
        "juggler_mean_delay": ("juggler_mean_delay", None, 0.0, 0.0, {}),
        "late_meeting": ("juggler_mean_delay", None, offset, 0.0, {}),
        "mean_delay_catch": ("juggler_mean_delay_catch", None, 0.0, 0.0, {}),
        "delay_estimator": ("juggler_delay_estimator", None, 0.0, 0.0, {}),
        "delay_estimator_catch": (v2.ESTIMATOR_CONTROLLER, None, 0.0, 0.0, {}),
        "estimator_offset_catch": (v2.ESTIMATOR_CONTROLLER, None, estimator_offset, 0.0, {}),
        "fixed_point": ("fixed_point", None, 0.0, 0.0, {}),
        "random": ("juggler", "random", 0.0, 0.0, {}),
        "delay_tracker": ("juggler_delay_tracker", None, tracker[1], tracker[0], {}),
        "estimator_tracker_catch": (
            v2.ESTIMATOR_TRACKER_CONTROLLER,
            None,
            estimator_tracker[1],
            estimator_tracker[0],
            {},
        ),
        "pooled_estimator_catch": (
            v2.ESTIMATOR_CONTROLLER,
            None,
            0.0,
            0.0,
            pooled_extra(pooled_anchor),
        ),
    }


def row_summary(eps: Any) -> dict[str, Any]:
    """A row's entry of the results (:func:`~baselines.juggling_bench.cascade.summary`
    and the 95 % interval of the mean catches before the first drop; where the episodes
    carry ``deviations``, the hand deviation from the demonstrations with its interval,
    :meth:`~baselines.agents.cascade_score.CascadeDeviations.summary`); any episodes
    with seeds, catches, tosses, dropped and time (an agent's too)."""
    out = {**summary(eps), "catches_mean_ci": _mean_ci(eps)}
    deviations = getattr(eps, "deviations", None)
    if deviations is not None:
        out.update(deviations.summary())
    return out


def _paired(a: CascadeEpisodes, b: CascadeEpisodes) -> dict[str, Any]:
    """Mean catches of ``a`` minus ``b`` over the same seeds, with its 95 % interval."""
    from baselines.stats import group_bootstrap

    if not np.array_equal(a.seeds, b.seeds):
        raise ValueError("paired episodes must share their seeds")
    d = (a.catches - b.catches).astype(np.float64)
    value, lo, hi = group_bootstrap(lambda rows: float(d[rows].mean()), np.arange(d.size))
    return {"value": value, "ci": [lo, hi]}


def _mean_ci(eps: CascadeEpisodes) -> list[float]:
    from baselines.stats import group_bootstrap

    c = eps.catches.astype(np.float64)
    _, lo, hi = group_bootstrap(lambda rows: float(c[rows].mean()), np.arange(c.size))
    return [lo, hi]


def _train_ilc(level: str, config: CascadeV1Config) -> Any:
    """The task-error learner of ``level`` trained on its budget of TRAINING episodes
    (:class:`~baselines.juggling_bench.cascade_v1_ilc.CascadeTaskErrorILC`)."""
    from baselines.juggling_bench import cascade_v1_ilc
    from baselines.juggling_bench.ilc import ILCConfig

    ilc = cascade_v1_ilc.CascadeTaskErrorILC(
        level, config.pattern, RESIDUAL_SCALE, V2_LEVELS[level].mean_delay,
        ILCConfig(config.ilc_iterations, config.ilc_episodes, max_catches=config.max_catches),
    )  # fmt: skip
    ilc.train()
    return ilc


def run_cascade_v1(
    config: CascadeV1Config,
    play: Play = cascade_v1_episodes,
    offset_chooser: Any = choose_late_offset,
    constant_chooser: Any = choose_constant,
    keep: dict[str, dict[str, Any]] | None = None,
    tracker_chooser: Any = choose_tracker,
    estimator_offset_chooser: Any = choose_estimator_offset,
    estimator_tracker_chooser: Any = choose_estimator_tracker,
    pooled_chooser: Any = choose_pooled_anchor,
) -> dict[str, Any]:
    """Every level's rows (module docstring); JSON-ready. ``play`` and the choosers are
    for tests (the spy that proves the choices read no test seed). ``keep``, when given,
    receives each level's rows' TEST episodes as played (``keep[level][row]``), to pair
    another policy's episodes with them on the same seeds
    (``experiments/cascade_v1_agents.py``)."""
    check_cascade_v1_config(config)
    t0 = time.process_time()
    levels = []
    for level in config.levels:
        constant, constant_means = constant_chooser(level, config, play)
        offset, offset_means = offset_chooser(level, config, play)
        tracker, tracker_means = tracker_chooser(level, config, play)
        est_offset, est_means = estimator_offset_chooser(level, config, play)
        est_tracker, est_tracker_means = estimator_tracker_chooser(level, config, play)
        pooled_anchor, pooled_means = pooled_chooser(level, config, play)
        chosen = (offset, constant, tracker, est_offset, est_tracker, pooled_anchor)
        players = _players(level, config, *chosen)
        # the best non-oracle row, picked on the first pick_episodes VALIDATION episodes:
        # the grids' plays reused when they are those episodes
        reuse = {
            "juggler": (constant_means, v2.grid_key((0.0, 0.0))),
            "best_constant": (constant_means, v2.grid_key(constant)),
            "juggler_mean_delay": (offset_means, v2.offset_key(0.0)),
            "late_meeting": (offset_means, v2.offset_key(offset)),
            "delay_tracker": (tracker_means, v2.tracker_key(tracker)),
            "delay_estimator_catch": (est_means, v2.offset_key(0.0)),
            "estimator_offset_catch": (est_means, v2.offset_key(est_offset)),
            "estimator_tracker_catch": (est_tracker_means, v2.tracker_key(est_tracker)),
            "pooled_estimator_catch": (pooled_means, pooled_key(pooled_anchor)),
        }
        val_means: dict[str, float] = {}
        for name, (ctl, policy, off, gain, extra) in players.items():
            if name in REFERENCES:
                continue
            means, key = reuse.get(name, ({}, ""))
            if key in means and config.pick_episodes == config.val_episodes:
                val_means[name] = means[key]
            else:
                val_means[name] = _val_mean(
                    play, policy, _kwargs(level, config, ctl, off, gain, extra), config,
                    config.pick_episodes,
                )  # fmt: skip
        ilc = _train_ilc(level, config) if config.ilc else None
        if ilc is not None:
            val_means["task_error_ilc"] = float(
                ilc.evaluate("val", config.pick_episodes).catches.mean()
            )
        best = max((r for r in ROWS if r in val_means), key=lambda r: val_means[r])
        # the tracker's rival: the best other non-oracle row, picked on validation too
        rival = max((r for r in ROWS if r in val_means and r != "delay_tracker"),
                    key=lambda r: val_means[r])  # fmt: skip
        played = {
            name: play(
                policy, _kwargs(level, config, ctl, off, gain, extra), "test", config.episodes
            )
            # fresh players (no state is carried from the validation plays)
            for name, (ctl, policy, off, gain, extra) in _players(level, config, *chosen).items()
        }
        if ilc is not None:
            played["task_error_ilc"] = ilc.evaluate("test", config.episodes)
        if keep is not None:
            keep[level] = played
        rows = {name: row_summary(eps) for name, eps in played.items()}
        room = _paired(played[UPPER_REFERENCE], played[best])
        rate, rlo, rhi = catch_rate_difference(played[UPPER_REFERENCE], played[best])
        above = {
            name: _paired(played[UPPER_REFERENCE], eps)
            for name, eps in played.items()
            if name != UPPER_REFERENCE
        }
        levels.append(
            {
                "level": level,
                "values": asdict(V2_LEVELS[level]),
                "constant": list(constant),
                "constant_val_mean_catches": constant_means,
                "late_offset_s": offset,
                "late_offset_val_mean_catches": offset_means,
                "tracker": {"gain": tracker[0], "offset_s": tracker[1]},
                "tracker_val_mean_catches": tracker_means,
                "estimator_offset_s": est_offset,
                "estimator_offset_val_mean_catches": est_means,
                "estimator_tracker": {"gain": est_tracker[0], "offset_s": est_tracker[1]},
                "estimator_tracker_val_mean_catches": est_tracker_means,
                "pooled_anchor_frames": pooled_anchor[0],
                "pooled_anchor_start": pooled_anchor[1],
                "pooled_val_mean_catches": pooled_means,
                "val_mean_catches": val_means,
                "best_non_oracle": best,
                "rows": rows,
                "room": room,
                "room_catch_rate": {"value": rate, "ci": [rlo, rhi]},
                "target_room": room_for_target(best, UPPER_REFERENCE, rate, [rlo, rhi]),
                "upper_minus_rows": above,
                "upper_is_upper": all(d["value"] >= 0 for d in above.values()),
                "oracle_minus_best": _paired(played["oracle"], played[best]),
                "best_minus_juggler": _paired(played[best], played["juggler"]),
                "delay_tracker_minus": {
                    "rival": rival,
                    "minus_rival": _paired(played["delay_tracker"], played[rival]),
                    "minus_mean_delay_catch": _paired(
                        played["delay_tracker"], played["mean_delay_catch"]
                    ),
                },
                "estimator_offset_catch_minus": v2.offset_row_minus(played, best, _paired),
                "estimator_tracker_catch_minus": v2.offset_row_minus(
                    played, best, _paired, "estimator_tracker_catch"
                ),
                "pooled_estimator_catch_minus": v2.pooled_row_minus(played, best, _paired),
            }
        )
        if ilc is not None:
            levels[-1]["ilc"] = {
                "budget_train_episodes": config.ilc_iterations * config.ilc_episodes,
                "c_m": [float(v) for v in ilc.c],
                "d_s": ilc.d,
                "history": ilc.history,
            }
    spec = pattern_spec(config.pattern)
    return {
        "benchmark": f"juggling v2 rows, pattern {config.pattern} ({CASCADE_V1_ENV_ID})",
        "config": asdict(config),
        "demonstrations": SIMULATED_LABEL,
        "deviation": deviation_note(config.pattern),
        "pattern": {
            "name": spec.name,
            "siteswap": spec.siteswap,
            "balls": spec.balls,
            "juggler": "fitted cascade" if spec.fitted else "siteswap",
        },
        "residual_scale_m": RESIDUAL_SCALE,
        "seeds": {
            "choice": {"split": "val", "first": SPLIT_SEEDS["val"], "count": config.val_episodes},
            "pick": {"split": "val", "first": SPLIT_SEEDS["val"], "count": config.pick_episodes},
            "test": {"split": "test", "first": SPLIT_SEEDS["test"], "count": config.episodes},
        },
        "levels": levels,
        "timing": {"cpu_s": time.process_time() - t0},
    }


def deviation_note(pattern: str) -> str:
    """What the rows' ``deviation_m`` of ``pattern`` is measured against, or why it is
    not measured."""
    from baselines.agents.cascade_score import demonstrations_label, deviation_balls

    balls = deviation_balls(pattern)
    if balls is None:
        return (
            f"not measured: no demonstrations of pattern {pattern!r} (only the 3- and "
            "5-ball cascades have them)"
        )
    return (
        "hand deviation (m) from the "
        + demonstrations_label(balls, "test")
        + ": per hand in its own frame (the left mirrored), per phase segment the distance "
        "to the nearest demonstration segment after the departure from the line between "
        "its ends; the median over segments, 95 % interval resampling test episodes"
    )


def _deviation_cell(m: dict[str, Any]) -> str:
    if "deviation_m" not in m or not np.isfinite(m["deviation_m"]):
        return "not measured"
    lo, hi = m["deviation_ci"]
    return f"{m['deviation_m'] * 1000:5.1f} [{lo * 1000:5.1f}, {hi * 1000:5.1f}]"


def report_cascade_v1(doc: dict[str, Any]) -> str:
    """The printed table of :func:`run_cascade_v1`'s document."""
    test, pat = doc["seeds"]["test"], doc["pattern"]
    lines = [
        f"Cascade-v1, pattern {pat['siteswap']} ({pat['juggler']} juggler; "
        f"{doc['demonstrations']}); {test['count']} test episodes per level and row (seeds "
        f"from {test['first']}), at most {doc['config']['max_catches']} catches; grid choices on "
        f"{doc['seeds']['choice']['count']} validation episodes, the best non-oracle row "
        f"picked on {v2.pick_count(doc)}",
        f"hand deviation: {doc.get('deviation', 'not measured')}",
        f"{'level':7s} {'row':21s} {'catches median [95% CI]':24s} "
        f"{'mean [95% CI]':22s} {'catch rate [95% CI]':22s} {'censored':>8s}  "
        "deviation mm [95% CI]",
    ]
    for lv in doc["levels"]:
        for name, m in lv["rows"].items():
            c, (clo, chi) = m["catches_median"], m["catches_median_ci"]
            mean, (mlo, mhi) = m["catches_mean"], m["catches_mean_ci"]
            r, (rlo, rhi) = m["catch_rate"], m["catch_rate_ci"]
            label = _LABELS.get(name, name)
            lines.append(
                f"{lv['level']:7s} {label[:21]:21s} {c:5.1f} [{clo:5.1f}, {chi:5.1f}]{'':6s} "
                f"{mean:5.2f} [{mlo:5.2f}, {mhi:5.2f}]{'':3s} {r:.3f} [{rlo:.3f}, {rhi:.3f}]"
                f"{'':2s} {m['censored']:8d}  {_deviation_cell(m)}"
            )
        room, old = lv["room"], lv["oracle_minus_best"]
        upper = "the upper reference" if lv["upper_is_upper"] else "NOT an upper reference"
        below = [k for k, d in lv["upper_minus_rows"].items() if d["ci"][1] < 0]
        trk = lv.get("tracker")
        trk_text = (
            "" if trk is None else f"tracker {v2.tracker_key((trk['gain'], trk['offset_s']))}; "
        )
        est = lv.get("estimator_offset_s")
        if est is not None:
            trk_text += f"estimate's offset {v2.offset_key(est)}; "
        lines.append(
            f"{lv['level']:7s} best constant {tuple(lv.get('constant', (0.0, 0.0)))}; late "
            f"offset {lv['late_offset_s'] * 1000:.0f} ms; {trk_text}best non-oracle "
            f"row {lv['best_non_oracle']} (chosen on validation); ROOM oracle_catch - best "
            f"(paired mean catches): {room['value']:+.2f} [{room['ci'][0]:+.2f}, "
            f"{room['ci'][1]:+.2f}]; oracle - best {old['value']:+.2f} [{old['ci'][0]:+.2f}, "
            f"{old['ci'][1]:+.2f}]; oracle_catch is {upper}"
            + (f" (below {', '.join(below)})" if below else "")
        )
        if "target_room" in lv:
            lines.append(f"{lv['level']:7s} {lv['target_room']['sentence']} (catch rate)")
        val = ", ".join(f"{k} {v:.2f}" for k, v in lv.get("val_mean_catches", {}).items())
        lines.append(
            f"{lv['level']:7s} validation mean catches (the pick's {v2.pick_count(doc)} "
            f"episodes): {val}"
        )
        if "delay_tracker_minus" in lv:
            trk_line = v2.tracker_line(lv["delay_tracker_minus"], "+.2f")
            lines.append(f"{lv['level']:7s} {trk_line} (mean catches)")
        if "estimator_offset_catch_minus" in lv:
            est_line = v2.offset_row_line(lv["estimator_offset_catch_minus"], "+.2f")
            lines.append(f"{lv['level']:7s} {est_line} (mean catches)")
        if "estimator_tracker_catch_minus" in lv:
            et = lv["estimator_tracker"]
            et_line = v2.offset_row_line(lv["estimator_tracker_catch_minus"], "+.2f")
            lines.append(
                f"{lv['level']:7s} estimate's tracker "
                f"{v2.tracker_key((et['gain'], et['offset_s']))} (chosen on validation); "
                f"{et_line} (mean catches)"
            )
        if "pooled_estimator_catch_minus" in lv:
            frames = str(lv["pooled_anchor_frames"])
            if lv.get("pooled_anchor_start", False):
                frames += ", the start anchored on its throws"
            line = v2.pooled_row_line(lv["pooled_estimator_catch_minus"], frames, "+.2f")
            lines.append(f"{lv['level']:7s} {line} (mean catches)")
        if "ilc" in lv:
            ilc = lv["ilc"]
            lines.append(
                f"{lv['level']:7s} task_error_ilc learned c = ({ilc['c_m'][0]:+.3f}, "
                f"{ilc['c_m'][1]:+.3f}) m, d = {ilc['d_s'] * 1000:.0f} ms on "
                f"{ilc['budget_train_episodes']} training episodes"
            )
    lines.append(f"CPU {doc['timing']['cpu_s']:.1f} s")
    return "\n".join(lines)


#: The two criteria plotted against the deviation: key of a row, its interval's, axis label.
_PLOTTED = (
    ("catches_mean", "catches_mean_ci", "mean catches before the first drop"),
    ("catch_rate", "catch_rate_ci", "catch rate (catches per toss)"),
)


def row_styles() -> tuple[dict[str, str], dict[str, Any]]:
    """A marker and a colour of its own for each row of :data:`ROWS` (the default
    colour cycle repeats after 10: tab20's dark shades first, then its light ones)."""
    import matplotlib.pyplot as plt

    tab20 = plt.get_cmap("tab20")
    markers = dict(zip(ROWS, "osP^D<>hvxpXd8H12", strict=False))
    return markers, {name: tab20((2 * i) % 20 + (2 * i) // 20) for i, name in enumerate(ROWS)}


def plot_cascade_v1(doc: dict[str, Any]) -> Any:
    """Mean catches before the first drop (top) and catch rate (bottom) against the hand
    deviation from the held-out demonstrations (log scale), one point per row with its
    95 % interval bars, a panel per level (matplotlib imported on call); a row not in
    :data:`ROWS` (an agent's, ``experiments/cascade_v1_agents.py``) is drawn as a star.
    Rows without a deviation are left out."""
    from matplotlib.ticker import LogLocator, NullFormatter, ScalarFormatter

    from baselines.plots import new_figure

    levels = doc["levels"]
    n = len(levels)
    fig = new_figure(max(5.0 * n, 7.5), 8.6)
    axes = fig.subplots(2, n, squeeze=False, sharex="col")
    markers, colors = row_styles()
    seen: dict[str, Any] = {}
    for j, lv in enumerate(levels):
        for i, (key, ci_key, label) in enumerate(_PLOTTED):
            ax = axes[i][j]
            for name, m in lv["rows"].items():
                if "deviation_m" not in m or not np.isfinite(m["deviation_m"]):
                    continue
                x, xlo, xhi = (1000 * v for v in (m["deviation_m"], *m["deviation_ci"]))
                y, (ylo, yhi) = m[key], m[ci_key]
                agent = name not in ROWS
                h = ax.errorbar(x, y, xerr=[[x - xlo], [xhi - x]], yerr=[[y - ylo], [yhi - y]],
                                capsize=3, linestyle="none", marker=markers.get(name, "*"),
                                color=colors.get(name, "black"), markersize=12 if agent else 6,
                                label=_LABELS.get(name, name.replace("_", " ")))  # fmt: skip
                seen.setdefault(name, h)
            ax.set_xscale("log")  # the trivial rows lie an order of magnitude away
            ax.xaxis.set_major_locator(LogLocator(base=10, subs=(1.0, 2.0, 5.0)))
            ax.xaxis.set_major_formatter(ScalarFormatter())
            ax.xaxis.set_minor_formatter(NullFormatter())
            ax.grid(alpha=0.3, which="both")
            if j == 0:
                ax.set_ylabel(label)
        axes[0][j].set_title(f"Cascade-v1 pattern {doc['pattern']['siteswap']}, {lv['level']}",
                             fontsize=10)  # fmt: skip
        axes[1][j].set_xlabel("hand deviation from held-out demonstrations (mm, log scale)")
    labels = [_LABELS.get(k, k.replace("_", " ")) for k in seen]
    fig.legend(list(seen.values()), labels, fontsize=8, loc="outside lower center",
               ncol=4 if n > 1 else 3, frameon=False)  # fmt: skip
    fig.suptitle("demonstrations SIMULATED; bars: 95 % bootstrap intervals over test episodes",
                 fontsize=9)  # fmt: skip
    return fig


def write_cascade_v1(doc: dict[str, Any], out: str | Path) -> list[Path]:
    """``results.json`` in ``out`` and, where the rows have a deviation,
    ``cascade_v1_rows.png`` (:func:`plot_cascade_v1`), through :mod:`motion_envs._io`."""
    import matplotlib.pyplot as plt

    from motion_envs._io import atomic_write_text, save_figure

    out = Path(out)
    paths = [atomic_write_text(out / "results.json", json.dumps(doc, indent=2) + "\n")]
    if any("deviation_m" in m for lv in doc["levels"] for m in lv["rows"].values()):
        fig = plot_cascade_v1(doc)
        try:
            paths.append(save_figure(fig, out / "cascade_v1_rows.png", dpi=150))
        finally:
            plt.close(fig)
    return paths
