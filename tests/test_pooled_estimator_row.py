"""The benches' row ``pooled_estimator_catch``: ``juggler_delay_estimator_catch`` with the
pooled delay rule, its anchor frames chosen on VALIDATION seeds (a spy on every play
proves no test seed is read before the choice; synthetic rankings that differ between
the splits tell a choice made on test seeds apart)."""

from __future__ import annotations

from typing import Any

from _helpers import assert_validation_first_in_grid_order, run_ranked_cascade_v1, run_ranked_v2

from motion_envs.envs.juggling import CascadeV1Env, JugglingV2Env
from motion_envs.models.juggling import ANCHOR_FRAMES, pooled_flight_delay

NAME = "juggler_delay_estimator_catch"
#: The anchor frames the synthetic rankings favour per split.
FAVOURED = {"val": 16, "test": 8}


def _pooled(kwargs: dict[str, Any]) -> int | None:
    """The anchor frames of a play of the pooled row, None for any other play."""
    if kwargs.get("controller") != NAME or kwargs.get("delay_rule") is None:
        return None
    assert kwargs["delay_rule"] is pooled_flight_delay
    return int(kwargs["anchor_frames"])


def test_the_grid_is_declared_fewest_first_and_every_candidate_is_an_env_argument() -> None:
    from baselines.juggling_bench import v2

    grid = v2.POOLED_ANCHOR_FRAMES
    assert grid[0] == ANCHOR_FRAMES and list(grid) == sorted(grid)  # ties: the fewest
    assert len({v2.anchor_key(n) for n in grid}) == len(grid)
    for n in grid:
        JugglingV2Env(controller=NAME, **v2.pooled_kwargs(n))
        CascadeV1Env(controller=NAME, **v2.pooled_kwargs(n))


def _validation_first_in_grid_order(calls: list[tuple[str, dict[str, Any], bool]]) -> None:
    """The choice's plays are the grid's anchor frames in order, on validation seeds,
    before any test play."""
    from baselines.juggling_bench.v2 import POOLED_ANCHOR_FRAMES

    assert_validation_first_in_grid_order(calls, _pooled, POOLED_ANCHOR_FRAMES)


def test_juggling_v2_the_anchor_frames_are_chosen_on_validation_seeds() -> None:
    """On validation the row catches every toss only at 16 frames, on test only at 8: the
    row must carry 16 (and so catch nothing on test), the choice must play validation
    seeds only, in grid order, and the row enters the best non-oracle row's choice (the
    only row at 1.0 on validation)."""
    from baselines.juggling_bench.v2 import (
        POOLED_ANCHOR_FRAMES,
        anchor_key,
        choose_pooled_anchor,
        report_v2,
    )

    doc, calls = run_ranked_v2(
        NAME, lambda kw, split: _pooled(kw) == FAVOURED[split], pooled_chooser=choose_pooled_anchor
    )
    (lv,) = doc["levels"]
    _validation_first_in_grid_order(calls)
    assert lv["pooled_anchor_frames"] == 16
    assert lv["pooled_val_catch_rates"] == {
        anchor_key(k): 1.0 if k == 16 else 0.0 for k in POOLED_ANCHOR_FRAMES
    }
    assert lv["val_catch_rates"]["pooled_estimator_catch"] == 1.0
    assert lv["best_non_oracle"] == "pooled_estimator_catch"
    assert lv["rows"]["pooled_estimator_catch"]["catch_rate"] == 0.0  # 16 frames on test
    minus = lv["pooled_estimator_catch_minus"]
    assert minus["row"] == "pooled_estimator_catch" and minus["minus_best"]["value"] == 0.0
    assert minus["minus_delay_estimator_catch"]["value"] == 0.0  # neither catches on test
    room = minus["oracle_catch_minus_row"]["value"]
    assert room == lv["rows"]["oracle_catch"]["catch_rate"]
    assert "pooled estimate's anchor frames 16 (chosen on validation)" in report_v2(doc)
    tested = [_pooled(kw) for s, kw, _ in calls if s == "test" and _pooled(kw) is not None]
    assert tested == [16]


