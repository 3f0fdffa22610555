"""The agent against EVERY row, not only the row validation chose (the issue's last
target: each simple hand-written policy must stay below the agent), and the catch-timing
script's ``--rescore`` of earlier runs' kept policies."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from _helpers import load_experiment

from baselines.agents.against_rows import rows_not_beaten


def test_a_row_counts_as_beaten_only_when_the_interval_is_above_zero() -> None:
    out = rows_not_beaten(
        {
            "late_meeting": (0.040, [0.001, 0.080]),
            "delay_tracker": (0.030, [0.000, 0.060]),  # low end AT 0: not beaten
            "delay_estimator_catch": (-0.020, [-0.070, 0.030]),
        }
    )
    assert out["beaten"] == ["late_meeting"]
    assert out["not_beaten"] == ["delay_estimator_catch", "delay_tracker"]  # lowest first
    assert not out["every_row_beaten"]
    assert out["sentence"] == (
        "the agent is NOT above 2 of the 3 rows (agent - row, catch rate): "
        "delay_estimator_catch -0.020 [-0.070, +0.030]; delay_tracker +0.030 [+0.000, +0.060]"
    )


def test_every_row_beaten_says_so_and_no_rows_is_an_error() -> None:
    out = rows_not_beaten({"juggler": (0.5, [0.4, 0.6]), "random": (0.7, [0.6, 0.8])})
    assert out["every_row_beaten"] and out["not_beaten"] == []
    assert out["sentence"] == "the agent is above every one of the 2 rows (catch rate)"
    with pytest.raises(ValueError, match="differences: no rows"):
        rows_not_beaten({})


def _earlier(tmp_path: Path, seed: int, n_weights: int) -> Path:
    run = {"seed": seed, "kept": 3, "weights": [0.1] * n_weights, "val_scores": [1.0] * 4,
           "train_scores": [1.0] * 4, "train_cpu_s": 12.0}  # fmt: skip
    doc = {"blocks": [{"block": "cascade3-medium", "base_val_score": 3.08, "runs": [run]}]}
    path = tmp_path / f"seed{seed}.json"
    path.write_text(json.dumps(doc))
    return path


def test_rescore_pools_the_seeds_of_several_files_and_checks_the_policy_size(
    tmp_path: Path,
) -> None:
    cta = load_experiment("catch_timing_agents")
    n = cta.n_features(2, True)
    doc = cta.load_earlier([_earlier(tmp_path, 0, n), _earlier(tmp_path, 1, n)])
    assert cta.earlier_block(doc, "x", "cascade3-medium")["base_val_score"] == 3.08
    run = cta.earlier_run(doc, "x", "cascade3-medium", 1, True)
    assert run["weights"] == [0.1] * n and run["kept"] == 3 and run["train_cpu_s"] == 12.0
    with pytest.raises(ValueError, match="has no seed 2"):
        cta.earlier_run(doc, "x", "cascade3-medium", 2, True)
    with pytest.raises(ValueError, match="no block 'v2-drift'"):
        cta.earlier_block(doc, "x", "v2-drift")
    with pytest.raises(ValueError, match="without --memory takes"):  # a memory policy
        cta.earlier_run(doc, "x", "cascade3-medium", 0, False)


def test_rescore_refuses_an_unreadable_file_in_one_line(tmp_path: Path) -> None:
    cta = load_experiment("catch_timing_agents")
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    with pytest.raises(ValueError, match=r"--rescore .*bad.json: not a readable results file"):
        cta.load_earlier([bad])
    other = tmp_path / "other.json"
    other.write_text(json.dumps({"levels": []}))
    with pytest.raises(ValueError, match="no 'blocks' list"):
        cta.load_earlier([other])
    with pytest.raises(SystemExit):  # argparse's one-line error, exit status 2
        cta.main(["--rescore", str(tmp_path / "missing.json")])


def test_the_validation_pick_reads_the_base_score_when_the_base_was_kept() -> None:
    cta = load_experiment("catch_timing_agents")
    assert cta.kept_score({"kept": -1, "val_scores": [0.2, 0.9]}, 0.5) == 0.5
    assert cta.kept_score({"kept": 1, "val_scores": [0.2, 0.9]}, 0.5) == 0.9
