"""Issue 17's environment reproductions (items 6, 7, 8, 10, 11), each a regression test.

Juggling-v1 is left to its own module's tests (its files move in a parallel branch).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from motion_envs.envs.juggling import JugglingEnv

HUGE = 10**400  # an int beyond float64's range: float(HUGE) raises OverflowError
REACHING = ["MotionEnvs/OrientationReach-v0", "MotionEnvs/PositionReach-v0"]


# -- item 7: numeric arguments and actions ----------------------------------------------
@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"residual_scale": HUGE}, "residual_scale"),
        ({"gravity": HUGE}, "gravity"),
        ({"gravity": 1e-300}, "gravity"),
        ({"noise": HUGE}, "noise"),
        ({"noise": {"release": HUGE}}, r"noise\['release'\]"),
        ({"noise": {"tracking": 1e300}}, r"noise\['tracking'\]"),
        ({"reward_weights": {"catch": HUGE}}, r"reward_weights\['catch'\]"),
        ({"max_cycles": HUGE}, "max_cycles"),
        ({"frame_skip": HUGE}, "frame_skip"),
        ({"width": HUGE}, "width"),
        ({"residual_scale": 2.0}, "residual_scale"),
    ],
)
def test_juggling_huge_numbers_raise_value_error_naming_the_argument(kwargs, name):
    with pytest.raises(ValueError, match=name) as info:
        JugglingEnv(**kwargs)
    assert len(str(info.value)) < 200  # the 400 digits are abbreviated


@pytest.mark.parametrize(
    "kwargs",
    [
        {"residual_scale": HUGE},
        {"val_fraction": HUGE},
        {"test_fraction": HUGE},
        {"split_seed": HUGE},
    ],
)
@pytest.mark.parametrize("env_id", REACHING)
def test_reaching_huge_numbers_raise_value_error(env_id, kwargs):
    import gymnasium as gym

    with pytest.raises(ValueError, match=next(iter(kwargs))):
        gym.make(env_id, **kwargs)


BAD_ACTIONS = [
    np.array([1j, 0.0]),
    {"x": 0.0, "z": 0.0},
    np.array([None, None], dtype=object),
    [[0.0], [0.0, 1.0]],
    np.array([True, False]),
    "ab",
    np.zeros(3),
    [HUGE, 0],
]


@pytest.mark.parametrize("action", BAD_ACTIONS, ids=lambda a: type(a).__name__)
def test_juggling_step_rejects_non_real_actions_with_value_error(action):
    env = JugglingEnv(max_cycles=1)
    env.reset(seed=0)
    with pytest.raises(ValueError, match="action must"):
        env.step(action)
    env.step(np.zeros(2))  # the episode is intact


@pytest.mark.parametrize("env_id", REACHING)
@pytest.mark.parametrize("action", BAD_ACTIONS[:5], ids=lambda a: type(a).__name__)
def test_reaching_step_rejects_the_same_actions(env_id, action):
    import gymnasium as gym

    env = gym.make(env_id).unwrapped
    env.reset(seed=0)
    with pytest.raises(ValueError, match="action must"):
        env.step(action)


def test_every_env_uses_the_one_action_check():
    """The shared check in ``envs._common`` is the only one: no env converts its action
    with ``np.asarray(action, dtype=...)`` itself."""
    import pathlib

    import motion_envs.envs as envs

    root = pathlib.Path(envs.__file__).parent
    for path in [root / "juggling" / "_env.py", root / "_reach.py", root / "_reach_vector.py"]:
        text = path.read_text()
        assert "as_action(" in text, path
        assert "np.asarray(action" not in text, path


def test_nan_action_is_zero_and_flagged():
    env = JugglingEnv(max_cycles=1)
    env.reset(seed=0)
    _, reward, *_, info = env.step(np.array([math.nan, 0.0]))
    assert info["action_invalid"] and math.isfinite(reward)
