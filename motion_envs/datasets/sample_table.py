"""Reading and writing the users' one-row-per-sample CSV files, with line-numbered errors.

Both the orientation and the position CSV formats share this layout::

    trajectory, subject, task, t, <value columns ...>[, extra columns ...]

The rows of one trajectory are contiguous; ``t`` strictly increases within a
trajectory; ``subject`` and ``task`` are constant within it. :func:`read_sample_table`
checks all of that and raises ``ValueError`` naming the file and the offending line
numbers (the header is line 1); the format-specific loaders add their own checks with
:meth:`SampleTable.fail` and :meth:`SampleTable.per_trajectory`.

Line numbers are the physical lines of the file: blank lines (which are skipped) and
quoted fields spanning several lines are counted, so the number shown is the line a
text editor shows. The file must be UTF-8 text (a byte-order mark is allowed);
compressed files (``.gz``, ``.bz2``, ``.xz``, ``.zip``, ``.zst``) are read as pandas does.

Missing values: only an empty label is missing (``NA``, ``None``, ``null`` are valid
labels); in numeric columns the empty string and :data:`NA_STRINGS` are missing (and
rejected as such).

Plausible ranges: ``|t|`` at most :data:`MAX_ABS_TIME` seconds (10^10 s covers Unix
time stamps until the year 2286) and every numeric value at most the loader's
``max_abs_value`` in absolute value (:data:`MAX_ABS_VALUE` by default); anything
beyond is a corrupt or mis-scaled file, rejected with its line.
"""

from __future__ import annotations

import csv
import gzip
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NoReturn

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from motion_envs._io import atomic_write_bytes, atomic_write_text

__all__ = [
    "LABEL_COLUMNS",
    "MAX_ABS_TIME",
    "MAX_ABS_VALUE",
    "MAX_CSV_BYTES",
    "NA_STRINGS",
    "SampleTable",
    "fail_rows",
    "missing_columns_message",
    "not_text_message",
    "numeric_columns",
    "read_csv_exact",
    "read_csv_text",
    "read_sample_table",
    "replicate_numbers",
    "write_csv",
]

#: Label columns every sample CSV starts with.
LABEL_COLUMNS: tuple[str, ...] = ("trajectory", "subject", "task")

#: Largest accepted ``|t|`` in seconds (10^10 s: Unix time stamps until the year 2286).
MAX_ABS_TIME = 1e10

#: Default largest accepted ``|value|`` of a numeric column (any unit).
MAX_ABS_VALUE = 1e12

#: Largest users' CSV file read, in bytes (1 GiB: 10^7 samples are a few hundred MB).
MAX_CSV_BYTES = 2**30

#: Cells read as missing in numeric columns (pandas' defaults); labels only miss when empty.
NA_STRINGS: tuple[str, ...] = (
    "",
    "#N/A",
    "#N/A N/A",
    "#NA",
    "-1.#IND",
    "-1.#QNAN",
    "-NaN",
    "-nan",
    "1.#IND",
    "1.#QNAN",
    "<NA>",
    "N/A",
    "NA",
    "NULL",
    "NaN",
    "None",
    "n/a",
    "nan",
    "null",
)

_COMPRESSED = (".gz", ".bz2", ".xz", ".zip", ".zst", ".tar")


def replicate_numbers(subjects: NDArray[np.str_], tasks: NDArray[np.str_]) -> NDArray[np.int64]:
    """Number trajectories 0, 1, ... in order within each (subject, task) pair."""
    keys = pd.Series(list(zip(subjects, tasks, strict=True)))
    return keys.groupby(keys).cumcount().to_numpy(dtype=np.int64)


_PANDAS_MAJOR = int(pd.__version__.split(".", 1)[0])


def read_csv_exact(path: str | os.PathLike[str], **kwargs: Any) -> pd.DataFrame:
    """``pandas.read_csv`` that parses every float exactly (round trip).

    pandas 3 parses floats exactly by default; pandas 2 needs
    ``float_precision="round_trip"`` (which pandas 3 deprecates), else a float written with
    17 significant digits can read back 1 ulp off.
    """
    if _PANDAS_MAJOR < 3:
        kwargs.setdefault("float_precision", "round_trip")
    return pd.read_csv(path, **kwargs)


