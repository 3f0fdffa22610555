"""MotionEnvs/PositionReach-v0 and -v1: what is special to them (the contract every id keeps,
checkers, determinism, pickling, spaces, is in ``test_env_contract.py``).

Every test runs on both versions (the autouse fixture ``env_version`` sets ``ENV_ID``).
"""

from __future__ import annotations

import json

import gymnasium as gym
import numpy as np
import pytest

from motion_envs.envs.orientation_reach import N_STEPS
from motion_envs.envs.position_reach import PositionReachEnv

ENV_ID = "MotionEnvs/PositionReach-v0"
SHAPES = ["Angle", "CShape", "GShape"]
VERSIONS = ("v0", "v1")


@pytest.fixture(autouse=True, params=VERSIONS)
def env_version(request, monkeypatch):
    """Run every test of this module on each registered version."""
    monkeypatch.setitem(globals(), "ENV_ID", f"MotionEnvs/PositionReach-{request.param}")
    return request.param


def make(**kwargs):
    kwargs.setdefault("shapes", SHAPES)
    return gym.make(ENV_ID, **kwargs)


def test_registered_class_and_spaces(env_version):
    env = make()
    assert isinstance(env.unwrapped, PositionReachEnv)
    assert env.spec.max_episode_steps == N_STEPS
    assert env.action_space.shape == (2,)
    timing = 2 if env_version == "v1" else 0  # v1: duration and elapsed time
    assert env.observation_space.shape == (4 * 2 + 1 + 3 + timing,)


def run_bench(out, split: str) -> dict:
    """``motion-bench position`` on the test shapes, 50-point grid, one split."""
    from baselines.cli import main

    argv = ["position", "--no-peers", "--no-progress", "--n-points", "50", "--out", str(out)]
    assert main([*argv, "--split", split, "--shapes", *SHAPES]) == 0
    return json.loads((out / "results.json").read_text())


@pytest.fixture(scope="module")
def bench_doc(tmp_path_factory) -> dict:
    return run_bench(tmp_path_factory.mktemp("bench"), "loo")


@pytest.fixture(scope="module")
def bench_doc_test(tmp_path_factory) -> dict:
    return run_bench(tmp_path_factory.mktemp("bench_test"), "test")


@pytest.mark.parametrize(
    ("nominal", "column"), [("line", "line"), ("null", "null"), ("sine", "lippi")]
)
@pytest.mark.parametrize("split", ["loo", "test"])
def test_zero_action_invariant_matches_motion_bench_position(
    bench_doc, bench_doc_test, nominal, column, split
):
    """Zero-action episodes of a split reproduce ``motion-bench position --split``'s max error."""
    doc = bench_doc if split == "loo" else bench_doc_test
    assert doc["split"]["split"] == split
    offline = doc["summary_median_across_shapes"][column]["max_error"]
    env = make(split=split, nominal=nominal)
    task = env.unwrapped.task
    maxima = []
    for l in range(task.n_trajectories):
        env.reset(options={"trajectory": l})
        for _ in range(N_STEPS):
            _, _, terminated, _, info = env.step(np.zeros(2, np.float32))
        assert terminated
        maxima.append(info["max_error"])
    per_shape = [np.median(np.array(maxima)[task.tasks == s]) for s in SHAPES]
    assert abs(float(np.median(per_shape)) - offline) <= 1e-9
    for s, value in zip(SHAPES, per_shape, strict=True):
        assert abs(value - doc["per_shape"][s]["criteria"][column]["max_error"]) <= 1e-9


def test_train_test_split_by_replicate():
    from motion_envs.datasets.lasa import load_lasa
    from motion_envs.datasets.splits import split_by_replicate

    ds = load_lasa(SHAPES)
    train, test = split_by_replicate(ds, test_fraction=0.25, seed=0)
    assert len(train) + len(test) == len(ds)
    assert not set(train.trajectory_ids) & set(test.trajectory_ids)
    for s in SHAPES:
        assert np.count_nonzero(test.tasks == s) == 2  # round(0.25 * 7)
    env_test = PositionReachEnv(shapes=SHAPES, split="test").task
    assert sorted(env_test.trajectory_ids) == sorted(test.trajectory_ids)
    other = split_by_replicate(ds, seed=1, mask=True)
    assert not np.array_equal(other, split_by_replicate(ds, seed=0, mask=True))


