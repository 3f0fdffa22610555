"""Motion capture import (C3D, BVH, Qualisys TSV): round trips of a known synthetic
movement through files the tests write themselves (ezc3d's writer for C3D, text for TSV
and BVH), the benchmarks' results on a recording vs the same data as the project's CSV,
and one-line errors naming the file."""

from __future__ import annotations

import dataclasses
import itertools
import os
from pathlib import Path

import ezc3d
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from baselines import orientation_bench, position_bench
from baselines.cli import main
from motion_envs.datasets import load_orientation_dataset, load_position_dataset
from motion_envs.datasets.juggling import generate_demonstrations
from motion_envs.datasets.mocap import (
    YUP_TO_ZUP,
    ImportOptions,
    import_juggling,
    import_orientation,
    import_position,
    read_bvh,
)
from motion_envs.models.juggling import load_juggling_csv

RATE = 120.0
N_MOVES = 8
#: The rigid body's markers in its own frame: ORIGIN, X (on +x), PLANE (in the xy-plane, +y).
BODY = np.array([[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.03, 0.08, 0.0]])


def minimum_jerk(s: np.ndarray) -> np.ndarray:
    return 10 * s**3 - 15 * s**4 + 6 * s**5


def synthetic_movement() -> tuple[np.ndarray, Rotation, np.ndarray]:
    """Times, orientations and origin positions (Z-up, m): 8 reaches of 1 s between rests.

    Reach ``k`` starts at ``0.5 + 1.5 k`` s and turns the body by ``angles[k]`` about
    ``axes[k]`` while its origin moves to ``targets[k + 1]``, both on a minimum-jerk profile.
    """
    t = np.arange(round((0.5 + N_MOVES * 1.5) * RATE)) / RATE
    rng = np.random.default_rng(3)
    axes = rng.normal(size=(N_MOVES, 3))
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    angles = np.radians(rng.uniform(40, 80, N_MOVES))
    targets = rng.uniform(-0.3, 0.3, (N_MOVES + 1, 3)) + np.array([0.0, 0.4, 1.0])
    bases = [Rotation.from_rotvec([0.2, -0.1, 0.3])]
    for k in range(N_MOVES):
        bases.append(Rotation.from_rotvec(axes[k] * angles[k]) * bases[-1])
    k = np.clip(np.floor((t - 0.5) / 1.5).astype(int), 0, N_MOVES - 1)
    s = minimum_jerk(np.clip(t - (0.5 + 1.5 * k), 0.0, 1.0))
    base = Rotation.concatenate([bases[i] for i in k])
    rot = Rotation.from_rotvec(axes[k] * (angles[k] * s)[:, None]) * base
    pos = targets[k] + s[:, None] * (targets[k + 1] - targets[k])
    return t, rot, pos


@pytest.fixture(scope="module")
def movement():
    return synthetic_movement()


def marker_points(rot: Rotation, pos: np.ndarray) -> np.ndarray:
    """``(F, 3, 3)`` world positions of the three markers (Z-up, m)."""
    return np.stack([pos + rot.apply(b) for b in BODY], axis=1)


#: Frames where marker X is missing: a short gap in reach 1 (filled) and a long one in
#: the rest between reaches 4 and 5 (7.625 to 7.875 s; splits the recording).
SHORT_GAP = np.arange(300, 303)
LONG_GAP = np.arange(915, 945)


def write_c3d(path: Path, points_zup: np.ndarray, labels: list[str]) -> np.ndarray:
    """Write ``points_zup`` (F, M, 3, m) as a Y-up C3D in mm with X missing in the gaps.

    Returns the Z-up positions as stored (float32 in the file) in metres.
    """
    yup = points_zup @ YUP_TO_ZUP  # the inverse rotation: Z-up -> Y-up
    c3d = ezc3d.c3d()
    c3d["parameters"]["POINT"]["RATE"]["value"] = [RATE]
    c3d["parameters"]["POINT"]["LABELS"]["value"] = labels
    c3d["parameters"]["POINT"]["UNITS"]["value"] = ["mm"]
    data = np.ones((4, len(labels), yup.shape[0]))
    data[:3] = (yup * 1000.0).transpose(2, 1, 0)
    residuals = np.zeros((1, len(labels), yup.shape[0]))
    residuals[0, 1, SHORT_GAP[SHORT_GAP < yup.shape[0]]] = -1
    residuals[0, 1, LONG_GAP[LONG_GAP < yup.shape[0]]] = -1
    c3d["data"]["points"] = data
    c3d["data"]["meta_points"] = {
        "residuals": residuals,
        "camera_masks": np.zeros((7, len(labels), yup.shape[0]), dtype=bool),
    }
    c3d.write(str(path))
    stored = data[:3].astype(np.float32).astype(np.float64).transpose(2, 1, 0) / 1000.0
    return stored @ YUP_TO_ZUP.T


