"""Agent hyper-parameter files: parsing, merging and validation errors (file, line, key)."""

from __future__ import annotations

from pathlib import Path

import pytest

from baselines.agents.checks import check_env_kwargs
from baselines.agents.config import (
    ALGOS,
    load_hyperparams,
    make_schedule,
    parse_env_kwargs,
    resolve_hyperparams,
    validate_hyperparams,
)

ORIENTATION = "MotionEnvs/OrientationReach-v1"


def write(tmp_path, text: str):
    path = tmp_path / "agent.yaml"
    path.write_text(text)
    return path


@pytest.mark.parametrize("algo", ALGOS)
@pytest.mark.parametrize(
    "env_id",
    [
        "MotionEnvs/OrientationReach-v0",
        "MotionEnvs/OrientationReach-v1",
        "MotionEnvs/PositionReach-v0",
        "MotionEnvs/PositionReach-v1",
    ],
)
def test_committed_configs_resolve_for_every_env(algo, env_id):
    hp = resolve_hyperparams(algo, env_id)
    assert hp["env_kwargs"]["val_fraction"] > 0  # checkpoints chosen on validation
    assert hp["action_head_scale"] == 0.0  # the policy starts at the nominal
    if "Position" in env_id:
        assert hp["env_kwargs"]["nominal"] == "null"  # the string, not YAML's null


@pytest.mark.parametrize("algo", ALGOS)
def test_committed_juggling_config_builds_the_env(algo):
    """Juggling-v0 has its own block: keywords its constructor takes (no val_fraction:
    its validation split is a seed range), the issue's 5 % release noise."""
    import gymnasium as gym

    import motion_envs  # noqa: F401

    hp = resolve_hyperparams(algo, "MotionEnvs/Juggling-v0")
    assert "val_fraction" not in hp["env_kwargs"] and hp["env_kwargs"]["noise"] == 0.05
    assert hp["action_head_scale"] == 0.0
    check_env_kwargs("MotionEnvs/Juggling-v0", hp["env_kwargs"])
    gym.make("MotionEnvs/Juggling-v0", **hp["env_kwargs"]).close()


@pytest.mark.parametrize(
    "path", sorted(Path(__file__).parents[1].glob("configs/sweeps/*.yaml")), ids=lambda p: p.name
)
def test_committed_sweep_files_load(path, tmp_path):
    from baselines.agents.sweep import load_sweep

    sweep = load_sweep(path, out=str(tmp_path))
    assert sweep.configurations and sweep.seeds
    for cfg in sweep.configurations:
        hp = resolve_hyperparams(cfg["algo"], cfg["env_id"], overrides=cfg["overrides"])
        check_env_kwargs(cfg["env_id"], hp["env_kwargs"])


def test_env_block_overrides_default_key_by_key(tmp_path):
    path = write(
        tmp_path,
        """
default:
  n_envs: 4
  gamma: 0.9
  env_kwargs: {val_fraction: 0.2, nominal: slerp}
  policy_kwargs: {net_arch: [32], log_std_init: -1.0}
MotionEnvs/OrientationReach-v1:
  gamma: 0.5
  env_kwargs: {nominal: bezier-null}
""",
    )
    hp = load_hyperparams(path, "ppo", ORIENTATION)
    assert hp["n_envs"] == 4 and hp["gamma"] == 0.5
    assert hp["env_kwargs"] == {"val_fraction": 0.2, "nominal": "bezier-null"}
    assert hp["policy_kwargs"] == {"net_arch": [32], "log_std_init": -1.0}
    other = load_hyperparams(path, "ppo", "MotionEnvs/PositionReach-v0")
    assert other["gamma"] == 0.9 and other["env_kwargs"]["nominal"] == "slerp"


