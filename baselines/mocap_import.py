"""``motion-bench import``: a motion capture recording (C3D, BVH, Qualisys TSV) into the
project's orientation, position or juggling CSV.

The conversion is :mod:`motion_envs.datasets.mocap` (units to metres, Z-up, tracks,
gaps, movements); juggling recordings are then cut into cycles by the paper's online
criteria (:func:`motion_envs.models.juggling.segment_demos`). The CSV
written is what ``--data`` of ``motion-bench orientation|position|juggling`` and the
environments' ``data=`` take; they also take the recording itself with the same
options after its name (``--data 'rec.c3d?markers=O,X,P'``). Guide: docs/recordings.md.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

from baselines import options
from motion_envs.datasets import OrientationDataset, PositionDataset
from motion_envs.datasets.juggling import JugglingDemos, write_juggling_csv
from motion_envs.datasets.mocap import (
    KINDS,
    MOCAP_SUFFIXES,
    ImportOptions,
    ImportReport,
    import_juggling,
    import_orientation,
    import_position,
    missing_option,
    parse_option,
)
from motion_envs.models.juggling import segment_demos

__all__ = ["ImportConfig", "ImportResults", "check", "main", "register", "report", "run", "write"]


@dataclass(frozen=True)
class ImportConfig:
    """What to import: the recording ``source``, the data ``kind`` and the options."""

    source: Path
    kind: str = "orientation"
    options: ImportOptions = field(default_factory=ImportOptions)


@dataclass(frozen=True)
class ImportResults:
    """The imported data (one of the three kinds) and the import report."""

    config: ImportConfig
    data: OrientationDataset | PositionDataset | JugglingDemos
    report: ImportReport


def check(config: ImportConfig) -> None:
    """Raise :class:`~baselines.options.ConfigError` naming the option the import lacks."""
    missing = missing_option(config.source, config.kind, config.options)
    if missing is not None:
        raise options.ConfigError(*missing)


def run(config: ImportConfig) -> ImportResults:
    """Import ``config.source`` (pure: reads the file, writes nothing).

    Raises :class:`~baselines.options.ConfigError` for a missing option and
    ``ValueError`` naming the file for unusable data.
    """
    check(config)
    data: OrientationDataset | PositionDataset | JugglingDemos
    if config.kind == "orientation":
        data, rep = import_orientation(config.source, config.options)
    elif config.kind == "position":
        data, rep = import_position(config.source, config.options)
    else:
        demos, rep = import_juggling(config.source, config.options)
        data = segment_demos(demos, config.source)
    return ImportResults(config, data, rep)


def report(results: ImportResults) -> str:
    """The text printed: the import report and what was made of it."""
    lines = results.report.lines()
    data = results.data
    if isinstance(data, JugglingDemos):
        lines.append(f"{len(data.cycles())} complete juggling cycle(s) by the online criteria")
    else:
        n_subjects, n_tasks = len(set(data.subjects.tolist())), len(set(data.tasks.tolist()))
        lines.append(
            f"{len(data)} {results.config.kind} trajectories, "
            f"{n_subjects} subject(s), {n_tasks} task(s)"
        )
    return "\n".join(lines)


def write(results: ImportResults, out: Path) -> list[Path]:
    """Write the project's CSV of the imported kind to ``out``.

    A juggling CSV holds the recordings without the ``phase`` column (samples after the
    last complete cycle have no phase): whoever reads it cuts it by the same online
    criteria, so it gives the cycles reported here.
    """
    data = results.data
    if isinstance(data, JugglingDemos):
        return [write_juggling_csv(data, out, phase=False)]
    return [data.to_csv(path=out)]  # atomic: sample_table.write_csv


@options.reads_files
def _source(text: str) -> Path:
    path = options.input_file(text)
    if path.suffix.lower() not in MOCAP_SUFFIXES:
        raise argparse.ArgumentTypeError(
            f"{text}: expected a {', '.join(MOCAP_SUFFIXES)} motion capture file"
        )
    return path


def _checker(name: str) -> Callable[[str], Any]:
    def check_value(text: str) -> Any:
        try:
            return parse_option(name, text)
        except ValueError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None

    check_value.__name__ = name
    if name == "segments":  # a file the import reads
        options.reads_files(check_value)
    return check_value


_HELP = {
    "marker": "C3D/TSV marker imported as a position (the hand for juggling)",
    "markers": "ORIGIN,X,PLANE: three rigid C3D/TSV markers whose frame is the orientation",
    "joint": "BVH joint: global position and orientation by forward kinematics",
    "relative_to": "orientation relative to this frame: ORIGIN,X,PLANE markers (e.g. "
    "wrist,elbow,shoulder as in Faraway & Choe) or a BVH joint (e.g. the forearm)",
    "ball": "C3D/TSV marker of the ball (juggling)",
    "balls": "'unlabelled': assemble the ball from a Qualisys TSV's unlabelled fragments",
    "unit": "length unit of the file: m, cm, mm, in, or the metres per file unit as a "
    "number (0.056444 for CMU BVH files; default: C3D POINT:UNITS, TSV mm; a BVH needs it)",
    "up": "the file's vertical axis, rotated to the project's Z-up",
    "max_gap": "fill gaps of up to this many frames (slerp for orientations); longer split",
    "speed_threshold": "cut movements where the speed exceeds this (m/s, rad/s for "
    "orientations); default: one trajectory per gap-free piece",
    "min_duration": "drop movements shorter than this (s)",
    "min_pause": "rests shorter than this (s) do not end a movement",
    "segments": "CSV with start,end (s from the file's start)[,subject,task,trajectory]: "
    "the movements, instead of --speed-threshold",
    "subject": "subject label (default: the file's stem)",
    "task": "task label",
    "lateral": "horizontal axis that becomes the juggling plane's x",
}


def main(args: argparse.Namespace) -> int:
    """Build the config, check it, run, print the report, write the CSV."""
    values = {f.name: getattr(args, f.name) for f in fields(ImportOptions)}
    values = {k: v for k, v in values.items() if v is not None}
    config = ImportConfig(source=args.file, kind=args.kind, options=ImportOptions(**values))
    check(config)
    results = run(config)
    print(report(results))
    written = write(results, args.out)
    print(f"wrote {written[0]}")
    return 0


def register(subparsers: argparse._SubParsersAction[options.Parser]) -> None:
    """Add the ``import`` sub-command."""
    p = options.add_subcommand(
        subparsers,
        "import",
        help="a C3D, BVH or Qualisys TSV recording into the project's CSV formats",
        description=(
            "Import a motion capture recording (C3D via ezc3d, BVH via pybvh, Qualisys TSV "
            "3D export) as orientation, position or juggling trajectories: units to "
            "metres, the file's up axis to Z-up, gaps filled or split, movements cut by a "
            "speed threshold or a segments table; juggling cycles by the paper's online "
            "criteria. The CSV written is what --data of the benchmarks takes; --data also "
            "takes the recording itself with these options after '?', e.g. "
            "'rec.c3d?markers=O,X,P&up=y'. Guide: docs/recordings.md."
        ),
    )
    p.add_argument("file", type=_source, help="the recording (.c3d, .bvh or .tsv)")
    p.add_argument("--kind", choices=KINDS, required=True, help="the data kind to write")
    p.add_argument("--out", type=options.output_file, required=True, help="the CSV written")
    defaults = ImportOptions()
    for f in fields(ImportOptions):
        default = getattr(defaults, f.name)
        p.add_argument(
            options.option_name(f.name),
            type=_checker(f.name),
            default=None,
            help=_HELP[f.name] + ("" if default is None else f" (default: {default})"),
        )
    p.set_defaults(func=main)
