"""motion-bench train / agent: tiny runs of every algorithm on every environment.

Each run starts at the nominal (its first validation equals the zero action's), saves a
run folder that reloads without unpickling to the same actions as SB3's own loader, and
the validation criterion the callback recorded equals ``motion-bench agent --split val``.
Modified, mismatched or foreign run folders raise one-line errors.
"""

from __future__ import annotations

import dataclasses
import json
import shutil

import numpy as np
import pytest

pytest.importorskip("stable_baselines3")

from baselines.agents.evaluate import AgentConfig, split_criterion
from baselines.agents.evaluate import run as evaluate_run
from baselines.agents.rundir import file_sha256, load_run, manifest_sha256
from baselines.agents.train import TrainConfig
from baselines.agents.train import run as train_run
from baselines.cli import main

pytestmark = pytest.mark.filterwarnings("ignore:.*out of date.*:DeprecationWarning")

SHAPES = ["Angle", "GShape"]
ENVS = {
    "MotionEnvs/OrientationReach-v0": {},
    "MotionEnvs/OrientationReach-v1": {},
    "MotionEnvs/PositionReach-v0": {"shapes": SHAPES},
    "MotionEnvs/PositionReach-v1": {"shapes": SHAPES},
    # no native vector env (SB3's DummyVecEnv); validated on its own seed range
    "MotionEnvs/Juggling-v0": {"max_cycles": 1},
}


def tiny_config(algo: str, env_id: str, out, seed: int = 0, **kw) -> TrainConfig:
    overrides: dict = {"eval_freq": 1000}
    if env_id == "MotionEnvs/Juggling-v0":
        overrides["eval_episodes"] = 3
    if algo != "ppo":
        overrides.update(learning_starts=200, buffer_size=5000, batch_size=64)
    else:
        overrides.update(n_steps=100, batch_size=100, n_epochs=2)
    return TrainConfig(
        algo=algo,
        env_id=env_id,
        out=str(out),
        seed=seed,
        timesteps=2000,
        n_envs=2,
        env_kwargs=ENVS[env_id],
        overrides=overrides,
        progress=False,
        tensorboard=kw.get("tensorboard", False),
    )


@pytest.fixture(scope="module")
def ppo_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("runs") / "ppo"
    result = train_run(tiny_config("ppo", "MotionEnvs/OrientationReach-v1", out, tensorboard=True))
    return out, result


@pytest.mark.slow
@pytest.mark.parametrize("env_id", list(ENVS))
@pytest.mark.parametrize("algo", ["ppo", "sac", "td3"])
def test_2000_steps_train_save_reload_same_actions(tmp_path, algo, env_id):
    from stable_baselines3 import PPO, SAC, TD3

    out = tmp_path / "run"
    result = train_run(tiny_config(algo, env_id, out))
    assert result.timesteps >= 2000
    for name in ("agent.zip", "final_agent.zip", "config.json", "run.json", "normalization.npz"):
        assert (out / name).is_file()
    # the policy starts at the nominal: the first validation is the zero action's
    assert result.evaluations[0]["timesteps"] == 0
    assert result.evaluations[0]["val_criterion"] == result.val_nominal_criterion
    assert result.best_val_criterion == min(e["val_criterion"] for e in result.evaluations)
    assert result.evaluations[-1]["timesteps"] == result.timesteps
    # reload without unpickling == SB3's own loader (which unpickles), same actions
    loaded = load_run(out, "final")
    sb3 = {"ppo": PPO, "sac": SAC, "td3": TD3}[algo].load(out / "final_agent.zip", device="cpu")
    obs = np.random.default_rng(0).normal(size=(64, *sb3.observation_space.shape))
    mine = loaded.model.predict(obs.astype(np.float32), deterministic=True)[0]
    theirs = sb3.predict(obs.astype(np.float32), deterministic=True)[0]
    np.testing.assert_array_equal(mine, theirs)
    # the best checkpoint evaluates to the criterion the callback recorded
    best = load_run(out)
    episodes = best.config["hyperparams"].get("eval_episodes")
    crit = split_criterion(best.predict, env_id, best.env_kwargs, "val", episodes)
    assert crit == result.best_val_criterion


@pytest.mark.slow
def test_callback_criterion_equals_motion_bench_agent(ppo_run, tmp_path):
    out, result = ppo_run
    assert main(["agent", str(out), "--split", "val", "--out", str(tmp_path)]) == 0
    doc = json.loads((tmp_path / "results.json").read_text())
    assert doc["criterion"] == result.best_val_criterion
    assert doc["nominal_criterion"] == result.val_nominal_criterion
    assert (tmp_path / "results.csv").is_file() and (tmp_path / "agent_vs_nominal.png").is_file()
    header = (tmp_path / "results.csv").read_text().splitlines()[0].split(",")
    assert header[-1] == "learned_max_error"
    assert doc["learned_ratio"] == doc["criterion"] / doc["learned_criterion"]
    assert any((out / "tb").rglob("events.out.tfevents.*"))


@pytest.mark.slow
def test_agent_on_test_split_scores_the_nominal_like_the_env(ppo_run):
    import gymnasium as gym

    out, _ = ppo_run
    res = evaluate_run(AgentConfig(str(out), "test"))
    kwargs = {k: v for k, v in res["env_kwargs"].items() if k != "val_fraction"}
    task = gym.make(res["env_id"], split="test", **kwargs).unwrapped.task
    assert res["nominal_criterion"] == pytest.approx(task.criterion, abs=1e-12)
    assert res["n_episodes"] == task.n_trajectories
    assert res["ratio"] == res["criterion"] / res["nominal_criterion"]
    few = evaluate_run(AgentConfig(str(out), "test", episodes=5))
    assert few["n_episodes"] == 5
    assert few["episodes"]["agent_max_error"] == res["episodes"]["agent_max_error"][:5]
    # the learned regressor on the same episodes, the same criterion
    learned = res["episodes"]["learned_max_error"]
    assert len(learned) == res["n_episodes"]
    assert res["learned_criterion"] == float(np.median(learned))
    assert few["episodes"]["learned_max_error"] == learned[:5]


