"""Command-line plumbing shared by the ``motion-bench`` sub-commands.

A sub-command module exposes a frozen ``*Config`` dataclass, a pure
``run(config) -> results`` (no argparse, no printing, no files), ``report(results)`` (the
text printed), ``write(results, out)`` (files and plots) and ``register(subparsers)``.
This module holds what they share on the argparse side:

* :class:`Parser`: an ``ArgumentParser`` without abbreviated options whose errors are
  one line, ``motion-bench CMD: error: argument --opt: ...``, exit status 2;
* :class:`HelpFormatter`: every non-empty default shown once, ``(default: X)``;
* ``type=`` checkers (:func:`positive_int`, :func:`input_file`, :func:`output_folder`,
  ...) so that every user error is reported, naming its option, *before* any
  computation starts;
* THE input and output rules of the command line: every option that names a file the
  command reads has a checker marked :func:`reads_files` that goes through
  :func:`input_file` (regular files only, opened non-blocking, bounded); every output
  (``--out``, :func:`output_file`, :func:`output_folder`) follows
  :func:`motion_envs._io.check_output`, and :func:`guarded_outputs` runs the sub-command
  with its inputs protected from being replaced and its output folders locked;
* :class:`ConfigError`: raised by a ``run`` that finds an inconsistent config after
  loading its data (e.g. a ``--plot-task`` the data does not have), naming the field.
"""

from __future__ import annotations

import argparse
import contextlib
import csv
import math
import os
import re
import sys
import tempfile
import textwrap
from collections.abc import Callable, Iterable, Iterator, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, NoReturn, TypeVar

from motion_envs import _io

if TYPE_CHECKING:
    from motion_envs.datasets.registry import Kind

__all__ = [
    "ConfigError",
    "HelpFormatter",
    "Parser",
    "add_subcommand",
    "fail",
    "float_in",
    "fraction",
    "guarded_outputs",
    "header_line",
    "hold_folder",
    "input_file",
    "input_paths",
    "int_at_least",
    "mocap_data",
    "non_negative_float",
    "non_negative_int",
    "option_name",
    "output_file",
    "output_folder",
    "positive_int",
    "reads_files",
    "results_folder",
    "wrote",
]


class ConfigError(ValueError):
    """A config value is invalid for the data it is used with; ``field`` names it."""

    def __init__(self, field: str, message: str) -> None:
        super().__init__(f"{field}: {message}")
        self.field = field
        self.message = message


def option_name(field: str) -> str:
    """The command-line option of a config field: ``plot_task`` -> ``--plot-task``."""
    return "--" + field.replace("_", "-")


class Parser(argparse.ArgumentParser):
    """``ArgumentParser`` with ``allow_abbrev=False`` and one-line errors (exit 2)."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        kwargs.setdefault("allow_abbrev", False)
        kwargs.setdefault("formatter_class", HelpFormatter)
        super().__init__(*args, **kwargs)

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message}\n")


class HelpFormatter(argparse.HelpFormatter):
    """Descriptions re-filled paragraph by paragraph (blank lines and list items kept);
    ``(default: X)`` added once to each option's help when the default is not empty
    (None, False, an empty list) and the help does not already say it."""

    def _fill_text(self, text: str, width: int, indent: str) -> str:
        blocks = []
        for paragraph in text.strip().split("\n\n"):
            items: list[str] = []
            for line in paragraph.splitlines():
                stripped = line.strip()
                if not items or re.match(r"(\d+\.|[-*]) ", stripped):
                    items.append(stripped)
                else:
                    items[-1] += " " + stripped
            for item in items:
                marker = re.match(r"(\d+\.|[-*]) ", item)
                hang = " " * (len(marker.group(0)) if marker else 0)
                blocks.append(
                    textwrap.fill(
                        item, width, initial_indent=indent, subsequent_indent=indent + hang
                    )
                )
            blocks.append("")
        return "\n".join(blocks).rstrip()

    def _get_help_string(self, action: argparse.Action) -> str | None:
        text = action.help or ""
        default = action.default
        if (
            default in (None, False, argparse.SUPPRESS)
            or default == []
            or "%(default)" in text
            or "default:" in text
            or action.option_strings == []
        ):
            return action.help
        return f"{text} (default: %(default)s)"


def add_subcommand(
    subparsers: argparse._SubParsersAction[Parser], name: str, help: str, description: str
) -> Parser:
    """A sub-command parser with the project's formatter and error style."""
    parser: Parser = subparsers.add_parser(
        name,
        help=help,
        description=description,
        formatter_class=HelpFormatter,
        allow_abbrev=False,
    )
    return parser


