"""``motion-bench juggling --version v2``: Juggling-v2's reference rows, on catches and
human likeness together.

For each level (``medium`` and ``hard`` by default; :data:`motion_envs.models.juggling.V2_LEVELS`)
the rows (:data:`ROWS`) are played in ``MotionEnvs/Juggling-v2`` with the residual in
the env's own action space (``ROW_ENV_KWARGS``: every phase, :data:`RESIDUAL_SCALE` m per
unit action, the scale an agent is given):

* ``juggler``: the analytic juggler (the zero action; also the trivial *zero* policy);
* ``oracle``: the juggler given the episode's true delay and drag (``juggler_oracle``):
  a reference, not a competitor. It is not an upper reference: the mean-delay juggler
  and the late meeting catch more (BENCHMARKS, Juggling-v2). Why (measured on VALIDATION
  seeds, BENCHMARKS): the oracle predicts the flight best (after 0.3-0.5 s of flight its
  mean state error is under 8 mm against the mean-delay fit's 26-37 mm), but what it
  feeds is the juggler's plan, which puts the palm AT the predicted ball at the planned
  catch time; an exact prediction makes the palm meet the ball there while the hand
  still rushes up to it, and the ball bounces off (medium: 16 of the oracle's 19 drops
  met a rising hand, 8 within 15 mm and 5 ms of the plan at 4.9-6.5 m/s against the 5
  m/s limit; hard: 33 of 34 rising). A late prediction (the true delay + 40 ms) puts the
  hand lower on the ball's path, where it waits and the ball falls in: it catches more
  (medium 0.938 against 0.798, hard 46 against 33 catches); the mean-delay fit errs that
  way too (its estimate 12-37 mm low). Not a bug in the flight model (the drag, its sign
  and the delay are used as the env applies them); an upper reference would need the
  oracle's information AND a catch planned for the capture rule (the palm at rest or
  moving down with the ball when they meet): ``oracle_catch``;
* ``oracle_catch``: the UPPER REFERENCE, the oracle's estimator with the catch plan
  (``juggler_oracle_catch``; :mod:`motion_envs.models.juggling._v2_catch`: the reach
  ends ``lead`` s before the planned meeting, above it, and the palm descends at
  ``descent`` m/s to meet the ball; both numbers chosen on TRAINING seeds and declared
  in the model); given what the world hides, never a competitor and never chosen;
* ``best_constant``: the constant action, from the grid :data:`CONSTANT_GRID`, with the
  highest catch rate on the VALIDATION seeds;
* ``velocity_x_mean_delay``: in the catch phase, the ball's velocity (from the oldest and
  newest of the observed frames) times the level's mean delay, as the residual (the
  two-line fix of Juggling-v1);
* ``juggler_mean_delay``: the env's ``juggler_mean_delay`` controller (the camera frames
  shifted by the level's mean delay before the juggler's state estimate; no learning);
* ``late_meeting``: ``juggler_mean_delay`` told a later delay, the level's mean plus the
  offset of :data:`LATE_OFFSETS` (the env's ``delay_offset``) with the highest catch rate
  on the VALIDATION seeds (:func:`choose_offset`): the hand-written fix of the oracle
  diagnosis above (a late estimate puts the hand lower on the ball's path, where it
  waits and the ball falls in);
* ``mean_delay_catch``: the catch plan on the level's mean delay (``juggler_mean_delay_catch``,
  its lead and descent chosen on TRAINING seeds; no hidden information: a competitor);
* ``delay_estimator``: the hand-written delay estimator (``juggler_delay_estimator``: the
  delay found from the release, per episode);
* ``delay_estimator_catch``: the two hand-written fixes together
  (``juggler_delay_estimator_catch``: the catch plan on the delay estimator's delay,
  with the mean delay's plan, not re-tuned), the strongest simple fix without learning;
* ``estimator_offset_catch``: the same told the estimate plus an offset (the env's
  ``delay_offset`` on that controller, a correction of the estimate's bias; may be
  negative) from :data:`ESTIMATOR_OFFSETS` (declared here before any run), the offset
  with the highest catch rate on the VALIDATION seeds (:func:`choose_estimator_offset`;
  offset 0 is ``delay_estimator_catch`` itself);
* ``delay_tracker``: the online delay tracker (``juggler_delay_tracker``: the mean-delay
  catch plan whose delay ``D`` starts at the level's mean and, after every catch, moves
  by the catch's timing error ``e`` relative to the planned meeting, ``D <- clip(D - k
  (e - offset))`` over the level's delay range, the flight fitted with ``D + offset``;
  :mod:`motion_envs.models.juggling._delay_tracker`), its gain ``k`` and offset the pair
  of :data:`TRACKER_GRID` with the highest catch rate on the VALIDATION seeds
  (:func:`choose_tracker`; ``k = 0``, offset 0 is ``mean_delay_catch`` itself);
* ``estimator_tracker_catch``: the two corrections together
  (``juggler_estimator_tracker_catch``: ``delay_estimator_catch`` whose frames are placed
  by the release-anchored estimate plus a correction ``C + offset``, ``C`` starting at 0
  and moving after every catch as the tracker's ``D``, ``C <- clip(C - k (e - offset),
  -50 ms, +50 ms)``; :class:`~motion_envs.models.juggling.CorrectionTracker`), its gain
  and offset the pair of :data:`ESTIMATOR_TRACKER_GRID` with the highest catch rate on
  the VALIDATION seeds (:func:`choose_estimator_tracker`; ``k = 0``, offset 0 is
  ``delay_estimator_catch`` itself); a competitor;
* ``pooled_estimator_catch``: ``delay_estimator_catch`` whose delay is the POOLED estimate
  (the env's ``delay_rule``
  :func:`~motion_envs.models.juggling.pooled_flight_delay`: one least-squares delay fitted
  to all the episode's anchored flights at once, refined below the 5 ms grid, instead of
  the mean of each flight's grid delay) found from each flight's first ``anchor_frames``
  frames, the number of :data:`POOLED_ANCHOR_FRAMES` (declared here before any run) with
  the highest catch rate on the VALIDATION seeds (:func:`choose_pooled_anchor`); no
  offset (the upper reference is told the exact delay, with no offset); a competitor;
* ``gaze_estimator_catch``: the same catch plan on the hand-written gaze-aware estimator
  (``juggler_gaze_estimator_catch``: the latency ``d + k ecc`` with the delay ``d`` and
  the gaze slope ``k`` found from the releases, pooled over the episode's flights, each
  frame's eccentricity from the apex anticipated from the hand's release; written for the
  level ``gaze``, where a single delay cannot place every frame; a competitor);
* ``random``: uniform random actions (seeded);
* ``task_error_ilc``: the residual learner from the task-error vector
  (:class:`~baselines.juggling_bench.ilc.TaskErrorILC`: iterative learning control, a
  Gauss-Newton update of ``r = c + d v``, starting from the level's mean delay), trained
  on a budget of ``ilc_iterations x ilc_episodes`` TRAINING episodes (default 6 x 10).

Choices are made on the validation seeds (``SPLIT_SEEDS["val"] + i``) before any test
seed is played (tested with a spy): the constant, the late offset, the tracker's gain and
offset, the estimate's offset, the estimate's tracker's gain and offset, the pooled
estimate's anchor frames, each on the first ``val_episodes`` (30) VALIDATION episodes;
and then the best non-oracle row and the tracker's rival, on the first ``pick_episodes``
(200) VALIDATION episodes (the highest catch rate; ties: the first in :data:`ROWS`;
every row played with the parameter its grid chose, the ILC row scored after its
training; when ``pick_episodes == val_episodes`` the grids' plays are reused: the
constant grid's for ``juggler`` and ``best_constant``, the offset grid's for
``juggler_mean_delay`` and ``late_meeting``, the tracker grid's for ``delay_tracker``,
the estimate's offset grid's for ``delay_estimator_catch`` and
``estimator_offset_catch``, the anchor grid's for ``pooled_estimator_catch``; the pick's
rates are ``val_catch_rates``, its seeds ``seeds["pick"]``; 30 episodes picked the wrong
row on Cascade-v1's three balls medium, BENCHMARKS). Every row is then played on the
TEST seeds (``SPLIT_SEEDS["test"] + i``). Each row reports its catch rate (catches per toss,
pooled) and the hand's deviation from the held-out SIMULATED demonstrations
(:mod:`baselines.agents.juggling_score`, the likeness criterion), each with a 95 %
bootstrap interval over episodes, and the ROOM left below the upper reference by the
best non-oracle row (``oracle_catch`` minus it, a paired interval), with
``oracle_catch`` minus every other row (paired) to tell whether it is above them all;
``room_below_oracle`` keeps the old ``oracle`` minus the best row. ``target_room`` says
in words whether that room can decide the agents' target (``agent - best >= +0.05``;
:func:`baselines.agents.against_rows.room_for_target`): when the room's interval stays
below +0.05 an agent would have to beat the upper reference itself. :func:`write_v2`
writes ``results.json`` and ``juggling_v2_rows.png`` (catch rate against deviation, one
point per row with its interval bars, a panel per level).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from baselines import options
from baselines.agents.against_rows import room_for_target
from baselines.agents.juggling_score import (
    JugglingEpisodes,
    Policy,
    catch_rate_difference,
    juggling_episodes,
)
from baselines.juggling_bench.grid_choice import best_on_grid
from baselines.juggling_bench.ilc import ILCConfig, TaskErrorILC
from baselines.juggling_bench.levels import summary
from motion_envs.datasets.juggling import SIMULATED_LABEL, SPLIT_SEEDS
from motion_envs.models.juggling import ANCHOR_FRAMES, V2_LEVELS, pooled_flight_delay

__all__ = [
    "CONSTANT_GRID",
    "ENV_ID_V2",
    "ESTIMATOR_OFFSETS",
    "ESTIMATOR_TRACKER_GRID",
    "LATE_OFFSETS",
    "POOLED_ANCHOR_FRAMES",
    "RESIDUAL_SCALE",
    "ROWS",
    "TRACKER_GRID",
    "V2Config",
    "VelocityTimesDelay",
    "anchor_key",
    "check_pick_episodes",
    "check_v2_config",
    "choose_constant",
    "choose_estimator_offset",
    "choose_estimator_tracker",
    "choose_offset",
    "choose_pooled_anchor",
    "choose_tracker",
    "frame_velocity",
    "grid_key",
    "offset_key",
    "offset_row_line",
    "offset_row_minus",
    "pick_count",
    "pooled_kwargs",
    "pooled_row_minus",
    "report_v2",
    "row_players",
    "run_v2",
    "tracker_key",
    "tracker_kwargs",
    "tracker_line",
    "write_v2",
]

ENV_ID_V2 = "MotionEnvs/Juggling-v2"
#: m of residual per unit action for every residual row.
RESIDUAL_SCALE = 0.2
#: The constant actions tried (each coordinate in -0.5, 0, 0.5: up to 10 cm).
CONSTANT_GRID: tuple[tuple[float, float], ...] = tuple(
    (x, z) for x in (-0.5, 0.0, 0.5) for z in (-0.5, 0.0, 0.5)
)
#: s added to the level's mean delay by ``late_meeting`` (the env's ``delay_offset``):
#: 0 to 200 ms in steps of 20 ms, declared before the run that measured it (the first
#: grid, 0-80 ms, chose its largest value on medium and hard).
LATE_OFFSETS: tuple[float, ...] = tuple(round(0.02 * i, 2) for i in range(11))
#: s added to the delay estimator's estimate by ``estimator_offset_catch`` (the env's
#: ``delay_offset`` on ``juggler_delay_estimator_catch``), declared before any run: -20 to
#: +40 ms in 10 ms steps, ordered by distance from 0, the later first (ties: the smallest
#: correction; on Cascade-v1 the pooled estimate was found 0.3-7.0 ms EARLY on average on
#: three balls, docs/models.md, so a later told delay is the expected correction, and
#: late meeting's offsets show that a later meeting helps by itself).
ESTIMATOR_OFFSETS: tuple[float, ...] = (0.0, 0.01, -0.01, 0.02, -0.02, 0.03, 0.04)
#: ``delay_tracker``'s ``(gain k, offset s)`` pairs tried on VALIDATION seeds, declared
#: before any bench run (offset first, then gain; ties: the first, ``(0, 0)`` being
#: ``mean_delay_catch``): gains 0 to 1 (``k s`` below 2 for the timing slopes ``s``
#: 0.85-1 measured on training seeds; 0.1 for the five-ball juggler's ``s = 2.3``),
#: offsets 0-40 ms (the late meeting's first steps).
TRACKER_GRID: tuple[tuple[float, float], ...] = tuple(
    (k, o) for o in (0.0, 0.02, 0.04) for k in (0.0, 0.1, 0.25, 0.5, 1.0)
)
#: ``estimator_tracker_catch``'s ``(gain k, offset s)`` pairs tried on VALIDATION seeds:
#: the delay tracker's grid (:data:`TRACKER_GRID`, declared before any run of either),
#: not re-tuned; ``(0, 0)`` is ``delay_estimator_catch``.
ESTIMATOR_TRACKER_GRID: tuple[tuple[float, float], ...] = TRACKER_GRID
#: ``pooled_estimator_catch``'s anchor frames (each flight's first frames the pooled delay
#: is fitted to) tried on VALIDATION seeds, declared before any bench run of the row: the
#: default 8 first (ties: the fewest, the earliest estimate), then 12, 16 and 20 (on 40
#: VALIDATION episodes of Cascade-v1 three balls and Juggling-v2 medium and hard the first
#: flight's estimate from 8 frames erred with an sd of 12-21 ms, from 16 of 5-9 ms, its
#: mean within +4.5 ms: ``experiments/delay_estimate_error.py``).
POOLED_ANCHOR_FRAMES: tuple[int, ...] = (8, 12, 16, 20)
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
    "random",
    "task_error_ilc",
    "delay_tracker",
    "gaze_estimator_catch",
    "estimator_tracker_catch",
    "pooled_estimator_catch",
)
#: The references (given what the world hides): never a competitor, never chosen.
REFERENCES = ("oracle", "oracle_catch")
#: The upper reference the room is measured against.
UPPER_REFERENCE = "oracle_catch"
#: Observation indices (JugglingV2Env's docstring): the catch phase's one-hot and the
#: first frame slot ``(x, z, age, valid)``.
_CATCH, _FRAME0 = 7, 16

Play = Callable[[Policy | None, str, dict[str, Any], str, int], JugglingEpisodes]


@dataclass(frozen=True)
class V2Config:
    """What ``motion-bench juggling --version v2`` runs."""

    levels: tuple[str, ...] = ("medium", "hard")
    episodes: int = 100
    val_episodes: int = 30
    #: the validation episodes the best non-oracle row is picked on (>= ``val_episodes``)
    pick_episodes: int = 200
    max_catches: int = 3
    ilc: bool = True
    ilc_iterations: int = 6
    ilc_episodes: int = 10


def check_v2_config(config: V2Config) -> None:
    """Raise :class:`baselines.options.ConfigError` naming the first bad field."""
    if not config.levels:
        raise options.ConfigError("levels", "must name at least one level")
    for level in config.levels:
        if level not in V2_LEVELS:
            raise options.ConfigError("levels", f"must be among {list(V2_LEVELS)}; got {level!r}")
    for name in ("episodes", "val_episodes", "ilc_iterations", "ilc_episodes"):
        if getattr(config, name) < 2:
            raise options.ConfigError(name, f"must be >= 2; got {getattr(config, name)}")
    check_pick_episodes(config.pick_episodes, config.val_episodes)
    if config.max_catches < 1:
        raise options.ConfigError("max_catches", f"must be >= 1; got {config.max_catches}")


def check_pick_episodes(pick_episodes: int, val_episodes: int) -> None:
    """Raise :class:`baselines.options.ConfigError` (``pick_episodes``) unless the best
    row's validation episodes include the grids' (``pick_episodes >= val_episodes``)."""
    if pick_episodes < val_episodes:
        raise options.ConfigError(
            "pick_episodes", f"must be >= val_episodes ({val_episodes}); got {pick_episodes}"
        )


class VelocityTimesDelay:
    """The residual ``v delay / scale`` in the catch phase (0 elsewhere): ``v`` the ball's
    velocity from the newest and the oldest valid frame of the observation (their
    arrival ages apart), ``delay`` the level's mean delay; clipped to the action box."""

    def __init__(self, delay: float, scale: float) -> None:
        self.delay, self.scale = float(delay), float(scale)

    def __call__(self, obs: NDArray[np.float32]) -> NDArray[np.float64]:
        o = np.asarray(obs, dtype=np.float64)
        v, ok = frame_velocity(o[:, _FRAME0 : _FRAME0 + 16].reshape(-1, 4, 4))
        ok &= o[:, _CATCH] > 0.5
        out = np.where(ok[:, None], v * self.delay / self.scale, 0.0)
        return np.clip(out, -1.0, 1.0)