def _record_lines(path: Path) -> list[int] | None:
    """Physical line number (1-based) where each data row of ``path`` starts.

    Counts what pandas skips (blank lines) and quoted fields spanning several lines, so
    row ``i`` of the frame starts on line ``lines[i]``. None for compressed files or when
    the file cannot be re-read as text (then rows are numbered as if one per line).
    """
    if path.suffix.lower() in _COMPRESSED:
        return None
    try:
        with open(path, encoding="utf-8-sig", newline="") as fh:
            reader = csv.reader(fh)
            lines: list[int] = []
            previous_end = 0
            for record in reader:
                start = previous_end + 1
                previous_end = reader.line_num
                if not record or (len(record) == 1 and not record[0].strip()):
                    continue  # a blank line: pandas skips it
                lines.append(start)
    except (OSError, UnicodeDecodeError, csv.Error):
        return None
    return lines[1:]  # the first record is the header


def _fail(path: Path, mask: NDArray[np.bool_], what: str) -> NoReturn:
    rows = np.flatnonzero(mask)
    lines = _record_lines(path)
    if lines is not None and len(lines) >= mask.size:
        bad = np.asarray(lines)[rows]
    else:
        bad = rows + 2  # the header is line 1
    shown = ", ".join(str(b) for b in bad[:10]) + (" ..." if bad.size > 10 else "")
    raise ValueError(f"{path}: {what} on line(s) {shown} ({bad.size} row(s))")


#: Other separators a spreadsheet's "CSV" may use, by the name said in messages.
_SEPARATORS = {";": "';'", "\t": "tab", "|": "'|'"}
#: The first bytes of spreadsheet workbooks, which are not CSV text.
_WORKBOOKS = {
    b"PK\x03\x04": "an Excel workbook (.xlsx, .xlsm) or another zip file",
    b"\xd0\xcf\x11\xe0\xa1\xb1\x1a\xe1": "an Excel 97-2003 workbook (.xls)",
}


def missing_columns_message(
    where: str, columns: Sequence[str], missing: Sequence[str], expected: str
) -> str:
    """``"{where}: missing column(s) [...]; expected header {expected}"``, and when the
    header was read as one column holding ``;``, a tab or ``|``, why: the file is
    separated by that character (a spreadsheet in a locale whose decimal mark is a comma
    writes ``;``)."""
    message = f"{where}: missing column(s) {list(missing)}; expected header {expected}"
    names = [str(c) for c in columns]
    if len(names) == 1:
        for sep, said in _SEPARATORS.items():
            if sep in names[0]:
                return (
                    f"{message}. The header is one column ({names[0]!r}): the file is "
                    f"{said}-separated, not comma-separated (a spreadsheet set to a "
                    "decimal comma writes ';'); save it as comma-separated CSV with '.' as "
                    "the decimal mark"
                )
    return message


def not_text_message(where: str, head: bytes) -> str:
    """Why ``head`` (a file's first bytes, binary) is not a CSV: a spreadsheet workbook
    (save the sheet as CSV) or any other binary file."""
    for magic, what in _WORKBOOKS.items():
        if head.startswith(magic):
            return (
                f"{where}: {what}, not a CSV text file; save the sheet as 'CSV (comma delimited)'"
            )
    return f"{where}: binary file (NUL bytes), not a CSV text file"


def read_csv_text(
    path: str | os.PathLike[str], kind: str, label_columns: Sequence[str] = LABEL_COLUMNS
) -> pd.DataFrame:
    """THE front end of every users' CSV loader: the raw table, checked as text.

    ``FileNotFoundError`` for a missing file; ``ValueError`` naming the file for a folder,
    a FIFO or device, a file over :data:`MAX_CSV_BYTES`, an empty, binary (NUL bytes),
    non-UTF-8 or malformed file. ``label_columns`` are read as text and only an empty
    label is missing (``NA``, ``None`` are labels); in the other columns
    :data:`NA_STRINGS` are missing.
    """
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"{kind} CSV {path} does not exist")
    if path.is_dir():
        raise ValueError(f"{kind} CSV {path} is a folder, not a file")
    if not path.is_file():  # a FIFO or a device would block or never end
        raise ValueError(f"{kind} CSV {path} is not a regular file")
    if path.stat().st_size > MAX_CSV_BYTES:
        raise ValueError(
            f"{path}: {path.stat().st_size} bytes, more than the {MAX_CSV_BYTES} bytes "
            "a users' CSV may have"
        )
    if path.suffix.lower() not in _COMPRESSED:
        with open(path, "rb") as fh:
            head = fh.read(65536)
        if not head.strip():
            raise ValueError(f"{path}: empty file; expected a header line and data rows")
        if b"\0" in head or any(head.startswith(m) for m in _WORKBOOKS):
            raise ValueError(not_text_message(str(path), head))
        try:
            head.decode("utf-8")
        except UnicodeDecodeError as exc:
            if exc.end < len(head) - 3:  # not merely a character cut at the chunk's end
                raise _encoding_error(path, exc) from None
    try:
        header = read_csv_exact(path, nrows=0).columns
        na = {c: ([""] if c in label_columns else list(NA_STRINGS)) for c in header}
        return read_csv_exact(
            path,
            dtype={c: str for c in label_columns if c in header},
            keep_default_na=False,
            na_values=na,
        )
    except pd.errors.EmptyDataError:
        raise ValueError(f"{path}: empty file; expected a header line and data rows") from None
    except UnicodeDecodeError as exc:
        raise _encoding_error(path, exc) from None
    except pd.errors.ParserError as exc:
        raise ValueError(f"{path}: not a well-formed CSV file: {exc}") from None
    except (OSError, EOFError) as exc:  # a corrupt compressed file, a read error
        raise ValueError(f"{path}: cannot be read: {exc}") from None


