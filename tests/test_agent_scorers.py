"""The agents' scorer registry (one scorer per environment family, looked up by id) and
the module-level SB3 callbacks ``motion-bench train`` composes."""

from __future__ import annotations

import itertools

import gymnasium as gym
import numpy as np
import pytest

pytest.importorskip("stable_baselines3")

import motion_envs  # noqa: F401  (registers the ids)
from baselines.agents.callbacks import (
    EvaluationHookCallback,
    SaveBestCallback,
    ValidationCallback,
)
from baselines.agents.cascade_score import cascade_agent_episodes
from baselines.agents.evaluate import split_criterion
from baselines.agents.juggling_score import juggling_episodes
from baselines.agents.reaching_score import episode_max_errors
from baselines.agents.scorers import (
    SCORERS,
    Scorer,
    check_validation_split,
    env_family,
    register_scorer,
    scorer_for,
)
from baselines.options import ConfigError
from motion_envs.datasets.juggling import SPLIT_SEEDS

MOTION_IDS = sorted(i for i in gym.registry if i.startswith("MotionEnvs/"))


def test_env_family_drops_the_version_only():
    assert env_family("MotionEnvs/Juggling-v0") == "MotionEnvs/Juggling"
    assert env_family("MotionEnvs/OrientationReach-v12") == "MotionEnvs/OrientationReach"
    assert env_family("MotionEnvs/Odd-v1-name") == "MotionEnvs/Odd-v1-name"


@pytest.mark.parametrize("env_id", MOTION_IDS)
def test_every_registered_id_has_its_familys_scorer(env_id):
    scorer = scorer_for(env_id)
    if "Cascade" in env_id:
        assert scorer.episodes is cascade_agent_episodes
        assert scorer.first_val_seed == SPLIT_SEEDS["val"]
    elif "Juggling" in env_id:
        assert scorer.episodes is juggling_episodes
        assert scorer.first_val_seed == SPLIT_SEEDS["val"]
    else:
        assert scorer.episodes is episode_max_errors
        assert scorer.first_val_seed is None


def test_unknown_family_and_second_registration_are_refused():
    with pytest.raises(ValueError, match="no agent scorer for CartPole-v1"):
        scorer_for("CartPole-v1")
    existing = SCORERS["MotionEnvs/Juggling"]
    with pytest.raises(ValueError, match="already registered"):
        register_scorer(existing)
    assert SCORERS["MotionEnvs/Juggling"] is existing


def test_split_criterion_is_the_familys_episodes_criterion():
    env_id = "MotionEnvs/OrientationReach-v1"
    kwargs = {"val_fraction": 0.2}
    direct = episode_max_errors(None, env_id, kwargs, "val", 3).criterion
    assert split_criterion(None, env_id, kwargs, "val", 3) == direct


def test_validation_split_checks_follow_the_family():
    with pytest.raises(ConfigError, match="validation seeds"):
        check_validation_split("MotionEnvs/Juggling-v0", {}, SPLIT_SEEDS["val"] - 1, 2)
    check_validation_split("MotionEnvs/Juggling-v0", {}, SPLIT_SEEDS["val"] - 2, 2)
    with pytest.raises(ConfigError, match="validation seeds"):
        check_validation_split("MotionEnvs/Cascade-v0", {}, SPLIT_SEEDS["val"] - 3, 4)
    check_validation_split("MotionEnvs/Cascade-v0", {}, SPLIT_SEEDS["val"] - 4, 4)
    with pytest.raises(ValueError, match="val_fraction must be > 0"):
        check_validation_split("MotionEnvs/OrientationReach-v1", {}, 0, 2)
    check_validation_split("MotionEnvs/OrientationReach-v1", {"val_fraction": 0.2}, 0, 2)


def test_a_registered_family_is_used(monkeypatch):
    calls = []

    class Episodes:
        criterion = 0.25

    def episodes(policy, env_id, env_kwargs, split, n=None):
        calls.append((env_id, split, n))
        return Episodes()

    scorer = Scorer("Test/Thing", episodes, lambda loaded, split, n: {})
    monkeypatch.setitem(SCORERS, "Test/Thing", scorer)
    assert split_criterion(None, "Test/Thing-v3", {}, "val", 4) == 0.25
    assert calls == [("Test/Thing-v3", "val", 4)]


class CountingSave(SaveBestCallback):
    def __init__(self, run_dir) -> None:
        super().__init__(run_dir)
        self.saved_at: list[int] = []

    def _on_step(self) -> bool:
        self.saved_at.append(self.num_timesteps)
        return super()._on_step()


def test_callbacks_compose_as_sb3s_eval_callback(tmp_path):
    """A new best triggers the save (strict improvements only), every evaluation the
    hook; start, every eval_freq steps and the end are evaluated."""
    from stable_baselines3 import PPO

    scripted = iter([3.0, 2.0, 2.0, 5.0, 1.0, 1.5, 0.5, 4.0, 4.0, 4.0])
    seen_policies = []

    def criterion(policy):
        seen_policies.append(policy(np.zeros((2, 4), dtype=np.float32)).shape)
        return next(scripted)

    reports: list[dict] = []
    save = CountingSave(tmp_path)
    validation = ValidationCallback(
        criterion,
        eval_freq=64,
        callback_on_new_best=save,
        callback_after_eval=EvaluationHookCallback(reports.append, tmp_path),
    )
    model = PPO("MlpPolicy", "CartPole-v1", n_steps=32, batch_size=32, n_epochs=1, seed=0)
    model.learn(total_timesteps=200, callback=validation)
    crit = [e["val_criterion"] for e in validation.evaluations]
    steps = [int(e["timesteps"]) for e in validation.evaluations]
    assert steps[0] == 0 and steps[-1] == model.num_timesteps
    assert all(b - a >= 64 for a, b in itertools.pairwise(steps[:-1]))
    improved = [
        s for i, (s, c) in enumerate(zip(steps, crit, strict=True)) if c < min([*crit[:i], np.inf])
    ]
    assert save.saved_at == improved
    assert validation.best == min(crit)
    assert validation.best_timesteps == improved[-1]
    assert (tmp_path / "agent.zip").is_file()
    assert [r["val_criterion"] for r in reports] == crit
    assert [r["is_best"] for r in reports] == [s in improved for s in steps]
    assert {r["run_dir"] for r in reports} == {str(tmp_path)}
    assert seen_policies and all(shape == (2,) for shape in seen_policies)
