"""motion-bench juggling --levels: the results' shape, the intervals, the agent, the CLI."""

from __future__ import annotations

import json

import numpy as np
import pytest

from baselines.agents.juggling_score import (
    JugglingEpisodes,
    catch_rate_difference,
    catch_rate_interval,
    juggling_episodes,
)
from baselines.cli import main
from baselines.juggling_bench import LevelsConfig, check_levels_config, run_levels
from baselines.juggling_bench.levels import level_episodes
from baselines.options import ConfigError


def test_small_run_has_the_documented_shape():
    config = LevelsConfig(
        levels=("easy",), methods=("juggler", "fixed_point"), episodes=6, max_catches=1
    )
    doc = run_levels(config)
    (level,) = doc["levels"]
    assert level["level"] == "easy"
    assert set(level["methods"]) == {"juggler", "fixed_point"}
    for m in level["methods"].values():
        lo, hi = m["catch_rate_ci"]
        assert 0 <= lo <= m["catch_rate"] <= hi <= 1
        assert 0 <= m["consecutive_catches_median"] <= 1
        assert m["deviation_m"] >= 0
        assert m["catches"] + m["drops"] <= m["tosses"]
    assert doc["seeds"] == {"split": "test", "first": 2_000_000_000, "count": 6}
    assert "SIMULATED" in doc["demonstrations"]
    target = doc["targets"]["juggler_easy>=0.95"]
    assert target["value"] == level["methods"]["juggler"]["catch_rate"]
    # the pooled rate: catches per toss over the same seeds, played again
    eps = level_episodes("easy", config, "fixed_point")
    assert level["methods"]["fixed_point"]["catch_rate"] == eps.catches.sum() / eps.tosses.sum()
    assert np.all(eps.tosses == 1)  # one toss per episode at max_catches=1


def _episodes(catches, tosses):
    n = len(catches)
    return JugglingEpisodes(
        seeds=np.arange(n),
        tosses=np.asarray(tosses),
        catches=np.asarray(catches),
        dropped=np.asarray(catches) < np.asarray(tosses),
        segment_phase=np.empty(0, dtype=str),
        segment_episode=np.empty(0, dtype=np.int64),
        segment_deviation=np.empty(0),
    )


def test_catch_rate_interval_against_an_independent_bootstrap():
    rng = np.random.default_rng(1)
    tosses = rng.integers(1, 4, 200)
    catches = np.minimum(tosses, rng.binomial(tosses, 0.7))
    eps = _episodes(catches, tosses)
    rate, lo, hi = catch_rate_interval(eps)
    assert rate == catches.sum() / tosses.sum()
    # oracle: plain numpy percentile bootstrap over episodes
    idx = np.random.default_rng(7).integers(0, 200, (4000, 200))
    reps = catches[idx].sum(1) / tosses[idx].sum(1)
    assert lo == pytest.approx(np.percentile(reps, 2.5), abs=0.01)
    assert hi == pytest.approx(np.percentile(reps, 97.5), abs=0.01)


def test_paired_difference_is_zero_for_the_same_policy_and_needs_the_same_seeds():
    eps = _episodes([1, 2, 0, 3], [2, 3, 1, 3])
    assert catch_rate_difference(eps, eps) == (0.0, 0.0, 0.0)
    better = _episodes([2, 3, 1, 3], [2, 3, 1, 3])
    diff, lo, hi = catch_rate_difference(better, eps)
    assert diff == pytest.approx(1 - 6 / 9)
    assert 0 < lo <= diff <= hi
    other = JugglingEpisodes(**{**eps.__dict__, "seeds": np.arange(4) + 1})
    with pytest.raises(ValueError, match="different seeds"):
        catch_rate_difference(eps, other)


