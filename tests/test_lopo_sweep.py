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
    from motion_envs.models.orientation_nominal import OrientationNominal

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
    assert sweep.inner_folds == 3  # checkpoints by inner folds over people, then a refit
    assert all("val_fraction" not in c["overrides"]["env_kwargs"] for c in sweep.configurations)


@pytest.mark.slow
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
    doc["inner_folds"] = 2  # nested: 2 inner agents and a refit per trial
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
    assert lopo["verdict"] == "cannot decide"  # 2 people: fewer than MIN_GROUPS
    assert lopo["selection"] == "inner folds over the training people"
    assert all(t["inner_val_ratio"] is not None for t in results["trials"])
    assert lopo["agent_over_ridge"]["verdict"] == "cannot decide"


# -- checkpoints chosen by inner folds over people ---------------------------------------
@pytest.mark.parametrize("fold", [0, 5])
def test_val_folds_cut_the_training_people_into_groups(fold):
    env_id, k = "MotionEnvs/OrientationCoefficients-v0", 3
    from motion_envs.envs.orientation_reach import orientation_split_parts
    from motion_envs.models.orientation_nominal import OrientationNominal

    (person,) = set(gym.make(env_id, split="test", fold=fold).unwrapped.task.subjects)
    training = set(gym.make(env_id, split="train", fold=fold).unwrapped.task.subjects)
    groups = []
    for j in range(k):
        kw = {"fold": fold, "val_folds": k, "val_fold": j, "nominal": "bezier-null"}
        val = gym.make(env_id, split="val", **kw).unwrapped.task
        train = gym.make(env_id, split="train", **kw).unwrapped.task
        groups.append(set(val.subjects))
        assert len(groups[-1]) >= 2 and person not in groups[-1] | set(train.subjects)
        assert set(train.subjects) == training - groups[-1]
        # the inner nominal is fitted on the inner training people only
        _, fit, part = orientation_split_parts("vr-kitchen", "val", 0.25, 0, 10.0, 0.0, fold, k, j)
        assert set(fit.subjects) == set(train.subjects)
        g = OrientationNominal("bezier-null", 2, 50).fit(fit).grids(part)
        np.testing.assert_array_equal(g.predicted_residuals, val.grids.predicted_residuals)
    assert set().union(*groups) == training and sum(map(len, groups)) == len(training)
    with pytest.raises(ValueError, match="val_folds"):
        gym.make(env_id, split="val", fold=fold, val_folds=8, val_fold=0)
    with pytest.raises(ValueError, match="val_fold"):
        gym.make(env_id, split="val", fold=fold, val_folds=3, val_fold=3)
    with pytest.raises(ValueError, match="val_fraction"):
        gym.make(env_id, split="val", fold=fold, val_folds=3, val_fraction=0.2)


def test_choose_step_is_the_lowest_mean_inner_ratio_first_of_ties():
    from baselines.agents.sweep.nested import choose_step

    steps = [[0, 10, 20, 30]] * 2
    crit = [[2.0, 1.0, 1.5, 1.0], [4.0, 4.0, 2.0, 4.0]]  # ratios /2 and /4
    got = choose_step(steps, crit, [2.0, 4.0])
    # mean ratios: 1.0, 0.75, 0.625, 0.75
    assert got["timesteps"] == 20 and got["val_ratio"] == pytest.approx(0.625)
    assert got["curve"]["val_ratio"] == pytest.approx([1.0, 0.75, 0.625, 0.75])
    tie = choose_step(steps, [[2.0, 1.0, 2.0, 1.0], [4.0] * 4], [2.0, 4.0])
    assert tie["timesteps"] == 10  # the earliest of equal ratios
    with pytest.raises(ValueError, match="different steps"):
        choose_step([[0, 10], [0, 11]], [[1, 1], [1, 1]], [1.0, 1.0])


def _tiny(**env_kwargs):
    return {
        "algo": "ppo",
        "env_id": "MotionEnvs/OrientationCoefficients-v0",
        "overrides": {
            "env_kwargs": {"nominal": "bezier-null", **env_kwargs},
            "eval_freq": 128,
            "n_steps": 64,
            "batch_size": 64,
        },
    }