def frame_velocity(
    frames: NDArray[np.float64],
) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """The ball's velocity ``(B, 2)`` from ``frames (B, 4, 4)`` (the observation's four
    received frames ``x, z, age, valid``, newest first): the newest and the oldest valid
    frame's positions over their arrival ages apart; and ``(B,)`` True where it exists
    (the newest slot holds a frame, another one does, their ages differ); 0 elsewhere."""
    valid = frames[:, :, 3] > 0.5
    last = np.where(valid.all(axis=1), 3, np.maximum(valid.sum(axis=1) - 1, 0))
    old = frames[np.arange(frames.shape[0]), last]
    span = old[:, 2] - frames[:, 0, 2]
    ok = valid[:, 0] & (last > 0) & (span > 0)
    v = (frames[:, 0, :2] - old[:, :2]) / np.where(ok, span, 1.0)[:, None]
    return np.where(ok[:, None], v, 0.0), ok


class _Constant:
    def __init__(self, action: tuple[float, float]) -> None:
        self.action = np.asarray(action, dtype=np.float64)

    def __call__(self, obs: NDArray[np.float32]) -> NDArray[np.float64]:
        out: NDArray[np.float64] = np.tile(self.action, (len(obs), 1))
        return out


class _Random:
    def __init__(self, seed: int) -> None:
        self.rng = np.random.default_rng(seed)

    def __call__(self, obs: NDArray[np.float32]) -> NDArray[np.float64]:
        return self.rng.uniform(-1.0, 1.0, (len(obs), 2))