def test_zero_action_reproduces_the_nominal_and_ends_at_the_goal():
    env = make(split="test", nominal="null")
    task = env.unwrapped.task
    env.reset(options={"trajectory": 1})
    errors = []
    for _ in range(N_STEPS):
        obs, reward, terminated, truncated, info = env.step(np.zeros(2, np.float32))
        errors.append(info["error"])
        assert reward == -info["error"]
    assert terminated and truncated
    g = task.grids
    np.testing.assert_allclose(
        errors, np.linalg.norm(g.human[1] - g.nominal[1], axis=1), atol=1e-12
    )
    assert info["max_error"] == max(errors)
    np.testing.assert_allclose(obs[4:6], obs[2:4], atol=1e-4)  # ends at the goal


def test_residual_scale_is_the_offset_of_a_unit_action():
    env = make(residual_scale=2.0)
    obs, _ = env.reset(seed=0)
    nominal = obs[7:9].astype(np.float64)
    obs, *_ = env.step(np.array([1.0, -0.5], np.float32))
    np.testing.assert_allclose(obs[4:6] - nominal, [2.0, -1.0], atol=1e-4)


def test_clipping_and_non_finite_actions():
    a, b = make(), make()
    a.reset(seed=1)
    b.reset(seed=1)
    big = np.array([3.0, -9.0], np.float32)
    ra, rb = a.step(big), b.step(np.clip(big, -1, 1))
    np.testing.assert_array_equal(ra[0], rb[0])
    assert ra[1] == rb[1]
    for bad in (np.nan, np.inf, -np.inf):
        with pytest.raises(ValueError, match="finite"):
            a.step(np.array([bad, 0.0], np.float32))
    for _ in range(5):
        ra, rb = a.step(np.full(2, 0.3, np.float32)), b.step(np.full(2, 0.3, np.float32))
        np.testing.assert_array_equal(ra[0], rb[0])


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"split": "validation"}, "split"),
        ({"nominal": "bezier"}, "nominal"),
        ({"n_sines": -1}, "n_sines"),
        ({"residual_scale": 0.0}, "residual_scale"),
        ({"reward_weights": {"geodesic": 1.0}}, "reward_weights"),
        ({"shapes": ["NoSuchShape"]}, "NoSuchShape"),
        ({"data": "nowhere"}, "data"),
        ({"render_mode": "human"}, "render_mode"),
    ],
)
def test_bad_arguments_raise_value_error(kwargs, match):
    kwargs.setdefault("shapes", SHAPES)
    with pytest.raises(ValueError, match=match):
        PositionReachEnv(**kwargs)


def test_users_csv_in_3d(tmp_path):
    from motion_envs.datasets.lasa import load_lasa

    ds = load_lasa(SHAPES)
    rows = ["trajectory,subject,task,t,x,y,z"]
    for i in range(len(ds)):
        y, t = ds.positions[i], ds.times[i]
        for j in range(0, y.shape[0], 10):
            vals = [t[j], y[j, 0], y[j, 1], 0.01 * y[j, 0] * y[j, 1]]
            rows.append(
                f"{ds.trajectory_ids[i]},s,{ds.tasks[i]}," + ",".join(map(repr, map(float, vals)))
            )
    path = tmp_path / "mine.csv"
    path.write_text("\n".join(rows) + "\n")
    env = gym.make(ENV_ID, data=str(path), nominal="null", split="test")
    assert env.action_space.shape == (3,)
    env.reset(seed=0)
    obs, *_ = env.step(np.zeros(3, np.float32))
    assert env.observation_space.contains(obs)
