"""From a :class:`MocapRecording` to the project's three data kinds.

Order of the steps (each documented in ``docs/recordings.md``): read (units to metres)
-> the file's up axis to the project's Z-up -> the track (a marker or joint position, a
marker-triad or joint orientation; quaternions made sign-continuous first) -> gaps
(short ones filled, long ones split) -> movements (speed threshold or a segments table)
-> :class:`~motion_envs.datasets.OrientationDataset`,
:class:`~motion_envs.datasets.PositionDataset` or unlabelled
:class:`~motion_envs.datasets.juggling.JugglingDemos` (cut into cycles by
:func:`motion_envs.models.juggling.segment_demos`). Every sample keeps its
time from the start of the file.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from motion_envs._typing import FloatArray
from motion_envs.datasets.juggling import JugglingDemos, JugglingRecording, JugglingTask
from motion_envs.datasets.mocap._balls import assemble_balls
from motion_envs.datasets.mocap._gaps import GapCounts, Piece, fill_gaps
from motion_envs.datasets.mocap._options import ImportOptions
from motion_envs.datasets.mocap._readers import read_recording
from motion_envs.datasets.mocap._recording import MocapRecording
from motion_envs.datasets.mocap._segments import read_segments, speed, speed_segments
from motion_envs.datasets.orientation import OrientationDataset
from motion_envs.datasets.position_csv import PositionDataset
from motion_envs.datasets.ragged import MIN_SAMPLES
from motion_envs.datasets.sample_table import replicate_numbers
from motion_envs.geometry import quaternion as quat

__all__ = [
    "YUP_TO_ZUP",
    "ImportReport",
    "Movement",
    "import_juggling",
    "import_orientation",
    "import_position",
    "triad_quaternions",
]

#: Rotation taking a Y-up world to the project's Z-up one: ``(x, y, z) -> (x, -z, y)``
#: (+90 degrees about x; the file's forward ``+z`` becomes ``-y``).
YUP_TO_ZUP = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])


@dataclass(frozen=True)
class ImportReport:
    """What an import did (printed by ``motion-bench import``)."""

    source: str
    n_frames: int
    rate: float
    gaps: GapCounts
    movements: int
    short_dropped: int = 0
    balls: dict[str, int] = field(default_factory=dict)
    first_frame: int = 0

    def lines(self) -> list[str]:
        g = self.gaps
        start = self.first_frame / self.rate
        out = [
            f"{self.source}: {self.n_frames} frames at {self.rate:.10g} Hz "
            f"({self.n_frames / self.rate:.3f} s"
            + (
                f"; first frame {self.first_frame} counted from 0: t from {start:.6g} s"
                if self.first_frame
                else ""
            )
            + ")",
            f"samples missing {g.missing}, filled {g.filled}, dropped {g.dropped}; "
            f"{g.pieces} gap-free piece(s)",
            f"{self.movements} movement(s)"
            + (
                f"; {self.short_dropped} shorter than --min-duration dropped"
                if self.short_dropped
                else ""
            ),
        ]
        if self.balls:
            out.append("balls: " + ", ".join(f"{k} {v}" for k, v in self.balls.items()))
        return out


@dataclass(frozen=True)
class Movement:
    """One imported trajectory: labels, times from the start of the file, values."""

    trajectory: str
    subject: str
    task: str
    t: FloatArray
    values: FloatArray


def _markers_used(opts: ImportOptions) -> tuple[str, ...]:
    """The C3D markers an import reads (the others are not kept in memory)."""
    names = [opts.marker, *(opts.markers or ()), opts.ball, *(opts.relative_to or ())]
    return tuple(n for n in names if n is not None)


def _to_zup(points: FloatArray, up: str) -> FloatArray:
    if up == "z":
        return points
    out: FloatArray = points @ YUP_TO_ZUP.T
    return out


def triad_quaternions(
    origin: FloatArray, x_marker: FloatArray, plane: FloatArray
) -> tuple[FloatArray, NDArray[np.bool_]]:
    """Orientation ``(F, 4)`` ``(w, x, y, z)`` of the frame of three rigid markers.

    ``e_x`` points from ORIGIN to X; ``e_z = e_x x (PLANE - ORIGIN)`` normalised (normal
    to the markers' plane, PLANE on the ``+y`` side); ``e_y = e_z x e_x``. The rotation
    has columns ``e_x, e_y, e_z`` (body to world). Frames with a missing marker or three
    (nearly) collinear markers are not valid (``(F,)`` mask; their rows are identity).
    """
    ex = x_marker - origin
    v = plane - origin
    ez = np.cross(ex, v)
    nx = np.linalg.norm(ex, axis=1)
    nz = np.linalg.norm(ez, axis=1)
    with np.errstate(invalid="ignore"):
        valid = np.isfinite(nz) & (nz > 1e-12 * np.maximum(nx * np.linalg.norm(v, axis=1), 1e-300))
    q = np.tile([1.0, 0.0, 0.0, 0.0], (origin.shape[0], 1))
    if valid.any():
        ex_v = ex[valid] / nx[valid, None]
        ez_v = ez[valid] / nz[valid, None]
        ey_v = np.cross(ez_v, ex_v)
        rot = np.stack([ex_v, ey_v, ez_v], axis=-1)
        q[valid] = quat.from_rotation(Rotation.from_matrix(rot))
    return q, valid


def _position(
    rec: MocapRecording, opts: ImportOptions, name: str | None, role: str
) -> tuple[FloatArray, NDArray[np.bool_]]:
    what = "joint" if rec.fmt == "bvh" else "marker"
    if name is None:
        option = "--joint" if rec.fmt == "bvh" else ("--ball" if role == "ball" else "--marker")
        raise ValueError(f"{rec.path}: give the {role} {what} ({option} NAME)")
    if rec.fmt == "bvh" and rec.scale is None:
        raise ValueError(
            f"{rec.path}: BVH lengths carry no unit; give --unit (m, cm, mm, in or metres per unit)"
        )
    j = rec.index(name, what)
    present = ~rec.missing()[:, j]
    if not present.any():
        raise ValueError(f"{rec.path}: {what} {name!r} has no sample (all missing)")
    return _to_zup(rec.points[:, j], opts.up), present


def _frame(
    rec: MocapRecording, opts: ImportOptions, names: tuple[str, ...]
) -> tuple[FloatArray, NDArray[np.bool_]]:
    """World orientation (Z-up) of a BVH joint (one name) or a marker triad (three names)."""
    if rec.fmt == "bvh":
        assert rec.quaternions is not None
        q = rec.quaternions[:, rec.index(names[0], "joint")]
        if opts.up == "y":
            turn = quat.from_rotation(Rotation.from_matrix(YUP_TO_ZUP))
            q = quat.multiply(np.broadcast_to(turn, q.shape), q)
        return q, np.ones(q.shape[0], dtype=bool)
    idx = [rec.index(m) for m in names]
    miss = rec.missing()
    for m, j in zip(names, idx, strict=True):
        if miss[:, j].all():
            raise ValueError(f"{rec.path}: marker {m!r} has no sample (all missing)")
    pts = _to_zup(rec.points[:, idx], opts.up)
    q, valid = triad_quaternions(pts[:, 0], pts[:, 1], pts[:, 2])
    return q, valid & ~miss[:, idx].any(axis=1)


def _orientation(rec: MocapRecording, opts: ImportOptions) -> tuple[FloatArray, NDArray[np.bool_]]:
    """The imported orientation, relative to ``opts.relative_to`` when given.

    Relative: ``q_ref* q`` (the body's orientation in the reference frame), present
    where both are; sign-continuous over the present samples.
    """
    names: tuple[str, ...]
    if rec.fmt == "bvh":
        if opts.joint is None:
            raise ValueError(f"{rec.path}: give the joint whose orientation is imported (--joint)")
        names = (opts.joint,)
    else:
        if opts.markers is None:
            raise ValueError(
                f"{rec.path}: give the three rigid markers of the orientation "
                "(--markers ORIGIN,X,PLANE)"
            )
        names = opts.markers
    q, valid = _frame(rec, opts, names)
    if opts.relative_to is not None:
        want = 1 if rec.fmt == "bvh" else 3
        if len(opts.relative_to) != want:
            raise ValueError(
                f"{rec.path}: --relative-to needs {'one joint' if want == 1 else 'three markers'}"
            )
        q_ref, valid_ref = _frame(rec, opts, opts.relative_to)
        q = quat.multiply(quat.conjugate(q_ref), q)
        valid &= valid_ref
    if not valid.any():
        raise ValueError(
            f"{rec.path}: the markers of the orientation are never all present together"
        )
    q[valid] = quat.make_continuous(q[valid])
    return q, valid


def _movements(
    rec: MocapRecording, pieces: list[Piece], opts: ImportOptions, rotation: bool | None
) -> tuple[list[Movement], int]:
    """Cut the pieces into movements (``rotation`` None: no speed rule, e.g. juggling)."""
    stem = rec.path.stem
    subject = opts.subject or stem
    spans: list[tuple[Piece, int, int, str | None, str | None, str | None]] = []
    short = 0
    if opts.segments is not None:
        half = 0.5 / rec.rate  # a row's times are rounded to the nearest frame (C3D
        # EVENT:TIMES are float32: 3.39 s is stored as 3.3900001)
        for row in read_segments(opts.segments):
            piece = next(
                (p for p in pieces if p.t[0] <= row.start + half and row.end <= p.t[-1] + half),
                None,
            )
            if piece is None:
                raise ValueError(
                    f"{opts.segments}: line {row.line}: {row.start:g} to {row.end:g} s is not "
                    f"inside one gap-free piece of {rec.path}"
                )
            # the samples with row.start - half < t < row.end + half (piece.t increases)
            first = int(np.searchsorted(piece.t, row.start - half, side="right"))
            stop = int(np.searchsorted(piece.t, row.end + half, side="left"))
            inside = np.arange(first, stop)
            if inside.size < MIN_SAMPLES:
                raise ValueError(
                    f"{opts.segments}: line {row.line}: fewer than {MIN_SAMPLES} samples"
                )
            spans.append(
                (piece, int(inside[0]), int(inside[-1]), row.subject, row.task, row.trajectory)
            )
    elif opts.speed_threshold is not None and rotation is not None:
        for piece in pieces:
            s = speed(piece.t, piece.values, rotation)
            found, n_short = speed_segments(
                piece.t, s, opts.speed_threshold, opts.min_duration, opts.min_pause
            )
            short += n_short
            spans.extend(
                (piece, a, b, None, None, None) for a, b in found if b - a + 1 >= MIN_SAMPLES
            )
            short += sum(1 for a, b in found if b - a + 1 < MIN_SAMPLES)
    else:
        spans = [(p, 0, len(p.t) - 1, None, None, None) for p in pieces]
    out = []
    for k, (piece, a, b, subj, task, name) in enumerate(spans):
        out.append(
            Movement(
                trajectory=name or f"{stem}-{k:03d}",
                subject=subj or subject,
                task=task or opts.task,
                t=piece.t[a : b + 1],
                values=piece.values[a : b + 1],
            )
        )
    if not out:
        raise ValueError(f"{rec.path}: no movement of at least {MIN_SAMPLES} samples found")
    return out, short


def _trajectories(
    rec: MocapRecording,
    values: FloatArray,
    present: NDArray[np.bool_],
    opts: ImportOptions,
    rotation: bool,
) -> tuple[
    list[Movement], tuple[NDArray[np.str_], NDArray[np.str_], NDArray[np.str_]], ImportReport
]:
    """Gaps, then movements: the movements, their (ids, subjects, tasks) and the report."""
    pieces, counts = fill_gaps(rec.t, values, present, opts.max_gap, rotation=rotation)
    moves, short = _movements(rec, pieces, opts, rotation=rotation)
    ids = np.array([m.trajectory for m in moves], dtype=str)
    if len(set(ids.tolist())) != ids.size:
        raise ValueError(f"{rec.path}: trajectory names in the segments table are not unique")
    subjects = np.array([m.subject for m in moves], dtype=str)
    tasks = np.array([m.task for m in moves], dtype=str)
    report = ImportReport(
        str(rec.path), rec.n_frames, rec.rate, counts, len(moves), short,
        first_frame=rec.first_frame,
    )  # fmt: skip
    return moves, (ids, subjects, tasks), report


def import_orientation(
    path: str | os.PathLike[str], options: ImportOptions | None = None
) -> tuple[OrientationDataset, ImportReport]:
    """An orientation dataset from a C3D/TSV marker triad or a BVH joint (see the module)."""
    opts = options or ImportOptions()
    rec = read_recording(path, opts.unit, _markers_used(opts))
    q, present = _orientation(rec, opts)
    moves, (ids, subjects, tasks), rep = _trajectories(rec, q, present, opts, rotation=True)
    ds = OrientationDataset(
        name=rec.path.name,
        quaternions=tuple(quat.make_continuous(m.values) for m in moves),
        times=tuple(m.t for m in moves),
        trajectory_ids=ids,
        subjects=subjects,
        tasks=tasks,
        replicates=replicate_numbers(subjects, tasks),
    )
    return ds, rep


def import_position(
    path: str | os.PathLike[str], options: ImportOptions | None = None
) -> tuple[PositionDataset, ImportReport]:
    """A 3-D position dataset (metres, Z-up) from a C3D/TSV marker or a BVH joint."""
    opts = options or ImportOptions()
    rec = read_recording(path, opts.unit, _markers_used(opts))
    name = opts.joint if rec.fmt == "bvh" else opts.marker
    y, present = _position(rec, opts, name, "position")
    moves, (ids, subjects, tasks), rep = _trajectories(rec, y, present, opts, rotation=False)
    ds = PositionDataset(
        name=rec.path.name,
        positions=tuple(m.values for m in moves),
        times=tuple(m.t for m in moves),
        trajectory_ids=ids,
        subjects=subjects,
        tasks=tasks,
        replicates=replicate_numbers(subjects, tasks),
        unit="m",
    )
    return ds, rep


def import_juggling(
    path: str | os.PathLike[str],
    options: ImportOptions | None = None,
    task: JugglingTask | None = None,
) -> tuple[JugglingDemos, ImportReport]:
    """Unlabelled juggling recordings (hand and ball in the vertical plane, metres).

    The hand is ``--marker`` (C3D/TSV) or ``--joint`` (BVH); the ball is ``--ball``, or
    with ``--balls unlabelled`` (Qualisys TSV) the flights assembled from the unlabelled
    fragments. The plane's ``x`` is the ``--lateral`` axis, its ``z`` the vertical. Frames
    where hand or ball is missing are gaps (filled up to ``--max-gap``, else split). The
    recordings have no phase labels: cut them into cycles with
    :func:`motion_envs.models.juggling.segment_demos`.
    """
    opts = options or ImportOptions()
    rec = read_recording(path, opts.unit, _markers_used(opts))
    hand_name = opts.joint if rec.fmt == "bvh" else opts.marker
    hand, hand_ok = _position(rec, opts, hand_name, "hand")
    ball_counts: dict[str, int] = {}
    if opts.balls == "unlabelled":
        cols = [j for j, name in enumerate(rec.labels) if not name]
        if not cols:
            raise ValueError(
                f"{rec.path}: --balls unlabelled needs unlabelled trajectories; the file has none"
            )
        ball, ball_ok, ball_counts = assemble_balls(
            rec.t, _to_zup(rec.points[:, cols], opts.up), str(rec.path)
        )
    else:
        ball, ball_ok = _position(rec, opts, opts.ball, "ball")
    lateral = 0 if opts.lateral == "x" else 1
    both = np.concatenate([hand[:, [lateral, 2]], ball[:, [lateral, 2]]], axis=1)
    pieces, counts = fill_gaps(rec.t, both, hand_ok & ball_ok, opts.max_gap, rotation=False)
    moves, short = _movements(rec, pieces, opts, rotation=None)
    recordings = tuple(
        JugglingRecording(
            name=m.trajectory, t=m.t, hand=m.values[:, :2], ball=m.values[:, 2:], person=m.subject
        )
        for m in moves
    )
    demos = JugglingDemos(
        name=rec.path.name, recordings=recordings, simulated=False, task=task or JugglingTask()
    )
    report = ImportReport(
        str(rec.path), rec.n_frames, rec.rate, counts, len(moves), short, ball_counts,
        rec.first_frame,
    )  # fmt: skip
    return demos, report
