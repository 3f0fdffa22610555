"""motion-bench sweep on a local Ray (2 CPUs): a two-trial, tiny-budget sweep.

Its per-configuration table must equal what ``motion-bench train`` + ``motion-bench agent``
give for the same configuration and seeds, run in this process. ``--resume`` after a
Ctrl-C keeps the finished trial's run folder as it is and trains the other one again, to
the same numbers as an uninterrupted sweep.
"""

from __future__ import annotations

import csv
import hashlib
import json
import os
import signal
import threading
import time
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("stable_baselines3")
ray = pytest.importorskip("ray", reason="the sweep extra (ray[tune]) is not installed")

from baselines.agents.evaluate import AgentConfig  # noqa: E402
from baselines.agents.evaluate import run as evaluate  # noqa: E402
from baselines.agents.sweep import expand_configurations, load_sweep, summarize  # noqa: E402
from baselines.agents.train import TrainConfig  # noqa: E402
from baselines.agents.train import run as train  # noqa: E402

pytestmark = [
    pytest.mark.ray,
    pytest.mark.slow,
    pytest.mark.filterwarnings("ignore::DeprecationWarning"),
    pytest.mark.filterwarnings("ignore::FutureWarning"),
]
TINY = Path(__file__).resolve().parents[1] / "configs" / "sweeps" / "tiny.yaml"


@pytest.fixture(scope="module")
def local_ray():
    try:
        ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    except Exception as exc:  # pragma: no cover - depends on the machine
        pytest.skip(f"Ray cannot start here: {exc}")
    yield
    ray.shutdown()


def test_two_trial_sweep_equals_the_single_run_command(local_ray, tmp_path):
    from baselines.cli import main

    out = tmp_path / "sweep"
    assert main(["sweep", "--config", str(TINY), "--out", str(out), "--no-progress"]) == 0
    doc = json.loads((out / "results.json").read_text())
    assert doc["n_trials"] == 2 and len(doc["configurations"]) == 1
    for name in ("trials.csv", "table.csv", "table.md", "sweep.png"):
        assert (out / name).is_file()
    row = doc["configurations"][0]
    assert row["best_on_validation"] and row["seeds"] == [0, 1]
    # trials.csv: run folders relative to --out (once absolute paths)
    with open(out / "trials.csv", newline="") as fh:
        dirs = [r["run_dir"] for r in csv.DictReader(fh)]
    assert len(dirs) == 2 and all(not Path(d).is_absolute() for d in dirs)
    assert all((out / d / "run.json").is_file() for d in dirs)

    sweep = load_sweep(TINY, out=str(out))
    cfg = sweep.configurations[0]
    single, curves = [], []
    for seed in sweep.seeds:
        run_dir = tmp_path / f"single{seed}"
        result = train(
            TrainConfig(
                algo=cfg["algo"],
                env_id=cfg["env_id"],
                out=str(run_dir),
                seed=seed,
                timesteps=sweep.timesteps,
                n_envs=sweep.n_envs,
                overrides=cfg["overrides"],
                progress=False,
                tensorboard=False,
            )
        )
        test = evaluate(AgentConfig(str(run_dir), "test"))
        trial = next(t for t in doc["trials"] if t["seed"] == seed)
        assert trial["best_val_criterion"] == result.best_val_criterion
        assert trial["test_criterion"] == test["criterion"]
        assert trial["test_nominal_criterion"] == test["nominal_criterion"]
        # the kept checkpoint may be the initial policy for both; the validation curve and
        # the final policy are where the two seeds differ, so compare those too
        trial_dir = Path(trial["run_dir"])
        curve = (run_dir / "evaluations.csv").read_text()
        assert (trial_dir / "evaluations.csv").read_text() == curve
        curves.append(curve)
        finals = [
            evaluate(AgentConfig(str(d), "test", episodes=5, which="final"))["criterion"]
            for d in (trial_dir, run_dir)
        ]
        assert finals[0] == finals[1]
        single.append(test["criterion"])
    assert curves[0] != curves[1]
    assert row["test_criterion_median"] == float(np.median(single))
    assert row["test_criterion_min"] == min(single)


