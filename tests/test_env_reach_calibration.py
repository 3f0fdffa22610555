"""``calibration=K`` on the reaching step environments: the default observation unchanged,
the summary of K other reaches of the same person (never the episode's own, poisoned
rows), PositionReach refusing it, and the native vector environment equal to
SyncVectorEnv."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from _helpers import reset_poisoned
from gymnasium.vector import AutoresetMode

import motion_envs  # noqa: F401  (registers the ids)
from motion_envs.envs._calibration import orientation_calibration_features
from motion_envs.models.person_calibration import calibration_summaries

ORIENTATION = "MotionEnvs/OrientationReach-v1"


def _rollout(env: gym.Env, seed: int, steps: int = 120) -> list[np.ndarray]:
    rng = np.random.default_rng(seed)
    out = [env.reset(seed=seed)[0]]
    for _ in range(steps):
        obs, _, term, trunc, _ = env.step(rng.uniform(-1, 1, 3).astype(np.float32))
        out.append(obs)
        if term or trunc:
            out.append(env.reset()[0])
    return out


@pytest.mark.parametrize("env_id", ["MotionEnvs/OrientationReach-v0", ORIENTATION])
def test_calibration_zero_is_the_default_bit_for_bit(env_id):
    plain, zero = gym.make(env_id), gym.make(env_id, calibration=0)
    assert plain.observation_space == zero.observation_space
    for a, b in zip(_rollout(plain, 3), _rollout(zero, 3), strict=True):
        assert a.dtype == b.dtype and a.tobytes() == b.tobytes()


def test_summary_is_the_drawn_reaches_and_constant_over_the_episode():
    plain = gym.make(ORIENTATION)
    env = gym.make(ORIENTATION, calibration=4, split="test")
    base = gym.make(ORIENTATION, split="test").unwrapped
    u = env.unwrapped
    assert env.observation_space.shape == (plain.observation_space.shape[0] + 10,)
    features = orientation_calibration_features(u.task)
    subjects = np.asarray(u.task.subjects).astype(str)
    env.reset(seed=1)
    for l in (0, 9, u.task.n_trajectories - 1):
        obs, info = env.reset(options={"trajectory": l})
        drawn = info["calibration_trajectories"]
        assert drawn.shape == (4,) and l not in drawn
        assert np.all(subjects[drawn[drawn >= 0]] == subjects[l])
        summary = calibration_summaries(features, drawn, 4).astype(np.float32)
        np.testing.assert_array_equal(obs[-10:], summary)
        ref, _ = base.reset(options={"trajectory": l})
        np.testing.assert_array_equal(obs[:-10], ref)
        for _ in range(50):
            a = np.full(3, 0.3, np.float32)
            obs, *_ = env.step(a)
            ref, *_ = base.step(a)
            np.testing.assert_array_equal(obs[:-10], ref)
            np.testing.assert_array_equal(obs[-10:], summary)
            assert env.observation_space.contains(obs)


def test_poisoned_rows_never_reach_the_observation():
    """The episode's own features and every other person's are NaN: the observation stays
    finite and the summary is the drawn reaches' mean."""
    env = gym.make(ORIENTATION, calibration=5).unwrapped
    clean = env._calibration.features.copy()
    subjects = np.asarray(env.task.subjects).astype(str)
    env.reset(seed=0)
    for l in np.random.default_rng(0).integers(env.task.n_trajectories, size=40).tolist():
        obs, info = reset_poisoned(env, clean, subjects, l)
        drawn = info["calibration_trajectories"]
        assert np.all(np.isfinite(obs)) and l not in drawn
        np.testing.assert_allclose(obs[-10:-1], np.clip(clean[drawn].mean(0), -3, 3), rtol=1e-6)
        obs, *_ = env.step(np.zeros(3, np.float32))
        assert np.all(np.isfinite(obs))


@pytest.mark.parametrize("env_id", ["MotionEnvs/PositionReach-v0", "MotionEnvs/PositionReach-v1"])
def test_position_has_no_persons(env_id):
    with pytest.raises(ValueError, match="calibration needs a dataset with persons"):
        gym.make(env_id, calibration=2)
    with pytest.raises(ValueError, match="calibration"):
        gym.make(env_id, calibration=-1)
    gym.make(env_id, calibration=0).reset(seed=0)


def _pair(num_envs, mode, backend="auto", steps=17):
    from test_env_vector_modes import make_pair

    kwargs = {"calibration": 4, "nominal": "bezier-null"}
    return make_pair(ORIENTATION, kwargs, num_envs, mode, backend, max_episode_steps=steps)


@pytest.mark.parametrize("mode", [AutoresetMode.NEXT_STEP, AutoresetMode.SAME_STEP])
@pytest.mark.parametrize("num_envs", [3, 9])
def test_vector_env_bit_identical_to_sync(mode, num_envs):
    from test_env_vector_modes import assert_same_infos, step_against_sync

    native, sync = _pair(num_envs, mode)
    assert native.unwrapped.backend == "numpy"
    step_against_sync(native, sync, 80)
    obs_n, info_n = native.reset(options={"trajectory": 5})
    obs_s, info_s = sync.reset(options={"trajectory": 5})
    np.testing.assert_array_equal(obs_n, obs_s)
    assert_same_infos(info_n, info_s)


def test_vector_env_disabled_mode_and_numba_refused():
    from test_env_vector_modes import assert_same_step

    native, sync = _pair(4, AutoresetMode.DISABLED, steps=13)
    np.testing.assert_array_equal(native.reset(seed=7)[0], sync.reset(seed=7)[0])
    for a in np.random.default_rng(3).uniform(-1, 1, (40, 4, 3)).astype(np.float32):
        out_n, out_s = native.step(a), sync.step(a)
        assert_same_step(out_n, out_s)
        done = out_s[2] | out_s[3]
        if done.any():
            obs_n, _ = native.reset(options={"reset_mask": done})
            obs_s, _ = sync.reset(options={"reset_mask": done.copy()})
            np.testing.assert_array_equal(obs_n, obs_s)
    with pytest.raises(ValueError, match="backend"):
        gym.make_vec(ORIENTATION, num_envs=2, backend="numba", calibration=3)
