"""pandas exports: recordings, predictions and segments as long tables.

Long format (one row per sample) is what seaborn, statsmodels' formulas and per-subject
``groupby`` summaries expect. Other results export themselves:
:meth:`motion_envs.datasets.ragged.RaggedTrajectories.to_frame` and
:meth:`motion_envs.models.sine_regression.LinearHypothesisReport.to_frame`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from motion_envs.geometry.resampling import recording_times
from motion_envs.models.segmentation import Segment

if TYPE_CHECKING:
    import pandas as pd

__all__ = ["segments_frame", "trajectories_frame"]


def trajectories_frame(
    positions: Sequence[ArrayLike],
    times: Sequence[ArrayLike] | None = None,
    *,
    rate: float | None = None,
    labels: Mapping[str, ArrayLike] | None = None,
    columns: Sequence[str] | None = None,
) -> pd.DataFrame:
    """One row per sample of ``positions[i]`` ``(n_i, D)``.

    Columns: ``trajectory`` (``i``), ``sample``, ``t`` (seconds, from ``times`` or
    ``rate``), ``tau`` (normalised time), one column per label (``labels[name]`` has one
    value per trajectory, e.g. ``{"subject": ..., "task": ...}``), then the coordinates
    (``columns``, default ``x``, ``y``, ``z`` for ``D = 3``, else ``y0 .. y{D-1}``).
    """
    import pandas as pd

    ts = recording_times(positions, times, rate)
    ys = [
        np.asarray(y, dtype=np.float64).reshape(len(t), -1)
        for y, t in zip(positions, ts, strict=True)
    ]
    dims = ys[0].shape[1]
    names = (
        list(columns)
        if columns is not None
        else (["x", "y", "z"] if dims == 3 else [f"y{d}" for d in range(dims)])
    )
    if len(names) != dims:
        raise ValueError(f"columns must name the {dims} coordinates; got {names}")
    lengths = np.array([len(t) for t in ts])
    traj = np.repeat(np.arange(len(ts)), lengths)
    data: dict[str, object] = {
        "trajectory": traj,
        "sample": np.concatenate([np.arange(n) for n in lengths]),
        "t": np.concatenate(ts),
        "tau": np.concatenate([(t - t[0]) / (t[-1] - t[0]) for t in ts]),
    }
    for name, values in (labels or {}).items():
        v = np.asarray(values)
        if v.shape[:1] != (len(ts),):
            raise ValueError(f"labels[{name!r}] must have one value per trajectory ({len(ts)})")
        data[name] = v[traj]
    stacked = np.concatenate(ys)
    for d, name in enumerate(names):
        data[name] = stacked[:, d]
    return pd.DataFrame(data)


def segments_frame(segments: Sequence[Segment], times: ArrayLike | None = None) -> pd.DataFrame:
    """One row per :class:`~motion_envs.models.segmentation.Segment`: ``name``, ``start``,
    ``stop`` (sample indices) and, with the recording's ``times``, ``t_start``, ``t_stop``,
    ``duration`` (seconds)."""
    import pandas as pd

    frame = pd.DataFrame(
        {
            "name": [s.name for s in segments],
            "start": np.array([s.start for s in segments], dtype=np.int64),
            "stop": np.array([s.stop for s in segments], dtype=np.int64),
        }
    )
    if times is not None:
        t = np.asarray(times, dtype=np.float64)
        frame["t_start"] = t[frame["start"].to_numpy()]
        frame["t_stop"] = t[frame["stop"].to_numpy()]
        frame["duration"] = frame["t_stop"] - frame["t_start"]
    return frame
