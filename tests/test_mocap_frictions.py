"""A modeller's own files, each friction as the modeller's call: a CMU BVH needs a numeric
``--unit`` and keeps its ``Frame Time`` as written; a cropped C3D keeps its first frame so
that the file's event times line up with ``t``; a Qualisys TSV with blank fields for the
frames a marker was not seen imports with those frames as gaps."""

from __future__ import annotations

from pathlib import Path

import ezc3d
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from baselines.cli import main
from motion_envs.datasets import load_position_dataset
from motion_envs.datasets.mocap import (
    YUP_TO_ZUP,
    ImportOptions,
    import_position,
    parse_source,
    read_bvh,
    read_qualisys_tsv,
)

#: The CMU database's BVH conversions: lengths in units of (1 / 0.45) inch (0.056444 m),
#: 120 Hz written as ``Frame Time: .0083333``.
CMU_SCALE = 0.056444
CMU_FRAME_TIME = ".0083333"
#: The forearm-to-hand offset of the test skeleton, in CMU units (about 25 cm).
HAND_OFFSET = np.array([4.5, 0.0, 0.0])


def write_cmu_bvh(path: Path, n: int) -> tuple[np.ndarray, Rotation]:
    """A two-joint BVH in CMU's style (ZYX root channels, Frame Time .0083333).

    Returns the root positions (file units, Y-up) and the root rotations per frame.
    """
    k = np.arange(n)
    root = np.column_stack([2.0 * np.sin(k / 40), 17.0 + 0.01 * k, np.cos(k / 50)])
    zyx = np.column_stack([30 * np.sin(k / 30), 20 * np.cos(k / 45), 10 * np.sin(k / 25)])
    text = f"""HIERARCHY
ROOT Hips
{{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation
  JOINT LeftHand
  {{
    OFFSET {HAND_OFFSET[0]} {HAND_OFFSET[1]} {HAND_OFFSET[2]}
    CHANNELS 3 Zrotation Yrotation Xrotation
    End Site
    {{
      OFFSET 1.0 0 0
    }}
  }}
}}
MOTION
Frames: {n}
Frame Time: {CMU_FRAME_TIME}
"""
    rows = [" ".join(repr(float(v)) for v in (*root[i], *zyx[i], 0.0, 0.0, 0.0)) for i in range(n)]
    path.write_text(text + "\n".join(rows) + "\n")
    return root, Rotation.from_euler("ZYX", zyx, degrees=True)


def test_cmu_bvh_numeric_unit_and_the_files_frame_time(tmp_path, capsys):
    root, rot = write_cmu_bvh(tmp_path / "cmu.bvh", 240)
    hand_yup = (root + rot.apply(HAND_OFFSET)) * CMU_SCALE  # the oracle, metres
    # the modeller's calls: the API, the data string and the command line
    ds, report = import_position(
        tmp_path / "cmu.bvh", ImportOptions(joint="LeftHand", unit=str(CMU_SCALE), up="y")
    )
    np.testing.assert_allclose(ds.positions[0], hand_yup @ YUP_TO_ZUP.T, rtol=0, atol=1e-12)
    rate = 1.0 / float(CMU_FRAME_TIME)
    assert report.rate == rate != 120.0  # the file's number, not pybvh's 120 Hz
    np.testing.assert_array_equal(ds.times[0], np.arange(240) / rate)
    assert read_bvh(tmp_path / "cmu.bvh", unit="0.056444").rate == 1.0 / 0.0083333
    _, options = parse_source(f"{tmp_path / 'cmu.bvh'}?joint=LeftHand&unit=0.056444&up=y")
    assert options.unit == "0.056444"
    same = load_position_dataset(f"{tmp_path / 'cmu.bvh'}?joint=LeftHand&unit=0.056444&up=y")
    np.testing.assert_array_equal(same.positions[0], ds.positions[0])
    status = main(
        ["import", str(tmp_path / "cmu.bvh"), "--kind", "position", "--joint", "LeftHand",
         "--unit", "0.056444", "--up", "y", "--out", str(tmp_path / "hand.csv")]
    )  # fmt: skip
    assert status == 0 and "at 120.00048 Hz" in capsys.readouterr().out
    csv = load_position_dataset(tmp_path / "hand.csv")
    np.testing.assert_allclose(csv.positions[0], ds.positions[0], rtol=0, atol=1e-9)


