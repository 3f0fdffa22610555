"""motion-bench sweep on a local Ray (2 CPUs): a two-trial, tiny-budget sweep.

Its per-configuration table must equal what ``motion-bench train`` + ``motion-bench agent``
give for the same configuration and seeds, run in this process.
"""

from __future__ import annotations

import json
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

    sweep = load_sweep(TINY, out=str(out))
    cfg = sweep.configurations[0]
    single = []
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
        single.append(test["criterion"])
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