def write_tsv(
    path: Path,
    points_mm: np.ndarray,
    names: list[str],
    frame_time: bool = True,
    rate: float | None = None,
) -> None:
    """A Qualisys TSV 3D export: header lines, Frame/Time header, mm, 0 = missing (at
    ``rate`` Hz; None: the module's ``RATE`` when called)."""
    rate = RATE if rate is None else rate
    n = points_mm.shape[0]
    head = [
        f"NO_OF_FRAMES\t{n}",
        "NO_OF_CAMERAS\t8",
        f"NO_OF_MARKERS\t{len(names)}",
        f"FREQUENCY\t{rate:g}",
        "NO_OF_ANALOG\t0",
        "ANALOG_FREQUENCY\t0",
        "DESCRIPTION\t--",
        "TIME_STAMP\t2026-12-02, 06:00:00",
        "DATA_INCLUDED\t3D",
        "MARKER_NAMES\t" + "\t".join(names),
    ]
    cols = ["Frame", "Time"] + [f"{m} {a}".strip() for m in names for a in "XYZ"]
    body = np.nan_to_num(points_mm.reshape(n, -1), nan=0.0)
    rows = [
        "\t".join([str(i + 1), repr(i / rate), *(repr(float(v)) for v in row)])
        for i, row in enumerate(body)
    ]
    path.write_text("\n".join([*head, "\t".join(cols), *rows]) + "\n")


def segments_table(path: Path, t: np.ndarray) -> Path:
    """The 8 reaches as a side table: 2 subjects x 2 tasks x 2 replicates."""
    lines = ["start,end,subject,task"]
    for k in range(N_MOVES):
        start = 0.5 + 1.5 * k - 0.1
        lines.append(f"{start:.6f},{start + 1.2:.6f},s{k // 4},{'ab'[k % 2]}")
    path.write_text("\n".join(lines) + "\n")
    return path


def frames_of(times: np.ndarray) -> np.ndarray:
    return np.rint(times * RATE).astype(int)


def triad_oracle(points: np.ndarray) -> Rotation:
    """scipy's alignment: X - ORIGIN exactly on +x, PLANE - ORIGIN best on +y."""
    out = []
    for o, x, p in points:
        r, _ = Rotation.align_vectors([x - o, p - o], [[1, 0, 0], [0, 1, 0]], weights=[np.inf, 1])
        out.append(r.as_quat())
    return Rotation.from_quat(out)


def angle_to(q_wxyz: np.ndarray, rot: Rotation) -> np.ndarray:
    mine = Rotation.from_quat(q_wxyz[:, [1, 2, 3, 0]])
    return (mine * rot.inv()).magnitude()


# --------------------------------------------------------------------------------------
# round trips
# --------------------------------------------------------------------------------------


def test_c3d_round_trip_mm_yup_with_gaps(tmp_path, movement):
    t, rot, pos = movement
    points = marker_points(rot, pos)
    stored = write_c3d(tmp_path / "rec.c3d", points, ["O", "X", "P"])
    options = ImportOptions(markers=("O", "X", "P"), up="y", max_gap=5)
    ds, report = import_orientation(tmp_path / "rec.c3d", options)
    assert report.gaps.missing == SHORT_GAP.size + LONG_GAP.size
    assert report.gaps.filled == SHORT_GAP.size
    assert report.gaps.dropped == LONG_GAP.size
    assert report.gaps.pieces == 2 == len(ds)
    times = np.concatenate(ds.times)
    k = frames_of(times)
    np.testing.assert_allclose(times, k / RATE, rtol=0, atol=1e-12)  # time from the file start
    q = np.concatenate(ds.quaternions)
    measured = ~np.isin(k, SHORT_GAP)
    oracle = triad_oracle(stored[k[measured]])
    assert angle_to(q[measured], oracle).max() < 1e-9
    assert angle_to(q[measured], rot[k[measured]]).max() < 1e-5  # float32 storage only
    filled = np.isin(k, SHORT_GAP)
    assert filled.sum() == SHORT_GAP.size
    assert angle_to(q[filled], rot[k[filled]]).max() < 1e-3  # slerp across 3 frames
    pos_ds, _ = import_position(tmp_path / "rec.c3d", ImportOptions(marker="O", up="y"))
    times = np.concatenate(pos_ds.times)
    assert len(pos_ds) == 1 and times.size == t.size  # O is never missing
    y = np.concatenate(pos_ds.positions)
    assert np.abs(y - stored[:, 0]).max() < 1e-12
    assert np.abs(y - pos).max() < 1e-6