# --------------------------------------------------------------------------------------
# type= checkers: argparse reports their ArgumentTypeError as "argument --opt: message"
# --------------------------------------------------------------------------------------


def _number(text: str, kind: Callable[[str], Any], what: str) -> Any:
    try:
        value = kind(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected {what}; got {text!r}") from None
    if isinstance(value, float) and not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"expected {what}; got {text!r}")
    return value


def int_at_least(low: int) -> Callable[[str], int]:
    """A ``type=`` checker accepting integers ``>= low``."""

    def check(text: str) -> int:
        what = f"an integer >= {low}"
        value: int = _number(text, int, what)
        if value < low:
            raise argparse.ArgumentTypeError(f"expected {what}; got {text!r}")
        return value

    check.__name__ = f"integer >= {low}"
    return check


#: An integer >= 1.
positive_int = int_at_least(1)
#: An integer >= 0.
non_negative_int = int_at_least(0)


def non_negative_float(text: str) -> float:
    """A finite number >= 0."""
    value: float = _number(text, float, "a finite number >= 0")
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected a finite number >= 0; got {text!r}")
    return value


def float_in(low: float, high: float, unit: str = "") -> Callable[[str], float]:
    """A ``type=`` checker accepting finite numbers in ``[low, high]`` (the documented
    plausible range of the option: ``1e-300`` or ``1e400`` are refused naming the option,
    before any computation could overflow)."""
    what = f"a finite number in [{low:g}, {high:g}]" + (f" {unit}" if unit else "")

    def check(text: str) -> float:
        value: float = _number(text, float, what)
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f"expected {what}; got {text!r}")
        return value

    check.__name__ = what
    return check


def fraction(text: str) -> float:
    """A number strictly between 0 and 1."""
    value: float = _number(text, float, "a number in (0, 1)")
    if not 0.0 < value < 1.0:
        raise argparse.ArgumentTypeError(f"expected a number in (0, 1); got {text!r}")
    return value


#: Largest file a command-line option reads (bytes); the readers' own bounds are lower.
MAX_INPUT_BYTES = 2**32
#: Bytes of a CSV read to check its header line before the run.
MAX_HEADER_BYTES = 1 << 16

_F = TypeVar("_F", bound=Callable[..., Any])


def reads_files(check: _F) -> _F:
    """Mark a ``type=`` checker whose option names a file (or a folder of files) that the
    command reads: :func:`input_paths` then counts its value among the run's inputs (an
    output may not replace one), and ``tests/fuzz_registry.py`` must list the option."""
    check.reads_files = True  # type: ignore[attr-defined]
    return check


@reads_files
def input_file(text: str) -> Path:
    """An existing, readable regular file (THE input rule of the command line).

    Opened non-blocking and checked on the descriptor (:func:`motion_envs._io.check_regular_file`):
    a folder, a FIFO, a device (``/dev/zero``) or a symbolic link to one is refused in one
    line before anything reads it, as is a file over :data:`MAX_INPUT_BYTES` bytes."""
    if Path(text).is_dir():
        raise argparse.ArgumentTypeError(f"{text} is a folder, not a file")
    try:
        path = _io.check_regular_file(text, max_bytes=MAX_INPUT_BYTES)
        _io.read_regular_file(path, max_bytes=1, head=True)  # readable (not /proc/self/mem)
    except _io.UserFileError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    return path


def header_line(text: str) -> list[str]:
    """The header line of the CSV ``text`` (a file :func:`input_file` accepts), read within
    :data:`MAX_HEADER_BYTES`: ``ArgumentTypeError`` for a file that is not UTF-8 text or
    whose first line is longer."""
    path = input_file(text)
    try:
        head = _io.read_regular_file(path, max_bytes=MAX_HEADER_BYTES, head=True)
    except _io.UserFileError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    line, newline, _ = head.partition(b"\n")
    if not newline and len(head) >= MAX_HEADER_BYTES:
        raise argparse.ArgumentTypeError(
            f"{text}: line 1 is longer than {MAX_HEADER_BYTES} bytes; not a CSV header"
        )
    try:
        decoded = line.decode("utf-8-sig")
    except UnicodeDecodeError:
        from motion_envs.datasets.sample_table import not_text_message

        message = not_text_message(text, head[:8])  # a spreadsheet workbook is named as one
        raise argparse.ArgumentTypeError(
            message if "workbook" in message else f"{text} is not a UTF-8 text CSV"
        ) from None
    return [h.strip() for h in next(csv.reader([decoded]), [])]