def _kwargs(
    level: str, config: V2Config, controller: str = "juggler", extra: dict[str, Any] | None = None
) -> dict[str, Any]:
    return {
        "level": level,
        "controller": controller,
        "max_catches": config.max_catches,
        "residual_scale": RESIDUAL_SCALE,
        **(extra or {}),
    }


def offset_key(offset: float) -> str:
    """A delay offset's key in the validation tables (``"40 ms"``)."""
    return f"{offset * 1000:.0f} ms"


def grid_key(action: tuple[float, float]) -> str:
    """A constant's key in the validation tables (``"+0.5,-0.5"``)."""
    return f"{action[0]:+.1f},{action[1]:+.1f}"


def tracker_key(choice: tuple[float, float]) -> str:
    """A tracker pair's key in the validation tables (``"k=0.5, +20 ms"``)."""
    return f"k={choice[0]:g}, +{choice[1] * 1000:.0f} ms"


def tracker_kwargs(choice: tuple[float, float]) -> dict[str, Any]:
    """The env keywords of ``juggler_delay_tracker`` with the pair ``(gain, offset)``."""
    return {"tracker_gain": float(choice[0]), "delay_offset": float(choice[1])}


def _val_catch_rate(
    play: Play,
    policy: Policy | None,
    kwargs: dict[str, Any],
    config: V2Config,
    episodes: int | None = None,
) -> float:
    """The catch rate of the first ``episodes`` (default ``config.val_episodes``)
    VALIDATION episodes played with ``kwargs``."""
    n = config.val_episodes if episodes is None else episodes
    return play(policy, ENV_ID_V2, kwargs, "val", n).catch_rate


