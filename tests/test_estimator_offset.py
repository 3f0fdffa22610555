"""``delay_offset`` on ``juggler_delay_estimator_catch`` (Juggling-v2 and Cascade-v1): the
frames placed by the release-anchored estimate plus the offset, and the benches' row
``estimator_offset_catch`` whose offset is chosen on VALIDATION seeds.

Independent checks: on hand-made noiseless frames of a known ballistic flight the
estimate is unchanged by the offset while the told ball is the true flight ``offset`` s
later (frames placed ``offset`` s early fit the same parabola shifted in time: worked by
hand); a zero offset plays ``delay_estimator_catch``'s episodes exactly and a nonzero one
does not; the benches' choice of the offset reads validation seeds only (a spy on every
play)."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from motion_envs.envs.juggling import CascadeV1Env, JugglingV2Env
from motion_envs.models.juggling import (
    CascadeBallView,
    FlightEstimator,
    PooledReleaseEstimator,
)
from tests._helpers import (
    P0,
    T_R,
    V0,
    assert_validation_first_in_grid_order,
    release_flight,
    release_frames,
    rollout_digest,
    run_ranked_cascade_v1,
    run_ranked_v2,
)

NAME = "juggler_delay_estimator_catch"
G = 9.81


@pytest.mark.parametrize("offset", [0.0, 0.02, -0.015])
def test_the_offset_tells_the_flight_offset_seconds_later_hand_worked(offset: float) -> None:
    """Frames arriving 135 ms late: the estimate is 135 ms whatever the offset; placed
    at ``arrival - (0.135 + offset)`` they lie ``offset`` s before their capture, so the
    fitted parabola is the true one shifted ``offset`` s earlier in time and the ball
    told at ``now`` is the true ball at ``now + offset`` (position and velocity)."""
    for est in (
        FlightEstimator("release", G, offset=offset),
        PooledReleaseEstimator(G, [], 0.15, offset),
    ):
        est.reset()
        est.released(T_R, *P0)
        est.add(release_frames(0.135, 12))
        assert est.delay_estimate == pytest.approx(0.135)
        now = 1.45
        got = est.estimate(now)
        assert got is not None
        np.testing.assert_allclose(got[0], release_flight(now + offset), atol=1e-9)
        s = now + offset - T_R
        np.testing.assert_allclose(got[1], [V0[0], V0[1] - G * s], atol=1e-9)


def test_the_offset_is_refused_outside_the_release_mode() -> None:
    with pytest.raises(ValueError, match="offset"):
        FlightEstimator("mean_delay", G, delay=0.15, offset=0.01)
    with pytest.raises(ValueError, match="offset"):
        CascadeBallView(3, "mean_delay", G, 0.15, 1.0, offset=0.01)
    with pytest.raises(ValueError, match="offset"):
        FlightEstimator("release", G, offset=float("nan"))


def _v2(offset: float | None, seeds: range) -> list[dict[str, Any]]:
    kw = {} if offset is None else {"delay_offset": offset}
    env = JugglingV2Env(level="medium", controller=NAME, max_catches=3, **kw)
    return [env.nominal_episode(s) for s in seeds]


def _same(a: list[dict[str, Any]], b: list[dict[str, Any]]) -> bool:
    keys = ("catches", "tosses", "dropped", "hand", "task_errors")
    return all(np.array_equal(x[k], y[k]) for x, y in zip(a, b, strict=True) for k in keys)


def test_juggling_v2_zero_offset_is_the_row_and_an_offset_changes_it() -> None:
    seeds = range(3)
    base = _v2(None, seeds)
    assert _same(base, _v2(0.0, seeds))
    assert not _same(base, _v2(0.02, seeds))
    assert not _same(base, _v2(-0.02, seeds))
    env = JugglingV2Env(controller=NAME, delay_offset=-0.02)
    assert env.controller.estimator.offset == -0.02


def test_cascade_v1_zero_offset_is_the_row_and_an_offset_changes_it() -> None:
    def digests(**kw: Any) -> list[str]:
        env = CascadeV1Env(level="medium", controller=NAME, max_catches=6, **kw)
        return [rollout_digest(env, s) for s in (0, 1)]

    base = digests()
    assert digests(delay_offset=0.0) == base
    assert digests(delay_offset=0.02) != base
    assert digests(delay_offset=-0.02) != base
    env = CascadeV1Env(controller=NAME, delay_offset=-0.02)
    assert all(e.offset == -0.02 for e in env.view.estimators)
    # the prior before the first estimate: the level's mean plus the offset
    assert env.view.estimators[0].fixed_delay == pytest.approx(0.15 - 0.02)


@pytest.mark.parametrize("env", [JugglingV2Env, CascadeV1Env])
@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"controller": NAME, "delay_offset": -0.06}, r"delay_offset must be in \[-0.05, 0.25\]"),
        ({"controller": NAME, "delay_offset": 0.3}, "delay_offset must be in"),
        ({"controller": NAME, "delay_offset": float("nan")}, "delay_offset must be in"),
        ({"controller": NAME, "delay_offset": "0.01"}, "delay_offset must be in"),
        ({"controller": "juggler_mean_delay", "delay_offset": -0.01}, r"must be in \[0, 0.25\]"),
        ({"controller": "juggler_delay_tracker", "delay_offset": -0.01}, "must be in"),
        ({"controller": "juggler_delay_estimator", "delay_offset": -0.01}, "must be in"),
        ({"controller": "juggler_delay_estimator", "delay_offset": 0.01}, "delay_offset is for"),
    ],
)
def test_a_bad_delay_offset_is_a_one_line_error_naming_it(
    env: Any, kwargs: dict[str, Any], match: str
) -> None:
    with pytest.raises(ValueError, match=match) as exc:
        env(**kwargs)
    assert "\n" not in str(exc.value) and "delay_offset" in str(exc.value)


# -- the benches' row ---------------------------------------------------------------------
def test_the_grid_is_declared_around_zero_smallest_correction_first() -> None:
    from baselines.juggling_bench import v2

    grid = v2.ESTIMATOR_OFFSETS
    assert grid[0] == 0.0 and min(grid) == -0.02 and max(grid) == 0.04
    assert [abs(o) for o in grid] == sorted(abs(o) for o in grid)  # ties: the smallest
    assert len({v2.offset_key(o) for o in grid}) == len(grid)
    for offset in grid:  # every candidate is a valid env argument
        JugglingV2Env(controller=NAME, delay_offset=offset)


def _validation_first_in_grid_order(calls: list[tuple[str, dict[str, Any], bool]]) -> None:
    """The choice's plays are the offsets in order, on validation seeds, before any test."""
    from baselines.juggling_bench.v2 import ESTIMATOR_OFFSETS

    assert_validation_first_in_grid_order(
        calls, lambda kw: kw.get("delay_offset", 0.0), ESTIMATOR_OFFSETS
    )


