"""The users' juggling CSV: bad-input matrix with line numbers, round trip, segmentation."""

from __future__ import annotations

import numpy as np
import pytest

from motion_envs.datasets.juggling import (
    generate_demonstrations,
    read_juggling_csv,
    write_juggling_csv,
)
from motion_envs.models.juggling import load_juggling_csv


@pytest.fixture(scope="module")
def demos():
    return generate_demonstrations(n_cycles=10, seed=5)


def _boundaries(labels):
    k = np.flatnonzero(labels[1:] != labels[:-1]) + 1
    return [(int(i), str(labels[i])) for i in k]


def test_round_trip_with_phase(demos, tmp_path):
    path = write_juggling_csv(demos, tmp_path / "j.csv")
    back = read_juggling_csv(path)
    assert not back.simulated  # a file is whatever the user says it is
    r, s = demos.recordings[0], back.recordings[0]
    np.testing.assert_array_equal(r.hand, s.hand)
    np.testing.assert_array_equal(r.ball, s.ball)
    np.testing.assert_array_equal(r.phase, s.phase)
    assert back.cycles() == demos.cycles()


def test_segmentation_of_an_unlabelled_csv_recovers_the_phases(demos, tmp_path):
    path = write_juggling_csv(demos, tmp_path / "nolabels.csv", phase=False)
    raw = read_juggling_csv(path)  # the datasets layer: raw recordings, no labels
    assert all(r.phase is None for r in raw.recordings)
    back = load_juggling_csv(path)
    truth = _boundaries(demos.recordings[0].phase)
    found = _boundaries(back.recordings[0].phase)
    found = [f for f in found if f[1] != "none"]
    assert [b[1] for b in found] == [b[1] for b in truth]
    for (kt, name), (kf, _) in zip(truth, found, strict=True):
        if name in ("go_down", "return"):  # release and catch events: exact
            assert kf == kt, (name, kt, kf)
        else:  # rest reached (speed criterion): a few samples early at most
            assert -10 <= kf - kt <= 0, (name, kt, kf)
    assert len(back.cycles()) == len(demos.cycles())


GOOD = "t,x,z,ball_x,ball_z,phase\n"


def _write(tmp_path, text, name="bad.csv"):
    path = tmp_path / name
    path.write_text(text)
    return path


def _rows(n=25, phase=True):
    out = []
    for k in range(n):
        ph = ["toss", "go_down", "catch", "return"][min(k * 4 // n, 3)]
        out.append(f"{k * 0.005},{0.1 + k * 1e-3},{1.0},{0.1},{1.0}" + (f",{ph}" if phase else ""))
    return out


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("t,x\n0,1\n", r"missing column\(s\) \['z'\]"),
        ("t,x,z\n", "no data rows"),
        ("t,x,z,ball_x\n" + "\n".join(f"{k},0,0,0" for k in range(25)), "both be present"),
        (
            GOOD + "\n".join([*_rows()[:3], "0.015,abc,1,0,1,toss", *_rows()[4:]]),
            r"non-numeric value .* line\(s\) 5 ",
        ),
        (GOOD + "\n".join([*_rows()[:6], "0.03,nan,1,0,1,toss", *_rows()[7:]]), r"line\(s\) 8 "),
        (
            GOOD + "\n".join([*_rows()[:9], "0.0,0.1,1,0,1,toss", *_rows()[10:]]),
            r"time not strictly increasing .* line\(s\) 11 ",
        ),
        (
            GOOD + "\n".join([*_rows()[:4], "0.02,0.1,1,0,1,juggle", *_rows()[5:]]),
            r"phase must be one of .* line\(s\) 6 ",
        ),
        (GOOD + "\n".join(_rows()[:10]), "fewer than 20 samples starts on line"),
        ("t,x,z\n" + "\n".join(f"{k * 0.005},0,1" for k in range(25)), "need the ball columns"),
        (GOOD + "\n".join(r.replace("return", "catch") for r in _rows()), "no complete toss"),
    ],
)
@pytest.mark.parametrize("reader", [read_juggling_csv, load_juggling_csv])
def test_bad_input_matrix(tmp_path, text, match, reader):
    with pytest.raises(ValueError, match=match) as info:
        reader(_write(tmp_path, text + "\n"))
    assert "bad.csv" in str(info.value)
    assert "\n" not in str(info.value)  # one line


def test_non_contiguous_recording(tmp_path):
    rows = ["t,x,z,ball_x,ball_z,phase,recording"]
    rows += [r + ",a" for r in _rows()] + [r + ",b" for r in _rows()] + [r + ",a" for r in _rows()]
    with pytest.raises(ValueError, match=r"recording 'a' is not contiguous .* line\(s\) 52 "):
        read_juggling_csv(_write(tmp_path, "\n".join(rows) + "\n"))


def test_missing_file(tmp_path):
    with pytest.raises(FileNotFoundError, match="does not exist"):
        read_juggling_csv(tmp_path / "nope.csv")


def test_unlabelled_csv_without_any_cycle_names_the_file(tmp_path):
    rows = "\n".join(f"{k * 0.005},0.2,1.0,0.2,1.0" for k in range(40))
    path = _write(tmp_path, "t,x,z,ball_x,ball_z\n" + rows + "\n")
    assert read_juggling_csv(path).recordings[0].phase is None
    with pytest.raises(ValueError, match=r"bad\.csv: no complete toss"):
        load_juggling_csv(path)