def choose_tracker(
    level: str, config: V2Config, play: Play = juggling_episodes
) -> tuple[tuple[float, float], dict[str, float]]:
    """The pair of :data:`TRACKER_GRID` with the highest catch rate on
    ``config.val_episodes`` VALIDATION episodes (ties: the first), and every candidate's
    validation catch rate (:func:`~baselines.juggling_bench.grid_choice.best_on_grid`)."""

    def rate(choice: tuple[float, float]) -> float:
        kw = _kwargs(level, config, "juggler_delay_tracker", tracker_kwargs(choice))
        return _val_catch_rate(play, None, kw, config)

    return best_on_grid(TRACKER_GRID, rate, tracker_key)


def choose_constant(
    level: str, config: V2Config, play: Play = juggling_episodes
) -> tuple[tuple[float, float], dict[str, float]]:
    """The constant of :data:`CONSTANT_GRID` with the highest catch rate on
    ``config.val_episodes`` VALIDATION episodes (ties: the first), and every candidate's
    validation catch rate (:func:`~baselines.juggling_bench.grid_choice.best_on_grid`)."""

    def rate(action: tuple[float, float]) -> float:
        policy = None if action == (0.0, 0.0) else _Constant(action)
        return _val_catch_rate(play, policy, _kwargs(level, config), config)

    return best_on_grid(CONSTANT_GRID, rate, grid_key)


def choose_offset(
    level: str, config: V2Config, play: Play = juggling_episodes
) -> tuple[float, dict[str, float]]:
    """The offset of :data:`LATE_OFFSETS` (s added to the level's mean delay by
    ``juggler_mean_delay``) with the highest catch rate on ``config.val_episodes``
    VALIDATION episodes (ties: the first, the smallest), and every candidate's validation
    catch rate (:func:`~baselines.juggling_bench.grid_choice.best_on_grid`)."""

    def rate(offset: float) -> float:
        kw = _kwargs(level, config, "juggler_mean_delay", {"delay_offset": offset})
        return _val_catch_rate(play, None, kw, config)

    return best_on_grid(LATE_OFFSETS, rate, offset_key)


def choose_estimator_offset(
    level: str, config: V2Config, play: Play = juggling_episodes
) -> tuple[float, dict[str, float]]:
    """The offset of :data:`ESTIMATOR_OFFSETS` (s added to the delay estimator's estimate
    by ``juggler_delay_estimator_catch``) with the highest catch rate on
    ``config.val_episodes`` VALIDATION episodes (ties: the first, the smallest
    correction), and every candidate's validation catch rate
    (:func:`~baselines.juggling_bench.grid_choice.best_on_grid`)."""

    def rate(offset: float) -> float:
        kw = _kwargs(level, config, ESTIMATOR_CONTROLLER, _estimate_offset(offset))
        return _val_catch_rate(play, None, kw, config)

    return best_on_grid(ESTIMATOR_OFFSETS, rate, offset_key)


