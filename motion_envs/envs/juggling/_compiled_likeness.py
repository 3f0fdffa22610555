"""The hand's human-likeness search, compiled by numba: a k-d tree over each phase's
demonstrated samples (:func:`likeness_tree`) and the exact nearest distance of a point
(:func:`nearest_point`) or of many (:func:`nearest_rows`): the number
:meth:`~motion_envs.models.juggling.HumanLikeness.distance` gives, bit for bit (tested).

Importing this module imports numba (the ``fast`` extra).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numba import njit

__all__ = [
    "likeness_forest",
    "likeness_tree",
    "nearest_in_tree",
    "nearest_point",
    "nearest_rows",
]


def likeness_tree(samples: Any, leaf: int = 64) -> tuple[Any, ...]:
    """A k-d tree over one phase's samples ``(M, 4)`` for :func:`nearest_rows`: the
    samples reordered so that each node's are contiguous, split at the median of the
    node's widest coordinate. Returns ``(points (M, 4), start, stop, left, right, lo,
    hi)``: per node its samples ``points[start:stop]``, its children (-1 at a leaf) and
    its samples' bounding box. ``leaf``: most samples a leaf holds (the search's result
    does not depend on it; 48-64 searched the juggler's 2,207 samples fastest, 0.68 µs
    per point against 1.06 µs with 8)."""
    pts = np.asarray(samples, dtype=np.float64)
    order = np.arange(len(pts))
    start: list[int] = []
    stop: list[int] = []
    left: list[int] = []
    right: list[int] = []

    def build(a: int, b: int) -> int:
        node = len(start)
        start.append(a)
        stop.append(b)
        left.append(-1)
        right.append(-1)
        if b - a > leaf:
            block = pts[order[a:b]]
            axis = int(np.argmax(np.ptp(block, axis=0)))
            mid = (b - a) // 2
            order[a:b] = order[a:b][np.argsort(block[:, axis], kind="stable")]
            left[node] = build(a, a + mid)
            right[node] = build(a + mid, b)
        return node

    build(0, len(pts))
    points = np.ascontiguousarray(pts[order])
    lo = np.array([points[s:e].min(axis=0) for s, e in zip(start, stop, strict=True)])
    hi = np.array([points[s:e].max(axis=0) for s, e in zip(start, stop, strict=True)])
    as_int = np.asarray
    return (
        points,
        as_int(start, dtype=np.int64),
        as_int(stop, dtype=np.int64),
        as_int(left, dtype=np.int64),
        as_int(right, dtype=np.int64),
        lo,
        hi,
    )


@njit(cache=True)
def _box(lo: Any, hi: Any, node: int, q: Any) -> float:
    """The squared distance of ``q`` to a node's box (0 inside)."""
    s = 0.0
    for c in range(4):
        e = lo[node, c] - q[c]
        if e < 0.0:
            e = q[c] - hi[node, c]
            if e < 0.0:
                e = 0.0
        s += e * e
    return s


def likeness_forest(trees: Any) -> tuple[tuple[Any, ...], Any]:
    """The trees of :func:`likeness_tree` (one per phase) as one tree's arrays holding
    them all, and each one's root node ``(P,)``: one tuple of 7 arrays to pass to
    compiled code instead of ``7 P`` (each array costs its unboxing at every call)."""
    parts: list[list[Any]] = [[] for _ in range(7)]
    roots, nodes, points = [], 0, 0
    for pts, start, stop, left, right, lo, hi in trees:
        roots.append(nodes)
        shifted = (
            pts, start + points, stop + points, np.where(left >= 0, left + nodes, -1),
            np.where(right >= 0, right + nodes, -1), lo, hi,
        )  # fmt: skip
        for part, array in zip(parts, shifted, strict=True):
            part.append(array)
        nodes += start.shape[0]
        points += pts.shape[0]
    forest = tuple(np.ascontiguousarray(np.concatenate(part)) for part in parts)
    return forest, np.array(roots, dtype=np.int64)


@njit(cache=True)
def nearest_in_tree(tree: Any, q: Any, stack: Any, root: int = 0) -> float:
    """m; the distance of ``q (4,)`` to the nearest sample of ``tree``
    (:func:`likeness_tree`; or of the tree at node ``root`` of a
    :func:`likeness_forest`), ``inf`` where not finite (:func:`nearest_rows`' search;
    ``stack``: the search's node stack, 256 entries)."""
    pts, start, stop, left, right, lo, hi = tree
    q0, q1, q2, q3 = q[0], q[1], q[2], q[3]
    if not (math.isfinite(q0) and math.isfinite(q1) and math.isfinite(q2)):
        return math.inf
    if not math.isfinite(q3):
        return math.inf
    best = math.inf
    stack[0] = root
    top = 1
    while top > 0:
        top -= 1
        node = stack[top]
        if _box(lo, hi, node, q) > best * (1.0 + 1e-9):
            continue
        a, b = left[node], right[node]
        if a < 0:
            for m in range(start[node], stop[node]):
                e0, e1 = pts[m, 0] - q0, pts[m, 1] - q1
                e2, e3 = pts[m, 2] - q2, pts[m, 3] - q3
                s = ((e0 * e0 + e1 * e1) + e2 * e2) + e3 * e3
                if s < best:
                    best = s
            continue
        # the nearer child last (searched first)
        if _box(lo, hi, a, q) <= _box(lo, hi, b, q):
            stack[top], stack[top + 1] = b, a
        else:
            stack[top], stack[top + 1] = a, b
        top += 2
    d = math.sqrt(best)
    return d if math.isfinite(d) else math.inf


@njit(cache=True)
def nearest_point(
    pts: Any, start: Any, stop: Any, left: Any, right: Any, lo: Any, hi: Any, q: Any, stack: Any
) -> float:
    """:func:`nearest_in_tree` of one point ``q (4,)`` in the tree :func:`likeness_tree` returned
    (its arrays passed one by one: a tuple costs more to pass from Python than the
    search)."""
    return nearest_in_tree((pts, start, stop, left, right, lo, hi), q, stack)


@njit(cache=True)
def nearest_rows(points: Any, phase: Any, trees: Any) -> Any:
    """m; per row ``j`` of ``points (m, 4)``, the distance to the nearest demonstrated
    sample of phase ``phase[j]``: :meth:`HumanLikeness.distance`'s number (the squared
    differences summed in coordinate order as the k-d tree sums them, the least one's
    square root; ``inf`` where not finite). ``trees``: per phase :func:`likeness_tree`.
    A node is skipped when its box is farther than the best sum with a margin of 1e-9
    against rounding (a sample's sum is at least its box's): exact."""
    out = np.empty(points.shape[0])
    stack = np.empty(256, dtype=np.int64)
    for j in range(points.shape[0]):
        out[j] = nearest_in_tree(trees[phase[j]], points[j], stack)
    return out