# -- issue 17 item 1: the juggling CSV at the bar of the other two loaders -------------
def test_absurd_positions_are_rejected_with_their_line(tmp_path):
    rows = _rows()
    rows[5] = "0.025,1e300,1,0,1,toss"
    with pytest.raises(ValueError, match=r"plausible range .* line\(s\) 7 ") as info:
        read_juggling_csv(_write(tmp_path, GOOD + "\n".join(rows) + "\n"))
    assert "bad.csv" in str(info.value)


def test_an_integer_too_large_for_a_float_is_rejected_with_its_line(tmp_path):
    """pandas reads a 400-digit integer as an int and overflows converting it (found by
    the fuzz harness): one ValueError naming the file and the line instead."""
    rows = [f"{k * 0.005},0,1,0,1,toss" for k in range(25)]  # integer columns
    rows[3] = "0.015,0,1,0," + "9" * 400 + ",toss"
    with pytest.raises(ValueError, match=r"non-numeric value .* line\(s\) 5 ") as info:
        read_juggling_csv(_write(tmp_path, GOOD + "\n".join(rows) + "\n"))
    assert "bad.csv" in str(info.value)


def test_absurd_time_is_rejected(tmp_path):
    rows = [f"{1e11 + k},0.1,1,0.1,1,toss" for k in range(25)]
    with pytest.raises(ValueError, match=r"time 't' beyond the plausible range"):
        read_juggling_csv(_write(tmp_path, GOOD + "\n".join(rows) + "\n"))


@pytest.mark.parametrize("label", ["NA", "None", "null", "nan"])
def test_na_like_recording_labels_are_labels(demos, tmp_path, label):
    path = write_juggling_csv(demos, tmp_path / "j.csv")
    text = path.read_text().splitlines()
    col = text[0].split(",").index("recording")
    rows = [",".join([*r.split(",")[:col], label]) for r in text[1:]]
    back = read_juggling_csv(_write(tmp_path, "\n".join([text[0], *rows]) + "\n"))
    assert [r.name for r in back.recordings] == [label]


def test_line_numbers_are_physical_after_blank_lines(tmp_path):
    rows = _rows()
    rows[3] = "0.015,abc,1,0,1,toss"
    text = GOOD + "\n\n\n" + "\n".join(rows) + "\n"  # three blank lines after the header
    with pytest.raises(ValueError, match=r"line\(s\) 8 "):
        read_juggling_csv(_write(tmp_path, text))


@pytest.mark.parametrize(
    ("make", "match"),
    [
        (lambda p: p.mkdir(), "is a folder"),
        (lambda p: p.write_bytes(b""), "empty file"),
        (lambda p: p.write_bytes(b"\n\n  \n"), "empty file"),
        (lambda p: p.write_bytes(b"t,x,z\n0,\xff\xfe,1\n"), "not UTF-8"),
        (lambda p: p.write_bytes(b"t,x,z\n0,0\x00,1\n"), "NUL bytes"),
    ],
)
@pytest.mark.parametrize("reader", [read_juggling_csv, load_juggling_csv])
def test_unreadable_files_are_one_value_error_naming_the_file(tmp_path, make, match, reader):
    path = tmp_path / "odd.csv"
    make(path)
    with pytest.raises(ValueError, match=match) as info:
        reader(path)
    assert "odd.csv" in str(info.value) and "\n" not in str(info.value)


def test_a_fifo_is_refused_without_blocking(tmp_path):
    import os

    path = tmp_path / "pipe.csv"
    os.mkfifo(path)
    with pytest.raises(ValueError, match="not a regular file"):
        read_juggling_csv(path)


def test_bench_with_absurd_data_fails_with_one_line(tmp_path, capsys):
    """``motion-bench juggling --data FILE`` with x = 1e300: one line, exit 2, no results
    (it printed inf/nan rows and N = 0)."""
    from baselines.cli import main

    rows = [f"{k * 0.005},1e300,1.0,0.1,1.0" for k in range(40)]
    path = _write(tmp_path, "t,x,z,ball_x,ball_z\n" + "\n".join(rows) + "\n")
    code = main(["juggling", "--data", str(path), "--cycles", "2", "--out", str(tmp_path / "o")])
    assert code == 2
    out, err = capsys.readouterr()
    assert "plausible range" in err and len(err.strip().splitlines()) == 1, err
    assert "nan" not in out and "inf" not in out


def test_too_few_cycles_says_why_eight():
    """The split's minimum is explained, and it is the right one: of 8 complete cycles
    the default split keeps 6 to fit, as many as the juggler's fit needs per phase."""
    from motion_envs.datasets.juggling import MIN_SPLIT_CYCLES, split_cycles
    from motion_envs.models.juggling import FIT_TEST_FRACTION, AnalyticJuggler

    few = generate_demonstrations(n_cycles=MIN_SPLIT_CYCLES - 1, seed=5)
    assert len(few.cycles()) < MIN_SPLIT_CYCLES
    with pytest.raises(ValueError, match="at least 8 are needed: ") as err:
        split_cycles(few, FIT_TEST_FRACTION, 0)
    assert "6 training cycles" in str(err.value) and "a quarter" in str(err.value)
    enough = generate_demonstrations(n_cycles=MIN_SPLIT_CYCLES, seed=5)
    assert len(enough.cycles()) == MIN_SPLIT_CYCLES
    train, test = split_cycles(enough, FIT_TEST_FRACTION, 0)
    assert (len(train), len(test)) == (6, 2)
    AnalyticJuggler(n_sines=4).fit(enough, train)  # 6 training cycles: enough
    with pytest.raises(ValueError, match="at least 6 are needed"):
        AnalyticJuggler(n_sines=4).fit(enough, set(sorted(train)[:5]))