@pytest.mark.slow
@pytest.mark.filterwarnings("ignore::DeprecationWarning")
def test_nested_trial_never_sees_the_held_out_person(tmp_path, monkeypatch):
    """Every split built while the inner agents train, validate and the checkpoint is
    chosen and refitted is recorded: the held-out person is in none (not in a nominal's
    fit, not in an episode), every validation has >= 2 people, and the test split is
    not even built."""
    import json

    from baselines.agents.sweep.nested import nested_train
    from motion_envs.envs import _orientation_task as ot

    fold = 2
    (person,) = set(
        gym.make(
            "MotionEnvs/OrientationCoefficients-v0", split="test", fold=fold
        ).unwrapped.task.subjects
    )
    seen = []
    original = ot.orientation_split_parts

    def recording(data, split, *args, **kwargs):
        dataset, fit, part = original(data, split, *args, **kwargs)
        seen.append((split, set(fit.subjects), set(part.subjects)))
        return dataset, fit, part

    monkeypatch.setattr(ot, "orientation_split_parts", recording)
    ot._build_task_cached.cache_clear()  # every build goes through the recorder
    try:
        run_dir = tmp_path / "runs" / "config000-seed0"
        sel = nested_train(_tiny(fold=fold), 0, run_dir, 3, 256, 2)
    finally:
        ot._build_task_cached.cache_clear()
    splits = {s for s, _, _ in seen}
    assert splits == {"train", "val"}  # the test split never built
    for split, fit, part in seen:
        assert person not in fit and person not in part
        if split == "val":
            assert len(part) >= 2 and not part & fit
    vals = {frozenset(p) for s, _, p in seen if s == "val"}
    assert len(vals) == 3  # three inner groups
    manifest = json.loads((run_dir / "run.json").read_text())
    assert manifest["best_timesteps"] == sel["timesteps"]
    assert manifest["selection"]["val_ratio"] == sel["val_ratio"]
    assert manifest["timesteps"] <= max(sel["timesteps"], 2) + 2  # stopped once kept
    config = json.loads((run_dir / "config.json").read_text())
    env_kwargs = config["hyperparams"]["env_kwargs"]
    assert env_kwargs["val_fraction"] == 0 and "val_folds" not in env_kwargs  # all 7 people
    for d in sel["inner_run_dirs"]:
        assert (
            json.loads((Path(d) / "config.json").read_text())["hyperparams"]["env_kwargs"][
                "val_folds"
            ]
            == 3
        )


@pytest.mark.filterwarnings("ignore::DeprecationWarning")
def test_refit_keeps_the_chosen_step_of_the_schedule(tmp_path):
    import json

    from baselines.agents.train import TrainConfig, run

    cfg = _tiny(fold=1, val_fraction=0.0)
    base = {"algo": "ppo", "env_id": cfg["env_id"], "seed": 0, "timesteps": 512, "n_envs": 2}
    checked = _tiny(fold=1, val_fraction=0.3)["overrides"]
    full = run(
        TrainConfig(
            out=str(tmp_path / "full"), overrides=checked, progress=False, tensorboard=False, **base
        )
    )
    points = [int(e["timesteps"]) for e in full.evaluations]
    keep = points[2]
    refit = run(
        TrainConfig(
            out=str(tmp_path / "refit"),
            overrides=cfg["overrides"],
            progress=False,
            tensorboard=False,
            keep_timesteps=keep - 1,
            selection={"val_criterion": 0.5, "val_nominal_criterion": 0.6},
            **base,
        )
    )
    assert refit.best_timesteps == keep  # the first point of the schedule at or after it
    assert refit.timesteps < 512 and refit.best_val_criterion == 0.5
    manifest = json.loads((tmp_path / "refit" / "run.json").read_text())
    assert manifest["selection"]["val_nominal_criterion"] == 0.6
    with pytest.raises(ValueError, match="keep_timesteps"):
        run(TrainConfig(out=str(tmp_path / "bad"), overrides=cfg["overrides"],
                        keep_timesteps=10**6, **base))  # fmt: skip


