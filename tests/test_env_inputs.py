"""Environment arguments and actions: the same ValueError from single and vector envs,
finite observations and bounds at the ends of every accepted range, vector reset infos
shaped as SyncVectorEnv's."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest

import motion_envs  # noqa: F401  (registers the ids)

ORIENTATION = "MotionEnvs/OrientationReach-v0"
POSITION = "MotionEnvs/PositionReach-v0"
SHAPES = ["GShape", "Angle"]

# (env id, bad keyword arguments, fragment of the message)
BAD_ARGUMENTS = [
    *[
        (env_id, {"residual_scale": v}, "residual_scale must")
        for env_id in (ORIENTATION, POSITION)
        for v in (math.nan, math.inf, -math.inf, -1.0, 0.0, "0.5", True, 1j, None, 1e300)
    ],
    (ORIENTATION, {"residual_scale": 3.2}, "residual_scale must be finite and in (0, 3.14159]"),
    (POSITION, {"residual_scale": 2e9}, "residual_scale must be finite and in (0, 1e+09]"),
    *[
        (env_id, {"test_fraction": v}, "test_fraction must")
        for env_id in (ORIENTATION, POSITION)
        for v in (0, 1, 1.5, -0.1, math.nan, "0.3", False)
    ],
    *[
        (env_id, {"split_seed": v}, "split_seed must be an integer")
        for env_id in (ORIENTATION, POSITION)
        for v in (-1, 1.5, "0", True, 2**64)
    ],
    *[(ORIENTATION, {"min_deg": v}, "min_deg must") for v in (math.nan, -1.0, 181.0, "10")],
    *[(ORIENTATION, {"degree": v}, "degree must be an integer") for v in (0, 13, 2.0, "2")],
    *[(POSITION, {"n_sines": v}, "n_sines must be an integer") for v in (-1, 49, 2.5, 10**9)],
    *[
        (env_id, {key: v}, f"{key} must be an integer")
        for env_id in (ORIENTATION, POSITION)
        for key in ("width", "height")
        for v in (15, 5000, 100.0, "480")
    ],
    *[
        (ORIENTATION, {"reward_weights": w}, "reward_weights")
        for w in ({"residual": 1e300}, {"residual": math.nan}, {"geodesic": -1.0}, {"x": 1.0})
    ],
    *[(POSITION, {"reward_weights": w}, "reward_weights") for w in ({"distance": math.inf}, [1])],
]


def _kwargs(env_id: str, kwargs: dict) -> dict:
    return {"shapes": SHAPES, **kwargs} if env_id == POSITION else dict(kwargs)


def _error(make) -> str:
    with pytest.raises(ValueError) as info:
        make()
    return str(info.value)


@pytest.mark.parametrize(
    ("env_id", "kwargs", "fragment"),
    BAD_ARGUMENTS,
    ids=[f"{e.split('/')[1][:8]}-{k}" for e, k, _ in BAD_ARGUMENTS],
)
def test_single_and_vector_envs_raise_the_same_error(env_id, kwargs, fragment):
    kw = _kwargs(env_id, kwargs)
    single = _error(lambda: gym.make(env_id, **kw))
    vector = _error(
        lambda: gym.make_vec(env_id, num_envs=2, vectorization_mode="vector_entry_point", **kw)
    )
    assert single == vector
    assert fragment in single, single
    assert "\n" not in single


@pytest.mark.parametrize(
    ("num_envs", "max_episode_steps", "fragment"),
    [
        (0, None, "num_envs"),
        (1.5, None, "num_envs"),
        (2**25, None, "num_envs"),
        (True, None, "num_envs"),
        (2, 0, "max_episode_steps"),
        (2, 2.5, "max_episode_steps"),
    ],
)
def test_vector_only_arguments(num_envs, max_episode_steps, fragment):
    from motion_envs.envs.vector import PositionReachVectorEnv

    with pytest.raises(ValueError, match=rf"^{fragment} must be an integer"):
        PositionReachVectorEnv(
            num_envs=num_envs, max_episode_steps=max_episode_steps, shapes=SHAPES
        )


@pytest.mark.parametrize(
    ("env_id", "kwargs"),
    [
        (
            ORIENTATION,
            {
                "residual_scale": math.pi,
                "reward_weights": {"residual": 1e6, "geodesic": 1e6, "action": 1e6},
                "degree": 12,
            },
        ),
        (ORIENTATION, {"residual_scale": 1e-300, "min_deg": 0.0, "test_fraction": 0.9}),
        (POSITION, {"residual_scale": 1e9, "reward_weights": {"distance": 1e6, "action": 1e6}}),
        (POSITION, {"residual_scale": 5e-324, "n_sines": 48, "test_fraction": 1e-9}),
    ],
)
def test_extreme_accepted_arguments_keep_everything_finite(env_id, kwargs):
    env = gym.make(env_id, **_kwargs(env_id, kwargs)).unwrapped
    space = env.observation_space
    assert np.isfinite(space.low).all() and np.isfinite(space.high).all()
    rng = np.random.default_rng(0)
    obs, _ = env.reset(seed=0)
    for k in range(50):
        a = rng.choice([-1.0, 1.0, 0.0, 7.0, -7.0], size=env.action_space.shape)
        obs, reward, terminated, _, info = env.step(a.astype(np.float32))
        assert np.isfinite(obs).all() and space.contains(obs), (k, obs)
        assert math.isfinite(reward)
    assert terminated and math.isfinite(info["max_error"])


@pytest.mark.parametrize("env_id", [ORIENTATION, POSITION])
@pytest.mark.parametrize(
    "action",
    [
        {"x": 1.0},
        "abc",
        "0.5",
        ["0.1", "0.2", "0.3"],
        np.array([1j, 0, 0]),
        [1 + 0j, 0, 0],
        None,
        object(),
    ],
    ids=["dict", "str", "numeric-str", "str-list", "complex", "complex-list", "none", "object"],
)
def test_step_rejects_non_numeric_actions(env_id, action):
    env = gym.make(env_id, **_kwargs(env_id, {})).unwrapped
    env.reset(seed=0)
    with pytest.raises(ValueError, match=r"^action must"):
        env.step(action)
    # nothing changed: the next valid step is the first one
    assert env._k == 0
    venv = gym.make_vec(
        env_id, num_envs=2, vectorization_mode="vector_entry_point", **_kwargs(env_id, {})
    )
    venv.reset(seed=0)
    batch = action if isinstance(action, (dict, str)) or action is None else [action, action]
    with pytest.raises(ValueError, match=r"^actions must"):
        venv.step(batch)


@pytest.mark.parametrize("env_id", [ORIENTATION, POSITION])
def test_vector_reset_infos_have_sync_vector_env_keys(env_id):
    """The native reset infos: SyncVectorEnv's numeric keys, equal; its text keys
    (``trajectory_id``, ``task``, ``subject``) looked up by ``trajectory_index`` in
    ``trajectory_labels``, not in the infos (which array converters take whole)."""
    kw = _kwargs(env_id, {"max_episode_steps": 3})
    native = gym.make_vec(env_id, num_envs=3, vectorization_mode="vector_entry_point", **kw)
    sync = gym.make_vec(env_id, num_envs=3, vectorization_mode="sync", **kw)
    labels = native.unwrapped.trajectory_labels
    assert {"trajectory_id", "task"} <= set(labels)

    def check(info_n, info_s):
        assert all(np.asarray(v).dtype != object for v in info_n.values())
        assert not {k.lstrip("_") for k in info_n} & set(labels)
        mask = info_s["_trajectory_index"]
        np.testing.assert_array_equal(info_n["_trajectory_index"], mask)
        idx = info_n["trajectory_index"][mask]
        np.testing.assert_array_equal(idx, info_s["trajectory_index"][mask])
        for name in labels:
            np.testing.assert_array_equal(labels[name][idx], info_s[name][mask])

    _, info_n = native.reset(seed=5)
    _, info_s = sync.reset(seed=5)
    check(info_n, info_s)
    assert set(info_n) == {k for k in info_s if k.lstrip("_") not in labels}
    for key, value in info_s.items():
        if key.lstrip("_") not in labels:
            assert np.asarray(info_n[key]).dtype == np.asarray(value).dtype, key
            np.testing.assert_array_equal(info_n[key], value)
    # a partial reset (the autoreset step after a truncation at 3 steps, one env ahead)
    zeros = np.zeros((3, *native.single_action_space.shape), np.float32)
    for _ in range(4):
        out_n, out_s = native.step(zeros), sync.step(zeros)
    assert out_s[4]["_trajectory_index"].any()
    check(out_n[4], out_s[4])
    native.close()
    sync.close()
