"""The validation-grid choice shared by the juggling choosers
(:func:`baselines.juggling_bench.grid_choice.best_on_grid`): a hand-worked grid, the tie
rule against an independent oracle (numpy's argmax, the first maximum), errors, and the
six choosers of Juggling-v2 and Cascade-v1 playing their grids in order through it."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from baselines.agents.juggling_score import JugglingEpisodes
from baselines.juggling_bench import cascade_v1, v2
from baselines.juggling_bench.cascade import CascadeEpisodes
from baselines.juggling_bench.grid_choice import best_on_grid
from motion_envs.datasets.juggling import episode_seeds


def test_a_hand_worked_grid() -> None:
    """Scores 0.2, 0.5, 0.5, 0.1, 0.5: the best is 0.5, first reached at "b" (the tie
    with "c" and "e" broken to the first in grid order); every candidate scored once, in
    grid order, and the table keyed and ordered like the grid."""
    scores = {"a": 0.2, "b": 0.5, "c": 0.5, "d": 0.1, "e": 0.5}
    order: list[str] = []

    def score(c: str) -> float:
        order.append(c)
        return scores[c]

    best, table = best_on_grid(("a", "b", "c", "d", "e"), score, str.upper)
    assert best == "b"
    assert order == ["a", "b", "c", "d", "e"]
    assert list(table.items()) == [("A", 0.2), ("B", 0.5), ("C", 0.5), ("D", 0.1), ("E", 0.5)]


def test_ties_everywhere_and_negative_scores_keep_the_first() -> None:
    assert best_on_grid((3, 1, 2), lambda c: 0.0, str)[0] == 3
    # a first candidate below any starting bound still starts the ranking
    assert best_on_grid((3, 1, 2), lambda c: -5.0 - c, str)[0] == 1
    assert best_on_grid((7,), lambda c: -np.inf, str) == (7, {"7": -np.inf})


def test_the_chosen_element_and_the_scores_are_returned_unconverted() -> None:
    grid = ((0.0, 0.5), (0.5, 0.0))
    best, table = best_on_grid(grid, lambda c: np.float64(c[0]), v2.grid_key)
    assert best is grid[1]
    assert all(type(v) is np.float64 for v in table.values())


@given(st.lists(st.integers(0, 4), min_size=1, max_size=12))
def test_the_first_maximum_as_numpy_argmax_finds_it(values: list[int]) -> None:
    """Scores with many ties (integers 0-4 as k / 4): the chosen index is
    ``np.argmax``'s, which returns the first occurrence of the maximum."""
    grid = tuple(range(len(values)))
    best, table = best_on_grid(grid, lambda i: values[i] / 4, str)
    assert best == int(np.argmax(values))
    assert list(table.values()) == [v / 4 for v in values]


def test_a_candidate_that_raises_propagates_and_stops_the_grid() -> None:
    scored: list[int] = []

    def score(c: int) -> float:
        if c == 2:
            raise RuntimeError("env failed on candidate 2")
        scored.append(c)
        return float(c)

    with pytest.raises(RuntimeError, match="env failed on candidate 2"):
        best_on_grid((1, 2, 3), score, str)
    assert scored == [1]


def test_bad_grids_and_scores_are_refused_with_a_clear_error() -> None:
    with pytest.raises(ValueError, match="grid: must hold at least one candidate"):
        best_on_grid((), lambda c: 1.0, str)
    played: list[float] = []
    with pytest.raises(ValueError, match=r"grid: candidates share the keys \['0 ms'\]"):
        best_on_grid((0.0, 0.0001, 0.02), lambda c: played.append(c) or 1.0, v2.offset_key)
    assert played == []  # refused before any candidate is played
    with pytest.raises(ValueError, match="grid: candidate 'b' scored NaN"):
        best_on_grid(("a", "b"), lambda c: 1.0 if c == "a" else float("nan"), str)


# -- the six choosers: each plays its declared grid in order, ties to the first ------------


def _v2_play(calls: list[dict[str, Any]], catches: int) -> Any:
    def play(policy: Any, env_id: str, kwargs: dict[str, Any], split: str, n: int) -> Any:
        calls.append({"policy": policy, **kwargs, "split": split})
        return JugglingEpisodes(
            seeds=episode_seeds(split, n),
            tosses=np.full(n, 3, dtype=np.int64),
            catches=np.full(n, catches, dtype=np.int64),
            dropped=np.full(n, catches < 3),
            segment_phase=np.array(["catch"] * n),
            segment_episode=np.arange(n, dtype=np.int64),
            segment_deviation=np.linspace(0.01, 0.02, n),
        )

    return play


def _cascade_play(calls: list[dict[str, Any]], catches: int) -> Any:
    def play(policy: Any, kwargs: dict[str, Any], split: str, n: int) -> CascadeEpisodes:
        calls.append({"policy": policy, **kwargs, "split": split})
        rows = [(catches, catches + 1, True, 1.0)] * n
        return CascadeEpisodes.from_rows(episode_seeds(split, n), rows, None)

    return play


@pytest.mark.parametrize("name", ["choose_constant", "choose_offset", "choose_tracker"])
def test_v2_choosers_play_their_grid_in_order_and_keep_the_first_of_a_tie(name: str) -> None:
    grid, field = {
        "choose_constant": (v2.CONSTANT_GRID, None),
        "choose_offset": (v2.LATE_OFFSETS, "delay_offset"),
        "choose_tracker": (v2.TRACKER_GRID, "tracker_gain"),
    }[name]
    calls: list[dict[str, Any]] = []
    config = v2.V2Config(levels=("medium",), val_episodes=4)
    best, table = getattr(v2, name)("medium", config, _v2_play(calls, 2))
    assert best == grid[0] and table == dict.fromkeys(table, 2 / 3) and len(table) == len(grid)
    assert {c["split"] for c in calls} == {"val"} and len(calls) == len(grid)
    if name == "choose_constant":
        played = [(0.0, 0.0) if c["policy"] is None else tuple(c["policy"].action) for c in calls]
        assert played == list(grid)
    elif name == "choose_offset":
        assert [c[field] for c in calls] == list(grid)
    else:
        assert [(c["tracker_gain"], c["delay_offset"]) for c in calls] == list(grid)


@pytest.mark.parametrize("name", ["choose_constant", "choose_late_offset", "choose_tracker"])
def test_cascade_choosers_play_their_grid_in_order_and_keep_the_first_of_a_tie(
    name: str,
) -> None:
    grid = {
        "choose_constant": cascade_v1.CONSTANT_GRID,
        "choose_late_offset": cascade_v1.LATE_OFFSETS,
        "choose_tracker": v2.TRACKER_GRID,
    }[name]
    calls: list[dict[str, Any]] = []
    config = cascade_v1.CascadeV1Config(levels=("medium",), val_episodes=4)
    best, table = getattr(cascade_v1, name)("medium", config, _cascade_play(calls, 5))
    assert best == grid[0] and table == dict.fromkeys(table, 5.0) and len(table) == len(grid)
    assert {c["split"] for c in calls} == {"val"} and len(calls) == len(grid)
    if name == "choose_constant":
        played = [(0.0, 0.0) if c["policy"] is None else c["policy"].xz for c in calls]
    elif name == "choose_late_offset":
        played = [c.get("delay_offset", 0.0) for c in calls]
    else:
        played = [(c.get("tracker_gain", 0.0), c.get("delay_offset", 0.0)) for c in calls]
    assert played == list(grid)
