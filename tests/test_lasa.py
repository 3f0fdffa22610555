"""LASA loader and the users' position CSV."""

from __future__ import annotations

import numpy as np
import pytest

from motion_envs.datasets.lasa import LASA_SHAPES, load_lasa
from motion_envs.datasets.position_csv import read_position_csv


def test_lasa_shapes_and_goal_centred():
    assert len(LASA_SHAPES) == 30
    d = load_lasa(["Angle", "Sine"])
    assert len(d) == 14 and d.n_dims == 2 and d.unit == "mm"
    assert d.task_names() == ["Angle", "Sine"]
    np.testing.assert_array_equal(d.replicates, np.tile(np.arange(7), 2))
    for y, t in zip(d.positions, d.times, strict=True):
        assert y.shape == (1000, 2) and t.shape == (1000,)
        np.testing.assert_array_equal(y[-1], [0.0, 0.0])  # every demo ends at the origin
        assert t[0] == 0.0 and np.all(np.diff(t) > 0)
    # Angle demo 0 starts at a known point (mm), read from the .mat file
    assert np.all(np.abs(d.positions[0][0]) > 1.0)


def test_lasa_unknown_shape():
    with pytest.raises(ValueError, match="unknown LASA shape"):
        load_lasa(["Circle"])


def test_csv_round_trip(tmp_path):
    d = load_lasa(["Line"]).subset([0, 1, 2])
    d = type(d)(
        name=d.name,
        positions=tuple(p[::50] for p in d.positions),
        times=tuple(t[::50] for t in d.times),
        trajectory_ids=d.trajectory_ids,
        subjects=d.subjects,
        tasks=d.tasks,
        replicates=d.replicates,
    )
    path = d.to_csv(tmp_path / "pos.csv")
    back = read_position_csv(path)
    assert len(back) == 3 and back.n_dims == 2
    for a, b in zip(d.positions, back.positions, strict=True):
        np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(back.tasks, ["Line"] * 3)


def _write(tmp_path, rows, header="trajectory,subject,task,t,x,y,z"):
    path = tmp_path / "bad.csv"
    path.write_text(header + "\n" + "\n".join(rows) + "\n")
    return path


def _good(traj="a", n=5, t0=0.0):
    return [f"{traj},s,k,{t0 + i * 0.1},{i},{2 * i},0" for i in range(n)]


def test_csv_three_dimensions(tmp_path):
    d = read_position_csv(_write(tmp_path, _good("a") + _good("b", 6)))
    assert d.n_dims == 3 and [len(p) for p in d.positions] == [5, 6]


@pytest.mark.parametrize(
    ("rows", "message"),
    [
        (
            [*_good("a")[:2], "a,s,k,0.05,9,9,0", *_good("a")[3:]],
            r"not strictly increasing.*line\(s\) 4",
        ),
        ([*_good("a")[:3], "a,s,k,0.3,nan,1,0", *_good("a")[4:]], r"NaN.*line\(s\) 5"),
        (_good("a") + _good("b", 4), r"fewer than 5 samples.*line\(s\) 7"),
        (_good("a") + _good("b") + _good("a"), r"not contiguous.*line\(s\) 12"),
    ],
)
def test_csv_bad_rows_reported_by_line(tmp_path, rows, message):
    with pytest.raises(ValueError, match=message):
        read_position_csv(_write(tmp_path, rows))


def test_csv_missing_column(tmp_path):
    with pytest.raises(ValueError, match="missing column"):
        read_position_csv(_write(tmp_path, ["a,s,k,0,1"], header="trajectory,subject,task,t,x"))
    with pytest.raises(FileNotFoundError):
        read_position_csv(tmp_path / "nope.csv")
