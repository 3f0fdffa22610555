"""baselines.sb3: SB3's VecEnv interface over the native Gymnasium vector environments."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

pytest.importorskip("stable_baselines3")

from baselines.sb3 import GymnasiumVecEnv, TqdmCallback
from motion_envs.envs.orientation_reach import N_STEPS

ENV_ID = "MotionEnvs/OrientationReach-v0"


def make(n: int = 3) -> GymnasiumVecEnv:
    venv = gym.make_vec(ENV_ID, num_envs=n, vectorization_mode="vector_entry_point")
    return GymnasiumVecEnv(venv)


def test_episode_end_resets_in_the_same_step_with_terminal_observation():
    env = make(3)
    env.seed(7)
    obs = env.reset()
    assert obs.shape == (3, *env.observation_space.shape)
    zeros = np.zeros((3, 3), dtype=np.float32)
    for k in range(N_STEPS):
        obs, reward, done, infos = env.step(zeros)
        assert reward.dtype == np.float32
        if k < N_STEPS - 1:
            assert not done.any() and all(i == {} for i in infos)
    assert done.all()
    for info in infos:
        assert info["terminal_observation"][12] == 1.0  # tau after the last step
        assert info["TimeLimit.truncated"] is False  # the episode terminated
        assert info["max_error"] >= 0.0
    assert np.all(obs[:, 12] == 0.0)  # already the next episodes' first observation
    obs, _, done, _ = env.step(zeros)  # and the next step is a real step of them
    assert not done.any() and np.allclose(obs[:, 12], 1 / (N_STEPS - 1))
    env.close()


def test_max_error_matches_single_environment():
    """The adapter passes on the environment's own per-trajectory criterion."""
    env = make(2)
    env.seed(3)
    env.reset()
    zeros = np.zeros((2, 3), dtype=np.float32)
    for _ in range(N_STEPS):
        _, _, _, infos = env.step(zeros)
    single = gym.make(ENV_ID)
    errors = []
    for l in range(single.unwrapped.task.n_trajectories):
        single.reset(options={"trajectory": l})
        for _ in range(N_STEPS):
            *_, info = single.step(np.zeros(3, np.float32))
        errors.append(info["max_error"])
    for info in infos:
        assert np.isclose(np.asarray(errors), info["max_error"], rtol=0, atol=1e-12).any()


def test_ppo_learns_a_few_steps_with_progress_bar(capsys):
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import VecMonitor

    env = VecMonitor(make(4))
    model = PPO("MlpPolicy", env, n_steps=64, batch_size=64, seed=0, device="cpu")
    model.learn(256, callback=TqdmCallback(256, "test"))
    assert model.num_timesteps >= 256
    assert "test" in capsys.readouterr().err
    action, _ = model.predict(env.reset(), deterministic=True)
    assert action.shape == (4, 3)


def test_rejects_same_step_autoreset():
    venv = gym.make_vec(
        ENV_ID,
        num_envs=2,
        vectorization_mode="sync",
        vector_kwargs={"autoreset_mode": gym.vector.AutoresetMode.SAME_STEP},
    )
    with pytest.raises(ValueError, match="NEXT_STEP"):
        GymnasiumVecEnv(venv)
