"""The bookkeeping every native vector environment shares (envs/_native_vector.py): the
same refusals and seeds for a reaching, a coefficient and a juggling id."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import motion_envs  # noqa: F401  (registers the ids)
from motion_envs.envs._native_vector import NativeVectorEnv

IDS = [
    ("MotionEnvs/PositionReach-v1", {"shapes": ["Angle", "CShape"]}),
    ("MotionEnvs/PositionCoefficients-v0", {"shapes": ["Angle", "CShape"]}),
    ("MotionEnvs/Juggling-v1", {"backend": "python"}),
]


@pytest.fixture(params=IDS, ids=[i for i, _ in IDS], scope="module")
def venv(request):
    env_id, kwargs = request.param
    env = gym.make_vec(env_id, num_envs=3, vectorization_mode="vector_entry_point", **kwargs)
    assert isinstance(env.unwrapped, NativeVectorEnv)
    yield env
    env.close()


def test_refusals_are_one_line_value_errors_before_any_reset(venv):
    with pytest.raises(RuntimeError, match="reset"):
        venv.step(venv.action_space.sample())
    bad = [
        ({"seed": True}, "seed must be an int or a list of 3 seeds"),
        ({"seed": [1, 2]}, "seed must be an int or a list of 3 seeds; got 2"),
        ({"options": {"reset_mask": np.array([1, 0, 1])}}, r"must be a bool array \(3,\)"),
        ({"options": {"reset_mask": np.zeros(2, dtype=bool)}}, r"must be a bool array \(3,\)"),
        ({"options": {"reset_mask": np.zeros(3, dtype=bool)}}, "with a True entry"),
        ({"options": {"reset_mask": np.array([True, False, True])}}, "first reset must reset"),
    ]
    for kwargs, match in bad:
        with pytest.raises(ValueError, match=match) as info:
            venv.reset(**kwargs)
        assert "\n" not in str(info.value)


def test_seeds_and_masked_resets(venv):
    """``seed=s`` is ``[s, s + 1, s + 2]``; a masked reset keeps the other rows."""
    obs_int, _ = venv.reset(seed=5)
    obs_list, _ = venv.reset(seed=[5, 6, 7])
    np.testing.assert_array_equal(obs_int, obs_list)
    obs_mask, info = venv.reset(
        seed=[None, 9, None], options={"reset_mask": np.array([0, 1, 0], bool)}
    )
    np.testing.assert_array_equal(obs_mask[[0, 2]], obs_list[[0, 2]])
    masks = [v for k, v in info.items() if k.startswith("_")]
    assert masks and all(m.tolist() == [False, True, False] for m in masks)
    obs_again, _ = venv.reset(seed=[5, 9, 7])
    np.testing.assert_array_equal(obs_again[1], obs_mask[1])
    with pytest.raises(ValueError, match=r"actions must have shape \(3,"):
        venv.step(np.zeros((2, *venv.single_action_space.shape)))