def test_optuna_sweep_trains_each_proposal_on_every_seed(local_ray, tmp_path):
    pytest.importorskip("optuna")
    from baselines.agents.sweep import run as sweep_run

    path = tmp_path / "optuna.yaml"
    path.write_text(
        TINY.read_text()
        .replace("search: grid", "search: optuna\nnum_samples: 1")
        .replace("n_epochs: [2]", "n_epochs: {randint: [1, 2]}")
    )
    sweep = load_sweep(path, out=str(tmp_path / "out"))
    assert sweep.search == "optuna" and sweep.space["hyperparams.n_epochs"] == {"randint": [1, 2]}
    results = sweep_run(sweep)
    assert results["n_trials"] == 2  # one proposal x 2 seeds
    (row,) = results["configurations"]
    assert row["seeds"] == [0, 1] and row["overrides"]["n_epochs"] in (1, 2)
    assert row["best_on_validation"]


def test_best_configuration_is_chosen_on_validation_only():
    sweep = load_sweep(TINY, out="unused")
    sweep = type(sweep)(**{**sweep.__dict__, "configurations": sweep.configurations * 2})
    trials = [
        # configuration 0: better on validation, worse on test
        {"config_index": 0, "seed": 0, "best_val_criterion": 0.1, "test_criterion": 0.9,
         "test_ratio": 0.9, "test_nominal_criterion": 1.0},
        {"config_index": 1, "seed": 0, "best_val_criterion": 0.2, "test_criterion": 0.5,
         "test_ratio": 0.5, "test_nominal_criterion": 1.0},
    ]  # fmt: skip
    summary = summarize(trials, sweep)
    assert summary["best_config_index"] == 0


def test_a_juggling_sweep_reports_catch_rates_where_no_ratio_exists(local_ray, tmp_path):
    """Juggling-v0's nominal drops nothing (criterion 0), so criterion / nominal has no
    value: the table says n/a and adds catch rates and the deviation ratio, which equal
    motion-bench agent's on the same run folder; the plot shows the criterion itself."""
    from baselines.agents.sweep import format_table
    from baselines.cli import main

    path = tmp_path / "juggling.yaml"
    path.write_text(
        "search: grid\nseeds: [0]\ntimesteps: 512\nn_envs: 2\ntest_split: val\nspace:\n"
        "  algo: [ppo]\n  env_id: [MotionEnvs/Juggling-v0]\n"
        "  env_kwargs: {max_cycles: [1]}\n"
        "  hyperparams: {n_steps: [128], batch_size: [128], n_epochs: [1], eval_freq: [256],"
        " eval_episodes: [2]}\n"
    )
    out = tmp_path / "out"
    assert main(["sweep", "--config", str(path), "--out", str(out), "--no-progress"]) == 0
    doc = json.loads((out / "results.json").read_text())
    (trial,) = doc["trials"]
    agent = evaluate(AgentConfig(trial["run_dir"], "val"))
    assert trial["test_catch_rate"] == agent["catch_rate"]
    assert trial["test_nominal_catch_rate"] == agent["nominal_catch_rate"]
    assert trial["test_deviation_ratio"] == agent["deviation_ratio"]
    (row,) = doc["configurations"]
    assert row["test_catch_rate_median"] == agent["catch_rate"]
    assert agent["nominal_criterion"] == 0  # the juggler catches all 20 validation balls
    assert trial["test_ratio"] is None and row["test_ratio_median"] is None
    assert "| n/a |" in (out / "table.md").read_text()
    assert "nominal catch rate" in format_table(doc)
    assert (out / "sweep.png").stat().st_size > 5_000


def test_tables_of_reaching_and_juggling_rows_side_by_side(tmp_path):
    from baselines.agents.sweep import format_table, plot_sweep

    sweep = load_sweep(TINY, out="unused")
    sweep = type(sweep)(**{**sweep.__dict__, "configurations": sweep.configurations * 2})
    reach = {
        "best_val_criterion": 0.2,
        "test_criterion": 0.45,
        "test_ratio": 0.9,
        "test_nominal_criterion": 0.5,
        "test_catch_rate": None,
        "test_nominal_catch_rate": None,
        "test_deviation_ratio": None,
    }
    juggle = {
        "best_val_criterion": 0.0,
        "test_criterion": 0.0,
        "test_ratio": None,
        "test_nominal_criterion": 0.0,
        "test_catch_rate": 1.0,
        "test_nominal_catch_rate": 1.0,
        "test_deviation_ratio": 1.25,
    }
    trials = [{"config_index": 0, "seed": s, **reach} for s in (0, 1)] + [
        {"config_index": 1, "seed": s, **juggle} for s in (0, 1)
    ]  # fmt: skip
    summary = summarize(trials, sweep)
    first, second = summary["configurations"]
    assert first["test_ratio_median"] == 0.9 and first["test_catch_rate_median"] is None
    assert second["test_ratio_median"] is None and second["test_deviation_ratio_max"] == 1.25
    table = format_table(summary).splitlines()
    assert table[2].endswith("| 0.900 (0.900-0.900) | n/a | n/a | n/a |")
    assert table[3].endswith("| n/a | 1.000 (1.000-1.000) | 1.000 | 1.250 (1.250-1.250) |")
    plot_sweep({**summary, "test_split": "test"}, tmp_path / "mixed.png")
    assert (tmp_path / "mixed.png").stat().st_size > 5_000