def test_lopo_summary_chooses_hyperparameters_by_inner_folds_not_test():
    configs = [
        {"overrides": {"env_kwargs": {"fold": f}, "learning_rate": lr}}
        for f in range(3)
        for lr in (1e-3, 1e-4)
    ]
    trials = []
    for i, _ in enumerate(configs):
        good_inner = i % 2 == 1  # lr 1e-4 wins inside; lr 1e-3 wins on the test person
        for s in range(2):
            trials.append(
                {
                    "config_index": i,
                    "seed": s,
                    "test_ratio": 0.99 if good_inner else 0.80,
                    "inner_val_ratio": 0.90 if good_inner else 0.95,
                    "test_learned_ratio": 1.01,
                    "test_learned_criterion": 0.3,
                    "test_nominal_criterion": 0.32,
                }
            )
    got = lopo_summary(trials, configs)
    assert got["chosen_config_per_person"] == {"0": 1, "1": 3, "2": 5}
    assert got["ratio_per_person_median"] == {"0": 0.99, "1": 0.99, "2": 0.99}
    assert got["selection"] == "inner folds over the training people"
    over = got["agent_over_ridge"]
    assert over["iqm_ratio"] == pytest.approx(1.01)
    assert over["ridge_over_nominal_per_person"]["0"] == pytest.approx(0.3 / 0.32)
    assert "agent / ridge" in format_lopo(got)


def test_lopo_interval_resamples_people_not_only_seeds():
    """With the same ratio on every seed, rliable's interval (seeds within each person)
    is a point; the people interval is not, and it is a point only when every person has
    the same ratio."""
    per_person = [0.8, 0.9, 1.0, 1.1, 1.2, 0.95, 1.05, 0.85]
    configs = [{"overrides": {"env_kwargs": {"fold": f}}} for f in range(8)]
    got = lopo_summary(_trials([[r] * 3 for r in per_person]), configs)
    lo, hi = got["iqm_ratio_ci95"]
    assert got["iqm_ratio_ci95_seeds"] == [pytest.approx(got["iqm_ratio"])] * 2
    assert min(per_person) <= lo < got["iqm_ratio"] < hi <= max(per_person)
    assert got["verdict"] == "no difference"
    flat = lopo_summary(_trials([[0.9] * 3] * 8), configs)
    assert flat["iqm_ratio_ci95"] == [pytest.approx(0.9)] * 2 and flat["verdict"] == "better"


class _Stop(Exception):
    pass


@pytest.mark.parametrize("how", ["--address", "RAY_ADDRESS"])
def test_lopo_sweep_joins_a_cluster_unchanged(tmp_path, monkeypatch, how):
    """The shipped file runs on a cluster as it is: ``--address`` or Ray's RAY_ADDRESS
    reach ``ray.init(address=...)`` with no local CPU count (intercepted: no Ray starts)."""
    ray = pytest.importorskip("ray")
    from baselines.agents.sweep import load_sweep
    from baselines.agents.sweep import run as sweep_run

    seen = {}

    def fake_init(**kwargs):
        seen.update(kwargs)
        raise _Stop

    monkeypatch.setattr(ray, "init", fake_init)
    monkeypatch.setattr(ray, "is_initialized", lambda: False)
    address = "ray://head.example:10001"
    if how == "RAY_ADDRESS":
        monkeypatch.setenv("RAY_ADDRESS", address)
        sweep = load_sweep(LOPO, out=str(tmp_path / "out"))
    else:
        monkeypatch.delenv("RAY_ADDRESS", raising=False)
        sweep = load_sweep(LOPO, out=str(tmp_path / "out"), address=address)
    with pytest.raises(_Stop):
        sweep_run(sweep)
    assert seen["address"] == address and "num_cpus" not in seen


def test_refit_keep_step_is_within_the_refits_timesteps(tmp_path, monkeypatch):
    """An on-policy agent ends on a whole rollout, so the inner agents' chosen step can lie
    past ``timesteps`` (30,208 of 30,000 in the shipped sweep, which the refit's preflight
    refused): the refit is asked to keep the first evaluation at or after ``timesteps``."""
    from baselines.agents.sweep import nested

    configs = []
    monkeypatch.setattr(nested, "_evaluations", lambda d: ([30000, 30208], [1.0, 0.9], 0))
    monkeypatch.setattr(nested, "choose_step", lambda *a: {"timesteps": 30208, "val_ratio": 0.9})
    cfg = {"algo": "ppo", "env_id": "MotionEnvs/OrientationCoefficients-v0", "overrides": {}}
    nested.nested_train(cfg, 0, tmp_path / "runs" / "c-s0", 3, 30000, 2, configs.append)
    assert configs[-1].keep_timesteps == 30000
    assert all(c.keep_timesteps is None for c in configs[:-1])  # the inner agents
