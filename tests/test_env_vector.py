"""Native vector environments: bit-identical to N single environments; Sync/Async wrappers."""

from __future__ import annotations

import pickle

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode

import motion_envs  # noqa: F401  (registers the ids)

ORIENTATION = "MotionEnvs/OrientationReach-v0"
POSITION = "MotionEnvs/PositionReach-v0"
SHAPES = ["Angle", "CShape", "GShape"]
VECTOR_CASES = [
    (ORIENTATION, {"nominal": "bezier-task"}),
    (ORIENTATION, {"split": "test", "reward_weights": {"geodesic": 0.5, "action": 0.1}}),
    (POSITION, {"shapes": SHAPES}),
    (POSITION, {"shapes": SHAPES, "split": "test", "reward_weights": {"action": 0.3}}),
    ("MotionEnvs/OrientationReach-v1", {"split": "val", "val_fraction": 0.2}),
    ("MotionEnvs/PositionReach-v1", {"shapes": SHAPES, "split": "val", "val_fraction": 0.2}),
]


def _actions(env: gym.vector.VectorEnv, steps: int, seed: int = 0) -> np.ndarray:
    shape = (steps, env.num_envs, *env.single_action_space.shape)
    # a quarter of the entries out of bounds, to exercise the clipping
    return np.random.default_rng(seed).uniform(-1.5, 1.5, size=shape).astype(np.float32)


def _assert_same_step(native, reference) -> None:
    for x, y in zip(native[:4], reference[:4], strict=True):
        np.testing.assert_array_equal(x, y)
    info_n, info_r = native[4], reference[4]
    for key in ("max_error", "error", "geodesic_error", "reward_residual", "reward_action"):
        if "_" + key in info_r:
            mask = info_r["_" + key]
            np.testing.assert_array_equal(info_n["_" + key], mask)
            np.testing.assert_array_equal(info_n[key][mask], info_r[key][mask])


@pytest.mark.parametrize(("env_id", "kwargs"), VECTOR_CASES)
@pytest.mark.parametrize(("num_envs", "max_episode_steps"), [(3, None), (9, None), (9, 17)])
def test_native_vector_env_is_bit_identical_to_sync(env_id, kwargs, num_envs, max_episode_steps):
    """3 environments take the scalar-kernel path of the orientation env, 9 the batch one."""
    from test_env_vector_modes import make_pair, step_against_sync

    mode = AutoresetMode.NEXT_STEP
    native, sync = make_pair(env_id, kwargs, num_envs, mode, max_episode_steps=max_episode_steps)
    assert type(native).__name__.endswith("VectorEnv")
    step_against_sync(native, sync, 160)
    native.close()
    sync.close()


@pytest.mark.parametrize(("env_id", "kwargs"), [(ORIENTATION, {}), (POSITION, {"shapes": SHAPES})])
def test_native_vector_env_equals_single_envs_stepped_by_hand(env_id, kwargs):
    n = 3
    native = gym.make_vec(env_id, num_envs=n, vectorization_mode="vector_entry_point", **kwargs)
    singles = [gym.make(env_id, **kwargs) for _ in range(n)]
    obs, _ = native.reset(seed=9)
    for i, env in enumerate(singles):
        np.testing.assert_array_equal(obs[i], env.reset(seed=9 + i)[0])
    pending = [False] * n
    for a in _actions(native, 120, seed=1):
        obs, rew, term, trunc, _ = native.step(a)
        for i, env in enumerate(singles):
            if pending[i]:
                o, _ = env.reset()
                r, te, tr = 0.0, False, False
            else:
                o, r, te, tr, _ = env.step(a[i])
            np.testing.assert_array_equal(obs[i], o)
            assert rew[i] == r and term[i] == te and trunc[i] == tr
            pending[i] = te or tr


@pytest.mark.parametrize(
    ("env_id", "kwargs"),
    [(ORIENTATION, {"nominal": "bezier-null"}), (POSITION, {"shapes": SHAPES})],
)
def test_async_vector_env_with_spawn_matches_sync(env_id, kwargs):
    sync = gym.make_vec(env_id, num_envs=2, vectorization_mode="sync", **kwargs)
    spawn = gym.make_vec(
        env_id,
        num_envs=2,
        vectorization_mode="async",
        vector_kwargs={"context": "spawn"},
        **kwargs,
    )
    try:
        np.testing.assert_array_equal(sync.reset(seed=1)[0], spawn.reset(seed=1)[0])
        for a in _actions(sync, 60):
            _assert_same_step(spawn.step(a), sync.step(a))
    finally:
        spawn.close()
        sync.close()


def test_vector_env_rejects_bad_actions_and_stays_usable():
    env = gym.make_vec(ORIENTATION, num_envs=4, vectorization_mode="vector_entry_point")
    ref = gym.make_vec(ORIENTATION, num_envs=4, vectorization_mode="vector_entry_point")
    env.reset(seed=0)
    ref.reset(seed=0)
    with pytest.raises(ValueError, match="shape"):
        env.step(np.zeros((3, 3), np.float32))
    with pytest.raises(ValueError, match="shape"):
        env.step(np.zeros((4, 2), np.float32))
    bad = np.zeros((4, 3), np.float32)
    bad[2, 1] = np.nan
    with pytest.raises(ValueError, match="finite"):
        env.step(bad)
    bad[2, 1] = np.inf
    with pytest.raises(ValueError, match="finite"):
        env.step(bad)
    for a in _actions(env, 60):
        _assert_same_step(env.step(a), ref.step(a))
    env.close()
    env.close()


def test_vector_env_partial_reset_and_trajectory_option():
    env = gym.make_vec(ORIENTATION, num_envs=3, vectorization_mode="vector_entry_point")
    _, info = env.reset(seed=0, options={"trajectory": [0, 1, 2]})
    np.testing.assert_array_equal(info["trajectory_index"], [0, 1, 2])
    for _ in range(5):
        env.step(np.zeros((3, 3), np.float32))
    mask = np.array([False, True, False])
    obs2, info2 = env.reset(options={"reset_mask": mask, "trajectory": 7})
    np.testing.assert_array_equal(info2["_trajectory_index"], mask)
    assert info2["trajectory_index"][1] == 7
    assert obs2[1, 12] == 0.0 and obs2[0, 12] > 0.0
    with pytest.raises(ValueError, match="trajectory"):
        env.reset(options={"trajectory": 10**6})


def test_pickled_vector_env_reproduces_its_original():
    env = gym.make_vec(ORIENTATION, num_envs=4, vectorization_mode="vector_entry_point")
    env.reset(seed=3)
    acts = _actions(env, 100)
    for a in acts[:30]:
        env.step(a)
    clone = pickle.loads(pickle.dumps(env))
    for a in acts[30:]:
        _assert_same_step(clone.step(a), env.step(a))


@pytest.mark.parametrize("n", [1, 8])
@pytest.mark.parametrize(
    ("env_id", "kwargs"), [(ORIENTATION, {"residual_scale": 3.0}), (POSITION, {"shapes": SHAPES})]
)
def test_vector_observations_in_space(n, env_id, kwargs):
    env = gym.make_vec(env_id, num_envs=n, vectorization_mode="vector_entry_point", **kwargs)
    obs, _ = env.reset(seed=0)
    assert env.observation_space.contains(obs)
    for a in _actions(env, 200):
        obs, *_ = env.step(np.clip(a, -1, 1))
        assert env.observation_space.contains(obs)
