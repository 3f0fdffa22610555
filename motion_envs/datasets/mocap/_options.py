"""The import options and the ``FILE?option=value&...`` data string that carries them.

``motion-bench import`` takes them as options (``--marker RFIN``); ``--data`` of the
benchmarks and the environments' ``data=`` take the same options after the file name,
written as a query: ``rec.c3d?marker=RFIN&up=y&max-gap=5``. Every value goes through
:func:`parse_option`, so both ways report the same one-line errors naming the option.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from dataclasses import dataclass, fields, replace
from pathlib import Path
from typing import Any

from motion_envs._io import check_regular_file

__all__ = [
    "IMPORT_OPTIONS",
    "KINDS",
    "MAX_RECORDING_BYTES",
    "MAX_SEGMENTS_BYTES",
    "MAX_SEGMENT_ROWS",
    "MOCAP_SUFFIXES",
    "UNITS",
    "ImportOptions",
    "is_mocap_source",
    "missing_option",
    "parse_option",
    "parse_source",
    "unit_scale",
]

#: File suffixes read as motion capture (case-insensitive).
MOCAP_SUFFIXES: tuple[str, ...] = (".c3d", ".bvh", ".tsv")

#: Largest motion capture file read (bytes); larger is refused before reading.
MAX_RECORDING_BYTES = 2**32
#: Largest segments table (bytes) and most rows (a movement each).
MAX_SEGMENTS_BYTES = 16 * 2**20
MAX_SEGMENT_ROWS = 10_000

#: Length units accepted by ``--unit`` by name, in metres (``--unit`` also takes a
#: number: the metres per file unit, e.g. ``0.056444`` for the CMU database's BVH files).
UNITS: dict[str, float] = {"m": 1.0, "cm": 0.01, "mm": 0.001, "in": 0.0254}


def unit_scale(text: str) -> float:
    """Metres per file unit: a name of :data:`UNITS` or a finite number > 0.

    Raises ``ValueError`` (naming no option; the caller adds it) for anything else.
    """
    key = text.strip().lower()
    if key in UNITS:
        return UNITS[key]
    try:
        value = float(key)
    except ValueError:
        value = math.nan
    if not math.isfinite(value) or value <= 0:
        raise ValueError(
            f"expected one of {', '.join(UNITS)} or a number > 0 (metres per file unit, "
            f"e.g. 0.056444); got {text!r}"
        )
    return value


@dataclass(frozen=True)
class ImportOptions:
    """How a recording becomes trajectories (every field is a command-line option).

    Attributes
    ----------
    marker:
        C3D/TSV marker whose position is imported (``position``; the hand for ``juggling``).
    markers:
        ``(ORIGIN, X, PLANE)``: three rigid markers whose frame is the orientation.
    joint:
        BVH joint: its global position and orientation by forward kinematics (the hand
        for ``juggling``).
    relative_to:
        The orientation is taken relative to this frame: three markers
        ``ORIGIN,X,PLANE`` (C3D/TSV; e.g. wrist, elbow, shoulder as in Faraway & Choe) or
        one BVH joint (e.g. the forearm).
    ball:
        C3D/TSV marker of the ball (``juggling``).
    balls:
        ``labelled`` (the ``ball`` marker) or ``unlabelled``: the ball flights are
        assembled from a Qualisys TSV's unlabelled fragments.
    unit:
        Length unit of the file: ``m``, ``cm``, ``mm``, ``in``, or a number, the metres
        per file unit (``"0.056444"`` for the CMU database's BVH files); C3D's
        ``POINT:UNITS`` and TSV's millimetres are used when None; a BVH needs it for
        positions.
    up:
        The file's vertical axis, ``y`` or ``z``; rotated to the project's Z-up.
    max_gap:
        Longest run of missing frames filled by interpolation; longer gaps split.
    speed_threshold:
        Segment into movements where the speed exceeds this (m/s, or rad/s for
        orientations); None: one trajectory per gap-free piece.
    min_duration, min_pause:
        Movements shorter than ``min_duration`` s are dropped; pauses shorter than
        ``min_pause`` s do not end a movement.
    segments:
        CSV with ``start,end`` (s from the start of the file) and optional
        ``subject,task,trajectory`` columns: the movements, instead of the threshold.
    subject, task:
        Labels of every movement (default: the file's stem and ``import``); a segments
        file's columns override them.
    lateral:
        Horizontal axis (``x`` or ``y``, after the up rotation) that becomes the
        juggling plane's ``x``.
    """

    marker: str | None = None
    markers: tuple[str, str, str] | None = None
    joint: str | None = None
    relative_to: tuple[str, ...] | None = None
    ball: str | None = None
    balls: str = "labelled"
    unit: str | None = None
    up: str = "z"
    max_gap: int = 10
    speed_threshold: float | None = None
    min_duration: float = 0.2
    min_pause: float = 0.1
    segments: Path | None = None
    subject: str | None = None
    task: str = "import"
    lateral: str = "x"

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if value is not None and f.name in _CHECKS and not isinstance(value, Path):
                try:
                    parse_option(f.name, value if isinstance(value, str) else _text(value))
                except ValueError as exc:
                    raise ValueError(f"{f.name}: {exc}") from None


def _text(value: Any) -> str:
    if isinstance(value, tuple):
        return ",".join(value)
    return str(value)


def _name(text: str) -> str:
    if not text.strip():
        raise ValueError("expected a non-empty name")
    return text


def _triad(text: str) -> tuple[str, str, str]:
    parts = tuple(p.strip() for p in text.split(","))
    if len(parts) != 3 or not all(parts) or len(set(parts)) != 3:
        raise ValueError(f"expected three different marker names ORIGIN,X,PLANE; got {text!r}")
    return (parts[0], parts[1], parts[2])


def _one_or_three(text: str) -> tuple[str, ...]:
    parts = tuple(p.strip() for p in text.split(","))
    if len(parts) == 1 and parts[0]:
        return parts
    return _triad(text)


def _unit(text: str) -> str:
    unit_scale(text)  # the check; the text is kept as given
    return text


def _choice(*allowed: str) -> Callable[[str], str]:
    def check(text: str) -> str:
        if text not in allowed:
            raise ValueError(f"expected one of {', '.join(allowed)}; got {text!r}")
        return text

    return check


def _int_at_least(low: int) -> Callable[[str], int]:
    def check(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise ValueError(f"expected an integer >= {low}; got {text!r}") from None
        if value < low:
            raise ValueError(f"expected an integer >= {low}; got {text!r}")
        return value

    return check


def _float(low: float, strict: bool) -> Callable[[str], float]:
    what = f"a finite number {'>' if strict else '>='} {low:g}"

    def check(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise ValueError(f"expected {what}; got {text!r}") from None
        if not math.isfinite(value) or value < low or (strict and value == low):
            raise ValueError(f"expected {what}; got {text!r}")
        return value

    return check


def _file(text: str) -> Path:
    if not os.path.lexists(text):
        raise ValueError(f"{text} does not exist or is not a file")
    return check_regular_file(text, max_bytes=MAX_SEGMENTS_BYTES)  # no FIFO, device, folder


_CHECKS: dict[str, Callable[[str], Any]] = {
    "marker": _name,
    "markers": _triad,
    "joint": _name,
    "relative_to": _one_or_three,
    "ball": _name,
    "balls": _choice("labelled", "unlabelled"),
    "unit": _unit,
    "up": _choice("y", "z"),
    "max_gap": _int_at_least(0),
    "speed_threshold": _float(0.0, strict=True),
    "min_duration": _float(0.0, strict=False),
    "min_pause": _float(0.0, strict=False),
    "segments": _file,
    "subject": _name,
    "task": _name,
    "lateral": _choice("x", "y"),
}

#: Option names, spelled as on the command line (``max-gap``).
IMPORT_OPTIONS: tuple[str, ...] = tuple(k.replace("_", "-") for k in _CHECKS)


def parse_option(name: str, text: str) -> Any:
    """The value of option ``name`` (``max_gap`` or ``max-gap``) given as ``text``.

    Raises ``ValueError`` with a message that names no option (the caller adds it).
    """
    key = name.replace("-", "_")
    if key not in _CHECKS:
        raise ValueError(
            f"unknown import option {name!r}; expected one of {', '.join(IMPORT_OPTIONS)}"
        )
    return _CHECKS[key](text)


def is_mocap_source(data: object) -> bool:
    """True when ``data`` (a path or a data string) names a C3D, BVH or TSV file."""
    if not isinstance(data, (str, os.PathLike)):
        return False
    path = str(data).partition("?")[0]
    return Path(path).suffix.lower() in MOCAP_SUFFIXES


def parse_source(data: str | os.PathLike[str]) -> tuple[Path, ImportOptions]:
    """Split ``FILE?option=value&option=value`` into the file and its :class:`ImportOptions`.

    Raises ``ValueError`` naming the option for an unknown option or a bad value, and
    ``FileNotFoundError`` when the file does not exist.
    """
    path_text, _, query = os.fspath(data).partition("?")
    path = Path(path_text)
    values: dict[str, Any] = {}
    for item in filter(None, query.split("&")):
        name, eq, text = item.partition("=")
        if not eq:
            raise ValueError(f"{data}: import option {name!r} needs a value (option=value)")
        try:
            values[name.replace("-", "_")] = parse_option(name, text)
        except ValueError as exc:
            raise ValueError(f"{path}: option {name}: {exc}") from None
    if not os.path.lexists(path):
        raise FileNotFoundError(f"motion capture file {path} does not exist")
    check_regular_file(path, max_bytes=MAX_RECORDING_BYTES)  # no FIFO, device or folder
    return path, replace(ImportOptions(), **values)


#: Data kinds an import produces.
KINDS: tuple[str, ...] = ("orientation", "position", "juggling")


def missing_option(path: Path, kind: str, options: ImportOptions) -> tuple[str, str] | None:
    """``(field, message)`` when ``options`` lack what a ``kind`` import of ``path`` needs.

    Checked from the file name alone, before the file is read: a C3D/TSV orientation
    needs ``markers``, a position ``marker``, juggling ``marker`` and ``ball`` (or
    ``balls=unlabelled``, TSV only); a BVH needs ``joint``, and ``unit`` for positions.
    """
    suffix = path.suffix.lower()
    if kind not in KINDS:
        return "kind", f"expected one of {', '.join(KINDS)}; got {kind!r}"
    if suffix not in MOCAP_SUFFIXES:
        return "source", f"{path}: expected a .c3d, .bvh or .tsv file"
    if options.balls == "unlabelled" and suffix != ".tsv":
        return "balls", "unlabelled fragments are read from a Qualisys .tsv file only"
    if suffix == ".bvh":
        if options.joint is None:
            return "joint", f"{path} is a BVH file: give the joint to import"
        if kind != "orientation" and options.unit is None:
            return "unit", (
                f"{path}: BVH lengths carry no unit; give one of {', '.join(UNITS)} or the "
                "metres per file unit (e.g. 0.056444)"
            )
        return None
    if kind == "orientation" and options.markers is None:
        return "markers", f"{path}: give the three rigid markers ORIGIN,X,PLANE"
    if kind != "orientation" and options.marker is None:
        role = "hand" if kind == "juggling" else "position"
        return "marker", f"{path}: give the {role} marker"
    if kind == "juggling" and options.ball is None and options.balls != "unlabelled":
        return "ball", f"{path}: give the ball marker (or --balls unlabelled for a TSV)"
    return None
