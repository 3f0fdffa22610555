"""MotionEnvs/OrientationReach-v0 and -v1: what is special to them (the contract every id
keeps, checkers, determinism, pickling, spaces, is in ``test_env_contract.py``).

Every test runs on both versions (the autouse fixture ``env_version`` sets ``ENV_ID``).
"""

from __future__ import annotations

import json

import gymnasium as gym
import numpy as np
import pytest

from motion_envs.envs.orientation_reach import N_STEPS, OrientationReachEnv

ENV_ID = "MotionEnvs/OrientationReach-v0"
VERSIONS = ("v0", "v1")


@pytest.fixture(autouse=True, params=VERSIONS)
def env_version(request, monkeypatch):
    """Run every test of this module on each registered version."""
    monkeypatch.setitem(globals(), "ENV_ID", f"MotionEnvs/OrientationReach-{request.param}")
    return request.param


def test_registered_class_and_episode_length():
    env = gym.make(ENV_ID)
    assert isinstance(env.unwrapped, OrientationReachEnv)
    assert env.spec.max_episode_steps == N_STEPS
    env.close()


def test_episode_is_50_steps_on_the_grid():
    env = gym.make(ENV_ID)
    obs, info = env.reset(seed=3)
    assert obs[12] == 0.0
    np.testing.assert_allclose(obs[8:12], obs[0:4])  # current = start at reset
    for k in range(N_STEPS):
        obs, reward, terminated, truncated, info = env.step(np.zeros(3, np.float32))
        assert info["tau"] == pytest.approx(k / (N_STEPS - 1))
        assert reward == -info["error"]
        if k < N_STEPS - 1:
            assert not terminated and not truncated
    assert terminated and truncated
    assert "max_error" in info and "max_geodesic_error" in info
    np.testing.assert_allclose(obs[8:12], obs[4:8], atol=1e-6)  # zero action ends at the goal


def test_zero_action_on_slerp_reproduces_the_human_error_directly():
    """For the slerp nominal, the residual error is the geodesic angle to the human."""
    env = OrientationReachEnv(split="test")
    env.reset(options={"trajectory": 0})
    for _ in range(N_STEPS):
        _, _, _, _, info = env.step(np.zeros(3))
        assert info["error"] == pytest.approx(info["geodesic_error"], abs=1e-12)


@pytest.mark.parametrize(
    ("nominal", "degree"),
    [("slerp", 2), ("bezier-null", 2), ("bezier-task", 3), ("bezier-subject", 2)],
)
def test_zero_action_invariant_matches_motion_bench(tmp_path, nominal, degree):
    """Median over test episodes of info['max_error'] == motion-bench's offline criterion."""
    from baselines.cli import main

    out = tmp_path / "bench"
    code = main(
        [
            "orientation",
            "--split",
            "test",
            "--nominal",
            nominal,
            "--degree",
            str(degree),
            "--out",
            str(out),
        ]
    )
    assert code == 0
    offline = json.loads((out / "results.json").read_text())["nominal"]["criterion"]
    env = gym.make(ENV_ID, split="test", nominal=nominal, degree=degree)
    n = env.unwrapped.task.n_trajectories
    maxima = []
    for l in range(n):
        env.reset(options={"trajectory": l})
        for _ in range(N_STEPS):
            _, _, terminated, _, info = env.step(np.zeros(3, np.float32))
        assert terminated
        maxima.append(info["max_error"])
    assert abs(float(np.median(maxima)) - offline) <= 1e-9
    # and trajectory by trajectory
    np.testing.assert_allclose(maxima, env.unwrapped.task.grids.max_errors(), atol=1e-12)


def test_nominals_differ_and_bezier_subject_falls_back_to_null_on_test():
    null = OrientationReachEnv(split="test", nominal="bezier-null").task
    subject = OrientationReachEnv(split="test", nominal="bezier-subject").task
    task = OrientationReachEnv(split="test", nominal="bezier-task").task
    slerp = OrientationReachEnv(split="test", nominal="slerp").task
    np.testing.assert_array_equal(null.steps, subject.steps)
    assert not np.array_equal(null.steps, task.steps)
    assert not np.array_equal(slerp.steps, null.steps)


def test_train_and_test_splits_hold_different_subjects():
    train = OrientationReachEnv(split="train").task
    test = OrientationReachEnv(split="test").task
    assert not set(train.subjects) & set(test.subjects)
    assert train.n_trajectories + test.n_trajectories == 648
    other = OrientationReachEnv(split="test", split_seed=1).task
    assert set(other.subjects) != set(test.subjects)