def fail_rows(path: Path, mask: NDArray[np.bool_], what: str) -> NoReturn:
    """Raise ``ValueError`` naming ``path`` and the physical line numbers of the rows of
    the table :func:`read_csv_text` read where ``mask`` is set."""
    _fail(path, mask, what)


def numeric_columns(
    path: Path,
    frame: pd.DataFrame,
    columns: Sequence[str],
    max_abs_value: float = MAX_ABS_VALUE,
    value_unit: str = "",
) -> NDArray[np.float64]:
    """``frame[columns]`` as float64, the first column a time: ``ValueError`` with the
    lines of NaN, infinite or non-numeric cells, a time beyond :data:`MAX_ABS_TIME` or a
    value beyond ``max_abs_value`` (in ``value_unit``)."""
    numeric = list(columns)
    try:
        data = frame[numeric].apply(pd.to_numeric, errors="coerce").to_numpy(dtype=np.float64)
    except OverflowError:  # pandas reads an integer of hundreds of digits as an int first
        data = frame[numeric].map(_cell_float).to_numpy(dtype=np.float64)
    nonfinite = ~np.isfinite(data).all(axis=1)
    if nonfinite.any():
        _fail(path, nonfinite, f"NaN, infinite or non-numeric value in {'/'.join(numeric)}")
    absurd_t = np.abs(data[:, 0]) > MAX_ABS_TIME
    if absurd_t.any():
        _fail(
            path,
            absurd_t,
            f"time {numeric[0]!r} beyond the plausible range |t| <= {MAX_ABS_TIME:g} s",
        )
    huge = (np.abs(data[:, 1:]) > max_abs_value).any(axis=1)
    if huge.any():
        unit = f" {value_unit}" if value_unit else ""
        _fail(
            path,
            huge,
            f"value in {'/'.join(numeric[1:])} beyond the plausible range "
            f"|value| <= {max_abs_value:g}{unit}",
        )
    return data


def _cell_float(cell: object) -> float:
    """One cell as a float as :func:`float` reads it (an integer too large for a float is
    infinite), NaN where it is not a number."""
    try:
        return float(str(cell))
    except ValueError:
        return float("nan")


def _encoding_error(path: Path, exc: UnicodeDecodeError) -> ValueError:
    return ValueError(
        f"{path}: not UTF-8 text (byte 0x{exc.object[exc.start]:02x} at offset {exc.start}); "
        "save the CSV as UTF-8"
    )


def _per_trajectory(
    path: Path, frame: pd.DataFrame, column: str, starts: NDArray[Any], ends: NDArray[Any]
) -> NDArray[Any]:
    arr = frame[column].to_numpy()
    first = arr[starts]
    varies = arr != np.repeat(first, ends - starts)
    if np.any(varies):
        _fail(path, varies, f"{column!r} changes within a trajectory")
    return first


@dataclass(frozen=True)
class SampleTable:
    """A validated sample CSV split into trajectories.

    Attributes
    ----------
    path:
        The file read.
    frame:
        The raw table (``pandas.DataFrame``), one row per sample.
    t:
        ``(n_rows,)`` times.
    values:
        ``(n_rows, k)`` the numeric value columns asked for, all finite.
    value_columns:
        Names of the columns of ``values``.
    starts, ends:
        ``(L,)`` first row and one-past-last row of each trajectory.
    ids, subjects, tasks:
        ``(L,)`` labels of each trajectory.
    """

    path: Path
    frame: pd.DataFrame
    t: NDArray[np.float64]
    values: NDArray[np.float64]
    value_columns: tuple[str, ...]
    starts: NDArray[np.int64]
    ends: NDArray[np.int64]
    ids: NDArray[np.str_]
    subjects: NDArray[np.str_]
    tasks: NDArray[np.str_]

    def fail(self, mask: NDArray[np.bool_], what: str) -> NoReturn:
        """Raise ``ValueError`` listing the line numbers of the rows where ``mask`` is set."""
        _fail(self.path, mask, what)

    def segments(self) -> list[tuple[int, int]]:
        """``[(start, end), ...]`` row range of each trajectory."""
        return list(zip(self.starts.tolist(), self.ends.tolist(), strict=True))

    def per_trajectory(self, column: str) -> NDArray[Any]:
        """The value of ``column`` for each trajectory; it must not change within one."""
        return _per_trajectory(self.path, self.frame, column, self.starts, self.ends)