#: The controller ``estimator_offset_catch`` tells the offset.
ESTIMATOR_CONTROLLER = "juggler_delay_estimator_catch"
#: The controller of ``estimator_tracker_catch`` (the estimate with a tracked correction).
ESTIMATOR_TRACKER_CONTROLLER = "juggler_estimator_tracker_catch"


def choose_estimator_tracker(
    level: str, config: V2Config, play: Play = juggling_episodes
) -> tuple[tuple[float, float], dict[str, float]]:
    """The ``(gain, offset)`` of :data:`ESTIMATOR_TRACKER_GRID` for
    ``juggler_estimator_tracker_catch`` with the highest catch rate on
    ``config.val_episodes`` VALIDATION episodes (ties: the first), and every candidate's
    validation catch rate (:func:`~baselines.juggling_bench.grid_choice.best_on_grid`)."""

    def rate(choice: tuple[float, float]) -> float:
        kw = _kwargs(level, config, ESTIMATOR_TRACKER_CONTROLLER, tracker_kwargs(choice))
        return _val_catch_rate(play, None, kw, config)

    return best_on_grid(ESTIMATOR_TRACKER_GRID, rate, tracker_key)


def anchor_key(frames: int) -> str:
    """An anchor frames' key in the validation tables (``"16 frames"``)."""
    return f"{int(frames)} frames"


def pooled_kwargs(frames: int) -> dict[str, Any]:
    """The env keywords of ``pooled_estimator_catch`` with ``frames`` anchor frames: the
    pooled delay rule (:func:`~motion_envs.models.juggling.pooled_flight_delay`)."""
    return {"delay_rule": pooled_flight_delay, "anchor_frames": int(frames)}


def choose_pooled_anchor(
    level: str, config: V2Config, play: Play = juggling_episodes
) -> tuple[int, dict[str, float]]:
    """The anchor frames of :data:`POOLED_ANCHOR_FRAMES` for ``pooled_estimator_catch``
    (``juggler_delay_estimator_catch`` with the pooled delay rule) with the highest catch
    rate on ``config.val_episodes`` VALIDATION episodes (ties: the first, the fewest), and
    every candidate's validation catch rate
    (:func:`~baselines.juggling_bench.grid_choice.best_on_grid`)."""

    def rate(frames: int) -> float:
        kw = _kwargs(level, config, ESTIMATOR_CONTROLLER, pooled_kwargs(frames))
        return _val_catch_rate(play, None, kw, config)

    frames, rates = best_on_grid(POOLED_ANCHOR_FRAMES, rate, anchor_key)
    return int(frames), rates


def _estimate_offset(offset: float) -> dict[str, Any]:
    """The env keywords of the estimate's ``offset`` (none for 0: the row's own keywords)."""
    return {"delay_offset": float(offset)} if offset else {}


def row_players(
    level: str,
    constant: tuple[float, float],
    offset: float = 0.0,
    tracker: tuple[float, float] = (0.0, 0.0),
    estimator_offset: float = 0.0,
    estimator_tracker: tuple[float, float] = (0.0, 0.0),
    pooled_anchor: int = ANCHOR_FRAMES,
) -> dict[str, tuple[str, Policy | None, dict[str, Any]]]:
    """Every row of :data:`ROWS` but the trained ``task_error_ilc``: its controller,
    residual policy (None: the zero action) and extra env keywords, played with
    :func:`_kwargs`'s keywords; ``constant`` is :func:`choose_constant`'s choice,
    ``offset`` :func:`choose_offset`'s, ``tracker`` :func:`choose_tracker`'s,
    ``estimator_offset`` :func:`choose_estimator_offset`'s, ``estimator_tracker``
    :func:`choose_estimator_tracker`'s and ``pooled_anchor`` :func:`choose_pooled_anchor`'s."""
    delay = V2_LEVELS[level].mean_delay
    return {
        "juggler": ("juggler", None, {}),
        "oracle": ("juggler_oracle", None, {}),
        "oracle_catch": ("juggler_oracle_catch", None, {}),
        "best_constant": (
            "juggler",
            None if constant == (0.0, 0.0) else _Constant(constant),
            {},
        ),
        "velocity_x_mean_delay": ("juggler", VelocityTimesDelay(delay, RESIDUAL_SCALE), {}),
        "juggler_mean_delay": ("juggler_mean_delay", None, {}),
        "late_meeting": ("juggler_mean_delay", None, {"delay_offset": offset}),
        "mean_delay_catch": ("juggler_mean_delay_catch", None, {}),
        "delay_estimator": ("juggler_delay_estimator", None, {}),
        "delay_estimator_catch": (ESTIMATOR_CONTROLLER, None, {}),
        "estimator_offset_catch": (
            ESTIMATOR_CONTROLLER,
            None,
            _estimate_offset(estimator_offset),
        ),
        "random": ("juggler", _Random(0), {}),
        "delay_tracker": ("juggler_delay_tracker", None, tracker_kwargs(tracker)),
        "gaze_estimator_catch": ("juggler_gaze_estimator_catch", None, {}),
        "estimator_tracker_catch": (
            ESTIMATOR_TRACKER_CONTROLLER,
            None,
            tracker_kwargs(estimator_tracker),
        ),
        "pooled_estimator_catch": (ESTIMATOR_CONTROLLER, None, pooled_kwargs(pooled_anchor)),
    }


