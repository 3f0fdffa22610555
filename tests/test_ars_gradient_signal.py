"""``experiments/ars_gradient_signal.py``: the paired finite differences it measures.

Checked against what the design implies: with a zero perturbation the two candidates of
a direction play the same policy on the same seed, so every difference is exactly 0 (it
would not be if the candidates were played on different seeds); the zero policy's
episodes are the zero action's (the linear policy at W = 0 is the base controller); and
the normaliser is the observations' mean and std, checked by numpy on the same episode.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from _helpers import load_experiment

import motion_envs  # noqa: F401


def _script() -> Any:
    return load_experiment("ars_gradient_signal")


def test_zero_perturbation_gives_zero_differences() -> None:
    mod = _script()
    res = mod.run("drift", directions=3, stds=[0.0], norm_episodes=1, seed=0)
    m = res["stds"]["0.0"]
    assert np.all(np.asarray(m["d"]) == 0.0)
    catches = np.asarray(m["catches"])
    assert np.array_equal(catches[..., 0], catches[..., 1])
    assert m["fraction_d_nonzero"] == 0.0


def test_zero_policy_is_the_zero_action_and_normaliser_is_numpy_moments() -> None:
    mod = _script()
    env_id, kwargs = mod.BLOCKS["drift"]
    env = gym.make(env_id, **kwargs)
    try:
        mu, sigma = mod.normaliser(env, range(5, 6))
        rows, rewards = [], []
        obs, _ = env.reset(seed=5)
        rows.append(obs)
        done = False
        while not done:
            obs, r, term, trunc, info = env.step(np.zeros(env.action_space.shape, np.float32))
            rows.append(obs)
            rewards.append(r)
            done = term or trunc
        data = np.asarray(rows, dtype=np.float64)
        np.testing.assert_allclose(mu, data.mean(axis=0), rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(sigma, np.sqrt(data.var(axis=0) + 1e-8), rtol=1e-12)
        n_act, n_obs = int(np.prod(env.action_space.shape)), int(np.prod(mu.shape))
        ret, catches = mod.play(env, 5, np.zeros((n_act, n_obs)), (mu, sigma))
        assert ret == sum((float(r) for r in rewards), 0.0)
        assert catches == int(info["catches"])
    finally:
        env.close()
