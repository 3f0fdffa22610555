"""motion-bench juggling-levels: the results' shape, the bootstrap interval, the CLI."""

from __future__ import annotations

import json

import numpy as np
import pytest

from baselines import juggling_levels
from baselines.cli import main
from baselines.juggling_levels import LevelsConfig, run, run_method
from baselines.options import ConfigError


def test_small_run_has_the_documented_shape(tmp_path):
    config = LevelsConfig(
        levels=("easy",), methods=("juggler", "fixed_point"), episodes=6, max_catches=1
    )
    doc = run(config)
    (level,) = doc["levels"]
    assert level["level"] == "easy"
    assert set(level["methods"]) == {"juggler", "fixed_point"}
    for m in level["methods"].values():
        lo, hi = m["catch_rate_ci"]
        assert 0 <= lo <= m["catch_rate"] <= hi <= 1
        assert 0 <= m["consecutive_catches_median"] <= 1
        assert m["likeness_m"] >= 0
    assert doc["seeds"] == {"split": "test", "first": 2_000_000_000, "count": 6}
    assert "SIMULATED" in doc["demonstrations"]
    assert (
        doc["targets"]["juggler_easy_ge_0.95"]["value"] == level["methods"]["juggler"]["catch_rate"]
    )
    # the pooled rate is catches / (catches + drops) of the per-episode outcomes
    res = run_method("easy", "fixed_point", 6, 1, 9.81, 2_000_000_000)
    rate = res["catches"].sum() / (res["catches"] + res["drops"]).sum()
    assert level["methods"]["fixed_point"]["catch_rate"] == pytest.approx(rate)
    assert np.all(res["catches"] + res["drops"] == 1)  # one toss per episode at max_catches=1


def test_cli_writes_results_json(tmp_path, capsys):
    code = main(
        ["juggling-levels", "--levels", "easy", "--episodes", "3", "--max-catches", "1",
         "--out", str(tmp_path)]
    )  # fmt: skip
    assert code == 0
    doc = json.loads((tmp_path / "results.json").read_text())
    assert [lv["level"] for lv in doc["levels"]] == ["easy"]
    assert set(doc["levels"][0]["methods"]) == {
        "juggler",
        "juggler_latency_aware",
        "fixed_point",
        "commanded_intercept",
    }
    assert "catch rate" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--levels", "expert"], "argument --levels"),
        (["--episodes", "0"], "argument --episodes"),
        (["--max-catches", "-1"], "argument --max-catches"),
    ],
)
def test_cli_errors_exit_2_before_computing(argv, message, capsys, monkeypatch):
    def started(*args, **kwargs):
        raise AssertionError("computation started")

    monkeypatch.setattr(juggling_levels, "run_method", started)
    assert main(["juggling-levels", *argv]) == 2
    assert message in capsys.readouterr().err


def test_config_checks():
    with pytest.raises(ConfigError):
        juggling_levels.check_config(LevelsConfig(methods=("oracle",)))
    with pytest.raises(ConfigError):
        juggling_levels.check_config(LevelsConfig(episodes=1))