def test_tsv_round_trip_with_gaps(tmp_path, movement):
    _, rot, pos = movement
    points = marker_points(rot, pos) * 1000.0
    points[SHORT_GAP, 2] = np.nan
    points[LONG_GAP, 2] = np.nan
    write_tsv(tmp_path / "rec.tsv", points, ["O", "X", "P"])
    options = ImportOptions(markers=("O", "X", "P"), max_gap=3)
    ds, report = import_orientation(tmp_path / "rec.tsv", options)
    assert (report.gaps.filled, report.gaps.dropped, len(ds)) == (3, LONG_GAP.size, 2)
    k = frames_of(np.concatenate(ds.times))
    q = np.concatenate(ds.quaternions)
    measured = ~np.isin(k, SHORT_GAP)
    assert angle_to(q[measured], rot[k[measured]]).max() < 1e-9
    pos_ds, _ = import_position(tmp_path / "rec.tsv", ImportOptions(marker="X"))
    k = frames_of(np.concatenate(pos_ds.times))
    assert np.abs(np.concatenate(pos_ds.positions) - points[k, 1] / 1000.0).max() < 1e-6


def test_tsv_without_column_header(tmp_path, movement):
    """Older exports: no Frame/Time header line, only MARKER_NAMES and the X/Y/Z columns."""
    _, rot, pos = movement
    points = marker_points(rot, pos)[:200] * 1000.0
    write_tsv(tmp_path / "old.tsv", points, ["O", "X", "P"])
    lines = (tmp_path / "old.tsv").read_text().splitlines()
    kept = [ln for ln in lines if not ln.startswith("Frame")]
    kept = kept[:10] + ["\t".join(ln.split("\t")[2:]) for ln in kept[10:]]
    (tmp_path / "old.tsv").write_text("\n".join(kept) + "\n")
    ds, _ = import_position(tmp_path / "old.tsv", ImportOptions(marker="P"))
    assert np.abs(ds.positions[0] - points[:, 2] / 1000.0).max() < 1e-12


# BVH: root ZYX, child XZY, grandchild YXZ (mixed orders in one file, as CMU files have)
BVH_ORDERS = ("ZYX", "XZY", "YXZ")
BVH_OFFSETS = np.array([[0.0, 0.0, 0.0], [0.0, 30.0, 5.0], [20.0, 0.0, -3.0]])  # cm


def bvh_angles(t: np.ndarray) -> np.ndarray:
    """``(F, 3 joints, 3)`` Euler angles in degrees in each joint's CHANNELS order."""
    phase = 2 * np.pi * t[:, None, None] / 3.0
    amp = np.array([[40.0, 25.0, 60.0], [70.0, 35.0, 20.0], [15.0, 80.0, 45.0]])
    return amp * np.sin(phase * np.array([1.0, 1.3, 0.7]) + np.arange(3)[:, None])


def write_bvh(path: Path, t: np.ndarray, root: np.ndarray, angles: np.ndarray) -> None:
    def channels(order: str) -> str:
        return " ".join(f"{a}rotation" for a in order)

    o = BVH_OFFSETS
    text = f"""HIERARCHY
ROOT Hips
{{
  OFFSET 0.0 0.0 0.0
  CHANNELS 6 Xposition Yposition Zposition {channels(BVH_ORDERS[0])}
  JOINT Chest
  {{
    OFFSET {o[1, 0]} {o[1, 1]} {o[1, 2]}
    CHANNELS 3 {channels(BVH_ORDERS[1])}
    JOINT Hand
    {{
      OFFSET {o[2, 0]} {o[2, 1]} {o[2, 2]}
      CHANNELS 3 {channels(BVH_ORDERS[2])}
      End Site
      {{
        OFFSET 5.0 0.0 0.0
      }}
    }}
  }}
}}
MOTION
Frames: {t.size}
Frame Time: {1 / RATE!r}
"""
    rows = [
        " ".join(repr(float(v)) for v in np.concatenate([root[i], angles[i].ravel()]))
        for i in range(t.size)
    ]
    path.write_text(text + "\n".join(rows) + "\n")


