"""The users' juggling CSV: hand-tracker recordings of the paper's toss-and-catch task.

Format (one row per sample, header required, extra columns ignored)::

    t, x, z[, ball_x, ball_z][, phase][, recording]

* ``t``: time in s, strictly increasing within a recording (a 200 Hz tracker in the
  paper; any rate works).
* ``x, z``: hand position in m (``x`` horizontal, positive to the right; ``z`` up).
* ``ball_x, ball_z`` (optional, both or neither): the (virtual) ball's centre in m; while
  the ball is held it equals the hand position the virtual world saw.
* ``phase`` (optional): ``toss``, ``go_down``, ``catch`` or ``return`` on every row.
  Without it :func:`read_juggling_csv` returns the raw recordings (``phase`` None) and
  :func:`motion_envs.models.juggling.load_juggling_csv` segments them by
  the paper's online criteria, which need the ball columns.
* ``recording`` (optional): an identifier; the rows of one recording are contiguous.

Errors are one line naming the file and the physical line numbers (the header is line 1;
blank lines and multi-line quoted fields counted), as the other users' CSV formats (the
one front end :func:`motion_envs.datasets.sample_table.read_csv_text`): a missing file is
``FileNotFoundError``; a folder, an empty, binary (NUL bytes), non-UTF-8 or malformed
file, NaN/inf/non-numeric values, ``|t|`` beyond ``MAX_ABS_TIME`` (10^10 s) or a
position beyond :data:`MAX_ABS_JUGGLING_POSITION` (10^3 m: a tracker in a room, a ball
tossed 10 m up) are ``ValueError``. Labels (``phase``, ``recording``) are text: only an
empty label is missing, ``NA`` or ``None`` are recording names.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from motion_envs.datasets.juggling._records import JugglingDemos, JugglingRecording
from motion_envs.datasets.juggling._task import PHASES, JugglingTask
from motion_envs.datasets.sample_table import (
    fail_rows,
    missing_columns_message,
    numeric_columns,
    read_csv_text,
    write_csv,
)

__all__ = [
    "JUGGLING_COLUMNS",
    "MAX_ABS_JUGGLING_POSITION",
    "MIN_SAMPLES",
    "read_juggling_csv",
    "write_juggling_csv",
]

#: Required columns of the juggling CSV.
JUGGLING_COLUMNS: tuple[str, ...] = ("t", "x", "z")

#: Largest plausible ``|x|``, ``|z|``, ``|ball_x|``, ``|ball_z|`` in m.
MAX_ABS_JUGGLING_POSITION = 1e3

#: Label columns (text; only an empty label is missing).
_LABELS = ("phase", "recording")

#: Samples fewer than this in a recording are rejected.
MIN_SAMPLES = 20


def _fail(path: Path, mask: NDArray[np.bool_], what: str) -> None:
    fail_rows(path, mask, what)


def read_juggling_csv(
    path: str | os.PathLike[str], task: JugglingTask | None = None
) -> JugglingDemos:
    """Read and check a juggling CSV (format above): the recordings as they are.

    Without a ``phase`` column the recordings are returned unlabelled (``phase`` None);
    :func:`motion_envs.models.juggling.load_juggling_csv` reads and segments
    them by the paper's online criteria. Raises ``FileNotFoundError`` for a missing file
    and ``ValueError`` naming the file and the line numbers of the bad rows (or, for a
    labelled file, that it holds no complete cycle).
    """
    task = task or JugglingTask()
    p = Path(path)
    frame = read_csv_text(p, "juggling", _LABELS)
    missing = [c for c in JUGGLING_COLUMNS if c not in frame.columns]
    if missing:
        expected = "t,x,z[,ball_x,ball_z][,phase]"
        raise ValueError(missing_columns_message(str(p), frame.columns, missing, expected))
    if len(frame) == 0:
        raise ValueError(f"{p}: no data rows")
    has_ball = [c in frame.columns for c in ("ball_x", "ball_z")]
    if any(has_ball) and not all(has_ball):
        raise ValueError(f"{p}: ball_x and ball_z must both be present or both absent")
    numeric = [*JUGGLING_COLUMNS, *(["ball_x", "ball_z"] if all(has_ball) else [])]
    data = numeric_columns(p, frame, numeric, MAX_ABS_JUGGLING_POSITION, "m")
    if "phase" in frame.columns:
        lab = frame["phase"].to_numpy(dtype=object)
        wrong = ~np.isin(lab.astype(str), PHASES) | pd.isna(frame["phase"]).to_numpy()
        if wrong.any():
            _fail(p, wrong, f"phase must be one of {', '.join(PHASES)}")
    if "recording" in frame.columns:
        if frame["recording"].isna().any():
            _fail(p, frame["recording"].isna().to_numpy(), "empty 'recording'")
        rec = frame["recording"].to_numpy(dtype=str)
    else:
        rec = np.full(len(frame), p.stem)
    starts = np.flatnonzero(np.concatenate([[True], rec[1:] != rec[:-1]]))
    ids = rec[starts]
    if len(set(ids)) != len(ids):
        dup = pd.Series(ids)[pd.Series(ids).duplicated()].iloc[0]
        again = starts[ids == dup][1:]
        _fail(p, np.isin(np.arange(len(frame)), again), f"recording {dup!r} is not contiguous")
    ends = np.concatenate([starts[1:], [len(frame)]])
    short = np.isin(np.arange(len(frame)), starts[(ends - starts) < MIN_SAMPLES])
    if short.any():
        _fail(p, short, f"recording with fewer than {MIN_SAMPLES} samples starts")
    same = np.concatenate([[False], rec[1:] == rec[:-1]])
    unsorted = same & np.concatenate([[False], np.diff(data[:, 0]) <= 0])
    if unsorted.any():
        _fail(p, unsorted, "time not strictly increasing within its recording")
    if "phase" not in frame.columns and not all(has_ball):
        raise ValueError(
            f"{p}: without a 'phase' column the recording is segmented by the online "
            "criteria, which need the ball columns ball_x, ball_z"
        )
    recordings = []
    for s, e, name in zip(starts, ends, ids, strict=True):
        t = data[s:e, 0]
        hand = data[s:e, 1:3]
        ball = data[s:e, 3:5] if all(has_ball) else None
        phase = frame["phase"].to_numpy(dtype=str)[s:e] if "phase" in frame.columns else None
        recordings.append(
            JugglingRecording(
                name=str(name), t=t - t[0], hand=hand, ball=ball, phase=phase, person=str(name)
            )
        )
    demos = JugglingDemos(name=p.name, recordings=tuple(recordings), simulated=False, task=task)
    if "phase" in frame.columns and not demos.cycles():
        raise ValueError(f"{p}: no complete toss, go_down, catch, return cycle found")
    return demos


def write_juggling_csv(
    demos: JugglingDemos, path: str | os.PathLike[str], phase: bool = True
) -> Path:
    """Write ``demos`` in the CSV format above (atomic; ``phase=False`` drops the labels)."""
    frames = []
    for r in demos.recordings:
        cols: dict[str, object] = {"t": r.t, "x": r.hand[:, 0], "z": r.hand[:, 1]}
        if r.ball is not None:
            cols.update(ball_x=r.ball[:, 0], ball_z=r.ball[:, 1])
        if phase and r.phase is not None:
            cols["phase"] = r.phase
        cols["recording"] = r.name
        frames.append(pd.DataFrame(cols))
    return write_csv(frames, path)
