"""``juggler_estimator_tracker_catch`` (Juggling-v2 and Cascade-v1): the release-anchored
estimate told with a tracked correction ``C + offset``, ``C <- clip(C - k (e - offset),
-50 ms, +50 ms)`` after every catch from 0, and the benches' row
``estimator_tracker_catch`` whose ``(k, offset)`` is chosen on VALIDATION seeds.

Independent checks: one update after a catch with a known timing error, worked by hand,
and the ball then told ``C + offset`` s later than the true flight on hand-made noiseless
frames (frames placed ``told`` s early fit the same parabola shifted in time); ``k = 0``
plays ``juggler_delay_estimator_catch``'s episodes exactly (and with an offset
``estimator_offset_catch``'s), a nonzero gain does not; each flight keeps the correction
told at its release (the latch); bad arguments are one-line errors; Gymnasium's and
SB3's checkers; the benches' choice reads validation seeds only (a spy on every play)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from motion_envs.envs.juggling import CascadeV1Env, JugglingV2Env
from motion_envs.models.juggling import (
    CORRECTION_BOUND,
    CascadeBallView,
    CorrectionTracker,
    DelayTracker,
    EstimatorTrackerController,
    make_v2_controller,
    v1_juggler,
)
from tests._helpers import (
    P0,
    T_R,
    assert_validation_first_in_grid_order,
    check_env_contract,
    release_flight,
    release_frames,
    rollout_digest,
    run_ranked_cascade_v1,
    run_ranked_v2,
)

NAME = "juggler_estimator_tracker_catch"
BASE = "juggler_delay_estimator_catch"
G = 9.81


# -- the correction tracker --------------------------------------------------------------
def test_one_catch_moves_the_correction_by_hand() -> None:
    """``k = 0.5``, offset 20 ms, a catch 30 ms late: ``C = 0 - 0.5 (0.03 - 0.02) =
    -5 ms``, told ``-5 + 20 = 15 ms``; a catch 1 s late is clipped at -50 ms (told -30
    ms, below 0: a correction may be negative); a catch without timing leaves it."""
    t = CorrectionTracker(0.5, 0.02)
    assert (t.estimate, t.prior, t.told) == (0.0, 0.0, 0.02)
    assert t.update(0.03) == pytest.approx(-0.005)
    assert t.told == pytest.approx(0.015)
    assert t.update(1.0) == -CORRECTION_BOUND
    assert t.told == pytest.approx(-0.03)
    assert t.update(math.nan) == -CORRECTION_BOUND
    assert t.update(-1.0) == CORRECTION_BOUND
    t.reset()
    assert (t.estimate, t.told) == (0.0, 0.02)


def test_the_delay_tracker_keeps_its_behaviour() -> None:
    """The base class unchanged: its prior the range's middle, its told delay at least 0,
    its range refused below 0."""
    d = DelayTracker(0.5, 0.02, (0.1, 0.2))
    assert d.estimate == pytest.approx(0.15) and d.told == pytest.approx(0.17)
    assert d.update(0.03) == pytest.approx(0.145)
    with pytest.raises(ValueError, match="0 <= low <= high"):
        DelayTracker(0.5, 0.0, (-0.01, 0.2))


def test_juggling_v2_a_catch_retells_the_estimate_hand_worked() -> None:
    """The controller fed a catch's task error (relative to the reach's end, ``lead``
    before the planned meeting) 30 ms after the meeting: the estimator's offset becomes
    15 ms, and on frames arriving 135 ms late the ball told at ``now`` is the true ball
    at ``now + 15 ms`` (the estimate itself still 135 ms)."""
    env = JugglingV2Env(level="medium", controller=NAME, tracker_gain=0.5, delay_offset=0.02)
    ctrl = env.controller
    assert isinstance(ctrl, EstimatorTrackerController)
    assert ctrl.estimator.offset == 0.02
    ctrl.felt(np.array([0.01, ctrl.plan.lead + 0.03]))
    told = ctrl.tracker.told
    assert told == pytest.approx(0.015)
    est = ctrl.estimator
    assert est.offset == told
    est.reset()
    est.released(T_R, *P0)
    est.add(release_frames(0.135, 12))
    assert est.delay_estimate == pytest.approx(0.135)
    got = est.estimate(1.45)
    assert got is not None
    np.testing.assert_allclose(got[0], release_flight(1.45 + told), atol=1e-9)
    env.reset(seed=0)
    assert ctrl.tracker.estimate == 0.0 and est.offset == 0.02  # a new episode: C = 0


def test_cascade_v1_a_catch_moves_the_told_correction_not_the_flights_in_the_air() -> None:
    """The view fed one hand's timing 30 ms late (the other hand NaN): the tracker's
    correction -5 ms, told 15 ms, while every estimator keeps the 20 ms told at its
    release (and the prior, the level's mean plus it) until its ball's next release."""
    env = CascadeV1Env(level="medium", controller=NAME, tracker_gain=0.5, delay_offset=0.02)
    env.reset(seed=0)
    view = env.view
    assert all(e.offset == 0.02 for e in view.estimators)
    assert all(e.fixed_delay == pytest.approx(0.15 + 0.02) for e in view.estimators)
    view.felt(np.array([math.nan, 0.03]))
    assert view.tracker is not None and view.tracker.told == pytest.approx(0.015)
    assert all(e.offset == 0.02 for e in view.estimators)  # latched until a release


def _cascade_offsets(gain: float, seed: int) -> tuple[list[tuple[list[int], Any]], int]:
    """Every step's released balls and each estimator's offset before and after
    :meth:`CascadeBallView.record`, and the number of tracker moves."""
    env = CascadeV1Env(level="hard", controller=NAME, tracker_gain=gain, delay_offset=0.02,
                       max_catches=12)  # fmt: skip
    view = env.view
    record, felt = view.record, view.felt
    steps: list[tuple[list[int], Any]] = []
    moves = [0]

    def spy_record(true: Any, frames: Any) -> None:
        before = [e.offset for e in view.estimators]
        record(true, frames)
        after = [e.offset for e in view.estimators]
        steps.append(([int(b) for b in true.released if b >= 0], (before, after)))

    def spy_felt(timings: Any) -> None:
        assert view.tracker is not None
        old = view.tracker.estimate
        felt(timings)
        moves[0] += view.tracker.estimate != old

    view.record, view.felt = spy_record, spy_felt  # type: ignore[method-assign]
    env.reset(seed=seed)
    done = False
    while not done:
        _, _, term, trunc, _ = env.step(np.zeros(4))
        done = term or trunc
    return steps, moves[0]


def test_cascade_v1_each_flight_keeps_the_correction_told_at_its_release() -> None:
    steps, moves = _cascade_offsets(1.0, 3)
    assert moves > 0
    changed = 0
    mixed = False
    for released, (before, after) in steps:
        for b, (x, y) in enumerate(zip(before, after, strict=True)):
            if x != y:
                assert b in released  # only a release retells a ball
                changed += 1
        mixed |= len(set(after)) > 1  # balls in the air told different corrections
    assert changed > 0 and mixed


def test_juggling_v2_the_told_correction_changes_only_at_a_catch() -> None:
    """One ball: a catch ends the flight, so the correction changes only at a catch
    step (never within a flight) and is the one the next flight is fitted with."""
    env = JugglingV2Env(level="hard", controller=NAME, tracker_gain=1.0, delay_offset=0.02,
                        max_catches=5)  # fmt: skip
    env.reset(seed=2)
    est = env.controller.estimator
    last, changes, done = est.offset, 0, False
    while not done:
        _, _, term, trunc, info = env.step(np.zeros(2))
        done = term or trunc
        if est.offset != last:
            assert "task_error" in info
            changes += 1
        last = est.offset
    assert changes > 0


# -- k = 0 is the estimator with the catch plan --------------------------------------------
def _v2(controller: str, seeds: range, level: str = "medium", **kw: Any) -> list[dict[str, Any]]:
    env = JugglingV2Env(level=level, controller=controller, max_catches=3, **kw)
    return [env.nominal_episode(s) for s in seeds]


def _same(a: list[dict[str, Any]], b: list[dict[str, Any]]) -> bool:
    keys = ("catches", "tosses", "dropped", "hand", "task_errors")
    return all(np.array_equal(x[k], y[k]) for x, y in zip(a, b, strict=True) for k in keys)


@pytest.mark.parametrize("level", ["medium", "hard"])
def test_juggling_v2_gain_zero_is_the_estimator_with_the_catch_plan(level: str) -> None:
    seeds = range(3)
    base = _v2(BASE, seeds, level)
    assert _same(base, _v2(NAME, seeds, level))
    assert _same(_v2(BASE, seeds, level, delay_offset=0.02),
                 _v2(NAME, seeds, level, delay_offset=0.02))  # fmt: skip
    assert not _same(base, _v2(NAME, seeds, level, tracker_gain=1.0))


def test_cascade_v1_gain_zero_is_the_estimator_with_the_catch_plan() -> None:
    def digests(controller: str, **kw: Any) -> list[str]:
        env = CascadeV1Env(level="medium", controller=controller, max_catches=8, **kw)
        return [rollout_digest(env, s) for s in (0, 1, 2)]

    base = digests(BASE)
    assert digests(NAME) == base
    assert digests(NAME, delay_offset=0.02) == digests(BASE, delay_offset=0.02)
    assert digests(NAME, tracker_gain=1.0) != base
    five = {"level": "medium", "pattern": "5", "max_catches": 8}
    plain = CascadeV1Env(controller=BASE, **five)
    ours = CascadeV1Env(controller=NAME, **five)
    assert [plain.play(s) for s in range(2)] == [ours.play(s) for s in range(2)]


# -- bad arguments -------------------------------------------------------------------------
@pytest.mark.parametrize("env", [JugglingV2Env, CascadeV1Env])
@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"tracker_gain": 2.0}, r"tracker_gain must be in \[0, 1.5\]"),
        ({"tracker_gain": -0.1}, "tracker_gain must be in"),
        ({"tracker_gain": float("nan")}, "tracker_gain must be in"),
        ({"tracker_gain": "0.5"}, "tracker_gain must be in"),
        ({"delay_offset": -0.01}, r"delay_offset must be in \[0, 0.25\]"),
        ({"timing_scale": 0.05}, "timing_scale is for"),
    ],
)
def test_bad_arguments_are_one_line_errors_naming_them(
    env: Any, kwargs: dict[str, Any], match: str
) -> None:
    with pytest.raises(ValueError, match=match) as exc:
        env(controller=NAME, **kwargs)
    assert "\n" not in str(exc.value) and next(iter(kwargs)) in str(exc.value)


@pytest.mark.parametrize("env", [JugglingV2Env, CascadeV1Env])
def test_a_gain_for_another_controller_names_both_trackers(env: Any) -> None:
    with pytest.raises(ValueError, match="tracker_gain is for") as exc:
        env(controller=BASE, tracker_gain=0.5)
    assert NAME in str(exc.value) and "juggler_delay_tracker" in str(exc.value)


def test_the_models_refuse_a_wrong_tracker() -> None:
    with pytest.raises(ValueError, match="gain must be in"):
        CorrectionTracker(1.6, 0.0)
    with pytest.raises(ValueError, match="low <= 0 <= high"):
        CorrectionTracker(0.5, 0.0, (0.01, 0.05))
    with pytest.raises(ValueError, match="offset must be in"):
        CorrectionTracker(0.5, -0.01)
    juggler = v1_juggler(G)
    with pytest.raises(ValueError, match="tracker is for"):
        make_v2_controller(NAME, juggler, G, 0.15, DelayTracker(0.5, 0.0, (0.1, 0.2)))
    with pytest.raises(ValueError, match="tracker is for"):
        make_v2_controller(NAME, juggler, G, 0.15)
    with pytest.raises(ValueError, match="tracker is for"):
        make_v2_controller("juggler_delay_tracker", juggler, G, 0.15, CorrectionTracker(0.5, 0))
    with pytest.raises(ValueError, match="needs the estimators' mode 'release'"):
        CascadeBallView(3, "mean_delay", G, 0.15, 1.0, tracker=CorrectionTracker(0.5, 0.0))


# -- the checkers --------------------------------------------------------------------------
@pytest.mark.parametrize("env_cls", [JugglingV2Env, CascadeV1Env])
def test_gymnasium_and_sb3_checkers_pass_and_reset_is_deterministic(env_cls: Any) -> None:
    env = env_cls(level="medium", controller=NAME, tracker_gain=0.5, delay_offset=0.02,
                  max_catches=4)  # fmt: skip
    check_env_contract(env)


# -- the benches' row ----------------------------------------------------------------------
FAVOURED = {"val": (0.25, 0.02), "test": (1.0, 0.0)}


def _pair(kwargs: dict[str, Any]) -> tuple[float, float]:
    return (kwargs.get("tracker_gain", 0.0), kwargs.get("delay_offset", 0.0))


def _validation_first_in_grid_order(calls: list[tuple[str, dict[str, Any], bool]]) -> None:
    """The choice's plays are the grid's pairs in order, on validation seeds, before any
    test play, each of the row's controller."""
    from baselines.juggling_bench.v2 import ESTIMATOR_TRACKER_GRID

    assert all(kw["controller"] == NAME for _, kw, choosing in calls if choosing)
    assert_validation_first_in_grid_order(calls, _pair, ESTIMATOR_TRACKER_GRID)


def test_juggling_v2_the_estimates_tracker_is_chosen_on_validation_seeds() -> None:
    """On validation the row catches every toss only at ``(0.25, +20 ms)``, on test
    only at ``(1, 0)``: the row must carry ``(0.25, +20 ms)`` (and catch nothing on
    test), the choice must play validation seeds only, in grid order, and the row
    enters the best non-oracle row's choice (the only row at 1.0 on validation)."""
    from baselines.juggling_bench.v2 import (
        ESTIMATOR_TRACKER_GRID,
        choose_estimator_tracker,
        report_v2,
        tracker_key,
    )

    doc, calls = run_ranked_v2(
        NAME,
        lambda kw, split: _pair(kw) == FAVOURED[split],
        estimator_tracker_chooser=choose_estimator_tracker,
    )
    (lv,) = doc["levels"]
    _validation_first_in_grid_order(calls)
    assert lv["estimator_tracker"] == {"gain": 0.25, "offset_s": 0.02}
    assert lv["estimator_tracker_val_catch_rates"] == {
        tracker_key(p): 1.0 if p == FAVOURED["val"] else 0.0 for p in ESTIMATOR_TRACKER_GRID
    }
    assert lv["val_catch_rates"]["estimator_tracker_catch"] == 1.0
    assert lv["best_non_oracle"] == "estimator_tracker_catch"
    assert lv["rows"]["estimator_tracker_catch"]["catch_rate"] == 0.0  # the val pair on test
    minus = lv["estimator_tracker_catch_minus"]
    assert minus["row"] == "estimator_tracker_catch" and minus["minus_best"]["value"] == 0.0
    base = lv["rows"]["delay_estimator_catch"]["catch_rate"]
    assert minus["minus_delay_estimator_catch"]["value"] == pytest.approx(0.0 - base)
    assert "estimate's tracker k=0.25, +20 ms (chosen on validation)" in report_v2(doc)
    tested = [_pair(kw) for s, kw, _ in calls if s == "test" and kw["controller"] == NAME]
    assert tested == [FAVOURED["val"]]


def test_cascade_v1_the_estimates_tracker_is_chosen_on_validation_seeds() -> None:
    """Cascade-v1's bench likewise, by mean catches before the first drop: 15 on
    validation only at ``(0.25, +20 ms)``, on test only at ``(1, 0)``."""
    from baselines.juggling_bench.cascade_v1 import (
        choose_estimator_tracker,
        report_cascade_v1,
    )

    doc, calls = run_ranked_cascade_v1(
        lambda kw, split: (
            None if kw["controller"] != NAME else 15 if _pair(kw) == FAVOURED[split] else 2
        ),
        estimator_tracker_chooser=choose_estimator_tracker,
    )
    (lv,) = doc["levels"]
    _validation_first_in_grid_order(calls)
    assert lv["estimator_tracker"] == {"gain": 0.25, "offset_s": 0.02}
    assert lv["estimator_tracker_val_mean_catches"]["k=0.25, +20 ms"] == 15.0
    assert lv["val_mean_catches"]["estimator_tracker_catch"] == 15.0
    assert lv["best_non_oracle"] == "estimator_tracker_catch"
    assert lv["rows"]["estimator_tracker_catch"]["catches_mean"] == 2.0  # the val pair on test
    minus = lv["estimator_tracker_catch_minus"]
    assert minus["minus_delay_estimator_catch"]["value"] == 2.0 - 1.0
    assert "estimate's tracker k=0.25, +20 ms (chosen on validation)" in report_cascade_v1(doc)