@pytest.mark.parametrize(
    ("doc", "match"),
    [
        ({"search": "bayes", "space": {"algo": ["ppo"], "env_id": ["X-v0"]}}, "search must be"),
        ({"space": {"algo": ["ppo"]}}, r"space.env_id is required"),
        ({"space": {"algo": ["a2c"], "env_id": ["X-v0"]}}, "not one of"),
        ({"space": {"algo": ["ppo"], "env_id": ["X-v0"], "hyperparams": {"n_step": [1]}}},
         "unknown key"),
        ({"space": {"algo": "ppo", "env_id": ["X-v0"]}}, "non-empty list"),
        ({"search": "random", "space": {"algo": ["ppo"], "env_id": ["X-v0"]}}, "num_samples"),
    ],
)  # fmt: skip
def test_bad_sweep_documents(doc, match):
    with pytest.raises(ValueError, match=match):
        expand_configurations(doc)


def test_random_search_draws_once_per_configuration():
    doc = {
        "search": "random",
        "num_samples": 5,
        "random_seed": 3,
        "space": {
            "algo": ["ppo"],
            "env_id": ["MotionEnvs/OrientationReach-v1"],
            "hyperparams": {
                "learning_rate": {"loguniform": [1e-5, 1e-3]},
                "n_epochs": {"randint": [1, 4]},
            },
        },
    }
    a, b = expand_configurations(doc), expand_configurations(doc)
    assert a == b and len(a) == 5
    for c in a:
        assert 1e-5 <= c["overrides"]["learning_rate"] <= 1e-3
        assert c["overrides"]["n_epochs"] in (1, 2, 3, 4)


# ---------------------------------------------------------------- --resume


def _files(folder: Path) -> dict[str, tuple[str, int]]:
    """Every file under ``folder``: its SHA-256 and modification time (ns)."""
    return {
        str(f.relative_to(folder)): (
            hashlib.sha256(f.read_bytes()).hexdigest(),
            f.stat().st_mtime_ns,
        )
        for f in sorted(folder.rglob("*"))
        if f.is_file()
    }


def _numbers(trial: dict) -> dict:
    """A trial's metrics without the timings and the run folder's path."""
    return {
        k: v for k, v in trial.items() if k not in ("train_seconds", "trial_seconds", "run_dir")
    }


def _sweep(out: Path, *extra: str, config: Path = TINY) -> int:
    from baselines.cli import main

    return main(["sweep", "--config", str(config), "--out", str(out), "--no-progress", *extra])


@pytest.fixture(scope="module")
def finished_sweep(local_ray, tmp_path_factory):
    """The tiny sweep run to the end; ``--resume`` on an ``--out`` with no sweep starts one."""
    out = tmp_path_factory.mktemp("finished") / "sweep"
    assert _sweep(out, "--resume") == 0
    return out


def test_resume_with_no_sweep_in_out_starts_one(finished_sweep):
    doc = json.loads((finished_sweep / "results.json").read_text())
    assert doc["n_trials"] == 2 and doc["configurations"][0]["seeds"] == [0, 1]
    assert [t["resumed"] for t in doc["trials"]] == [False, False]
    settings = json.loads((finished_sweep / "sweep.json").read_text())
    assert settings["seeds"] == [0, 1] and settings["timesteps"] == 2000


def test_an_out_holding_a_sweep_is_refused_unless_resumed_with_the_same_file(
    finished_sweep, tmp_path, capsys
):
    before = _files(finished_sweep)
    # without --resume the finished run folders would be scored again as this sweep's
    assert _sweep(finished_sweep) == 2
    err = capsys.readouterr().err
    assert f"argument --out: {finished_sweep} already holds a sweep" in err and "--resume" in err
    # --resume with other settings would mix 1,000-step trials with 2,000-step ones
    other = tmp_path / "other.yaml"
    other.write_text(TINY.read_text().replace("timesteps: 2000", "timesteps: 1000"))
    assert _sweep(finished_sweep, "--resume", config=other) == 2
    err = capsys.readouterr().err
    assert f"argument --config: {other} is not the sweep in --out {finished_sweep}" in err
    assert _files(finished_sweep) == before


