"""The validation-grid choice shared by the juggling benches' choosers.

Juggling-v2's rows (:mod:`baselines.juggling_bench.v2`: the constant, the late offset,
the tracker's pair) and Cascade-v1's (:mod:`baselines.juggling_bench.cascade_v1`: the
same three) each pick one candidate of a declared grid by its score on VALIDATION
episodes. :func:`best_on_grid` is that choice, once: every candidate scored in grid
order, the highest score kept, ties broken to the first in grid order.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import TypeVar

__all__ = ["best_on_grid"]

T = TypeVar("T")


def best_on_grid(
    grid: Sequence[T], score: Callable[[T], float], key: Callable[[T], str]
) -> tuple[T, dict[str, float]]:
    """The candidate of ``grid`` with the highest ``score`` and every candidate's score,
    keyed by ``key`` in grid order.

    Each candidate is scored exactly once, in grid order (``score`` plays it on the
    VALIDATION episodes); an exception from ``score`` propagates and no later candidate
    is scored. Ties: the first in grid order (a later candidate replaces the best only
    with a strictly higher score). The chosen candidate is the grid's own element and
    the scores are ``score``'s values, unconverted. ``ValueError`` for an empty grid,
    two candidates with one key (checked before any is scored) or a NaN score (which
    no ordering could rank)."""
    if len(grid) == 0:
        raise ValueError("grid: must hold at least one candidate; got an empty grid")
    keys = [key(candidate) for candidate in grid]
    if len(set(keys)) < len(keys):
        repeated = sorted({k for k in keys if keys.count(k) > 1})
        raise ValueError(f"grid: candidates share the keys {repeated}")
    scores: dict[str, float] = {}
    best, best_score = grid[0], -math.inf
    for i, (k, candidate) in enumerate(zip(keys, grid, strict=True)):
        value = score(candidate)
        if math.isnan(value):
            raise ValueError(f"grid: candidate {k!r} scored NaN")
        scores[k] = value
        if i == 0 or value > best_score:
            best, best_score = candidate, value
    return best, scores