def read_sample_table(
    path: str | os.PathLike[str],
    value_columns: Sequence[str],
    min_samples: int,
    kind: str,
    optional_value_columns: Sequence[str] = (),
    max_abs_value: float = MAX_ABS_VALUE,
    value_unit: str = "",
) -> SampleTable:
    """Read a sample CSV and check the layout shared by every format.

    Parameters
    ----------
    path:
        The CSV file.
    value_columns:
        Required numeric columns after ``t`` (e.g. ``qw, qx, qy, qz`` or ``x, y``).
    min_samples:
        Fewest samples accepted per trajectory.
    kind:
        Word used in messages (``"orientation"``, ``"position"``).
    optional_value_columns:
        Numeric columns appended to ``values`` when the file has them (e.g. ``z``).
    max_abs_value:
        Largest plausible ``|value|`` of the value columns.
    value_unit:
        Unit named in the message when a value is beyond ``max_abs_value``.

    Raises ``FileNotFoundError`` for a missing file and ``ValueError`` naming the file
    for a folder, an empty, binary or non-UTF-8 file, and naming the file and the line
    numbers for: missing columns, empty labels, NaN/inf/non-numeric values, a time
    beyond :data:`MAX_ABS_TIME` or a value beyond ``max_abs_value``, non-contiguous
    trajectories, too few samples, times that do not strictly increase, subject or task
    labels changing within a trajectory.
    """
    p = Path(path)
    required = (*LABEL_COLUMNS, "t", *value_columns)
    frame = read_csv_text(p, kind)
    missing = [c for c in required if c not in frame.columns]
    if missing:
        expected = ",".join(required)
        raise ValueError(missing_columns_message(str(p), frame.columns, missing, expected))
    if len(frame) == 0:
        raise ValueError(f"{p}: no data rows")
    for col in LABEL_COLUMNS:
        empty = frame[col].isna().to_numpy()
        if empty.any():
            _fail(p, empty, f"empty {col!r}")
    numeric = ["t", *value_columns, *(c for c in optional_value_columns if c in frame.columns)]
    data = numeric_columns(p, frame, numeric, max_abs_value, value_unit)

    traj = frame["trajectory"].to_numpy(dtype=str)
    starts = np.flatnonzero(np.concatenate([[True], traj[1:] != traj[:-1]]))
    ids = traj[starts]
    if len(set(ids)) != ids.size:
        dup = pd.Series(ids)[pd.Series(ids).duplicated()].iloc[0]
        repeated = starts[ids == dup][1:]
        _fail(p, np.isin(np.arange(len(frame)), repeated), f"trajectory {dup!r} is not contiguous")
    ends = np.concatenate([starts[1:], [len(frame)]])
    lengths = ends - starts
    short = np.isin(np.arange(len(frame)), starts[lengths < min_samples])
    if short.any():
        _fail(p, short, f"trajectory with fewer than {min_samples} samples starts")
    seg = np.repeat(np.arange(ids.size), lengths)
    t = data[:, 0]
    unsorted = np.concatenate([[False], (np.diff(t) <= 0) & (seg[1:] == seg[:-1])])
    if unsorted.any():
        _fail(p, unsorted, "time not strictly increasing within its trajectory")
    labels = {c: _per_trajectory(p, frame, c, starts, ends).astype(str) for c in LABEL_COLUMNS[1:]}
    return SampleTable(
        path=p,
        frame=frame,
        t=t,
        values=data[:, 1:],
        value_columns=tuple(numeric[1:]),
        starts=starts.astype(np.int64),
        ends=ends.astype(np.int64),
        ids=ids.astype(str),
        subjects=labels["subject"],
        tasks=labels["task"],
    )


def write_csv(frames: Sequence[pd.DataFrame], path: str | os.PathLike[str]) -> Path:
    """Concatenate per-trajectory frames and write them to ``path`` atomically.

    Floats are written with 17 significant digits, so a float64 read back is identical.
    A path ending in ``.gz`` is gzip-compressed.
    """
    text = pd.concat(frames, ignore_index=True).to_csv(index=False, float_format="%.17g")
    if str(path).lower().endswith(".gz"):
        return atomic_write_bytes(path, gzip.compress(text.encode("utf-8"), mtime=0))
    return atomic_write_text(path, text)