def csv_with_columns(text: str, required: Sequence[str], expected: str) -> str:
    """An existing, readable CSV file whose header line holds every ``required`` column
    (its path); else ``ArgumentTypeError`` naming the missing ones and the ``expected``
    header. Only the header line is read (the rows are checked when a run loads them)."""
    from motion_envs.datasets.sample_table import missing_columns_message

    path = input_file(text)
    header = header_line(text)
    missing = [c for c in required if c not in header]
    if missing:
        raise argparse.ArgumentTypeError(
            missing_columns_message(f"{text}: line 1", header, missing, expected)
        )
    return str(path)


def input_paths(values: Iterable[object]) -> list[Path]:
    """The existing files and folders named by option values (``FILE?query`` is FILE,
    ``cohort:CONFIG`` is CONFIG; names of built-in data that are no paths are skipped)."""
    out: list[Path] = []
    for value in values:
        if value is None or isinstance(value, (bool, int, float)):
            continue
        items = value if isinstance(value, (list, tuple)) else [value]
        for item in items:
            text = str(item).partition("?")[0]
            text = text.removeprefix("cohort:")
            if text and os.path.lexists(text):
                out.append(Path(text))
    return out


def _probe_folder(folder: Path, text: str) -> None:
    """Check that files can be created in the nearest existing ancestor of ``folder``."""
    probe = folder
    while not probe.exists():
        if probe.parent == probe:
            break
        probe = probe.parent
    if not probe.is_dir():
        raise argparse.ArgumentTypeError(f"{probe} is a file, not a folder (in {text})")
    try:
        with tempfile.TemporaryFile(dir=probe):
            pass
    except OSError as exc:
        raise argparse.ArgumentTypeError(f"cannot write in {probe}: {exc.strerror}") from None


def output_folder(text: str) -> Path:
    """A folder that exists and is writable, or can be created (THE output rule,
    :func:`motion_envs._io.check_output`: not a symbolic link, not a file)."""
    path = Path(text)
    if path.is_file() and not path.is_symlink():
        raise argparse.ArgumentTypeError(f"{text} is a file, not a folder")
    try:
        _io.check_output(path, folder=True)
    except _io.UserFileError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    _probe_folder(path, text)
    return path


#: The folder the sub-commands write into without ``--out`` (as ``motion-bench all``).
RESULTS_ROOT = Path("results")


def results_folder(out: Path | None, job: str) -> Path:
    """``--out``, or ``results/JOB`` (``motion-bench all``'s folder of that job) when it is
    not given; the default is checked like ``--out`` (``ConfigError`` naming ``--out``),
    before anything is computed."""
    if out is not None:
        return out
    default = RESULTS_ROOT / job
    try:
        folder = output_folder(str(default))
    except argparse.ArgumentTypeError as exc:
        raise ConfigError("out", f"the default {exc}") from None
    hold_folder(folder)
    return folder


def output_file(text: str) -> Path:
    """A file path whose folder is writable (or can be created): not an existing folder,
    and by THE output rule (:func:`motion_envs._io.check_output`) not a symbolic link, a
    FIFO or a device (it would be replaced by a regular file); the check that it is no
    input is :func:`guarded_outputs`'s."""
    path = Path(text)
    if path.is_dir() and not path.is_symlink():
        raise argparse.ArgumentTypeError(f"{text} is a folder, not a file")
    try:
        _io.check_output(path)
    except _io.UserFileError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    _probe_folder(path.parent, text)
    return path


#: The output folders being written (their locks), innermost run last.
_RUNS: list[contextlib.ExitStack] = []


