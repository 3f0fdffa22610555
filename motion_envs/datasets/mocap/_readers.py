"""Readers: C3D through ezc3d, BVH through pybvh, Qualisys TSV 3D exports as text.

No binary C3D parser and no BVH grammar are written here: ezc3d reads C3D (points as
numpy, NaN for missing markers, residuals kept) and pybvh reads BVH (each joint's Euler
order from its CHANNELS line, forward kinematics). Every error is a ``ValueError`` that
names the file, in one line.
"""

from __future__ import annotations

import io
import math
import multiprocessing
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from scipy.spatial.transform import Rotation

from motion_envs._io import check_regular_file
from motion_envs._typing import FloatArray
from motion_envs.datasets.mocap._bounds import check_rate, check_unique_names
from motion_envs.datasets.mocap._options import MAX_RECORDING_BYTES, UNITS, unit_scale
from motion_envs.datasets.mocap._recording import MocapRecording
from motion_envs.geometry import quaternion as quat

__all__ = ["read_bvh", "read_c3d", "read_qualisys_tsv", "read_recording"]

_EXTRA = 'install the readers with  pip install "motion-envs[mocap]"'
#: Qualisys labels of trajectories that were not identified (unlabelled fragments).
_UNLABELLED_PREFIXES = ("unidentified", "unlabeled", "unlabelled", "unnamed")


def _unit_scale(path: Path, unit: str) -> float:
    try:
        return unit_scale(unit)
    except ValueError:
        raise ValueError(
            f"{path}: unknown length unit {unit!r}; give --unit ({', '.join(UNITS)}, or the "
            "metres per file unit as a number)"
        ) from None


def _c3d_fields(path: str, markers: Sequence[str] | None = None) -> dict[str, Any]:
    """What the import needs of a C3D file, read by ezc3d (in the guarded child): every
    label, and the points and residuals of ``markers`` (None: all) that the file has."""
    import ezc3d

    c3d = ezc3d.c3d(path)
    params = c3d["parameters"]["POINT"]
    labels: list[str] = []
    for key in ("LABELS", *(f"LABELS{i}" for i in range(2, 100))):
        if key not in params:
            break
        labels.extend(str(x).strip() for x in params[key]["value"])
    units = params["UNITS"]["value"] if "UNITS" in params else []
    raw = c3d["data"]["points"]
    labels = labels[: raw.shape[1]] + [f"point{i}" for i in range(len(labels), raw.shape[1])]
    keep = list(range(raw.shape[1]))
    if markers is not None:
        keep = [labels.index(m) for m in dict.fromkeys(markers) if m in labels]
    meta = c3d["data"].get("meta_points", {})
    residuals = meta.get("residuals")
    return {
        "rate": float(c3d["header"]["points"]["frame_rate"]),
        "first_frame": int(c3d["header"]["points"]["first_frame"]),
        "labels": labels,
        "kept": [labels[j] for j in keep],
        "n_frames": int(raw.shape[2]),
        "unit": str(units[0]) if len(units) else "mm",
        # (F, M, 3) as the import uses it; the transpose is done here, once
        "points": np.ascontiguousarray(raw[:3, keep].transpose(2, 1, 0), dtype=np.float64),
        "residuals": None
        if residuals is None or np.shape(residuals)[1:] != raw.shape[1:]
        else np.ascontiguousarray(residuals[0, keep].T, dtype=np.float64),
    }


def _c3d_child(path: str, markers: Sequence[str] | None, conn: Any) -> None:
    try:
        conn.send(_c3d_fields(path, markers))
    except Exception as exc:  # reported to the parent as one line
        conn.send(f"{type(exc).__name__}: {' '.join(str(exc).split())}")
    finally:
        conn.close()


def _read_c3d_guarded(path: Path, markers: Sequence[str] | None) -> dict[str, Any]:
    """:func:`_c3d_fields` in a forked child process, so that a corrupt file that crashes
    ezc3d (it can end the process with a segmentation fault) becomes a ``ValueError``.

    Without ``fork`` (Windows) ezc3d runs in this process.
    """
    if not hasattr(os, "fork"):  # pragma: no cover - Linux and macOS fork
        try:
            return _c3d_fields(str(path), markers)
        except (OSError, RuntimeError, ValueError, IndexError) as exc:
            raise ValueError(
                f"{path}: not a readable C3D file ({' '.join(str(exc).split())})"
            ) from None
    ctx = multiprocessing.get_context("fork")
    receive, send = ctx.Pipe(duplex=False)
    child = ctx.Process(target=_c3d_child, args=(str(path), markers, send), daemon=True)
    child.start()
    send.close()
    try:
        result: dict[str, Any] | str | None = receive.recv()
    except EOFError:
        result = None
    finally:
        receive.close()
        child.join()
    if result is None:
        raise ValueError(
            f"{path}: not a readable C3D file (ezc3d stopped with exit code {child.exitcode})"
        )
    if isinstance(result, str):
        raise ValueError(f"{path}: not a readable C3D file ({result})")
    return result