def bvh_oracle(root: np.ndarray, angles: np.ndarray) -> tuple[list[Rotation], list[np.ndarray]]:
    """World rotation and position of each joint by scipy (intrinsic = upper-case order)."""
    rots, positions = [], []
    parent_rot, parent_pos = None, None
    for j, order in enumerate(BVH_ORDERS):
        local = Rotation.from_euler(order, angles[:, j], degrees=True)
        if parent_rot is None:
            rot, p = local, root
        else:
            rot, p = parent_rot * local, parent_pos + parent_rot.apply(BVH_OFFSETS[j])
        rots.append(rot)
        positions.append(p)
        parent_rot, parent_pos = rot, p
    return rots, positions


def test_bvh_round_trip_mixed_rotation_orders(tmp_path, movement):
    t = movement[0][:600]
    root = np.column_stack([10 * np.sin(t), 90 + 2 * t, 5 * np.cos(t)])  # cm, Y-up
    angles = bvh_angles(t)
    write_bvh(tmp_path / "rec.bvh", t, root, angles)
    rots, positions = bvh_oracle(root, angles)
    rec = read_bvh(tmp_path / "rec.bvh", unit="cm")
    assert rec.labels == ("Hips", "Chest", "Hand") and rec.rate == pytest.approx(RATE)
    for j in range(3):
        assert angle_to(rec.quaternions[:, j], rots[j]).max() < 1e-9
        assert np.abs(rec.points[:, j] - positions[j] / 100.0).max() < 1e-9
    options = ImportOptions(joint="Hand", unit="cm", up="y")
    ds, _ = import_orientation(tmp_path / "rec.bvh", options)
    turn = Rotation.from_matrix(YUP_TO_ZUP)
    assert angle_to(ds.quaternions[0], turn * rots[2]).max() < 1e-9
    assert np.all(np.sum(ds.quaternions[0][1:] * ds.quaternions[0][:-1], axis=1) > 0)
    pos_ds, _ = import_position(tmp_path / "rec.bvh", options)
    expected = positions[2] / 100.0 @ YUP_TO_ZUP.T
    assert np.abs(pos_ds.positions[0] - expected).max() < 1e-9
    np.testing.assert_allclose(pos_ds.times[0], t, rtol=0, atol=1e-12)


def test_relative_orientation_like_the_paper(tmp_path, movement):
    """Faraway & Choe's hand orientation relative to the arm's marker triad (TSV), and a
    BVH joint relative to its parent (= its local rotation, scipy from the Euler angles)."""
    t, rot, pos = movement
    arm = Rotation.from_rotvec(np.column_stack([0.3 * np.sin(t), 0.2 * t / t[-1], 0 * t]))
    arm_pos = pos - [0.0, 0.25, 0.0]
    points = np.concatenate([marker_points(rot, pos), marker_points(arm, arm_pos)], axis=1)
    write_tsv(tmp_path / "two.tsv", points * 1000.0, ["O", "X", "P", "W", "E", "S"])
    options = ImportOptions(markers=("O", "X", "P"), relative_to=("W", "E", "S"))
    ds, _ = import_orientation(tmp_path / "two.tsv", options)
    assert angle_to(ds.quaternions[0], arm.inv() * rot).max() < 1e-9
    t = t[:300]
    angles = bvh_angles(t)
    write_bvh(tmp_path / "rec.bvh", t, np.zeros((t.size, 3)), angles)
    options = ImportOptions(joint="Hand", relative_to=("Chest",), up="y")
    ds, _ = import_orientation(tmp_path / "rec.bvh", options)
    local = Rotation.from_euler(BVH_ORDERS[2], angles[:, 2], degrees=True)
    assert angle_to(ds.quaternions[0], local).max() < 1e-9  # the up turn cancels


def test_sign_continuity_before_gap_filling(tmp_path, movement):
    """A BVH joint turning through 180 degrees: pybvh's per-frame canonical signs flip,
    the imported quaternions do not."""
    t = movement[0][:240]
    angles = np.zeros((t.size, 3, 3))
    angles[:, 0, 0] = np.linspace(0, 350, t.size)  # the root turns about Z
    write_bvh(tmp_path / "turn.bvh", t, np.zeros((t.size, 3)), angles)
    ds, _ = import_orientation(tmp_path / "turn.bvh", ImportOptions(joint="Hips"))
    q = ds.quaternions[0]
    assert np.all(np.sum(q[1:] * q[:-1], axis=1) > 0.99)


