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
from motion_envs.models.nominal import position_folds, resample_positions
from motion_envs.models.position_criteria import max_error


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


def test_cli_on_csv_without_peers(tmp_path, capsys):
    ds = load_lasa(["Sine"])
    path = ds.to_csv(tmp_path / "pos.csv")
    rc = main(["position", "--data", str(path), "--n-points", "30", "--n-sines", "3",
               "--no-peers", "--no-progress", "--conditions", "start"])  # fmt: skip
    assert rc == 0
    text = capsys.readouterr().out
    assert "dmp, promp: skipped" in text and "'pos.csv'" in text


def test_cli_errors(tmp_path, capsys):
    assert main(["position", "--data", "nope", "--no-progress"]) == 2
    assert "argument --data: expected one of ['lasa']" in capsys.readouterr().err
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