def test_resume_continues_an_interrupted_sweep_to_the_same_results(
    finished_sweep, local_ray, tmp_path, capsys
):
    from baselines.agents.sweep import train_and_score, trial_settings

    out = tmp_path / "sweep"
    runs = out / "runs"

    @ray.remote(num_cpus=1)
    class Hold:  # takes one of the 2 CPUs: the two trials run one after the other
        def ready(self) -> bool:
            return True

    hold = Hold.remote()
    ray.get(hold.ready.remote())
    done = threading.Event()
    sent: list[float] = []  # s after the start at which the ctrl-C was sent
    start = time.monotonic()

    def ctrl_c_when_the_second_trial_starts() -> None:
        # generous: on a loaded 2-core machine the first trial alone can take minutes
        deadline = start + 1200
        while not done.is_set() and time.monotonic() < deadline:
            entries = list(runs.iterdir()) if runs.is_dir() else []
            finished = [d for d in entries if (d / "run.json").is_file()]
            # the second trial has started: its locked run folder or its staging folder
            # beside the first trial's finished one
            if finished and len(entries) >= 2:
                sent.append(time.monotonic() - start)
                os.kill(os.getpid(), signal.SIGINT)  # Ray Tune's handler: save and stop
                return
            time.sleep(0.02)

    watcher = threading.Thread(target=ctrl_c_when_the_second_trial_starts, daemon=True)
    watcher.start()
    try:
        code = _sweep(out)
    finally:
        done.set()
        watcher.join()
        ray.kill(hold)
    err = capsys.readouterr().err
    when = f"ctrl-C sent {sent[0]:.0f} s in" if sent else "no ctrl-C sent (deadline passed)"
    assert code == 130, f"{when}; the sweep took {time.monotonic() - start:.0f} s; {err}"
    assert f"interrupted with 1 of 2 trials finished; continue it with --resume --out {out}" in err
    assert not (out / "results.json").exists()
    finished = [d for d in sorted(runs.iterdir()) if (d / "run.json").is_file()]
    assert len(finished) == 1, "the second trial must be cut short"
    (kept,) = finished
    rest = set(runs.iterdir()) - {kept}
    # the second trial had started (its staging folder, and its run folder locked but
    # still empty) or, on a busy machine, was cut before it created anything
    assert len(rest) <= 2, rest
    for leftover in rest:
        if leftover.name.startswith("."):
            assert leftover.name.startswith(".config") and ".partial-" in leftover.name
        else:
            assert leftover.name.startswith("config") and not any(leftover.iterdir())
    kept_files = _files(kept)

    assert _sweep(out, "--resume") == 0
    assert _files(kept) == kept_files  # not trained (nor written) again
    after = sorted(p.name for p in runs.iterdir())
    assert len(after) == 2 and kept.name in after, after  # the cut trial ran; no leftover
    cut = runs / next(n for n in after if n != kept.name)
    assert (cut / "run.json").is_file()
    ref = json.loads((finished_sweep / "results.json").read_text())
    doc = json.loads((out / "results.json").read_text())
    # the finished trial's result is Ray Tune's stored one (a rerun would say resumed);
    # the cut one was trained again from scratch
    assert [t["resumed"] for t in doc["trials"]] == [False, False]
    assert [_numbers(t) for t in doc["trials"]] == [_numbers(t) for t in ref["trials"]]
    assert doc["configurations"] == ref["configurations"]
    # training is deterministic for a seed on CPU: the same validation curve, step by step;
    # the seeds' curves differ (at 2,000 steps the best policy is the initial one, so the
    # criteria above are the same for both seeds and alone would not show this)
    curves = {d.name: (d / "evaluations.csv").read_text() for d in (kept, cut)}
    assert curves == {
        n: (finished_sweep / "runs" / n / "evaluations.csv").read_text() for n in curves
    }
    assert curves[kept.name] != curves[cut.name]

    # a trial restarted after its run folder was finished only scores it again
    sweep = load_sweep(TINY, out=str(out))
    trial = next(t for t in doc["trials"] if Path(t["run_dir"]).name == kept.name)
    again = train_and_score(
        sweep.configurations[0], trial["seed"], kept, trial_settings(sweep), True
    )
    assert {"config_index": trial["config_index"], **_numbers(again)} == {
        **_numbers(trial),
        "resumed": True,
    }
    assert _files(kept) == kept_files

    # resuming a finished sweep trains nothing and gives the same results
    every_run = _files(runs)
    assert _sweep(out, "--resume") == 0
    assert _files(runs) == every_run
    assert json.loads((out / "results.json").read_text())["trials"] == doc["trials"]