def test_out_of_bound_actions_are_clipped_to_the_bound():
    a = gym.make(ENV_ID)
    b = gym.make(ENV_ID)
    a.reset(seed=1)
    b.reset(seed=1)
    big = np.array([5.0, -7.0, 1.5], np.float32)
    for _ in range(10):
        ra = a.step(big)
        rb = b.step(np.clip(big, -1, 1))
        np.testing.assert_array_equal(ra[0], rb[0])
        assert ra[1] == rb[1]


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_action_raises_and_env_stays_usable(bad):
    a = gym.make(ENV_ID)
    b = gym.make(ENV_ID)
    a.reset(seed=2)
    b.reset(seed=2)
    a.step(np.full(3, 0.5, np.float32))
    b.step(np.full(3, 0.5, np.float32))
    with pytest.raises(ValueError, match="finite"):
        a.step(np.array([0.1, bad, 0.0], np.float32))
    for _ in range(5):
        ra, rb = a.step(np.full(3, 0.2, np.float32)), b.step(np.full(3, 0.2, np.float32))
        np.testing.assert_array_equal(ra[0], rb[0])
        assert ra[1] == rb[1]


def test_observations_stay_in_space_over_10000_random_steps():
    env = gym.make(ENV_ID, residual_scale=3.0)
    env.action_space.seed(0)
    obs, _ = env.reset(seed=0)
    space = env.observation_space
    for _ in range(10_000):
        obs, reward, terminated, truncated, _ = env.step(env.action_space.sample())
        assert space.contains(obs), obs
        assert np.isfinite(reward)
        if terminated or truncated:
            obs, _ = env.reset()
            assert space.contains(obs)


def test_reward_weights_and_info_terms():
    w = {"residual": 0.5, "geodesic": 2.0, "action": 0.1}
    env = OrientationReachEnv(reward_weights=w)
    env.reset(seed=4)
    a = np.array([0.3, -0.2, 0.9], np.float32)
    _, reward, _, _, info = env.step(a)
    aa = a.astype(np.float64)
    assert info["reward_residual"] == -0.5 * info["error"]
    assert info["reward_geodesic"] == -2.0 * info["geodesic_error"]
    assert info["reward_action"] == pytest.approx(-0.1 * float(aa @ aa), rel=1e-15)
    assert reward == pytest.approx(
        info["reward_residual"] + info["reward_geodesic"] + info["reward_action"], rel=1e-15
    )


def test_residual_scale_is_radians_of_a_unit_action():
    from motion_envs.geometry import quaternion as quat

    env = OrientationReachEnv(residual_scale=0.1)
    obs, _ = env.reset(seed=0)
    nominal = obs[13:17].astype(np.float64)
    obs, *_ = env.step(np.array([1.0, 0.0, 0.0], np.float32))
    current = obs[8:12].astype(np.float64)
    angle = quat.angle(nominal / np.linalg.norm(nominal), current / np.linalg.norm(current))
    assert angle == pytest.approx(0.1, abs=1e-6)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"split": "validation"}, "split"),
        ({"nominal": "spline"}, "nominal"),
        ({"degree": 0}, "degree"),
        ({"residual_scale": -1.0}, "residual_scale"),
        ({"residual_scale": float("nan")}, "residual_scale"),
        ({"reward_weights": {"distance": 1.0}}, "reward_weights"),
        ({"reward_weights": {"residual": -1.0}}, "reward_weights"),
        ({"test_fraction": 1.5}, "test_fraction"),
        ({"data": "no-such-dataset"}, "data"),
        ({"render_mode": "human"}, "render_mode"),
        ({"width": 3}, "width"),
    ],
)
def test_bad_arguments_raise_value_error(kwargs, match):
    with pytest.raises(ValueError, match=match):
        OrientationReachEnv(**kwargs)


def test_reset_trajectory_option_is_validated():
    env = OrientationReachEnv(split="test")
    with pytest.raises(ValueError, match="trajectory"):
        env.reset(options={"trajectory": 10_000})
    _, info = env.reset(options={"trajectory": 3})
    assert info["trajectory_index"] == 3
    assert info["trajectory_id"] == env.task.trajectory_ids[3]


def test_users_csv_data(tmp_path):
    from motion_envs.datasets import load_orientation_dataset

    path = load_orientation_dataset("vr-kitchen").to_csv(tmp_path / "mine.csv")
    env = OrientationReachEnv(data=str(path), split="test")
    ref = OrientationReachEnv(split="test")
    np.testing.assert_allclose(env.task.steps, ref.task.steps, atol=1e-12)