def test_yaml_12_floats_and_schedules(tmp_path):
    path = write(tmp_path, "default:\n  learning_rate: {kind: linear, start: 1e-3, end: 1e-4}\n")
    hp = load_hyperparams(path, "ppo", ORIENTATION)
    f = make_schedule(hp["learning_rate"])
    assert f(1.0) == pytest.approx(1e-3) and f(0.0) == pytest.approx(1e-4)
    assert f(0.5) == pytest.approx(0.5 * (1e-3 + 1e-4))
    assert make_schedule({"kind": "constant", "start": 0.2}) == 0.2
    assert make_schedule(3e-4) == 3e-4


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("default:\n  n_envs: 4\n  learning_rat: 0.1\n", r"line 3: .*learning_rat.*unknown key"),
        ("default:\n  n_envs: four\n", r"line 2: .*n_envs.*integer"),
        ("default:\n  n_envs: 2.5\n", r"line 2: .*n_envs.*integer"),
        ("default:\n  gamma: true\n", r"gamma.*finite number"),
        ("default:\n  learning_rate: lin_3e-4\n", r"looks like Python code"),
        ("default:\n  policy_kwargs: dict(net_arch=[64])\n", r"looks like Python code"),
        ("default:\n  policy_kwargs: {activation: nn.ReLU}\n", r"looks like Python code"),
        ("default:\n  policy_kwargs: {activation: sigmoid}\n", r"activation.*one of"),
        ("default:\n  policy_kwargs: {net_arch: [64, -1]}\n", r"net_arch.*positive"),
        ("default:\n  learning_rate: {kind: cosine, start: 0.1}\n", r"kind.*one of"),
        ("default:\n  learning_rate: {kind: linear}\n", r"needs 'start'"),
        ("default:\n  env_kwargs: {split: test}\n", r"split.*set by the command"),
        ("default:\n  env_kwargs: {nominal: __import__('os')}\n", r"Python code"),
        ("default:\n  n_steps: 64\n", r"line 2: .*n_steps.*unknown key for sac"),
        ("Orientation:\n  n_envs: 4\n", r"line 1: .*neither 'default' nor an environment id"),
        ("default: [1, 2]\n", r"mapping"),
        ("default:\n  n_envs: [\n", r"not valid YAML"),
    ],
)
def test_bad_files_raise_one_line_errors_naming_file_and_line(tmp_path, text, match):
    path = write(tmp_path, text)
    algo = "sac" if "n_steps" in text else "ppo"
    with pytest.raises(ValueError, match=match) as info:
        load_hyperparams(path, algo, ORIENTATION)
    assert str(path) in str(info.value) and "\n" not in str(info.value)


def test_td3_rejects_log_std_init_and_missing_file(tmp_path):
    with pytest.raises(ValueError, match=r"log_std_init.*unknown key"):
        validate_hyperparams("td3", {"policy_kwargs": {"log_std_init": -2.0}})
    with pytest.raises(FileNotFoundError, match="does not exist"):
        load_hyperparams(tmp_path / "nope.yaml", "ppo", ORIENTATION)
    with pytest.raises(ValueError, match="algo must be one of"):
        validate_hyperparams("a2c", {})


def test_env_kwargs_from_the_command_line():
    kw = parse_env_kwargs(["nominal=null", "shapes=[Angle, GShape]", "val_fraction=1e-1"])
    assert kw == {"nominal": "null", "shapes": ["Angle", "GShape"], "val_fraction": 0.1}
    with pytest.raises(ValueError, match="KEY=VALUE"):
        parse_env_kwargs(["nominal"])
    with pytest.raises(ValueError, match="set by the command"):
        parse_env_kwargs(["split=test"])


def test_ppo_gsde_keys_reach_sb3_and_start_at_the_nominal(tmp_path):
    """``use_sde`` / ``sde_sample_freq`` are checked, passed to SB3's PPO, and the policy
    still starts at the zero residual (its deterministic action is 0 everywhere)."""
    import numpy as np
    from stable_baselines3.common.env_util import make_vec_env

    from baselines.agents.policies import build_model

    path = write(
        tmp_path,
        "default:\n  n_envs: 1\n  n_steps: 64\n  batch_size: 64\n"
        "  use_sde: true\n  sde_sample_freq: 4\n",
    )
    hp = load_hyperparams(path, "ppo", ORIENTATION)
    assert hp["use_sde"] is True and hp["sde_sample_freq"] == 4
    env = make_vec_env("Pendulum-v1", n_envs=1, seed=0)
    model = build_model("ppo", hp, env, seed=0)
    assert model.use_sde and model.sde_sample_freq == 4
    obs = np.random.default_rng(0).normal(size=(16, 3)).astype(np.float32)
    assert np.all(model.predict(obs, deterministic=True)[0] == 0.0)
    bad = write(tmp_path, "default:\n  use_sde: 1\n")
    with pytest.raises(ValueError, match="use_sde"):
        load_hyperparams(bad, "ppo", ORIENTATION)
