"""Spaces independent of the split: equal on every split and seed, models move between splits."""

from __future__ import annotations

import pathlib

import gymnasium as gym
import numpy as np
import pytest

import motion_envs  # noqa: F401  (registers the ids)

ORIENTATION = "MotionEnvs/OrientationReach-v0"
POSITION = "MotionEnvs/PositionReach-v0"
SHAPES = ["Angle", "CShape", "GShape"]
# every split each environment has, and split arguments that change what is in them
SPLITS = {ORIENTATION: ("train", "test"), POSITION: ("train", "test", "loo")}
BASE = {ORIENTATION: {}, POSITION: {"shapes": SHAPES}}
SPLIT_ARGS = [{}, {"split_seed": 3}, {"split_seed": 11, "test_fraction": 0.5}]


def _spaces(env: gym.Env) -> tuple[gym.Space, gym.Space]:
    return env.observation_space, env.action_space


@pytest.mark.parametrize("env_id", [ORIENTATION, POSITION])
def test_spaces_equal_on_every_split_and_seed(env_id):
    ref = gym.make(env_id, **BASE[env_id])
    for split in SPLITS[env_id]:
        for extra in SPLIT_ARGS:
            env = gym.make(env_id, split=split, **BASE[env_id], **extra)
            assert _spaces(env) == _spaces(ref), (split, extra)
            assert env.observation_space.shape == ref.observation_space.shape
            np.testing.assert_array_equal(env.observation_space.low, ref.observation_space.low)
            np.testing.assert_array_equal(env.observation_space.high, ref.observation_space.high)
    vec = {split: gym.make_vec(env_id, 3, split=split, **BASE[env_id]) for split in SPLITS[env_id]}
    assert len({repr(v.single_observation_space) for v in vec.values()}) == 1
    assert all(v.single_observation_space == ref.observation_space for v in vec.values())


@pytest.mark.parametrize("version", ["v0", "v1"])
@pytest.mark.parametrize("env_id", [ORIENTATION, POSITION])
def test_spaces_equal_with_and_without_a_validation_split(env_id, version):
    """Carving a validation split (val_fraction > 0) from the training data changes no
    space: 'val', 'train' and 'test' with val_fraction equal the spaces without it."""
    env_id = env_id.replace("-v0", f"-{version}")
    ref = gym.make(env_id, **BASE[env_id.replace(f"-{version}", "-v0")])
    base = BASE[env_id.replace(f"-{version}", "-v0")]
    for split in ("train", "val", "test"):
        for extra in ({"val_fraction": 0.2}, {"val_fraction": 0.5, "split_seed": 3}):
            env = gym.make(env_id, split=split, **base, **extra)
            assert _spaces(env) == _spaces(ref), (split, extra)
            np.testing.assert_array_equal(env.observation_space.low, ref.observation_space.low)
            np.testing.assert_array_equal(env.observation_space.high, ref.observation_space.high)


def test_position_start_and_goal_bounds_are_the_whole_datasets_extent():
    """Oracle: the per-coordinate extent of every demonstration of the chosen shapes,
    taken from the splits' own episodes (train and test together are the whole dataset)."""
    env = gym.make(POSITION, shapes=SHAPES).unwrapped
    humans = np.concatenate(
        [
            gym.make(POSITION, shapes=SHAPES, split=s).unwrapped.task.grids.human
            for s in SPLITS[POSITION]
        ]
    )
    D = 2
    space = env.observation_space
    for part in (slice(0, D), slice(D, 2 * D)):
        np.testing.assert_array_equal(space.low[part], humans.min(axis=(0, 1)).astype(np.float32))
        np.testing.assert_array_equal(space.high[part], humans.max(axis=(0, 1)).astype(np.float32))
    # current and nominal position: widened by the extent + residual_scale on each side
    lo, hi = humans.min(axis=(0, 1)), humans.max(axis=(0, 1))
    margin = (hi - lo) + 5.0
    for part in (slice(2 * D, 3 * D), slice(3 * D + 1, 4 * D + 1)):
        np.testing.assert_array_equal(space.low[part], (lo - margin).astype(np.float32))
        np.testing.assert_array_equal(space.high[part], (hi + margin).astype(np.float32))
    assert (space.low[3 * D], space.high[3 * D]) == (0.0, 1.0)


@pytest.mark.parametrize("env_id", [ORIENTATION, POSITION])
def test_observations_inside_the_space_on_every_split_over_full_rollouts(env_id):
    rng = np.random.default_rng(0)
    for split in SPLITS[env_id]:
        env = gym.make(env_id, split=split, **BASE[env_id], split_seed=11, test_fraction=0.5)
        space = env.observation_space
        for index in range(env.unwrapped.task.n_trajectories):
            obs, _ = env.reset(seed=index, options={"trajectory": index})
            assert space.contains(obs), (split, index)
            done = False
            while not done:
                # extreme and out-of-range actions too (clipped to the action space)
                a = rng.choice([-3.0, -1.0, 0.0, 1.0, 3.0], size=env.action_space.shape)
                obs, _, terminated, truncated, _ = env.step(a.astype(np.float32))
                assert space.contains(obs), (split, index)
                done = terminated or truncated


