"""Agents judged by people: the leave-one-person-out folds of the orientation envs and the
LOPO sweep (configs/sweeps/orientation_lopo.yaml) with its per-person summary."""

from __future__ import annotations

from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
import yaml
from scipy import stats

import motion_envs  # noqa: F401  (registers the ids)
from baselines.agents.sweep.lopo import format_lopo, lopo_summary

LOPO = Path(__file__).resolve().parents[1] / "configs" / "sweeps" / "orientation_lopo.yaml"


@pytest.mark.parametrize(
    "env_id", ["MotionEnvs/OrientationCoefficients-v0", "MotionEnvs/OrientationReach-v1"]
)
def test_folds_hold_each_person_out_once_and_fit_on_the_others(env_id):
    people = []
    for fold in range(8):
        test = gym.make(env_id, split="test", fold=fold).unwrapped.task
        train = gym.make(env_id, split="train", fold=fold, val_fraction=0.3).unwrapped.task
        val = gym.make(env_id, split="val", fold=fold, val_fraction=0.3).unwrapped.task
        (person,) = set(test.subjects.tolist())
        people.append(person)
        assert person not in set(train.subjects) | set(val.subjects)
        assert len(set(val.subjects)) >= 2  # checkpoints never chosen on a single person
        assert not set(val.subjects) & set(train.subjects)
    assert people == sorted(people) and len(set(people)) == 8
    with pytest.raises(ValueError, match="fold"):
        gym.make(env_id, split="test", fold=8)


def test_fold_nominal_is_fitted_on_the_training_people_only():
    """The test person's nominal (bezier-null: the training people's mean residual) does
    not move when the test person's own data would change it: it equals a nominal fitted
    on the training split's trajectories."""
    from motion_envs.envs.orientation_reach import orientation_split_parts
    from motion_envs.models.nominal import OrientationNominal

    env = gym.make("MotionEnvs/OrientationCoefficients-v0", split="test", fold=3).unwrapped
    _, fit, part = orientation_split_parts("vr-kitchen", "test", 0.25, 0, 10.0, 0.0, 3)
    assert not set(fit.subjects) & set(part.subjects)
    g = OrientationNominal("slerp", 2, 50).fit(fit).grids(part)
    np.testing.assert_array_equal(g.base, env.task.grids.base)


def _trials(ratios):
    return [
        {"config_index": f, "seed": s, "test_ratio": r}
        for f, row in enumerate(ratios)
        for s, r in enumerate(row)
    ]


def test_lopo_summary_iqm_matches_a_trimmed_mean_and_words_the_verdict():
    rng = np.random.default_rng(0)
    ratios = rng.uniform(0.85, 0.97, size=(8, 3))  # (people, seeds): all below 1
    configs = [{"overrides": {"env_kwargs": {"fold": f}}} for f in range(8)]
    got = lopo_summary(_trials(ratios), configs)
    assert got["folds"] == list(range(8)) and got["seeds"] == [0, 1, 2]
    assert got["iqm_ratio"] == pytest.approx(stats.trim_mean(ratios.ravel(), 0.25))
    lo, hi = got["iqm_ratio_ci95"]
    assert lo <= got["iqm_ratio"] <= hi < 1.0
    assert got["verdict"] == "better" and got["people_below_nominal"] == 8
    assert "lower is better" in format_lopo(got)
    worse = lopo_summary(_trials(ratios + 0.2), configs)
    assert worse["verdict"] == "worse"
    assert lopo_summary(_trials(ratios), [{"overrides": {}}] * 8) is None


def test_shipped_lopo_sweep_is_leave_one_person_out():
    from baselines.agents.sweep import load_sweep

    sweep = load_sweep(LOPO, out="unused")
    folds = sorted(c["overrides"]["env_kwargs"]["fold"] for c in sweep.configurations)
    assert folds == list(range(8)) and sweep.seeds == (0, 1, 2)
    assert all(c["overrides"]["env_kwargs"]["val_fraction"] > 0 for c in sweep.configurations)


@pytest.mark.ray
@pytest.mark.filterwarnings("ignore::DeprecationWarning")
@pytest.mark.filterwarnings("ignore::FutureWarning")
def test_tiny_lopo_sweep_reports_people(tmp_path):
    ray = pytest.importorskip("ray")
    from baselines.agents.sweep import load_sweep
    from baselines.agents.sweep import run as sweep_run

    doc = yaml.safe_load(LOPO.read_text())
    doc["seeds"] = [0]
    doc["timesteps"] = 256
    doc["n_envs"] = 2
    doc["space"]["env_kwargs"]["fold"] = [0, 6]
    doc["space"]["hyperparams"] = {"eval_freq": [128], "n_steps": [64], "batch_size": [64]}
    path = tmp_path / "lopo.yaml"
    path.write_text(yaml.safe_dump(doc))
    try:
        ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    except Exception as exc:  # pragma: no cover - depends on the machine
        pytest.skip(f"Ray cannot start here: {exc}")
    try:
        results = sweep_run(load_sweep(path, out=str(tmp_path / "out"), num_cpus=2))
    finally:
        ray.shutdown()
    lopo = results["lopo"]
    assert lopo["folds"] == [0, 6] and lopo["n_people"] == 2
    by_fold = {
        str(doc["space"]["env_kwargs"]["fold"][t["config_index"]]): t for t in results["trials"]
    }
    for fold, per_seed in lopo["ratio_per_person"].items():
        assert per_seed[0] == by_fold[fold]["test_ratio"]
    assert lopo["verdict"] in ("better", "worse", "no difference")