def read_c3d(
    path: str | Path, unit: str | None = None, markers: Sequence[str] | None = None
) -> MocapRecording:
    """Read the 3D points of a C3D file with ezc3d (``unit`` overrides ``POINT:UNITS``).

    ``markers``: keep only these (None: all); a name the file lacks raises
    ``ValueError`` listing the file's labels. Missing samples are NaN (ezc3d sets them
    for negative residuals; residuals are kept). The first frame's time is the header's
    first frame (ezc3d's ``header.points.first_frame``, counted from 0) over the rate, so
    that the file's own times (``EVENT:TIMES``, a cropped trial's frames) line up with
    :attr:`MocapRecording.t`. ezc3d runs in a forked child process: a
    corrupt file can crash it. Raises ``ValueError`` naming the file when it is not a
    C3D file, is truncated (fewer frames than its header announces), has no points, or
    a frame rate that is not > 0.
    """
    p = Path(path)
    try:
        import ezc3d  # noqa: F401  (imported here so that the child does not import it)
    except ImportError:  # pragma: no cover - the extra is installed in the tests
        raise ValueError(f"{p}: reading C3D needs ezc3d; {_EXTRA}") from None
    fields = _read_c3d_guarded(p, markers)
    rate = check_rate(p, fields["rate"], "C3D header")
    points = fields["points"]
    expected = _announced_frames(p)
    if expected is not None and fields["n_frames"] < expected:
        raise ValueError(
            f"{p}: truncated C3D file: {fields['n_frames']} of the {expected} frames its "
            "header announces"
        )
    if fields["n_frames"] == 0 or not fields["labels"]:
        raise ValueError(f"{p}: the C3D file holds no 3D points")
    if markers is not None:
        every = MocapRecording(p, "c3d", rate, tuple(fields["labels"]), np.empty((0, 0, 3)))
        for name in markers:
            every.index(name)  # ValueError listing the file's markers
    labels = list(fields["kept"])
    scale = _unit_scale(p, unit if unit is not None else fields["unit"])
    points *= scale
    residuals = fields["residuals"]
    if residuals is not None:
        points[residuals < 0] = np.nan
    first = fields["first_frame"]
    return MocapRecording(p, "c3d", rate, tuple(labels), points, residuals, None, scale, first)


def _announced_frames(path: Path) -> int | None:
    """Frames the C3D header announces (words 4 and 5: first and last frame), or None.

    ezc3d reads a truncated file without error and shrinks its header to the frames it
    found, so the announced count is read from the file's fixed 512-byte header here
    (byte order from the processor type of the parameter section: 86 is big-endian).
    None when the header cannot say (more than 65534 frames: the count then lives in
    the parameters, which ezc3d has already rewritten).
    """
    with open(path, "rb") as fh:
        head = fh.read(512)
        param_block = head[0] if head else 0
        fh.seek(max(param_block - 1, 0) * 512)
        param_head = fh.read(4)
    if len(head) < 12 or len(param_head) < 4:
        return None
    order = ">" if param_head[3] == 86 else "<"
    first, last = (int(v) for v in np.frombuffer(head[6:10], dtype=f"{order}u2"))
    if last >= 65535 or last < first:
        return None
    return last - first + 1


def _global_rotations(bvh: Any) -> FloatArray:
    """``(F, J, 3, 3)`` world rotation of every joint: the parents' local rotations composed."""
    _, local = bvh.to_rotmat()
    names = list(bvh.joint_names)
    index = {n: j for j, n in enumerate(names)}
    out = np.empty_like(local)
    for node in bvh.nodes:
        if node.is_end_site():
            continue
        j = index[node.name]
        parent = node.parent
        if parent is None:
            out[:, j] = local[:, j]
        else:
            out[:, j] = out[:, index[parent.name]] @ local[:, j]
    return out