def run_v2(
    config: V2Config,
    play: Play = juggling_episodes,
    chooser: Any = choose_constant,
    offset_chooser: Any = choose_offset,
    tracker_chooser: Any = choose_tracker,
    estimator_offset_chooser: Any = choose_estimator_offset,
    estimator_tracker_chooser: Any = choose_estimator_tracker,
    pooled_chooser: Any = choose_pooled_anchor,
) -> dict[str, Any]:
    """Every level's rows (module docstring); JSON-ready. ``play`` and the choosers are
    for tests (the spy that proves the choices read no test seed)."""
    check_v2_config(config)
    t0 = time.process_time()
    levels = []
    for level in config.levels:
        constant, val_rates = chooser(level, config, play)
        offset, offset_rates = offset_chooser(level, config, play)
        tracker, tracker_rates = tracker_chooser(level, config, play)
        est_offset, est_rates = estimator_offset_chooser(level, config, play)
        est_tracker, est_tracker_rates = estimator_tracker_chooser(level, config, play)
        pooled_anchor, pooled_rates = pooled_chooser(level, config, play)
        delay = V2_LEVELS[level].mean_delay
        # The best non-oracle row, chosen on the first pick_episodes VALIDATION episodes
        # before any test seed: the grids' plays reused when they are those episodes.
        reuse = {
            "juggler": (val_rates, grid_key((0.0, 0.0))),
            "best_constant": (val_rates, grid_key(constant)),
            "juggler_mean_delay": (offset_rates, offset_key(0.0)),
            "late_meeting": (offset_rates, offset_key(offset)),
            "delay_tracker": (tracker_rates, tracker_key(tracker)),
            "delay_estimator_catch": (est_rates, offset_key(0.0)),
            "estimator_offset_catch": (est_rates, offset_key(est_offset)),
            "estimator_tracker_catch": (est_tracker_rates, tracker_key(est_tracker)),
            "pooled_estimator_catch": (pooled_rates, anchor_key(pooled_anchor)),
        }
        chosen = (constant, offset, tracker, est_offset, est_tracker, pooled_anchor)
        players = row_players(level, *chosen)
        val_catch: dict[str, float] = {}
        for name, (ctl, policy, extra) in players.items():
            rates, key = reuse.get(name, ({}, ""))
            if name in REFERENCES:
                continue
            if key in rates and config.pick_episodes == config.val_episodes:
                val_catch[name] = rates[key]
            else:
                val_catch[name] = _val_catch_rate(
                    play, policy, _kwargs(level, config, ctl, extra), config,
                    config.pick_episodes,
                )  # fmt: skip
        ilc = TaskErrorILC(
            level, RESIDUAL_SCALE, delay,
            ILCConfig(config.ilc_iterations, config.ilc_episodes, max_catches=config.max_catches),
        )  # fmt: skip
        if config.ilc:
            ilc.train()
            val_catch["task_error_ilc"] = ilc.evaluate("val", config.pick_episodes).catch_rate
        best = max((r for r in ROWS if r in val_catch), key=lambda r: val_catch[r])
        # the tracker's rival: the best other non-oracle row, picked on validation too
        rival = max((r for r in ROWS if r in val_catch and r != "delay_tracker"),
                    key=lambda r: val_catch[r])  # fmt: skip
        played = {
            name: play(
                policy, ENV_ID_V2, _kwargs(level, config, ctl, extra), "test", config.episodes
            )
            # fresh players: the random row's generator restarts for the test seeds
            for name, (ctl, policy, extra) in row_players(level, *chosen).items()
        }
        if config.ilc:
            played["task_error_ilc"] = ilc.evaluate("test", config.episodes)
        entries = {name: summary(eps) for name, eps in played.items()}
        room, lo, hi = catch_rate_difference(played[UPPER_REFERENCE], played[best])
        old = catch_rate_difference(played["oracle"], played[best])
        est = catch_rate_difference(played["oracle"], played["delay_estimator"])
        above = {
            name: _difference(played[UPPER_REFERENCE], eps)
            for name, eps in played.items()
            if name != UPPER_REFERENCE
        }
        levels.append(
            {
                "level": level,
                "values": asdict(V2_LEVELS[level]),
                "constant": list(constant),
                "constant_val_catch_rates": val_rates,
                "late_offset_s": offset,
                "late_offset_val_catch_rates": offset_rates,
                "tracker": {"gain": tracker[0], "offset_s": tracker[1]},
                "tracker_val_catch_rates": tracker_rates,
                "estimator_offset_s": est_offset,
                "estimator_offset_val_catch_rates": est_rates,
                "estimator_tracker": {"gain": est_tracker[0], "offset_s": est_tracker[1]},
                "estimator_tracker_val_catch_rates": est_tracker_rates,
                "pooled_anchor_frames": pooled_anchor,
                "pooled_val_catch_rates": pooled_rates,
                "rows": entries,
                "best_non_oracle": best,
                "val_catch_rates": val_catch,
                "ilc": {
                    "budget_train_episodes": config.ilc_iterations * config.ilc_episodes,
                    "c_m": [float(v) for v in ilc.c],
                    "d_s": ilc.d,
                    "history": ilc.history,
                },
                "room_below_oracle_catch": {"value": room, "ci": [lo, hi]},
                "target_room": room_for_target(best, UPPER_REFERENCE, room, [lo, hi]),
                "oracle_catch_minus_rows": above,
                "room_below_oracle": {"value": old[0], "ci": [old[1], old[2]]},
                "oracle_minus_delay_estimator": {"value": est[0], "ci": [est[1], est[2]]},
                "delay_tracker_minus": {
                    "rival": rival,
                    "minus_rival": _difference(played["delay_tracker"], played[rival]),
                    "minus_mean_delay_catch": _difference(
                        played["delay_tracker"], played["mean_delay_catch"]
                    ),
                },
                "estimator_offset_catch_minus": offset_row_minus(played, best, _difference),
                "estimator_tracker_catch_minus": offset_row_minus(
                    played, best, _difference, "estimator_tracker_catch"
                ),
                "pooled_estimator_catch_minus": pooled_row_minus(played, best, _difference),
            }
        )
    return {
        "benchmark": f"juggling v2 rows ({ENV_ID_V2})",
        "config": asdict(config),
        "demonstrations": SIMULATED_LABEL,
        "residual_scale_m": RESIDUAL_SCALE,
        "seeds": {
            "choice": {"split": "val", "first": SPLIT_SEEDS["val"], "count": config.val_episodes},
            "pick": {"split": "val", "first": SPLIT_SEEDS["val"], "count": config.pick_episodes},
            "test": {"split": "test", "first": SPLIT_SEEDS["test"], "count": config.episodes},
        },
        "levels": levels,
        "timing": {"cpu_s": time.process_time() - t0},
    }


