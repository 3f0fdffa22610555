"""Bad input to the orientation and position CSV loaders: one table, message and line.

Each case is a file's exact bytes; the expected line numbers are counted by hand
(header = line 1), so blank lines and quoted multi-line fields must be counted by the
loader as a text editor counts them.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from motion_envs.datasets import read_orientation_csv, read_position_csv

O_HEADER = "trajectory,subject,task,t,qw,qx,qy,qz"
P_HEADER = "trajectory,subject,task,t,x,y"


def _o_rows(traj: str, subject: str = "s1", task: str = "k1", n: int = 6) -> list[str]:
    """``n`` valid orientation rows: a rotation about z growing to 0.5 rad."""
    rows = []
    for i in range(n):
        half = 0.25 * i / (n - 1)
        rows.append(
            f"{traj},{subject},{task},{0.1 * i:.1f},{math.cos(half)!r},0,0,{math.sin(half)!r}"
        )
    return rows


def _p_rows(traj: str, subject: str = "s1", task: str = "k1", n: int = 6) -> list[str]:
    return [f"{traj},{subject},{task},{0.1 * i:.1f},{float(i)},{float(i * i)}" for i in range(n)]


def _set(rows: list[str], i: int, column: int, value: str) -> list[str]:
    out = list(rows)
    cells = out[i].split(",")
    cells[column] = value
    out[i] = ",".join(cells)
    return out


def _text(header: str, *blocks: list[str]) -> bytes:
    return ("\n".join([header, *(r for b in blocks for r in b)]) + "\n").encode()


_A, _B = _o_rows("a"), _o_rows("b")
_PA, _PB = _p_rows("a"), _p_rows("b")

# (id, loader, file bytes, message fragment, first bad line or None)
CASES = [
    # absurd times: 1e308 parses as a finite float and used to change the results
    ("o-time-1e308", "o", _text(O_HEADER, _A, _set(_B, 5, 3, "1e308")), "time 't' beyond", 13),
    ("o-time-negative", "o", _text(O_HEADER, _set(_A, 0, 3, "-2e10"), _B), "time 't'", 2),
    ("p-time-1e308", "p", _text(P_HEADER, _set(_PA, 2, 3, "1e308")), "time 't' beyond", 4),
    # finite but huge position
    ("p-huge-x", "p", _text(P_HEADER, _PA, _set(_PB, 1, 4, "1e200")), "plausible range", 9),
    ("p-huge-y", "p", _text(P_HEADER, _set(_PA, 3, 5, "-3e9")), "plausible range", 5),
    (
        "o-huge-predictor",
        "o",
        (
            "trajectory,subject,task,t,qw,qx,qy,qz,age\n"
            + "\n".join(r + ",30" for r in _A)
            + "\n"
            + "\n".join(r + ",1e300" for r in _B)
            + "\n"
        ).encode(),
        "predictor 'age' beyond",
        8,
    ),
    (
        "o-replicate-huge",
        "o",
        _text(O_HEADER + ",replicate", [r + ",1e20" for r in _A]),
        "replicate",
        2,
    ),
    # line numbers after blank lines
    (
        "o-blank-lines",
        "o",
        ("\n".join([O_HEADER, "", *_A, "", "", *_set(_B, 2, 4, "nan")]) + "\n").encode(),
        "NaN",
        13,  # header, blank, a's rows 3-8, blanks 9-10, b's rows 11-16: its third is 13
    ),
    (
        "p-blank-lines-whitespace",
        "p",
        ("\n".join([P_HEADER, *_PA, "   ", *_set(_PB, 0, 4, "oops")]) + "\n").encode(),
        "non-numeric",
        9,
    ),
    # line numbers after a quoted field spanning two lines (the subject of a)
    (
        "o-multiline-label",
        "o",
        _text(
            O_HEADER,
            [r.replace(",s1,", ',"first\nsecond",', 1) for r in _A],
            _set(_B, 1, 7, "0.9"),
        ),
        "quaternion norm",
        15,  # a's 6 rows take 12 lines (2-13); b starts on 14
    ),
    (
        "p-multiline-then-unsorted",
        "p",
        _text(P_HEADER, [_PA[0].replace(",k1,", ',"k\n1",', 1), *_PA[1:]], _set(_PB, 2, 3, "0.0")),
        "strictly increasing",
        11,
    ),
    # files that are not CSV text
    ("o-empty", "o", b"", "empty file", None),
    ("o-whitespace-only", "o", b"\n\n  \n", "empty file", None),
    (
        "p-binary",
        "p",
        b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR" + bytes(range(256)),
        "binary file",
        None,
    ),
    (
        "o-latin1",
        "o",
        _text(O_HEADER, [r.replace(",s1,", ",José,", 1) for r in _A]).decode().encode("latin-1"),
        "not UTF-8",
        None,
    ),
    ("p-header-only", "p", (P_HEADER + "\n").encode(), "no data rows", None),
    ("p-bad-quote", "p", _text(P_HEADER, _PA, ['b,"s1,k1,0.0,1,2', *_PB[1:]]), "", None),
]


@pytest.mark.parametrize(
    ("loader", "content", "fragment", "line"),
    [c[1:] for c in CASES],
    ids=[c[0] for c in CASES],
)
def test_bad_csv_names_file_and_line(tmp_path, loader, content, fragment, line):
    path = tmp_path / "data.csv"
    path.write_bytes(content)
    read = read_orientation_csv if loader == "o" else read_position_csv
    with pytest.raises(ValueError) as info:
        read(path)
    message = str(info.value)
    assert "\n" not in message.strip() or "Error tokenizing" in message
    assert str(path) in message
    assert fragment in message
    if line is not None:
        assert f"line(s) {line}," in message or f"line(s) {line} (" in message, message


@pytest.mark.parametrize("label", ["NA", "None", "null", "NaN", "N/A", "nan"])
def test_na_like_labels_are_labels(tmp_path, label):
    path = tmp_path / "o.csv"
    path.write_bytes(_text(O_HEADER, _o_rows(label, subject=label, task=label), _B))
    ds = read_orientation_csv(path)
    assert ds.trajectory_ids.tolist() == [label, "b"]
    assert ds.subjects.tolist() == [label, "s1"]
    assert ds.tasks.tolist() == [label, "k1"]
    ppath = tmp_path / "p.csv"
    ppath.write_bytes(_text(P_HEADER, _p_rows(label, subject=label, task=label)))
    assert read_position_csv(ppath).tasks.tolist() == [label]


def test_na_in_a_numeric_column_is_still_missing(tmp_path):
    path = tmp_path / "p.csv"
    path.write_bytes(_text(P_HEADER, _set(_PA, 4, 4, "NA")))
    with pytest.raises(ValueError, match=r"NaN, infinite or non-numeric .* line\(s\) 6 "):
        read_position_csv(path)


def test_an_empty_label_is_missing(tmp_path):
    path = tmp_path / "p.csv"
    path.write_bytes(_text(P_HEADER, _set(_PA, 2, 1, "")))
    with pytest.raises(ValueError, match=r"empty 'subject' on line\(s\) 4 "):
        read_position_csv(path)


def test_folder_and_missing_file(tmp_path):
    with pytest.raises(ValueError, match="is a folder"):
        read_position_csv(tmp_path)
    with pytest.raises(FileNotFoundError, match="does not exist"):
        read_orientation_csv(tmp_path / "nope.csv")


def test_plausible_edges_are_accepted(tmp_path):
    # Unix time stamps and large-but-plausible positions load unchanged
    rows = [f"a,s,k,{1.7e9 + 0.01 * i!r},{1e8 * i:.1f},-5e8" for i in range(6)]
    path = tmp_path / "p.csv"
    path.write_bytes(_text(P_HEADER, rows))
    ds = read_position_csv(path)
    np.testing.assert_array_equal(ds.times[0], [1.7e9 + 0.01 * i for i in range(6)])
    assert ds.positions[0][:, 0].max() == 5e8


def test_utf8_bom_and_utf8_labels(tmp_path):
    path = tmp_path / "o.csv"
    path.write_bytes(b"\xef\xbb\xbf" + _text(O_HEADER, [r.replace(",s1,", ",José,") for r in _A]))
    assert read_orientation_csv(path).subjects.tolist() == ["José"]


def test_gzip_csv_still_reads(tmp_path):
    import gzip

    path = tmp_path / "p.csv.gz"
    path.write_bytes(gzip.compress(_text(P_HEADER, _PA)))
    assert len(read_position_csv(path)) == 1
    Path(tmp_path / "bad.csv.gz").write_bytes(gzip.compress(_text(P_HEADER, _set(_PA, 1, 4, "x"))))
    with pytest.raises(ValueError, match=r"line\(s\) 3 "):
        read_position_csv(tmp_path / "bad.csv.gz")


def test_a_semicolon_or_tab_separated_file_is_named_as_such(tmp_path):
    """A spreadsheet set to a decimal comma saves "CSV" with ';' (and '1,5'): the header
    is then one column and every column is "missing"; the message says why."""
    semi = _text(O_HEADER.replace(",", ";"), [r.replace(",", ";") for r in _A]).replace(b".", b",")
    tab = _text(P_HEADER.replace(",", "\t"), [r.replace(",", "\t") for r in _PA])
    for name, content, loader, said in [
        ("semi.csv", semi, read_orientation_csv, "';'-separated"),
        ("tab.csv", tab, read_position_csv, "tab-separated"),
    ]:
        path = tmp_path / name
        path.write_bytes(content)
        with pytest.raises(ValueError, match="missing column") as err:
            loader(path)
        assert said in str(err.value) and "comma-separated" in str(err.value)
    # a comma-separated file missing a column gets no such hint
    path = tmp_path / "short.csv"
    path.write_bytes(_text(P_HEADER.replace(",y", ""), [r.rsplit(",", 1)[0] for r in _PA]))
    with pytest.raises(ValueError, match=r"missing column\(s\) \['y'\]") as err:
        read_position_csv(path)
    assert "separated" not in str(err.value)


@pytest.mark.parametrize(
    ("magic", "what"),
    [
        (b"PK\x03\x04\x14\x00\x06\x00", "Excel workbook"),
        (b"\xd0\xcf\x11\xe0\xa1\xb1\x1a\xe1", ".xls"),
    ],
)
def test_an_excel_workbook_is_named_as_such(tmp_path, magic, what):
    path = tmp_path / "data.csv"
    path.write_bytes(magic + b"\x00" * 64)
    with pytest.raises(ValueError, match=what) as err:
        read_orientation_csv(path)
    assert "CSV (comma delimited)" in str(err.value)