@pytest.mark.parametrize("bad", ["0", "-0.05", "nan", "furlong"])
def test_unit_refused_in_one_line_naming_the_option(tmp_path, capsys, bad):
    write_cmu_bvh(tmp_path / "cmu.bvh", 20)
    with pytest.raises(ValueError, match=r"option unit: expected one of m, cm, mm, in or a numb"):
        parse_source(f"{tmp_path / 'cmu.bvh'}?joint=LeftHand&unit={bad}")
    with pytest.raises(ValueError, match=r"^unit: expected"):
        ImportOptions(unit=bad)
    status = main(["position", "--data", f"{tmp_path / 'cmu.bvh'}?joint=LeftHand&unit={bad}"])
    err = capsys.readouterr().err.strip().splitlines()
    assert status == 2 and len(err) == 1 and "unit" in err[0]


def write_cropped_c3d(path: Path, first_frame: int, rate: float) -> tuple[np.ndarray, int]:
    """A trial cropped to start at frame ``first_frame + 1``, a reach between two events.

    The marker rests, reaches (peak speed at data index ``j``) and rests; EVENT:TIMES
    holds the reach's start and end as Vicon Nexus writes them (seconds of the trial's
    frame numbers, ``(first_frame + index) / rate``). Returns the points (m) and ``j``.
    """
    n, a, b = 300, 100, 220
    u = np.clip((np.arange(n) - a) / (b - a), 0.0, 1.0)
    s = 10 * u**3 - 15 * u**4 + 6 * u**5
    pts = np.column_stack([0.2 + 0.3 * s, 0.1 * s, 0.9 + 0.05 * s])
    c3d = ezc3d.c3d()
    c3d["parameters"]["POINT"]["RATE"]["value"] = [rate]
    c3d["parameters"]["POINT"]["LABELS"]["value"] = ["RFIN"]
    c3d["parameters"]["POINT"]["UNITS"]["value"] = ["m"]
    data = np.ones((4, 1, n))
    data[:3, 0] = pts.T
    c3d["data"]["points"] = data
    c3d["header"]["points"]["first_frame"] = first_frame
    c3d.add_parameter("EVENT", "USED", [2])
    c3d.add_parameter("EVENT", "LABELS", ["Reach start", "Reach end"])
    times = np.array([[0.0, 0.0], [(first_frame + a) / rate, (first_frame + b) / rate]])
    c3d.add_parameter("EVENT", "TIMES", times)
    c3d.write(str(path))
    return pts, (a + b) // 2


def test_c3d_first_frame_kept_so_the_files_events_line_up(tmp_path):
    pts, _ = write_cropped_c3d(tmp_path / "cropped.c3d", first_frame=239, rate=100.0)
    oracle = ezc3d.c3d(str(tmp_path / "cropped.c3d"))  # ezc3d's own header and events
    first = oracle["header"]["points"]["first_frame"]
    rate = oracle["header"]["points"]["frame_rate"]
    start, end = (float(v) for v in oracle["parameters"]["EVENT"]["TIMES"]["value"][1])
    ds, report = import_position(tmp_path / "cropped.c3d", ImportOptions(marker="RFIN"))
    assert first == 239 and report.first_frame == first
    np.testing.assert_array_equal(ds.times[0], (first + np.arange(300)) / rate)
    assert "t from 2.39 s" in report.lines()[0]
    # the file's events, as times, fall on the frames where the reach starts and ends
    k_start = int(np.argmin(np.abs(ds.times[0] - start)))
    k_end = int(np.argmin(np.abs(ds.times[0] - end)))
    assert (k_start, k_end) == (100, 220)
    moving = np.flatnonzero(np.linalg.norm(np.diff(ds.positions[0], axis=0), axis=1) > 0)
    assert (moving[0], moving[-1] + 1) == (k_start, k_end)
    # and a segments table written from the events cuts exactly the reach
    (tmp_path / "events.csv").write_text(f"start,end\n{start!r},{end!r}\n")
    cut, _ = import_position(
        tmp_path / "cropped.c3d",
        ImportOptions(marker="RFIN", segments=tmp_path / "events.csv"),
    )
    np.testing.assert_allclose(cut.positions[0], pts[100:221], rtol=0, atol=1e-6)