def test_cli_writes_results_json(tmp_path, capsys):
    code = main(
        ["juggling", "--levels", "easy", "--episodes", "3", "--max-catches", "1",
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


def test_agent_without_levels_is_an_error(tmp_path, capsys):
    (tmp_path / "run.json").write_text("{}")
    assert main(["juggling", "--agent", str(tmp_path)]) == 2
    assert "--agent: needs --levels" in capsys.readouterr().err


def test_config_checks():
    with pytest.raises(ConfigError, match="methods"):
        check_levels_config(LevelsConfig(methods=("oracle",)))
    with pytest.raises(ConfigError, match="episodes"):
        check_levels_config(LevelsConfig(episodes=1))
    with pytest.raises(ConfigError, match="levels"):
        check_levels_config(LevelsConfig(levels=()))


# -- a trained agent: motion-bench agent and juggling --levels --agent, end to end ------------
@pytest.fixture(scope="module")
def v1_run(tmp_path_factory):
    from baselines.agents.train import TrainConfig
    from baselines.agents.train import run as train_run

    out = tmp_path_factory.mktemp("v1runs") / "ppo"
    config = TrainConfig(
        algo="ppo",
        env_id="MotionEnvs/Juggling-v1",
        out=str(out),
        timesteps=2048,
        n_envs=2,
        env_kwargs={"level": "medium", "max_catches": 1},
        overrides={"n_steps": 512, "batch_size": 256, "n_epochs": 1, "eval_freq": 1024,
                   "eval_episodes": 3},
        progress=False,
        tensorboard=False,
    )  # fmt: skip
    train_run(config)
    return out


@pytest.mark.slow
def test_motion_bench_agent_reports_catch_rates_with_intervals(v1_run, tmp_path):
    assert main(["agent", str(v1_run), "--episodes", "4", "--out", str(tmp_path)]) == 0
    doc = json.loads((tmp_path / "results.json").read_text())
    for key in ("catch_rate", "nominal_catch_rate"):
        lo, hi = doc[f"{key}_ci"]
        assert 0 <= lo <= doc[key] <= hi <= 1
    lo, hi = doc["catch_rate_difference_ci"]
    assert doc["catch_rate_difference"] == doc["catch_rate"] - doc["nominal_catch_rate"]
    assert lo <= doc["catch_rate_difference"] <= hi


@pytest.mark.slow
def test_levels_play_the_agent_on_the_same_seeds(v1_run, tmp_path):
    from baselines.agents.rundir import load_run

    config = LevelsConfig(
        levels=("medium",), methods=("juggler",), episodes=4, max_catches=1, agent=str(v1_run)
    )
    doc = run_levels(config)
    methods = doc["levels"][0]["methods"]
    agent, juggler = methods["agent"], methods["juggler"]
    assert agent["catch_rate_difference"] == pytest.approx(
        agent["catch_rate"] - juggler["catch_rate"]
    )
    loaded = load_run(v1_run)
    eps = level_episodes("medium", config, "juggler", loaded.predict, loaded.env_kwargs)
    assert agent["catch_rate"] == eps.catches.sum() / eps.tosses.sum()
    assert "agent_medium>=juggler+0.10" in doc["targets"]


def test_all_has_a_levels_job_and_the_report_shows_it(tmp_path):
    from baselines import run_all
    from baselines.juggling_bench import write_levels
    from baselines.report import build_report

    (job,) = [j for j in run_all.JOBS if isinstance(j.config, LevelsConfig)]
    assert job.config == LevelsConfig()  # every level, 200 episodes
    assert job.command(tmp_path).startswith("motion-bench juggling --levels easy,medium,hard")
    assert job.with_learned("off") is job
    doc = run_levels(LevelsConfig(levels=("hard",), methods=("juggler",), episodes=2))
    write_levels(doc, tmp_path / job.folder)
    entry = {"folder": job.folder, "title": job.title, "command": "c", "exit_code": 0}
    (tmp_path / "index.json").write_text(json.dumps({"jobs": [entry]}))
    page = build_report(tmp_path)
    assert "no report section" not in page
    assert "catch rate [95 % CI]" in page and "SIMULATED" in page


def _same_episodes(a, b) -> bool:
    return all(
        np.array_equal(getattr(a, f), getattr(b, f))
        for f in (
            "seeds",
            "tosses",
            "catches",
            "dropped",
            "segment_phase",
            "segment_episode",
            "segment_deviation",
        )
    )


def test_nominal_episodes_are_the_stepped_zero_action_episodes():
    # juggling_episodes plays the zero action by nominal_episode (no observation, no
    # likeness reward); a zero policy goes through step(): the same episodes bit for bit
    kwargs = {"level": "hard", "controller": "fixed_point", "max_catches": 3}
    fast = juggling_episodes(None, "MotionEnvs/Juggling-v1", kwargs, "val", 4)
    stepped = juggling_episodes(
        lambda obs: np.zeros((obs.shape[0], 2)), "MotionEnvs/Juggling-v1", kwargs, "val", 4
    )
    assert _same_episodes(fast, stepped)
    assert fast.tosses.sum() > 0 and fast.segment_deviation.size > 0


def test_latency_aware_juggler_at_zero_latency_is_the_juggler():
    # run_levels reuses the juggler's episodes for it on easy (zero latency)
    config = LevelsConfig(episodes=3, split="val")
    aware = level_episodes("easy", config, "juggler_latency_aware")
    assert _same_episodes(aware, level_episodes("easy", config, "juggler"))