def read_bvh(path: str | Path, unit: str | None = None) -> MocapRecording:
    """Read a BVH file with pybvh: every joint's global position and orientation.

    pybvh honours each joint's Euler order from its CHANNELS line (intrinsic rotations,
    as the BVH format defines them) and computes the joints' world positions by forward
    kinematics; the world orientation of a joint is the product of the local rotations
    from the root down to it. Lengths are in the file's unit, scaled to metres when
    ``unit`` is given (a name of ``UNITS`` or the metres per file unit). The rate is
    ``1 / Frame Time`` as the file writes it (``.0083333`` gives 120.00048 Hz): pybvh
    rounds a frame time within 0.01 % of ``1 / N`` to it, so the line is read here.
    Raises ``ValueError`` naming the file for an unreadable or truncated file and a
    frame time that is not > 0.
    """
    p = Path(path)
    try:
        import pybvh
    except ImportError:  # pragma: no cover - the extra is installed in the tests
        raise ValueError(f"{p}: reading BVH needs pybvh; {_EXTRA}") from None
    try:
        bvh = pybvh.read_bvh_file(p, world_up="+y", warn_on_world_up_disagreement=False)
    except Exception as exc:  # pybvh raises various types for malformed text
        raise ValueError(f"{p}: {_bvh_problem(' '.join(str(exc).split()))}") from None
    frame_time = _bvh_frame_time(p, float(bvh.frame_time))
    if not math.isfinite(frame_time) or frame_time <= 0:
        raise ValueError(f"{p}: frame rate is zero (Frame Time: {frame_time:g}); expected > 0")
    check_rate(p, 1.0 / frame_time, f"Frame Time: {frame_time:g}")
    if bvh.frame_count == 0:
        raise ValueError(f"{p}: the BVH file holds no frames")
    check_unique_names(p, [str(n) for n in bvh.joint_names], "joint")
    scale = None if unit is None else _unit_scale(p, unit)
    points = np.asarray(bvh.joint_positions(), dtype=np.float64) * (scale or 1.0)
    rot = _global_rotations(bvh)
    shape = rot.shape[:2]
    q = quat.from_rotation(Rotation.from_matrix(rot.reshape(-1, 3, 3))).reshape(*shape, 4)
    labels = tuple(str(n) for n in bvh.joint_names)
    return MocapRecording(p, "bvh", 1.0 / frame_time, labels, points, None, q, scale)


def _bvh_frame_time(path: Path, parsed: float) -> float:
    """The ``Frame Time:`` of the BVH file as written (``parsed``, pybvh's, if none)."""
    with open(path, encoding="utf-8", errors="replace") as fh:
        for line in fh:
            key, colon, value = line.partition(":")
            if colon and key.strip().lower() == "frame time":
                try:
                    return float(value.split()[0])
                except (IndexError, ValueError):
                    raise ValueError(f"{path}: bad Frame Time line {line.strip()!r}") from None
    return parsed


def _bvh_problem(message: str) -> str:
    """pybvh's error, named: a truncated file, a zero frame time, or an unreadable file."""
    low = message.lower()
    if ("declares" in low and "frames" in low) or "number of columns changed" in low:
        return f"truncated BVH file ({message})"
    if "frame time" in low and "zero" in low:
        return f"frame rate is zero ({message})"
    return f"not a readable BVH file ({message})"