def test_juggling_v2_the_estimates_offset_is_chosen_on_validation_seeds() -> None:
    """On validation the estimator with the catch plan catches every toss only at +20 ms,
    on test only at 0 ms: the row must carry +20 ms (and so catch nothing on test), the
    choice must play validation seeds only, in grid order, and the row enters the best
    non-oracle row's choice (the only row at 1.0 on validation)."""

    from baselines.juggling_bench.v2 import (
        ESTIMATOR_OFFSETS,
        choose_estimator_offset,
        report_v2,
    )

    favoured = {"val": 0.02, "test": 0.0}
    doc, calls = run_ranked_v2(
        NAME,
        lambda kw, split: kw.get("delay_offset", 0.0) == favoured[split],
        estimator_offset_chooser=choose_estimator_offset,
    )
    (lv,) = doc["levels"]
    _validation_first_in_grid_order(calls)
    assert lv["estimator_offset_s"] == 0.02
    assert lv["estimator_offset_val_catch_rates"] == {
        f"{o * 1000:.0f} ms": 1.0 if o == 0.02 else 0.0 for o in ESTIMATOR_OFFSETS
    }
    assert lv["val_catch_rates"]["estimator_offset_catch"] == 1.0
    assert lv["val_catch_rates"]["delay_estimator_catch"] == 0.0  # the grid's 0 ms play
    assert lv["best_non_oracle"] == "estimator_offset_catch"
    assert lv["rows"]["estimator_offset_catch"]["catch_rate"] == 0.0  # +20 ms on test
    minus = lv["estimator_offset_catch_minus"]
    assert minus["minus_delay_estimator_catch"]["value"] == -1.0  # 0 ms catches all on test
    assert minus["best"] == "estimator_offset_catch" and minus["minus_best"]["value"] == 0.0
    assert "estimator_offset_catch - delay_estimator_catch (paired): -1.000" in report_v2(doc)
    tested = [kw for s, kw, _ in calls
              if s == "test" and kw["controller"] == NAME and "delay_rule" not in kw]  # fmt: skip
    assert [kw.get("delay_offset") for kw in tested] == [None, 0.02]  # the row, then ours


def test_cascade_v1_the_estimates_offset_is_chosen_on_validation_seeds() -> None:
    """Cascade-v1's bench likewise, by mean catches before the first drop: 15 on
    validation only at +20 ms, on test only at 0 ms."""
    from baselines.juggling_bench.cascade_v1 import (
        choose_estimator_offset,
    )

    favoured = {"val": 0.02, "test": 0.0}
    doc, calls = run_ranked_cascade_v1(
        lambda kw, split: (
            None
            if kw["controller"] != NAME
            else 15
            if kw.get("delay_offset", 0.0) == favoured[split]
            else 2
        ),
        estimator_offset_chooser=choose_estimator_offset,
    )
    (lv,) = doc["levels"]
    _validation_first_in_grid_order(calls)
    assert lv["estimator_offset_s"] == 0.02
    assert lv["estimator_offset_val_mean_catches"]["20 ms"] == 15.0
    assert lv["val_mean_catches"]["delay_estimator_catch"] == 2.0  # the grid's 0 ms play
    assert lv["best_non_oracle"] == "estimator_offset_catch"
    assert lv["rows"]["estimator_offset_catch"]["catches_mean"] == 2.0  # +20 ms on test
    minus = lv["estimator_offset_catch_minus"]
    assert minus["minus_delay_estimator_catch"]["value"] == -13.0  # 0 ms: 15 on test
    assert "estimate's offset 20 ms" in report_cascade(doc)


def report_cascade(doc: dict[str, Any]) -> str:
    from baselines.juggling_bench.cascade_v1 import report_cascade_v1

    return report_cascade_v1(doc)