@contextlib.contextmanager
def guarded_outputs(parser: argparse.ArgumentParser, args: argparse.Namespace) -> Iterator[None]:
    """Run a sub-command's ``main`` under THE output rule.

    The values of ``parser``'s options marked :func:`reads_files` are the inputs: an
    ``--out`` (file or folder) that is the same file as one of them is refused now
    (``ConfigError``), and while the block runs :func:`motion_envs._io.atomic_write`
    refuses to replace any of them (an output folder that holds an input). Every output
    folder (``--out``, and the default ones :func:`results_folder` picks) is locked
    (:func:`motion_envs._io.folder_lock`): a second process writing it gets one line.
    """
    inputs: list[Path] = []
    outputs: list[tuple[str, Path, bool]] = []
    for action in parser._actions:
        value = getattr(args, action.dest, None)
        kind = getattr(action.type, "__name__", "")
        if getattr(action.type, "reads_files", False):
            inputs += input_paths([value])
        elif kind in ("output_file", "output_folder") and value is not None:
            outputs.append((action.dest, Path(value), kind == "output_folder"))
    for dest, path, folder in outputs:
        try:
            _io.check_output(path, inputs=inputs, folder=folder)
        except _io.UserFileError as exc:
            raise ConfigError(dest, str(exc)) from None
    with _io.protected_inputs(inputs), contextlib.ExitStack() as stack:
        _RUNS.append(stack)
        try:
            for dest, path, folder in outputs:
                if folder:
                    hold_folder(path, dest)
            yield
        finally:
            _RUNS.pop()


def hold_folder(folder: Path, field: str = "out") -> None:
    """Lock the output ``folder`` until the running sub-command ends (nothing outside
    :func:`guarded_outputs`); ``ConfigError`` naming ``field`` when another process holds
    it."""
    if not _RUNS:
        return
    try:
        _RUNS[-1].enter_context(_io.folder_lock(folder))
    except _io.UserFileError as exc:
        raise ConfigError(field, str(exc)) from None


def mocap_data(text: str, kind: str) -> str | None:
    """``--data FILE.c3d|.bvh|.tsv[?option=value&...]``: a recording and its import options.

    None when ``text`` names no motion capture file (the caller checks it as a CSV).
    The options are those of ``motion-bench import`` without the dashes
    (``rec.c3d?markers=O,X,P&up=y``); the file must exist and the options must name
    what a ``kind`` import needs (checked here, before the file is read).
    """
    from motion_envs.datasets.mocap import is_mocap_source, missing_option, parse_source

    if not is_mocap_source(text):
        return None
    try:
        path, opts = parse_source(text)
    except (ValueError, FileNotFoundError) as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    input_file(str(path))
    missing = missing_option(path, kind, opts)
    if missing is not None:
        field, message = missing
        raise argparse.ArgumentTypeError(f"{message} (add {field.replace('_', '-')}=... after ?)")
    return text


def builtin_data(text: str, kind: Kind) -> bool:
    """``--data``: whether ``text`` names a built-in dataset of ``kind`` (its name, or
    ``NAME:VALUE`` for an entry with a parameter; :mod:`motion_envs.datasets.registry`).

    A built-in name of another kind is an error naming the kind's names.
    """
    from motion_envs.datasets.registry import lookup

    try:
        return lookup(text, kind) is not None
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def missing_data(text: str, kind: Kind) -> argparse.ArgumentTypeError:
    """``--data`` that is neither a built-in name of ``kind`` nor an existing file."""
    from motion_envs.datasets.registry import describe_names

    return argparse.ArgumentTypeError(
        f"expected a built-in {kind} dataset ({describe_names(kind)}) or a CSV file; "
        f"{text} does not exist"
    )


def data_file(text: str, kind: Kind) -> str:
    """``--data`` of a ``kind`` benchmark: a built-in name of ``kind``, a motion capture
    recording (``FILE.c3d?opt=...``) or an existing, readable CSV file (its path)."""
    if builtin_data(text, kind):
        return text
    if (recording := mocap_data(text, kind)) is not None:
        return recording
    if not Path(text).exists():
        raise missing_data(text, kind)
    return str(input_file(text))


def wrote(paths: Sequence[object]) -> str:
    """The line a sub-command prints after writing ``paths``: ``wrote a``, ``wrote a and
    b``, ``wrote a, b and c``."""
    names = [str(p) for p in paths]
    if not names:
        return "wrote nothing"
    if len(names) == 1:
        return f"wrote {names[0]}"
    return f"wrote {', '.join(names[:-1])} and {names[-1]}"


def fail(prog: str, message: str, status: int = 2) -> int:
    """Print ``prog: error: message`` on stderr (one line); return ``status``."""
    print(f"{prog}: error: {' '.join(message.split())}", file=sys.stderr)
    return status