def read_qualisys_tsv(path: str | Path, unit: str | None = None) -> MocapRecording:
    """Read a Qualisys TSV 3D export (tab-separated text; no extra dependency).

    Layout: header lines ``KEY<TAB>value...`` (``NO_OF_FRAMES``, ``FREQUENCY``,
    ``MARKER_NAMES``, ...), then optionally a column header ``Frame, Time, NAME X,
    NAME Y, NAME Z, ...``, then one line per frame. Positions are in mm (``unit``
    overrides); a sample whose X, Y and Z are all 0, or with a blank field (QTM's export
    of a marker not seen in that frame), is missing. Columns without a
    name, or named ``Unidentified ...`` / ``Unlabeled ...``, are unlabelled trajectory
    fragments (label ``""``). Raises ``ValueError`` naming the file for a missing or
    zero ``FREQUENCY``, a truncated file (fewer lines than ``NO_OF_FRAMES``, or a last
    line cut short), a line with fewer fields than the markers need, non-numeric values
    or a column header that does not match the markers.
    """
    p = Path(path)
    meta: dict[str, list[str]] = {}
    columns: list[str] | None = None
    n_header = 0
    try:
        with open(p, encoding="utf-8-sig", errors="strict") as fh:
            for line in fh:
                fields = line.rstrip("\r\n").split("\t")
                first = fields[0].strip()
                if first.lower() == "frame":
                    columns = fields
                    n_header += 1
                    break
                if _is_number(first) or (not first and any(map(_is_number, fields[1:]))):
                    break  # a data line (its first field blank: a marker not seen)
                n_header += 1
                if first:
                    meta[first.upper()] = fields[1:]
    except UnicodeDecodeError:
        raise ValueError(f"{p}: not a Qualisys TSV text file (not UTF-8)") from None
    if "FREQUENCY" not in meta:
        raise ValueError(f"{p}: not a Qualisys TSV 3D export (no FREQUENCY header line)")
    try:
        rate = float(meta["FREQUENCY"][0])
    except (IndexError, ValueError):
        raise ValueError(f"{p}: bad FREQUENCY header line {meta['FREQUENCY']!r}") from None
    rate = check_rate(p, rate, "FREQUENCY")
    names, has_frame_time = _tsv_markers(p, meta, columns)
    first_col = 2 if has_frame_time else 0
    width = first_col + 3 * len(names)
    try:  # the data lines too: a byte that is not UTF-8 may sit past the header
        with open(p, encoding="utf-8-sig", errors="strict") as fh:
            lines = fh.read().splitlines()[n_header:]
    except UnicodeDecodeError as exc:
        raise ValueError(
            f"{p}: not a Qualisys TSV text file (not UTF-8 at byte {exc.start})"
        ) from None
    rows = [k for k, line in enumerate(lines) if line]  # "\t\t..." is a frame: all blank
    if not rows:
        raise ValueError(f"{p}: no data lines")
    n_fields = np.array([lines[k].count("\t") + 1 for k in rows])
    announced = None
    if meta.get("NO_OF_FRAMES"):
        try:
            announced = int(meta["NO_OF_FRAMES"][0])
            if announced < 0:
                raise ValueError
        except ValueError:
            raise ValueError(
                f"{p}: bad NO_OF_FRAMES header line {meta['NO_OF_FRAMES']!r}"
            ) from None
    short = n_fields < width
    if (announced is not None and len(rows) < announced) or short[-1]:
        raise ValueError(
            f"{p}: truncated TSV file: {int((~short).sum())} complete frame(s)"
            + (f" of the {announced} announced" if announced is not None else "")
        )
    if short.any():
        k = int(np.flatnonzero(short)[0])
        raise ValueError(
            f"{p}: line {n_header + 1 + rows[k]} has {int(n_fields[k])} fields, expected "
            f"{width} for {len(names)} markers"
        )
    try:
        data = pd.read_csv(
            io.StringIO("\n".join(lines[k] for k in rows)),
            sep="\t",
            header=None,
            usecols=range(width),
            dtype=np.float64,
            engine="c",
        ).to_numpy()
    except (ValueError, pd.errors.ParserError) as exc:
        raise ValueError(f"{p}: bad data line ({' '.join(str(exc).split())})") from None
    scale = _unit_scale(p, unit or "mm")
    points = data[:, first_col:].reshape(data.shape[0], len(names), 3) * scale
    points[(points == 0).all(axis=2) | ~np.isfinite(points).all(axis=2)] = np.nan
    return MocapRecording(p, "tsv", rate, tuple(names), points, None, None, scale)


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _label(name: str) -> str:
    name = name.strip()
    return "" if name.lower().startswith(_UNLABELLED_PREFIXES) else name


def _tsv_markers(
    path: Path, meta: dict[str, list[str]], columns: list[str] | None
) -> tuple[list[str], bool]:
    """Marker labels (``""`` unlabelled) and whether Frame and Time columns come first."""
    if columns is not None:
        cols = [c.strip() for c in columns]
        if len(cols) < 2 or cols[1].lower() != "time":
            raise ValueError(f"{path}: column header must start with Frame, Time; got {cols[:2]}")
        coords = [c for c in cols[2:] if c]
        if len(coords) % 3:
            raise ValueError(f"{path}: {len(coords)} coordinate columns, not X, Y, Z per marker")
        names = []
        for k in range(0, len(coords), 3):
            triple = coords[k : k + 3]
            stems = {c[:-1].strip() if c[-1:].upper() in "XYZ" else c for c in triple}
            if len(stems) != 1 or [c[-1:].upper() for c in triple] != ["X", "Y", "Z"]:
                raise ValueError(f"{path}: columns {triple} are not one marker's X, Y, Z")
            names.append(_label(stems.pop()))
        return names, True
    if "MARKER_NAMES" not in meta:
        raise ValueError(f"{path}: not a Qualisys TSV 3D export (no MARKER_NAMES header line)")
    return [_label(n) for n in meta["MARKER_NAMES"]], False


def read_recording(
    path: str | os.PathLike[str], unit: str | None = None, markers: Sequence[str] | None = None
) -> MocapRecording:
    """Read a ``.c3d``, ``.bvh`` or ``.tsv`` file by its suffix (``markers``: of a C3D,
    only these are read into memory; None: all)."""
    p = Path(path)
    suffix = p.suffix.lower()
    if not os.path.lexists(p):
        raise FileNotFoundError(f"motion capture file {p} does not exist")
    check_regular_file(p, max_bytes=MAX_RECORDING_BYTES)  # no FIFO, device or folder
    if suffix == ".c3d":
        return read_c3d(p, unit, markers)
    readers = {".bvh": read_bvh, ".tsv": read_qualisys_tsv}
    if suffix not in readers:
        raise ValueError(f"{p}: unknown motion capture format; expected .c3d, .bvh or .tsv")
    return readers[suffix](p, unit)
