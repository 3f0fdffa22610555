"""``experiments/cascade_v1_replay_row.py --replay DIR --kept``: a kept row paired with
the others (mean catches and catch rate, hand-worked on synthetic episodes), the best
non-oracle row chosen again with the row's validation mean (the bench's rule: the
highest, ties to the first in ``ROWS`` order), and a clear error for a row not kept."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
from _helpers import load_experiment

from baselines.juggling_bench.cascade_v1 import CascadeV1Config
from motion_envs.datasets.juggling import episode_seeds

#: The bench's entry of the kept row (a deviation the kept episodes do not carry).
ROW = {"catches_mean": 3.0, "catches_mean_ci": [0.5, 5.5], "catches_median": 3.0,
       "catches_median_ci": [0.0, 6.0], "catch_rate": 0.75, "catch_rate_ci": [0.5, 0.9],
       "censored": 0, "deviation_m": 0.0089}  # fmt: skip


def _script() -> Any:
    return load_experiment("cascade_v1_replay_row")


def _kept(catches: list[int], tosses: list[int]) -> dict[str, list[Any]]:
    n = len(catches)
    return {"seeds": episode_seeds("test", n).tolist(), "catches": catches, "tosses": tosses,
            "dropped": [True] * n, "time": [1.0] * n}  # fmt: skip


def _folder(tmp_path: Path, val: dict[str, float]) -> Path:
    """Four test episodes of three rows: ``delay_estimator_catch`` catches (4, 2, 6, 0)
    of (5, 3, 7, 1) tosses, ``juggler`` (1, 1, 1, 1) of (2, 2, 2, 2), ``oracle_catch``
    (5, 5, 5, 5) of (6, 6, 6, 6)."""
    config = CascadeV1Config(levels=("medium",), episodes=4, val_episodes=2, ilc=False)
    doc = {"config": {**config.__dict__, "levels": list(config.levels)},
           "levels": [{"level": "medium", "late_offset_s": 0.0, "constant": [0.0, 0.0],
                       "val_mean_catches": val, "best_non_oracle": "juggler",
                       "rows": {"delay_estimator_catch": ROW}}]}  # fmt: skip
    kept = {"medium": {"juggler": _kept([1, 1, 1, 1], [2, 2, 2, 2]),
                       "oracle_catch": _kept([5, 5, 5, 5], [6, 6, 6, 6]),
                       "delay_estimator_catch": _kept([4, 2, 6, 0], [5, 3, 7, 1])}}  # fmt: skip
    (tmp_path / "results.json").write_text(json.dumps(doc))
    (tmp_path / "episodes.json").write_text(json.dumps(kept))
    return tmp_path


def test_a_kept_row_is_paired_with_every_other_row_hand_worked(tmp_path: Path) -> None:
    """Mean catches 3 against the juggler's 1 and the oracle's 5: +2 and -2, each
    episode's difference constant except (+3, +1, +5, -1) against the juggler; catch rate
    12 / 16 = 0.75 against 0.5 and 20 / 24: +0.25 and -1/12; the mean's interval within
    the episodes' differences."""
    mod = _script()
    folder = _folder(tmp_path, {"juggler": 1.0, "delay_estimator_catch": 3.0})
    got = mod.replay(folder, "delay_estimator_catch", kept_row=True)["medium"]
    assert got["row"] == ROW  # the bench's entry as written, its deviation too
    assert got["minus"]["juggler"]["value"] == pytest.approx(2.0)
    assert got["minus"]["oracle_catch"]["value"] == pytest.approx(-2.0)
    lo, hi = got["minus"]["oracle_catch"]["ci"]  # per episode -1, -3, +1, -5
    assert -5.0 <= lo < -2.0 < hi <= 1.0
    assert got["minus_catch_rate"]["juggler"]["value"] == pytest.approx(0.25)
    assert got["minus_catch_rate"]["oracle_catch"]["value"] == pytest.approx(0.75 - 20 / 24)
    assert got["rates"]["juggler"] == pytest.approx(0.5)
    assert got["best_non_oracle"] == "juggler"  # as the bench chose
    assert got["best_non_oracle_with_row"] == "delay_estimator_catch"
    assert got["top_test_mean_non_oracle"] == "juggler" and got["equals_kept"] is None


def test_a_tie_goes_to_the_first_row_in_bench_order(tmp_path: Path) -> None:
    mod = _script()
    folder = _folder(tmp_path, {"delay_estimator_catch": 2.0, "juggler": 2.0})
    got = mod.replay(folder, "delay_estimator_catch", kept_row=True)["medium"]
    assert got["best_non_oracle_with_row"] == "juggler"


def test_a_row_not_kept_is_refused(tmp_path: Path) -> None:
    mod = _script()
    folder = _folder(tmp_path, {"juggler": 1.0})
    with pytest.raises(ValueError, match="no kept episodes of row 'delay_tracker' on medium"):
        mod.replay(folder, "delay_tracker", kept_row=True)
