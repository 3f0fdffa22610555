"""The timing entry of Juggling-v2's and Cascade-v1's action (``timing_scale``): the
agent re-times the catch through the delay the juggler is told, on top of the delay
tracker (:mod:`motion_envs.models.juggling._delay_tracker`)."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from _helpers import check_timing_entry

import motion_envs  # noqa: F401  (registers the ids)
from motion_envs.models.juggling import DelayTracker

V2 = "MotionEnvs/Juggling-v2"
C1 = "MotionEnvs/Cascade-v1"


def _rollout(env_id: str, kwargs: dict[str, Any], seed: int, u: float | None, steps: int) -> Any:
    """Observations, rewards and true hand paths of ``steps`` steps from ``reset(seed)``
    with the zero residual and the timing entry ``u`` (None: no timing entry)."""
    env = gym.make(env_id, **kwargs).unwrapped
    obs, info = env.reset(seed=seed)
    n = env.action_space.shape[0]
    action = np.zeros(n, dtype=np.float32)
    if u is not None:
        action[-1] = u
    out = [obs]
    rewards, hands = [], []
    catches = 0
    for _ in range(steps):
        obs, r, term, trunc, info = env.step(action)
        out.append(obs)
        rewards.append(r)
        hands.append(np.asarray(info["hand"], dtype=np.float64))
        catches = int(info["catches"])
        if term or trunc:
            break
    env.close()
    return np.stack(out), np.array(rewards), np.stack(hands), catches


CASES = [
    (V2, {"level": "medium"}, 700),
    (C1, {"level": "medium", "pattern": "3", "max_catches": 6}, 500),
]


@pytest.mark.parametrize(("env_id", "base", "steps"), CASES)
def test_zero_timing_is_the_tracker(env_id: str, base: dict[str, Any], steps: int) -> None:
    """``u = 0`` plays the delay tracker's episode exactly (observations, rewards,
    hand), with a nonzero gain so the tracker moves."""
    kw = {**base, "controller": "juggler_delay_tracker", "tracker_gain": 0.5, "delay_offset": 0.02}
    a = _rollout(env_id, kw, 1001, None, steps)
    b = _rollout(env_id, {**kw, "timing_scale": 0.1}, 1001, 0.0, steps)
    np.testing.assert_array_equal(a[0], b[0])
    np.testing.assert_array_equal(a[1], b[1])
    np.testing.assert_array_equal(a[2], b[2])
    assert a[3] >= 1  # the tracker has been corrected at least once


def test_constant_timing_is_a_later_told_delay() -> None:
    """Independent oracle: with gain 0 the tracker never moves, so a constant timing
    entry ``u`` tells ``mean + timing_scale * u`` at every release: the episode of the
    tracker told ``delay_offset = timing_scale * u`` (a hand-worked 0.1 * 0.4 = 40 ms),
    and a different episode from ``u = 0`` (equal to rounding: ``0.1 * 0.4`` is not
    ``0.04`` in floating point)."""
    env_id, base, steps = CASES[0]
    kw = {**base, "controller": "juggler_delay_tracker"}
    offset = _rollout(env_id, {**kw, "delay_offset": 0.04}, 1002, None, steps)
    timed = _rollout(env_id, {**kw, "timing_scale": 0.1}, 1002, 0.4, steps)
    zero = _rollout(env_id, {**kw, "timing_scale": 0.1}, 1002, 0.0, steps)
    np.testing.assert_allclose(offset[2], timed[2], rtol=0, atol=1e-6)
    assert offset[3] == timed[3]
    assert zero[2].shape != timed[2].shape or not np.allclose(zero[2], timed[2])


@pytest.mark.parametrize(("env_id", "base", "steps"), CASES)
def test_timing_entry_spaces_and_checkers(env_id: str, base: dict[str, Any], steps: int) -> None:
    """One more action entry with ``timing_scale``; Gymnasium's and SB3's checkers
    pass; ``reset(seed)`` is deterministic under a random timing action."""
    kw = {**base, "controller": "juggler_delay_tracker", "timing_scale": 0.1}
    env = gym.make(env_id, **kw)
    plain = gym.make(env_id, **{**kw, "timing_scale": 0.0})
    check_timing_entry(env, plain)
    env.close()
    plain.close()


def test_cascade_flights_keep_the_delay_told_at_their_release() -> None:
    """Cascade-v1 (balls in the air at the reset are told before any action: the
    tracker's delay): every ball released under a constant timing entry ``u = 0.4`` is
    fitted with the level's mean delay + 40 ms (hand-worked: medium 150 + 40 ms), its
    flight keeps it; with ``u = 0`` the mean alone."""
    for u, told in ((0.4, 0.19), (0.0, 0.15)):
        env = gym.make(C1, **{**CASES[1][1], "controller": "juggler_delay_tracker",
                              "timing_scale": 0.1}).unwrapped  # fmt: skip
        env.reset(seed=1004)
        released: set[int] = set()
        action = np.array([0, 0, 0, 0, u], dtype=np.float32)
        for _ in range(1200):
            *_, term, trunc, _ = env.step(action)
            released |= {int(b) for b in env.world.state.released if b >= 0}
            if term or trunc or len(released) == 3:
                break
        assert len(released) >= 2
        for b in released:
            assert env.view.estimators[b].fixed_delay == pytest.approx(told, abs=1e-8)  # float32 u
        env.close()


def test_timing_entry_nan_is_zero_and_flagged() -> None:
    """A NaN timing entry counts as 0 (the tracker's step) and sets ``action_invalid``."""
    kw = {"level": "medium", "controller": "juggler_delay_tracker", "timing_scale": 0.1}
    env = gym.make(V2, **kw)
    env.reset(seed=5)
    _, _, _, _, info = env.step(np.array([0.0, 0.0, np.nan], dtype=np.float32))
    assert info["action_invalid"]
    assert env.unwrapped.controller.tracker.adjust == 0.0
    env.close()


@pytest.mark.parametrize("env_id", [V2, C1])
@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"controller": "juggler_mean_delay_catch", "timing_scale": 0.1}, "timing_scale is for"),
        ({"controller": "juggler_delay_tracker", "timing_scale": 0.5}, "timing_scale must be in"),
        ({"controller": "juggler_delay_tracker", "timing_scale": -0.1}, "timing_scale must be in"),
        ({"controller": "juggler_delay_tracker", "timing_scale": "0.1"}, "timing_scale must be in"),
        ({"controller": "juggler_delay_tracker", "timing_scale": float("nan")}, "must be in"),
    ],
)
def test_bad_timing_scale_is_one_line(env_id: str, kwargs: dict[str, Any], message: str) -> None:
    with pytest.raises(ValueError, match=message) as err:
        gym.make(env_id, **kwargs)
    assert "\n" not in str(err.value)


def test_tracker_told_adds_the_adjustment() -> None:
    """Hand-worked: estimate 0.15 (the middle of 0.1-0.2) + offset 0.02 + adjust -0.05 =
    0.12 s; an adjustment below 0 in all is told 0; a reset clears it."""
    tracker = DelayTracker(0.5, 0.02, (0.1, 0.2))
    tracker.adjust = -0.05
    assert tracker.told == pytest.approx(0.12)
    tracker.adjust = -1.0
    assert tracker.told == 0.0
    tracker.reset()
    assert tracker.adjust == 0.0
    assert tracker.told == pytest.approx(0.17)


def test_nominal_episode_with_a_timing_entry() -> None:
    """``nominal_episode`` (the zero action, what the benches score) plays the same
    episode with the timing entry as without it."""
    kw = {"level": "medium", "controller": "juggler_delay_tracker", "tracker_gain": 0.25}
    plain = gym.make(V2, **kw).unwrapped.nominal_episode(1005)
    timed = gym.make(V2, **kw, timing_scale=0.1).unwrapped.nominal_episode(1005)
    np.testing.assert_array_equal(plain["hand"], timed["hand"])
    assert plain["catches"] == timed["catches"]