def test_agent_without_scikit_learn_skips_the_learned_row(ppo_run, monkeypatch, capsys):
    import baselines.learned

    out, _ = ppo_run
    reason = "scikit-learn is not installed (pip install 'motion-envs[learned]')"
    monkeypatch.setattr(baselines.learned, "sklearn_missing_reason", lambda: reason)
    res = evaluate_run(AgentConfig(str(out), "val", episodes=3))
    assert res["learned_criterion"] is None and res["learned_skipped"] == reason
    assert "learned_max_error" not in res["episodes"]


def _copy(ppo_run, tmp_path):
    src, _ = ppo_run
    dst = tmp_path / "copy"
    shutil.copytree(src, dst)
    return dst


def _edit_json(path, edit, fix_hash_in=None):
    doc = json.loads(path.read_text())
    edit(doc)
    path.write_text(json.dumps(doc))
    if fix_hash_in is not None:
        manifest = json.loads(fix_hash_in.read_text())
        manifest["files"][path.name] = file_sha256(path)
        manifest["manifest_sha256"] = manifest_sha256(manifest)  # run.json's own, too
        fix_hash_in.write_text(json.dumps(manifest))


def test_modified_agent_zip_is_rejected(ppo_run, tmp_path):
    run = _copy(ppo_run, tmp_path)
    data = bytearray((run / "agent.zip").read_bytes())
    data[len(data) // 2] ^= 0xFF
    (run / "agent.zip").write_bytes(bytes(data))
    with pytest.raises(ValueError, match=r"agent.zip does not match its SHA-256"):
        load_run(run)


def test_missing_and_foreign_files_are_rejected(ppo_run, tmp_path):
    run = _copy(ppo_run, tmp_path)
    (run / "normalization.npz").unlink()
    with pytest.raises(ValueError, match=r"normalization.npz is missing"):
        load_run(run)
    with pytest.raises(ValueError, match=r"run.json is missing"):
        load_run(tmp_path)
    with pytest.raises(FileNotFoundError, match="does not exist"):
        load_run(tmp_path / "nowhere")


def test_other_version_and_mismatched_config_are_rejected(ppo_run, tmp_path):
    run = _copy(ppo_run, tmp_path)
    _edit_json(run / "run.json", lambda d: d.update(motion_envs_version="9.9.9"))
    with pytest.raises(ValueError, match=r"written by motion-envs 9.9.9"):
        load_run(run)
    run = _copy(ppo_run, tmp_path / "b")

    def wider(d):
        d["hyperparams"]["policy_kwargs"]["net_arch"] = {"pi": [8], "vf": [8]}

    _edit_json(run / "config.json", wider, fix_hash_in=run / "run.json")
    with pytest.raises(ValueError, match=r"does not fit config.json's network"):
        load_run(run)
    run = _copy(ppo_run, tmp_path / "c")
    _edit_json(run / "config.json", lambda d: d.update(seed=7), fix_hash_in=run / "run.json")
    with pytest.raises(ValueError, match=r"disagree on 'seed'"):
        load_run(run)


def test_train_refuses_to_overwrite_and_needs_a_validation_split(ppo_run, tmp_path):
    out, _ = ppo_run
    with pytest.raises(ValueError, match="not an empty folder"):
        train_run(tiny_config("ppo", "MotionEnvs/OrientationReach-v1", out))
    cfg = tiny_config("ppo", "MotionEnvs/OrientationReach-v1", tmp_path / "x")
    cfg = TrainConfig(**{**cfg.__dict__, "env_kwargs": {"val_fraction": 0.0}})
    with pytest.raises(ValueError, match="val_fraction must be > 0"):
        train_run(cfg)
    assert main(["train", "--algo", "ppo", "--env", "Nope-v0", "--out", str(tmp_path)]) == 2


@pytest.mark.parametrize("env_id", ["MotionEnvs/PositionReach-v1", "MotionEnvs/Juggling-v0"])
def test_training_never_touches_the_test_split(tmp_path, monkeypatch, env_id):
    """Out of sample: the environments train builds and the splits its callback scores
    are "train" and "val" only (the juggling scorer's split picks its seed range)."""
    import gymnasium as gym

    from baselines.agents.scorers import SCORERS

    seen: list[str] = []
    for family, scorer in list(SCORERS.items()):

        def spy(policy, env, kwargs, split, episodes=None, _original=scorer.episodes):
            seen.append(split)
            return _original(policy, env, kwargs, split, episodes)

        monkeypatch.setitem(SCORERS, family, dataclasses.replace(scorer, episodes=spy))
    for name in ("make", "make_vec"):
        original = getattr(gym, name)

        def spy_make(*args, _original=original, **kwargs):
            seen.append(kwargs.get("split", "(none)"))
            return _original(*args, **kwargs)

        monkeypatch.setattr(gym, name, spy_make)
    config = tiny_config("ppo", env_id, tmp_path / "run")
    train_run(dataclasses.replace(config, timesteps=400))
    assert "val" in seen and "test" not in seen, seen
    if env_id != "MotionEnvs/Juggling-v0":
        assert "train" in seen
