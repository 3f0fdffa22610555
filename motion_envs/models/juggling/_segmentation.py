"""Juggling recordings cut into phases by the paper's online criteria.

:func:`segment_juggling` labels one recording (hand and ball tracks) with the phases
``toss``, ``go_down``, ``catch`` and ``return`` using only causal criteria
(:mod:`motion_envs.models.segmentation`), as Lippi et al. require of the criteria that
end a phase. :func:`segment_demos` labels every unlabelled recording of a
:class:`~motion_envs.datasets.juggling.JugglingDemos`; :func:`load_juggling_csv`
reads the users' juggling CSV (:func:`motion_envs.datasets.juggling.read_juggling_csv`)
and segments it. The events are the world's rules (:mod:`motion_envs.datasets.juggling.rules`
``hand_acceleration``, ``release_fires``, ``catch_fires``) on the recorded tracks.
"""

from __future__ import annotations

import os
from dataclasses import replace
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from motion_envs._typing import FloatArray
from motion_envs.datasets.juggling import JugglingDemos, JugglingTask, read_juggling_csv, rules
from motion_envs.datasets.mocap import import_juggling, is_mocap_source, parse_source
from motion_envs.models.segmentation import EventOccurred, SpeedBelow, segment

__all__ = ["load_juggling_csv", "segment_demos", "segment_juggling"]


def _smooth(y: FloatArray, width: int) -> FloatArray:
    """Causal moving average over ``width`` samples (shorter at the start)."""
    c = np.cumsum(np.vstack([np.zeros((1, y.shape[1])), y]), axis=0)
    k = np.arange(1, len(y) + 1)
    lo = np.maximum(k - width, 0)
    return (c[k] - c[lo]) / (k - lo)[:, None]


def segment_juggling(
    t: FloatArray,
    hand: FloatArray,
    ball: FloatArray,
    task: JugglingTask | None = None,
    rest_speed: float = 0.02,
    min_elapsed: float = 0.3,
    smooth: int = 5,
) -> NDArray[np.str_]:
    """Phase labels ``(K,)`` of a recording by the paper's online criteria.

    Events, computed causally: ``release`` at sample ``k`` when the held ball's (= the
    tracked hand's) vertical acceleration ``(b_k - 2 b_{k-1} + b_{k-2}) / dt^2`` drops
    below ``-toss_threshold``; ``catch`` when the ball enters the catch radius of the
    hand (``|h_k - b_k| <= catch_radius < |h_{k-1} - b_{k-1}|``). Phases, with
    :func:`motion_envs.models.segmentation.segment`: toss ends at ``release``; go-down
    ends when the hand's speed (on a causal ``smooth``-sample moving average) is below
    ``rest_speed`` after ``min_elapsed`` s; catch ends at ``catch``; return ends like
    go-down. Samples after the last complete phase are labelled ``"none"``.
    """
    task = task or JugglingTask()
    t = np.asarray(t, dtype=np.float64)
    hand = np.asarray(hand, dtype=np.float64)
    ball = np.asarray(ball, dtype=np.float64)
    dt = np.diff(t)
    az = np.full(len(t), np.inf)
    az[2:] = rules.hand_acceleration(ball[2:, 1], ball[1:-1, 1], ball[:-2, 1], dt[1:], dt[:-1])
    dist = np.linalg.norm(hand - ball, axis=1)
    enter = np.zeros(len(t), dtype=bool)
    # the catch rule with "has left" = outside the radius at the previous sample
    enter[1:] = rules.catch_fires(dist[1:], dist[:-1] > task.catch_radius, False, task.catch_radius)
    events: dict[int, set[str]] = {}
    for k in np.flatnonzero(rules.release_fires(True, az, task.toss_threshold)):
        events.setdefault(int(k), set()).add("release")
    for k in np.flatnonzero(enter):
        events.setdefault(int(k), set()).add("catch")
    rest = SpeedBelow(threshold=rest_speed, min_elapsed=min_elapsed)
    segs = segment(
        t,
        _smooth(hand, smooth),
        [
            ("toss", EventOccurred(name="release")),
            ("go_down", rest),
            ("catch", EventOccurred(name="catch")),
            ("return", rest),
        ],
        events=events,
        window=None,
    )
    labels = np.full(len(t), "none", dtype="<U7")
    for s in segs:
        labels[s.start : s.stop] = s.name
    return labels


def segment_demos(
    demos: JugglingDemos, source: str | os.PathLike[str] | None = None
) -> JugglingDemos:
    """``demos`` with every unlabelled recording segmented by :func:`segment_juggling`.

    Labelled recordings are kept as they are. Raises ``ValueError`` (naming ``source``,
    default ``demos.name``) when a recording to segment has no ball track or when no
    complete toss, go_down, catch, return cycle is found.
    """
    where = demos.name if source is None else str(source)
    recordings = []
    for r in demos.recordings:
        if r.phase is None:
            if r.ball is None:
                raise ValueError(
                    f"{where}: recording {r.name!r} has no phase labels and no ball track; "
                    "the online criteria need the ball columns ball_x, ball_z"
                )
            r = replace(r, phase=segment_juggling(r.t, r.hand, r.ball, demos.task))
        recordings.append(r)
    out = replace(demos, recordings=tuple(recordings))
    if not out.cycles():
        raise ValueError(f"{where}: no complete toss, go_down, catch, return cycle found")
    return out


def load_juggling_csv(
    path: str | os.PathLike[str], task: JugglingTask | None = None
) -> JugglingDemos:
    """Read, check and (without a ``phase`` column) segment a juggling CSV.

    The format and the errors are those of
    :func:`motion_envs.datasets.juggling.read_juggling_csv`; recordings without
    labels are cut by :func:`segment_juggling` (errors name the file). A motion capture
    file (``.c3d``, ``.bvh``, ``.tsv``) with its options after the name,
    ``"rec.tsv?marker=HAND&balls=unlabelled"``, is imported by
    :func:`motion_envs.datasets.mocap.import_juggling` and cut the same way.
    """
    if is_mocap_source(path):
        source, options = parse_source(path)
        return segment_demos(import_juggling(source, options, task=task)[0], source)
    return segment_demos(read_juggling_csv(path, task=task), Path(path))