# --------------------------------------------------------------------------------------
# segmentation, and the benchmarks on a recording vs on the project's CSV
# --------------------------------------------------------------------------------------


def test_speed_threshold_finds_the_reaches(tmp_path, movement):
    _, rot, pos = movement
    write_tsv(tmp_path / "rec.tsv", marker_points(rot, pos) * 1000.0, ["O", "X", "P"])
    opts = ImportOptions(marker="O", speed_threshold=0.02, min_duration=0.2)
    ds, report = import_position(tmp_path / "rec.tsv", opts)
    assert len(ds) == N_MOVES == report.movements
    for k, times in enumerate(ds.times):  # rest to rest around each 1 s reach
        assert 0.5 + 1.5 * k - 0.05 < times[0] < 0.5 + 1.5 * k + 0.2
        assert 1.5 + 1.5 * k - 0.2 < times[-1] < 1.5 + 1.5 * k + 0.05
    ds_rot, _ = import_orientation(
        tmp_path / "rec.tsv", ImportOptions(markers=("O", "X", "P"), speed_threshold=0.05)
    )
    assert len(ds_rot) == N_MOVES


def test_orientation_and_position_bench_same_as_csv(tmp_path, movement):
    t, rot, pos = movement
    write_c3d(tmp_path / "rec.c3d", marker_points(rot, pos), ["O", "X", "P"])
    seg = segments_table(tmp_path / "seg.csv", t)
    source = f"{tmp_path / 'rec.c3d'}?markers=O,X,P&up=y&segments={seg}&max-gap=5"
    ds = load_orientation_dataset(source)
    assert len(ds) == N_MOVES and sorted(set(ds.subjects)) == ["s0", "s1"]
    ds.to_csv(tmp_path / "o.csv")
    a = orientation_bench.run(orientation_bench.OrientationConfig(data=source, learned="off"))
    b = orientation_bench.run(
        orientation_bench.OrientationConfig(data=str(tmp_path / "o.csv"), learned="off")
    )
    assert_same(a.table.criteria, b.table.criteria)
    psource = f"{tmp_path / 'rec.c3d'}?marker=O&up=y&segments={seg}"
    pds = load_position_dataset(psource)
    pds.to_csv(tmp_path / "p.csv")
    config = position_bench.PositionConfig(data=psource, learned="off", use_peers=False)
    pa = position_bench.run(config)
    pb = position_bench.run(dataclasses.replace(config, data=str(tmp_path / "p.csv")))
    assert pa["per_shape"].keys() == {"a", "b"}
    assert_same(pa["per_shape"], pb["per_shape"])
    assert_same(pa["summary_median_across_shapes"], pb["summary_median_across_shapes"])


def assert_same(a, b) -> None:
    """Equal structures, numbers equal to 1e-10 relative (the CSV renormalises quaternions)."""
    if isinstance(a, dict):
        assert a.keys() == b.keys()
        for key in a:
            assert_same(a[key], b[key])
    elif isinstance(a, (list, tuple)):
        assert len(a) == len(b)
        for x, y in zip(a, b, strict=True):
            assert_same(x, y)
    elif isinstance(a, (float, np.floating)):
        np.testing.assert_allclose(a, b, rtol=1e-10, atol=1e-14)
    else:
        assert a == b


def test_import_command_writes_the_csv_the_benchmarks_take(tmp_path, movement, capsys):
    t, rot, pos = movement
    write_c3d(tmp_path / "rec.c3d", marker_points(rot, pos), ["O", "X", "P"])
    seg = segments_table(tmp_path / "seg.csv", t)
    out = tmp_path / "o.csv"
    argv = ["import", str(tmp_path / "rec.c3d"), "--kind", "orientation", "--out", str(out)]
    assert main([*argv, "--markers", "O,X,P", "--up", "y", "--segments", str(seg)]) == 0
    text = capsys.readouterr().out
    assert "samples missing 33, filled 3, dropped 30" in text and "8 orientation" in text
    ds = load_orientation_dataset(out)
    direct = load_orientation_dataset(f"{tmp_path / 'rec.c3d'}?markers=O,X,P&up=y&segments={seg}")
    for a, b in zip(ds.quaternions, direct.quaternions, strict=True):
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-15)
    assert main(["orientation", "--data", str(out), "--learned", "off"]) == 0


# --------------------------------------------------------------------------------------
# juggling: a TSV with the ball as unlabelled fragments
# --------------------------------------------------------------------------------------


