"""Motion capture recordings (C3D, BVH, Qualisys TSV) into the project's data kinds.

Readers: :func:`read_c3d` (ezc3d), :func:`read_bvh` (pybvh), :func:`read_qualisys_tsv`
(plain text), :func:`read_recording` (by suffix), all returning a
:class:`MocapRecording` in metres. Conversions: :func:`import_orientation`,
:func:`import_position`, :func:`import_juggling` with :class:`ImportOptions`, each
returning the dataset and an :class:`ImportReport`. :func:`parse_source` reads the
``FILE?option=value&...`` data string that ``--data`` and the environments' ``data=``
accept. Every recording read is held to the physical bounds of :func:`check_recording`
(frame rate, duration, unique names, positions within a capture volume once the unit
is known). Guide: ``docs/recordings.md``.
"""

from __future__ import annotations

from motion_envs.datasets.mocap._balls import assemble_balls
from motion_envs.datasets.mocap._bounds import (
    MAX_ABS_POSITION_M,
    MAX_DURATION_S,
    MAX_RATE_HZ,
    MIN_EXTENT_M,
    MIN_RATE_HZ,
    check_recording,
)
from motion_envs.datasets.mocap._convert import (
    YUP_TO_ZUP,
    ImportReport,
    Movement,
    import_juggling,
    import_orientation,
    import_position,
    triad_quaternions,
)
from motion_envs.datasets.mocap._gaps import GapCounts, Piece, fill_gaps
from motion_envs.datasets.mocap._options import (
    IMPORT_OPTIONS,
    KINDS,
    MAX_RECORDING_BYTES,
    MAX_SEGMENT_ROWS,
    MAX_SEGMENTS_BYTES,
    MOCAP_SUFFIXES,
    UNITS,
    ImportOptions,
    is_mocap_source,
    missing_option,
    parse_option,
    parse_source,
    unit_scale,
)
from motion_envs.datasets.mocap._readers import (
    read_bvh,
    read_c3d,
    read_qualisys_tsv,
    read_recording,
)
from motion_envs.datasets.mocap._recording import MocapRecording
from motion_envs.datasets.mocap._segments import SegmentRow, read_segments, speed, speed_segments

__all__ = [
    "IMPORT_OPTIONS",
    "KINDS",
    "MAX_ABS_POSITION_M",
    "MAX_DURATION_S",
    "MAX_RATE_HZ",
    "MAX_RECORDING_BYTES",
    "MAX_SEGMENTS_BYTES",
    "MAX_SEGMENT_ROWS",
    "MIN_EXTENT_M",
    "MIN_RATE_HZ",
    "MOCAP_SUFFIXES",
    "UNITS",
    "YUP_TO_ZUP",
    "GapCounts",
    "ImportOptions",
    "ImportReport",
    "MocapRecording",
    "Movement",
    "Piece",
    "SegmentRow",
    "assemble_balls",
    "check_recording",
    "fill_gaps",
    "import_juggling",
    "import_orientation",
    "import_position",
    "is_mocap_source",
    "missing_option",
    "parse_option",
    "parse_source",
    "read_bvh",
    "read_c3d",
    "read_qualisys_tsv",
    "read_recording",
    "read_segments",
    "speed",
    "speed_segments",
    "triad_quaternions",
    "unit_scale",
]