@pytest.mark.parametrize("env_id", [ORIENTATION, POSITION])
def test_sb3_model_trained_on_train_loads_and_runs_on_other_splits(env_id, tmp_path):
    sb3 = pytest.importorskip("stable_baselines3")
    train = gym.make(env_id, split="train", **BASE[env_id])
    model = sb3.PPO("MlpPolicy", train, n_steps=64, batch_size=32, n_epochs=1, seed=0)
    model.learn(64)
    model.save(tmp_path / "ppo")
    for split in SPLITS[env_id][1:]:
        env = gym.make(env_id, split=split, **BASE[env_id])
        loaded = sb3.PPO.load(tmp_path / "ppo", env=env)  # raised on a space mismatch before
        model.set_env(env)
        obs, _ = env.reset(seed=0)
        for _ in range(60):
            action, _ = loaded.predict(obs, deterministic=True)
            obs, _, terminated, truncated, _ = env.step(action)
            assert env.observation_space.contains(obs)
            if terminated or truncated:
                obs, _ = env.reset()


@pytest.mark.parametrize("env_id", [ORIENTATION, POSITION])
def test_spec_json_round_trip_with_a_path_argument(env_id, tmp_path):
    from gymnasium.envs.registration import EnvSpec

    if env_id == ORIENTATION:
        from motion_envs.datasets import load_orientation_dataset

        path = load_orientation_dataset("vr-kitchen").to_csv(tmp_path / "mine.csv")
        kwargs = {"split": "test"}
    else:
        from motion_envs.datasets import load_position_dataset

        path = tmp_path / "mine.csv"
        load_position_dataset("lasa", SHAPES).to_csv(path)
        kwargs = {}
    path = pathlib.Path(path)
    env = gym.make(env_id, data=path, **kwargs)
    assert env.spec.kwargs["data"] == str(path)  # stored as a string
    spec = EnvSpec.from_json(env.spec.to_json())
    assert spec == env.spec
    remade = gym.make(spec)
    np.testing.assert_array_equal(remade.reset(seed=2)[0], env.reset(seed=2)[0])
    vec = gym.make_vec(env_id, 2, data=path, **kwargs)
    assert vec.spec.kwargs["data"] == str(path)
    EnvSpec.from_json(vec.spec.to_json())


# a split whose "sine" nominal diverges beyond the margin (fitted on 3-4 demonstrations)
DIVERGED = {"shapes": SHAPES, "split": "test", "split_seed": 6, "test_fraction": 0.5}


def test_diverged_nominal_is_clipped_in_the_observation_only():
    env = gym.make(POSITION, **DIVERGED)
    task = env.unwrapped.task
    outside = (task.grids.nominal < task.cur_low) | (task.grids.nominal > task.cur_high)
    index = int(np.flatnonzero(outside.any(axis=(1, 2)))[0])
    obs, _ = env.reset(seed=0, options={"trajectory": index})
    errors, clipped = [], 0
    space = env.observation_space
    for _ in range(50):
        obs, _, terminated, _, info = env.step(np.zeros(2, np.float32))
        assert space.contains(obs)
        errors.append(info["error"])
        slots = np.r_[4:6, 7:9]  # current and nominal position (D = 2)
        at_bound = (obs[slots] == space.low[slots]) | (obs[slots] == space.high[slots])
        clipped += int(at_bound.sum())
    assert terminated
    # the error uses the unclipped nominal: |n_k - h_k| under the zero action
    expected = np.linalg.norm(task.grids.nominal[index] - task.grids.human[index], axis=1)
    np.testing.assert_allclose(errors, expected, rtol=1e-12)
    assert clipped > 0  # the nominal and current position sat on the bounds


@pytest.mark.parametrize("backend", ["numba", "numpy"])
def test_vector_env_clips_like_the_single_env(backend):
    from motion_envs.envs import _kernels as K

    if backend == "numba" and not K.numba_available():
        pytest.skip("numba not installed")
    native = gym.make_vec(POSITION, 5, backend=backend, **DIVERGED)
    sync = gym.make_vec(POSITION, 5, vectorization_mode="sync", **DIVERGED)
    task = native.unwrapped.task
    outside = (task.grids.nominal < task.cur_low) | (task.grids.nominal > task.cur_high)
    first = {"trajectory": int(np.flatnonzero(outside.any(axis=(1, 2)))[0])}
    np.testing.assert_array_equal(
        native.reset(seed=1, options=first)[0], sync.reset(seed=1, options=first)[0]
    )
    rng = np.random.default_rng(0)
    for _ in range(120):
        a = rng.uniform(-2, 2, size=(5, 2)).astype(np.float32)
        out_n, out_s = native.step(a), sync.step(a)
        for x, y in zip(out_n[:4], out_s[:4], strict=True):
            np.testing.assert_array_equal(x, y)
        assert native.observation_space.contains(out_n[0])
