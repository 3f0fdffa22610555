"""``motion-bench position`` end to end on two LASA shapes and on a CSV (small grids)."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest

from baselines import position_bench as pb
from baselines.cli import main
from baselines.learned import torch_available
from baselines.peers import peers_available
from motion_envs.datasets.lasa import load_lasa
from motion_envs.datasets.resampling import resample_positions
from motion_envs.datasets.splits import position_folds
from motion_envs.models.position_criteria import max_error


@pytest.fixture(autouse=True)
def _in_tmp_path(tmp_path, monkeypatch):
    """A run without --out writes into results/ of the working folder: keep it in tmp."""
    monkeypatch.chdir(tmp_path)


@pytest.mark.slow
def test_cli_lasa_writes_results(tmp_path, capsys):
    out = tmp_path / "res"
    args = ["position", "--shapes", "Line", "Angle", "--n-points", "40", "--n-sines", "4"]
    rc = main([*args, "--out", str(out), "--no-progress", "--learned", "quick"])
    assert rc == 0
    text = capsys.readouterr().out
    assert "learned vs analytic" in text and "95% CI over shapes" in text
    assert "median over demos of max_t |error|" in text
    assert "validation of the linear hypothesis" in text
    doc = json.loads((out / "results.json").read_text())
    assert doc["conditions"] == ["start", "end"] and doc["n_points"] == 40
    assert set(doc["per_shape"]) == {"Line", "Angle"}
    expected = ["line", "null", "lippi"] + (["dmp", "promp"] if peers_available() else [])
    expected += ["ridge"] + (["mlp"] if torch_available() else [])
    assert doc["methods"] == expected
    assert (out / "learned_ratio.png").stat().st_size > 1000
    for m in expected:
        vals = [doc["per_shape"][s]["criteria"][m]["max_error"] for s in ("Line", "Angle")]
        assert doc["summary_median_across_shapes"][m]["max_error"] == pytest.approx(np.median(vals))
    # the line is always much worse than the learnt models on these curved shapes
    angle = doc["per_shape"]["Angle"]["criteria"]
    assert angle["lippi"]["max_error"] < angle["line"]["max_error"]
    rows = list(csv.DictReader((out / "results.csv").open()))
    assert len(rows) == 2 * len(expected)
    assert (out / "shapes.png").stat().st_size > 1000


def test_leave_one_out_matches_hand_computation():
    ds = load_lasa(["Line"])
    y, dur = resample_positions(ds, 30)
    folds = position_folds(ds, "loo")
    assert [f[2].tolist() for f in folds] == [[i] for i in range(7)]
    preds, chosen = pb.predict_folds(
        y, dur, folds, ["start", "end"], 3, ["line", "null"], pb.scoring._Timer()
    )
    assert chosen == []
    tau = np.linspace(0, 1, 30)[:, None]
    line0 = y[0, 0] + tau * (y[0, -1] - y[0, 0])
    np.testing.assert_allclose(preds["line"][0], line0)
    resid = y[1:] - y[1:, :1] - tau * (y[1:, -1:] - y[1:, :1])
    np.testing.assert_allclose(preds["null"][0], line0 + resid.mean(axis=0), atol=1e-12)
    assert max_error(y[0], preds["line"][0]) > 0


def test_test_split_scores_only_held_out_demos(tmp_path, capsys):
    out = tmp_path / "res"
    argv = ["position", "--shapes", "Line", "Angle", "--n-points", "30", "--n-sines", "3"]
    assert main([*argv, "--split", "test", "--no-peers", "--no-progress", "--out", str(out)]) == 0
    assert "test split (test fraction 0.25 per shape, seed 0)" in capsys.readouterr().out
    doc = json.loads((out / "results.json").read_text())
    ds = load_lasa(["Line", "Angle"])
    folds = position_folds(ds, "test")
    for task, train, scored in folds:
        assert doc["per_shape"][task]["n_scored"] == scored.size == 2
        assert train.size == 5 and not set(train) & set(scored)


def test_cli_on_csv_without_peers(tmp_path, capsys, monkeypatch):
    ds = load_lasa(["Sine"])
    path = ds.to_csv(tmp_path / "pos.csv")
    monkeypatch.chdir(tmp_path)  # without --out: results/position-pos, as motion-bench all
    rc = main(["position", "--data", str(path), "--n-points", "30", "--n-sines", "3",
               "--no-peers", "--no-progress", "--conditions", "start"])  # fmt: skip
    assert rc == 0
    text = capsys.readouterr().out
    assert "dmp, promp: skipped" in text and "'pos.csv'" in text
    assert (tmp_path / "results" / "position-pos" / "results.json").is_file()


def test_cli_errors(tmp_path, capsys):
    assert main(["position", "--data", "nope", "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert "argument --data: expected a built-in position dataset ('lasa')" in err
    assert main(["position", "--shapes", "Circle", "--no-progress"]) == 2
    assert main(["position", "--shapes", "Line", "--conditions", "speed"]) == 2


def test_cli_says_when_movement_primitives_is_missing(monkeypatch, capsys):
    monkeypatch.setattr(
        pb.cli, "peers_missing_reason", lambda: "No module named 'movement_primitives'"
    )
    monkeypatch.setattr(pb.scoring, "peers_available", lambda: False)
    args = ["position", "--shapes", "Line", "--n-points", "20", "--n-sines", "2", "--no-progress"]
    assert main(args) == 0
    captured = capsys.readouterr()
    assert "movement_primitives cannot be used" in captured.err
    assert "DMP and ProMP columns are skipped" in captured.err
    assert "dmp, promp: skipped" in captured.out


@pytest.mark.parametrize(
    ("n_demos", "extra", "expected"),
    [
        # once: "cross-validation needs at least 3 trajectories; got 2" (no shape named)
        (3, [], "shape 'Sine' has 3 demonstrations; leave-one-out with --n-sines auto and "
            "--learned needs at least 4"),
        (3, ["--n-sines", "3"], "shape 'Sine' has 3 demonstrations; leave-one-out with "
            "--learned needs at least 4"),
        (2, ["--n-sines", "3", "--learned", "off"], "each needs at least 3 demonstrations "
            "(demonstrations per shape: 'Sine': 2)"),
    ],
)  # fmt: skip
def test_too_few_demonstrations_one_line_naming_the_shape(
    tmp_path, capsys, n_demos, extra, expected
):
    import pandas as pd

    path = load_lasa(["Sine"]).to_csv(tmp_path / "all.csv")
    df = pd.read_csv(path)
    keep = df.trajectory.isin(df.trajectory.unique()[:n_demos])
    df[keep].to_csv(tmp_path / "few.csv", index=False)
    argv = ["position", "--data", str(tmp_path / "few.csv"), "--n-points", "30", "--no-peers"]
    assert main([*argv, "--no-progress", "--out", str(tmp_path / "o"), *extra]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and expected in err[0], err


def test_three_demonstrations_run_with_fixed_n_and_no_learned_rows(tmp_path):
    import pandas as pd

    path = load_lasa(["Sine"]).to_csv(tmp_path / "all.csv")
    df = pd.read_csv(path)
    df[df.trajectory.isin(df.trajectory.unique()[:3])].to_csv(tmp_path / "few.csv", index=False)
    argv = ["position", "--data", str(tmp_path / "few.csv"), "--n-points", "30", "--no-peers"]
    argv += ["--n-sines", "3", "--learned", "off", "--no-progress", "--out", str(tmp_path / "o")]
    assert main(argv) == 0
    assert (
        json.loads((tmp_path / "o" / "results.json").read_text())["per_shape"]["Sine"]["n_demos"]
        == 3
    )


def test_help_documents_the_csv_format(capsys):
    assert main(["position", "--help"]) == 0
    text = capsys.readouterr().out
    assert "trajectory,subject,task,t,x,y[,z]" in text and "at least 4" in text
