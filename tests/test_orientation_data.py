"""The users' orientation CSV: round trip, validation by line number."""

from __future__ import annotations

import numpy as np
import pytest

from motion_envs.datasets import load_orientation_dataset, load_vr_kitchen, read_orientation_csv
from motion_envs.models.criteria import table1

HEADER = "trajectory,subject,task,t,qw,qx,qy,qz,age\n"


def rows(traj, subject, task, n, age, angle=0.5, t0=0.0):
    out = []
    for k in range(n):
        h = 0.5 * angle * k / (n - 1)
        out.append(
            f"{traj},{subject},{task},{t0 + 0.04 * k:.2f},"
            f"{float(np.cos(h))!r},0,0,{float(np.sin(h))!r},{age}\n"
        )
    return out


def write(tmp_path, lines, name="d.csv"):
    path = tmp_path / name
    path.write_text(HEADER + "".join(lines))
    return path


def test_roundtrip_via_csv_preserves_table1(tmp_path):
    ds = load_vr_kitchen().subset(np.arange(40))
    path = ds.to_csv(tmp_path / "vr.csv")
    back = read_orientation_csv(path)
    assert len(back) == 40
    np.testing.assert_array_equal(back.subjects, ds.subjects)
    np.testing.assert_array_equal(back.tasks, ds.tasks)
    np.testing.assert_array_equal(back.replicates, ds.replicates)
    np.testing.assert_allclose(back.predictors["duration_s"], ds.predictors["duration_s"])
    for a, b in zip(back.quaternions, ds.quaternions, strict=True):
        np.testing.assert_allclose(a, b, atol=1e-15)
    ours = table1(back.ragged, back.subjects, back.tasks).criteria
    ref = table1(ds.ragged, ds.subjects, ds.tasks).criteria
    for k in ref:
        assert ours[k] == pytest.approx(ref[k], abs=1e-12, nan_ok=True), k


def test_reads_labels_predictors_and_replicates(tmp_path):
    lines = (
        rows("A", "s1", "t1", 6, 30) + rows("B", "s1", "t1", 7, 30) + rows("C", "s2", "t1", 5, 55)
    )
    ds = read_orientation_csv(write(tmp_path, lines))
    np.testing.assert_array_equal(ds.trajectory_ids, ["A", "B", "C"])
    np.testing.assert_array_equal(ds.replicates, [0, 1, 0])
    np.testing.assert_array_equal(ds.predictors["age"], [30.0, 30.0, 55.0])
    assert [len(q) for q in ds.quaternions] == [6, 7, 5]
    assert ds.rotation_angles() == pytest.approx([0.5, 0.5, 0.5])


def test_min_deg_drops_and_counts(tmp_path):
    lines = rows("A", "s1", "t1", 6, 30, angle=0.05) + rows("B", "s1", "t1", 6, 30, angle=0.5)
    ds = load_orientation_dataset(write(tmp_path, lines), min_deg=10)
    assert len(ds) == 1 and ds.n_dropped == 1 and ds.trajectory_ids[0] == "B"


@pytest.mark.parametrize(
    ("mutate", "match"),
    [
        (
            lambda L: [*L[:3], L[3].replace(",0.12,", ",0.05,"), *L[4:]],
            r"not strictly increasing.*line\(s\) 5",
        ),
        (lambda L: [*L[:2], L[2].replace(",0,0,", ",nan,0,"), *L[3:]], r"NaN.*line\(s\) 4"),
        (lambda L: [*L[:1], L[1].replace(",0,0,", ",0.3,0,"), *L[2:]], r"norm.*line\(s\) 3"),
        (lambda L: L[:9], r"fewer than 5 samples.*line\(s\) 8"),
        (lambda L: L[:7] + L[:1] + L[7:], r"not contiguous"),
        (lambda L: [*L[:1], L[1].replace(",30\n", ",31\n"), *L[2:]], r"'age' changes.*line\(s\) 3"),
        (lambda L: [*L[:1], L[1].replace("s1", "s9"), *L[2:]], r"'subject' changes.*line\(s\) 3"),
    ],
)
def test_bad_rows_are_reported_by_line(tmp_path, mutate, match):
    lines = rows("A", "s1", "t1", 6, 30) + rows("B", "s1", "t2", 6, 30)
    with pytest.raises(ValueError, match=match):
        read_orientation_csv(write(tmp_path, mutate(lines)))


def test_missing_columns_and_files(tmp_path):
    (tmp_path / "x.csv").write_text("trajectory,t,qw\nA,0,1\n")
    with pytest.raises(ValueError, match="missing column"):
        read_orientation_csv(tmp_path / "x.csv")
    with pytest.raises(FileNotFoundError):
        read_orientation_csv(tmp_path / "nope.csv")
    with pytest.raises(ValueError, match="'vr-kitchn' is not a built-in orientation dataset"):
        load_orientation_dataset("vr-kitchn")
    with pytest.raises(ValueError, match="min_deg"):
        load_vr_kitchen(min_deg=-1)