def test_cascade_v1_the_anchor_frames_are_chosen_on_validation_seeds() -> None:
    """Cascade-v1's bench likewise, by mean catches before the first drop: 15 on
    validation only at 16 frames, on test only at 8."""
    from baselines.juggling_bench.cascade_v1 import (
        choose_pooled_anchor,
        report_cascade_v1,
    )

    doc, calls = run_ranked_cascade_v1(
        lambda kw, split: (
            None if _pooled(kw) is None else 15 if _pooled(kw) == FAVOURED[split] else 2
        ),
        pooled_chooser=choose_pooled_anchor,
    )
    (lv,) = doc["levels"]
    _validation_first_in_grid_order_cascade(calls)
    assert lv["pooled_anchor_frames"] == 16
    assert lv["pooled_anchor_start"] is False  # tied with the start anchored: the first
    assert lv["pooled_val_mean_catches"]["16 frames"] == 15.0
    assert lv["val_mean_catches"]["pooled_estimator_catch"] == 15.0
    assert lv["best_non_oracle"] == "pooled_estimator_catch"
    assert lv["rows"]["pooled_estimator_catch"]["catches_mean"] == 2.0  # 16 frames on test
    minus = lv["pooled_estimator_catch_minus"]
    assert minus["minus_delay_estimator_catch"]["value"] == 2.0 - 1.0
    assert minus["minus_estimator_offset_catch"]["value"] == 2.0 - 1.0
    assert "pooled estimate's anchor frames 16 (chosen on validation)" in report_cascade_v1(doc)


def _pooled_pair(kwargs: dict[str, Any]) -> tuple[int, bool] | None:
    """Cascade-v1's pooled play's ``(anchor frames, start anchored)``, None for another."""
    frames = _pooled(kwargs)
    return None if frames is None else (frames, bool(kwargs.get("anchor_start", False)))


def _validation_first_in_grid_order_cascade(calls: list[tuple[str, dict[str, Any], bool]]) -> None:
    """Cascade-v1's choice's plays are its grid's pairs in order, on validation seeds,
    before any test play."""
    from baselines.juggling_bench.cascade_v1 import POOLED_GRID

    assert_validation_first_in_grid_order(calls, _pooled_pair, POOLED_GRID)


def test_cascade_v1_the_start_anchor_is_chosen_on_validation_seeds() -> None:
    """Validation favours 12 frames with the start anchored, test 20 frames without: the
    bench plays the validation pair on test and says it."""
    from baselines.juggling_bench.cascade_v1 import (
        POOLED_GRID,
        choose_pooled_anchor,
        report_cascade_v1,
    )

    favoured = {"val": (12, True), "test": (20, False)}
    assert POOLED_GRID[: len(POOLED_GRID) // 2] == tuple((f, False) for f, _ in POOLED_GRID[4:])
    doc, calls = run_ranked_cascade_v1(
        lambda kw, split: (
            None if _pooled_pair(kw) is None else 15 if _pooled_pair(kw) == favoured[split] else 2
        ),
        pooled_chooser=choose_pooled_anchor,
    )
    (lv,) = doc["levels"]
    _validation_first_in_grid_order_cascade(calls)
    assert (lv["pooled_anchor_frames"], lv["pooled_anchor_start"]) == (12, True)
    assert lv["pooled_val_mean_catches"]["12 frames, start anchored"] == 15.0
    assert lv["pooled_val_mean_catches"]["12 frames"] == 2.0
    assert lv["rows"]["pooled_estimator_catch"]["catches_mean"] == 2.0  # its pair on test
    tested = [_pooled_pair(kw) for s, kw, _ in calls if s == "test" and _pooled_pair(kw)]
    assert tested == [(12, True)]
    assert "anchor frames 12, the start anchored on its throws (chosen on validation)" in (
        report_cascade_v1(doc)
    )