def offset_row_minus(
    played: dict[str, Any], best: str, diff: Any, name: str = "estimator_offset_catch"
) -> dict[str, Any]:
    """The row ``name`` (``estimator_offset_catch`` or ``estimator_tracker_catch``) minus
    its base ``delay_estimator_catch`` and minus the best non-oracle row ``best`` (chosen
    on validation), paired by ``diff``."""
    row = played[name]
    return {
        "row": name,
        "best": best,
        "minus_delay_estimator_catch": diff(row, played["delay_estimator_catch"]),
        "minus_best": diff(row, played[best]),
    }


def pooled_row_minus(played: dict[str, Any], best: str, diff: Any) -> dict[str, Any]:
    """``pooled_estimator_catch`` minus its base ``delay_estimator_catch``, minus
    ``estimator_offset_catch``, minus the best non-oracle row ``best`` (chosen on
    validation), and ``oracle_catch`` minus it (the room it leaves), paired by ``diff``."""
    row = played["pooled_estimator_catch"]
    return {
        **offset_row_minus(played, best, diff, "pooled_estimator_catch"),
        "minus_estimator_offset_catch": diff(row, played["estimator_offset_catch"]),
        "oracle_catch_minus_row": diff(played[UPPER_REFERENCE], row),
    }


def pooled_row_line(d: dict[str, Any], frames: int | str, fmt: str = "+.3f") -> str:
    """The report's line of :func:`pooled_row_minus` (``frames`` the chosen anchor
    frames, or their key with the start anchor; ``fmt`` as :func:`tracker_line`'s)."""

    def f(m: dict[str, Any]) -> str:
        return f"{m['value']:{fmt}} [{m['ci'][0]:{fmt}}, {m['ci'][1]:{fmt}}]"

    offset = (
        ""
        if d["best"] == "estimator_offset_catch"  # said by offset_row_line already
        else f"; - estimator_offset_catch: {f(d['minus_estimator_offset_catch'])}"
    )
    return (
        f"pooled estimate's anchor frames {frames} (chosen on validation); "
        f"{offset_row_line(d, fmt)}{offset}; {UPPER_REFERENCE} - it (the room left): "
        f"{f(d['oracle_catch_minus_row'])}"
    )


def offset_row_line(d: dict[str, Any], fmt: str = "+.3f") -> str:
    """The report's line of :func:`offset_row_minus` (``fmt`` as :func:`tracker_line`'s)."""

    def f(m: dict[str, Any]) -> str:
        return f"{m['value']:{fmt}} [{m['ci'][0]:{fmt}}, {m['ci'][1]:{fmt}}]"

    return (
        f"{d.get('row', 'estimator_offset_catch')} - delay_estimator_catch (paired): "
        f"{f(d['minus_delay_estimator_catch'])}; - {d['best']} (the best non-oracle row): "
        f"{f(d['minus_best'])}"
    )


def _difference(a: JugglingEpisodes, b: JugglingEpisodes) -> dict[str, Any]:
    value, lo, hi = catch_rate_difference(a, b)
    return {"value": value, "ci": [lo, hi]}


def pick_count(doc: dict[str, Any]) -> int:
    """The validation episodes the document's best non-oracle row was picked on (a
    document written before ``pick_episodes``: the grids' ``choice`` count)."""
    seeds = doc["seeds"]
    return int(seeds.get("pick", seeds["choice"])["count"])


def _val(lv: dict[str, Any]) -> str:
    rates = lv.get("val_catch_rates", {})
    return ", ".join(f"{k} {v:.3f}" for k, v in rates.items()) or "not recorded"