def juggling_tsv(path: Path) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The SIMULATED demonstrations' hand and ball written as a TSV in mm, the ball
    as unlabelled fragments (a new column after each gap) plus a spurious fragment."""
    demos = generate_demonstrations(n_cycles=4, seed=1)
    rec = demos.recordings[0]
    n = rec.t.size
    hand = np.column_stack([rec.hand[:, 0], np.full(n, 0.2), rec.hand[:, 1]]) * 1000.0
    ball = np.column_stack([rec.ball[:, 0], np.full(n, 0.2), rec.ball[:, 1]]) * 1000.0
    gaps = [np.arange(100, 103), np.arange(400, 404)]
    cuts = [0, 100, 400, n]
    columns = [hand]
    for a, b in itertools.pairwise(cuts):
        frag = np.full((n, 3), np.nan)
        frag[a:b] = ball[a:b]
        columns.append(frag)
    for g in gaps:
        for c in columns[1:]:
            c[g] = np.nan
    ghost = np.full((n, 3), np.nan)
    ghost[250:252] = [500.0, 0.0, 500.0]
    columns.append(ghost)
    global RATE
    rate, RATE = RATE, 1.0 / float(np.diff(rec.t).mean())
    try:
        write_tsv(path, np.stack(columns, axis=1), ["HAND", "", "", "", ""])
    finally:
        RATE = rate
    return rec.t, hand / 1000.0, ball / 1000.0


def test_juggling_tsv_unlabelled_balls(tmp_path):
    t, hand, ball = juggling_tsv(tmp_path / "jug.tsv")
    demos, report = import_juggling(
        tmp_path / "jug.tsv", ImportOptions(marker="HAND", balls="unlabelled", max_gap=5)
    )
    assert report.balls["spurious dropped"] == 1
    assert report.balls["fragments in the ball"] == 3
    assert report.gaps.filled == 7 and report.gaps.dropped == 0
    r = demos.recordings[0]
    k = np.rint((r.t - 0) / (t[1] - t[0])).astype(int)
    measured = ~np.isin(k, np.r_[100:103, 400:404])
    assert np.abs(r.hand[measured] - hand[k[measured]][:, [0, 2]]).max() < 1e-6
    assert np.abs(r.ball[measured] - ball[k[measured]][:, [0, 2]]).max() < 1e-6
    segmented = load_juggling_csv(f"{tmp_path / 'jug.tsv'}?marker=HAND&balls=unlabelled")
    assert len(segmented.cycles()) >= 2


# --------------------------------------------------------------------------------------
# bad files: one line naming the file
# --------------------------------------------------------------------------------------


def bad_files(tmp_path: Path, movement) -> dict[str, tuple[str, str]]:
    t, rot, pos = movement
    pts = marker_points(rot, pos)[:100]
    write_c3d(tmp_path / "ok.c3d", pts, ["O", "X", "P"])
    data = (tmp_path / "ok.c3d").read_bytes()
    (tmp_path / "trunc.c3d").write_bytes(data[: len(data) * 2 // 3])
    write_tsv(tmp_path / "ok.tsv", pts * 1000.0, ["O", "X", "P"])
    text = (tmp_path / "ok.tsv").read_text()
    (tmp_path / "trunc.tsv").write_text(text[: len(text) * 2 // 3])
    (tmp_path / "zero.tsv").write_text(text.replace("FREQUENCY\t120", "FREQUENCY\t0"))
    nan_pts = pts.copy() * 1000.0
    nan_pts[:, 1] = np.nan
    write_tsv(tmp_path / "nan.tsv", nan_pts, ["O", "X", "P"])
    write_bvh(tmp_path / "ok.bvh", t[:50], np.zeros((50, 3)), bvh_angles(t[:50]))
    bvh = (tmp_path / "ok.bvh").read_text()
    (tmp_path / "trunc.bvh").write_text(bvh[: len(bvh) * 2 // 3])
    (tmp_path / "zero.bvh").write_text(bvh.replace(f"Frame Time: {1 / RATE!r}", "Frame Time: 0"))
    # ezc3d refuses to write a zero rate: set the header's and POINT:RATE's float32 to 0
    start = (int(np.frombuffer(data[16:18], "<u2")[0]) - 1) * 512  # header word 9
    head = data[:start].replace(np.float32(RATE).tobytes(), np.float32(0.0).tobytes())
    (tmp_path / "zero.c3d").write_bytes(head + data[start:])
    return {
        "truncated c3d": ("trunc.c3d?marker=O", "truncated C3D file"),
        "truncated tsv": ("trunc.tsv?marker=O", "truncated TSV file"),
        "truncated bvh": ("trunc.bvh?joint=Hand&unit=cm", "truncated BVH file"),
        "wrong marker": ("ok.c3d?marker=RFIN", "no marker 'RFIN'; the file has: O, P, X"),
        "wrong triad marker": ("ok.tsv?markers=O,X,Q", "no marker 'Q'"),
        "missing joint": ("ok.bvh?joint=Foot&unit=cm", "no joint 'Foot'"),
        "all-NaN marker": ("nan.tsv?marker=X", "marker 'X' has no sample (all missing)"),
        "zero rate tsv": ("zero.tsv?marker=O", "frame rate 0 Hz"),
        "zero rate bvh": ("zero.bvh?joint=Hand&unit=cm", "frame rate is zero"),
        "zero rate c3d": ("zero.c3d?marker=O", "frame rate 0 Hz"),
    }


BAD = [
    "truncated c3d",
    "truncated tsv",
    "truncated bvh",
    "wrong marker",
    "wrong triad marker",
    "missing joint",
    "all-NaN marker",
    "zero rate tsv",
    "zero rate bvh",
    "zero rate c3d",
]


@pytest.mark.parametrize("case", BAD)
def test_bad_files_one_line_naming_the_file(tmp_path, movement, case, capsys):
    source, fragment = bad_files(tmp_path, movement)[case]
    name = source.partition("?")[0]
    kind = "orientation" if "markers=" in source else "position"
    with pytest.raises(ValueError) as exc:
        (load_orientation_dataset if kind == "orientation" else load_position_dataset)(
            f"{tmp_path / name}?{source.partition('?')[2]}"
        )
    message = str(exc.value)
    assert str(tmp_path / name) in message and fragment in message and "\n" not in message
    status = main([kind, "--data", f"{tmp_path / name}?{source.partition('?')[2]}"])
    err = capsys.readouterr().err.strip().splitlines()
    assert status == 2 and len(err) == 1 and fragment in err[0] and name in err[0]


def test_options_dataclass_checks_its_values():
    with pytest.raises(ValueError, match="max_gap: expected an integer >= 0"):
        ImportOptions(max_gap=-1)
    with pytest.raises(ValueError, match="markers: expected three different"):
        ImportOptions(markers=("A", "A", "B"))
    assert dataclasses.replace(ImportOptions(), up="y").up == "y"


# --------------------------------------------------------------------------------------
# fuzz: corrupted files load or raise ValueError naming the file, nothing else (no crash)
# --------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def valid_files(tmp_path_factory, movement):
    folder = tmp_path_factory.mktemp("valid")
    t, rot, pos = movement
    pts = marker_points(rot, pos)[:60]
    write_c3d(folder / "ok.c3d", pts, ["O", "X", "P"])
    write_tsv(folder / "ok.tsv", pts * 1000.0, ["O", "X", "P"])
    write_bvh(folder / "ok.bvh", t[:60], np.zeros((60, 3)), bvh_angles(t[:60]))
    return {
        ".c3d": (folder / "ok.c3d", "markers=O,X,P"),
        ".tsv": (folder / "ok.tsv", "markers=O,X,P"),
        ".bvh": (folder / "ok.bvh", "joint=Hand"),
    }


@settings(
    max_examples=int(os.environ.get("FUZZ_EXAMPLES", "60")),
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)
@given(data=st.data())
def test_fuzzed_recordings_raise_only_value_error(valid_files, tmp_path, data):
    """Bytes overwritten, cut or spliced in a valid C3D, TSV or BVH file: the import
    succeeds or raises one ValueError naming the file (ezc3d runs in a child process, so
    a file that crashes it is reported too)."""
    suffix = data.draw(st.sampled_from(sorted(valid_files)))
    valid, query = valid_files[suffix]
    raw = bytearray(valid.read_bytes())
    for _ in range(data.draw(st.integers(1, 6))):
        at = data.draw(st.integers(0, len(raw) - 1))
        raw[at] = data.draw(st.integers(0, 255))
    if data.draw(st.booleans()):
        a = data.draw(st.integers(0, len(raw)))
        b = data.draw(st.integers(a, min(len(raw), a + 40)))
        raw[a:b] = data.draw(st.binary(max_size=8))
    path = tmp_path / f"fuzz{suffix}"
    path.write_bytes(bytes(raw))
    try:
        load_orientation_dataset(f"{path}?{query}", min_deg=0.0)
    except ValueError as exc:
        assert str(path) in str(exc)
        assert "\n" not in str(exc)


# --------------------------------------------------------------------------------------
# the environments' data= and motion-bench juggling take a recording too
# --------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("env_id", "query", "to_csv"),
    [
        ("MotionEnvs/OrientationReach-v0", "markers=O,X,P", load_orientation_dataset),
        ("MotionEnvs/PositionReach-v0", "marker=O", load_position_dataset),
    ],
)
def test_env_data_takes_a_recording(tmp_path, movement, env_id, query, to_csv):
    import gymnasium as gym

    import motion_envs  # noqa: F401  (registers the ids)

    t, rot, pos = movement
    write_tsv(tmp_path / "rec.tsv", marker_points(rot, pos) * 1000.0, ["O", "X", "P"])
    seg = segments_table(tmp_path / "seg.csv", t)
    source = f"{tmp_path / 'rec.tsv'}?{query}&segments={seg}"
    to_csv(source).to_csv(tmp_path / "same.csv")
    observations = []
    for data in (source, str(tmp_path / "same.csv")):
        env = gym.make(env_id, data=data)
        obs, _ = env.reset(seed=3)
        obs2, reward, *_ = env.step(np.zeros(env.action_space.shape, dtype=np.float32))
        observations.append((obs, obs2, reward))
        env.close()
    for a, b in zip(observations[0], observations[1], strict=True):
        np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-12)


def test_juggling_bench_on_a_tsv(tmp_path, capsys):
    juggling_tsv(tmp_path / "jug.tsv")
    source = f"{tmp_path / 'jug.tsv'}?marker=HAND&balls=unlabelled&max-gap=5"
    out = tmp_path / "jug.csv"
    argv = ["import", str(tmp_path / "jug.tsv"), "--kind", "juggling", "--out", str(out)]
    assert main([*argv, "--marker", "HAND", "--balls", "unlabelled", "--max-gap", "5"]) == 0
    text = capsys.readouterr().out
    assert "spurious dropped 1" in text and "complete juggling cycle(s)" in text
    direct = load_juggling_csv(source)
    from_csv = load_juggling_csv(out)
    assert len(direct.cycles()) == len(from_csv.cycles()) >= 2


def test_ball_assembly_decisions():
    """A flight cut by a 6-frame occlusion is joined by its ballistic prediction; a
    fragment far from every prediction starts another track; short ones are spurious."""
    from motion_envs.datasets.mocap import assemble_balls

    rate = 200.0
    t = np.arange(200) / rate
    flight = np.column_stack([0.3 * t, np.zeros_like(t), 1.0 + 3.0 * t - 4.905 * t**2])
    points = np.full((t.size, 4, 3), np.nan)
    points[:80, 0] = flight[:80]  # before the occlusion
    points[86:, 1] = flight[86:]  # after it, in another column
    points[100:140, 2] = [2.0, 2.0, 0.5]  # a marker elsewhere: another track
    points[50:53, 3] = [0.0, 1.0, 1.0]  # 3 frames: spurious
    ball, present, counts = assemble_balls(t, points, "rec.tsv")
    assert counts == {
        "fragments": 4,
        "spurious dropped": 1,
        "joined by ballistic prediction": 1,
        "tracks": 2,
        "other tracks ignored": 1,
        "fragments in the ball": 2,
    }
    assert np.array_equal(present, ~np.isin(np.arange(t.size), np.arange(80, 86)))
    np.testing.assert_array_equal(ball[present], flight[present])


def test_tsv_with_a_non_utf8_byte_past_the_header_is_one_value_error_naming_it(tmp_path):
    """Found by the recording fuzz test: a byte that is not UTF-8 in the data lines (the
    header read stops before it) raised Python's UnicodeDecodeError without the file."""
    from motion_envs.datasets.mocap._readers import read_qualisys_tsv

    path = tmp_path / "late.tsv"
    header = b"NO_OF_FRAMES\t2\nFREQUENCY\t100\nMARKER_NAMES\tO\tX\tP\n"
    path.write_bytes(header + b"1\t2\t3\t1\t2\t3\t1\t2\t3\n" * 2000 + b"\x80\t1\n")
    with pytest.raises(ValueError, match=r"late\.tsv: not a Qualisys TSV text file") as info:
        read_qualisys_tsv(path)
    assert type(info.value) is ValueError and "\n" not in str(info.value)