COLUMNS = [f"{m} {a}" for m in ("HAND", "HEAD") for a in "XYZ"]


def test_tsv_blank_fields_are_gaps(tmp_path):
    """QTM writes nothing between the tabs where a marker was not seen."""
    n = 120
    t = np.arange(n) / 100.0
    hand = np.column_stack([100 + 200 * t, 50 * t, 900 + 10 * t])  # mm
    head = ["NO_OF_FRAMES\t120", "NO_OF_CAMERAS\t8", "NO_OF_MARKERS\t2", "FREQUENCY\t100",
            "NO_OF_ANALOG\t0", "ANALOG_FREQUENCY\t0", "DESCRIPTION\t--",
            "TIME_STAMP\t2026-12-06, 06:00:00", "DATA_INCLUDED\t3D", "MARKER_NAMES\tHAND\tHEAD",
            "\t".join(["Frame", "Time", *COLUMNS])]  # fmt: skip
    lost = set(range(40, 44)) | set(range(70, 100))  # a short gap (filled), a long one (split)
    rows = []
    for i in range(n):
        h = ["", "", ""] if i in lost else [repr(float(v)) for v in hand[i]]
        head_marker = ["", "", ""] if i < 3 else ["0.0", "0.0", "1700.0"]  # not seen at first
        rows.append("\t".join([str(i + 1), repr(float(t[i])), *h, *head_marker]))
    (tmp_path / "blank.tsv").write_text("\n".join(head + rows) + "\n")
    rec = read_qualisys_tsv(tmp_path / "blank.tsv")
    assert np.isnan(rec.points[sorted(lost), 0]).all() and np.isnan(rec.points[:3, 1]).all()
    assert np.isfinite(rec.points[3:, 1]).all()
    ds, report = import_position(tmp_path / "blank.tsv", ImportOptions(marker="HAND", max_gap=5))
    assert (report.gaps.missing, report.gaps.filled, report.gaps.dropped) == (34, 4, 30)
    assert len(ds) == 2
    np.testing.assert_allclose(ds.positions[0], hand[:70] / 1000.0, rtol=0, atol=1e-12)
    np.testing.assert_allclose(ds.positions[1], hand[100:] / 1000.0, rtol=0, atol=1e-12)
    # a line cut short is still a truncated file, not a gap
    text = (tmp_path / "blank.tsv").read_text().splitlines()
    cut = "\n".join([*text[:-1], "\t".join(text[-1].split("\t")[:5])])
    (tmp_path / "cut.tsv").write_text(cut)
    with pytest.raises(ValueError, match=r"cut\.tsv: truncated TSV file: 119 complete frame"):
        read_qualisys_tsv(tmp_path / "cut.tsv")
    middle = [*text[:20], "\t".join(text[20].split("\t")[:5]), *text[21:]]
    (tmp_path / "short.tsv").write_text("\n".join(middle) + "\n")
    with pytest.raises(ValueError, match=r"short\.tsv: line 21 has 5 fields, expected 8"):
        read_qualisys_tsv(tmp_path / "short.tsv")