def report_v2(doc: dict[str, Any]) -> str:
    """The printed table of :func:`run_v2`'s document."""
    test = doc["seeds"]["test"]
    lines = [
        f"Juggling-v2 rows ({doc['demonstrations']}); {test['count']} test episodes per level "
        f"and row (seeds from {test['first']}); grid choices on "
        f"{doc['seeds']['choice']['count']} validation episodes, the best non-oracle row "
        f"picked on {pick_count(doc)}; oracle, oracle_catch = references given the true "
        "delay and drag (not competitors); oracle_catch (with the catch plan) is the "
        "UPPER REFERENCE",
        f"{'level':7s} {'row':22s} {'catch rate [95% CI]':24s} {'deviation m [95% CI]':24s}",
    ]
    for lv in doc["levels"]:
        for name, m in lv["rows"].items():
            lo, hi = m["catch_rate_ci"]
            dlo, dhi = m["deviation_ci"]
            lines.append(
                f"{lv['level']:7s} {name:22s} {m['catch_rate']:.3f} [{lo:.3f}, {hi:.3f}]   "
                f"{m['deviation_m']:.4f} [{dlo:.4f}, {dhi:.4f}]"
            )
        key = "room_below_oracle_catch" if "room_below_oracle_catch" in lv else "room_below_oracle"
        room = lv[key]
        ref = UPPER_REFERENCE if key == "room_below_oracle_catch" else "oracle"
        trk = lv.get("tracker")
        trk_text = "" if trk is None else f"tracker {tracker_key((trk['gain'], trk['offset_s']))}; "
        est = lv.get("estimator_offset_s")
        est_text = "" if est is None else f"estimate's offset {offset_key(est)}; "
        lines.append(
            f"{lv['level']:7s} best constant {tuple(lv['constant'])}; late offset "
            f"{lv.get('late_offset_s', 0.0) * 1000:.0f} ms; {trk_text}{est_text}best "
            "non-oracle row "
            f"{lv['best_non_oracle']} (picked on {pick_count(doc)} validation episodes: "
            f"{_val(lv)}); room below the "
            f"upper reference ({ref} - {lv['best_non_oracle']}, paired): {room['value']:+.3f} "
            f"[{room['ci'][0]:+.3f}, {room['ci'][1]:+.3f}]"
        )
        if "target_room" in lv:
            lines.append(f"{lv['level']:7s} {lv['target_room']['sentence']}")
        below = [
            name
            for name, d in lv.get("oracle_catch_minus_rows", {}).items()
            if name != "oracle" and d["ci"][0] <= 0
        ]
        if "oracle_catch_minus_rows" in lv:
            lines.append(
                f"{lv['level']:7s} {UPPER_REFERENCE} above every non-reference row (paired "
                "interval above 0): "
                + ("yes" if not below else f"no, not above {', '.join(below)}")
            )
        if "delay_tracker_minus" in lv:
            lines.append(f"{lv['level']:7s} {tracker_line(lv['delay_tracker_minus'])}")
        if "estimator_offset_catch_minus" in lv:
            lines.append(f"{lv['level']:7s} {offset_row_line(lv['estimator_offset_catch_minus'])}")
        if "estimator_tracker_catch_minus" in lv:
            et = lv["estimator_tracker"]
            lines.append(
                f"{lv['level']:7s} estimate's tracker "
                f"{tracker_key((et['gain'], et['offset_s']))} (chosen on validation); "
                f"{offset_row_line(lv['estimator_tracker_catch_minus'])}"
            )
        if "pooled_estimator_catch_minus" in lv:
            line = pooled_row_line(lv["pooled_estimator_catch_minus"], lv["pooled_anchor_frames"])
            lines.append(f"{lv['level']:7s} {line}")
        if "oracle_minus_delay_estimator" in lv:
            est = lv["oracle_minus_delay_estimator"]
            lines.append(
                f"{lv['level']:7s} oracle - delay_estimator (paired): {est['value']:+.3f} "
                f"[{est['ci'][0]:+.3f}, {est['ci'][1]:+.3f}]"
            )
    lines.append(f"CPU {doc['timing']['cpu_s']:.1f} s")
    return "\n".join(lines)


def tracker_line(d: dict[str, Any], fmt: str = "+.3f") -> str:
    """The report's line of the tracker against its rival (the best other non-oracle row,
    chosen on validation) and its base ``mean_delay_catch``, paired; ``fmt`` formats the
    differences (catch rates here, mean catches on the cascades)."""
    r, b = d["minus_rival"], d["minus_mean_delay_catch"]

    def f(m: dict[str, Any]) -> str:
        return f"{m['value']:{fmt}} [{m['ci'][0]:{fmt}}, {m['ci'][1]:{fmt}}]"

    return (
        f"delay_tracker - {d['rival']} (the best other row, paired): {f(r)}; "
        f"delay_tracker - mean_delay_catch: {f(b)}"
    )


_LABELS = {
    "oracle": "oracle (true delay and drag)",
    "oracle_catch": "oracle + catch plan (UPPER REFERENCE)",
}


def plot_v2(doc: dict[str, Any]) -> Any:
    """Catch rate against deviation, one point per row with its interval bars, a panel
    per level (matplotlib imported on call); a row not in :data:`ROWS` (an agent's,
    ``experiments/juggling_v2_agents.py``) is drawn as a star."""
    from baselines.plots import new_figure

    n = len(doc["levels"])
    fig = new_figure(5.2 * n, 4.4 if n > 1 else 5.0)
    axes = fig.subplots(1, n, squeeze=False, sharey=True)
    markers = dict(zip(ROWS, "osP^D<>hHvdxp8X12", strict=True))
    # one colour per row (the default cycle has 10; then black, grey, brown, navy, green,
    # magenta, teal)
    extra = ("black", "0.5", "saddlebrown", "navy", "darkgreen", "magenta", "teal")
    colors = {name: f"C{i}" if i < 10 else extra[i - 10] for i, name in enumerate(ROWS)}
    for ax, lv in zip(axes[0], doc["levels"], strict=True):
        for name, m in lv["rows"].items():
            dev, rate = m["deviation_m"] * 1000, m["catch_rate"]
            xerr = [[dev - m["deviation_ci"][0] * 1000], [m["deviation_ci"][1] * 1000 - dev]]
            yerr = [[rate - m["catch_rate_ci"][0]], [m["catch_rate_ci"][1] - rate]]
            label = _LABELS.get(name, name.replace("_", " "))
            ax.errorbar(dev, rate, xerr=xerr, yerr=yerr, fmt=markers.get(name, "*"), capsize=3,
                        label=label, color=colors.get(name))  # fmt: skip
        ax.set_title(f"Juggling-v2 {lv['level']}")
        ax.set_xlabel("hand deviation from held-out demonstrations (mm)")
        ax.grid(alpha=0.3)
    axes[0][0].set_ylabel("catch rate (catches per toss)")
    handles, labels = axes[0][0].get_legend_handles_labels()
    ncol = 4 if n > 1 else 2  # one panel: two columns fit its width
    fig.legend(handles, labels, fontsize=8, loc="outside lower center", ncol=ncol, frameon=False)
    fig.suptitle("demonstrations SIMULATED; bars: 95 % bootstrap intervals over test episodes",
                 fontsize=9)  # fmt: skip
    return fig


def write_v2(doc: dict[str, Any], out: str | Path) -> list[Path]:
    """``results.json`` and ``juggling_v2_rows.png`` in ``out`` (atomically)."""
    import json

    from motion_envs._io import atomic_write_text, save_figure

    out = Path(out)
    paths = [atomic_write_text(out / "results.json", json.dumps(doc, indent=2) + "\n")]
    paths.append(save_figure(plot_v2(doc), out / "juggling_v2_rows.png", dpi=150))
    return paths
