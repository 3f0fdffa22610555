"""``observe_task_error=True`` (Juggling-v2, Cascade-v1): each hand's last catch's task
error in the observation, held until its next catch.

The new entries are checked against an oracle written here from the infos alone (each
step's ``info["task_error"]``, held, counted, clipped to float32), step by step, so an
observation that lags the info by a step or shows a catch before its info fails; the
option changes nothing else (the same episodes, observation prefix, rewards and infos
as the default env under the same actions); the default keeps the observation's size
(its bit-identity with the code before the option is ``tools/output_identity.py``'s and
the digest tests')."""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym
import numpy as np
import pytest

import motion_envs  # noqa: F401  (registers the ids)
from motion_envs.envs.juggling import (
    V2_OBS_DIM,
    CascadeV1Env,
    JugglingV2Env,
    cascade_v1_obs_dim,
)
from motion_envs.envs.juggling._cascade_v1_errors import HeldTaskErrors

#: (constructor, arguments): many catches per episode (the catch-plan controllers).
SETUPS = [
    (JugglingV2Env, {"level": "medium", "controller": "juggler_mean_delay_catch"}),
    (JugglingV2Env, {"level": "drift", "controller": "juggler_oracle", "max_catches": 6}),
    (CascadeV1Env, {"level": "easy", "controller": "juggler_mean_delay_catch", "max_catches": 12}),
]
IDS = ["v2-medium", "v2-drift", "cascade-v1-easy"]


def _hands(env: Any) -> int:
    return 2 if isinstance(env, CascadeV1Env) else 1


def _episode(env: Any, seed: int, scale: float) -> list[tuple[np.ndarray, float, bool, bool, dict]]:
    """``reset(seed)`` then seeded actions in ``[-scale, scale]`` until the episode ends:
    ``(obs, reward, terminated, truncated, info)`` of the reset (reward 0) and every step."""
    rng = np.random.default_rng(100 + seed)
    obs, info = env.reset(seed=seed)
    rows = [(obs, 0.0, False, False, info)]
    done = False
    while not done:
        action = rng.uniform(-scale, scale, env.action_space.shape).astype(np.float32)
        obs, reward, term, trunc, info = env.step(action)
        rows.append((obs, reward, term, trunc, info))
        done = term or trunc
    return rows


def _expected_tails(rows: list, hands: int, max_catches: int, time_limit: float) -> np.ndarray:
    """The oracle: per step, each hand's ``(offset, timing, timed, catches)`` from the
    infos' task errors up to and including that step's, as float32, clipped."""
    held = np.zeros((hands, 4))
    out = []
    for _, _, _, _, info in rows:
        if "task_error" in info:
            for h, (offset, timing) in enumerate(np.reshape(info["task_error"], (-1, 2))):
                if not math.isnan(offset):
                    timed = not math.isnan(timing)
                    n = min(held[h, 3] + 1, max_catches)
                    held[h] = (offset, timing if timed else 0.0, float(timed), n)
        bounded = held.copy()
        bounded[:, 0] = np.clip(bounded[:, 0], -10.0, 10.0)
        bounded[:, 1] = np.clip(bounded[:, 1], -time_limit, time_limit)
        out.append(bounded.ravel().astype(np.float32))
    return np.array(out)


@pytest.mark.parametrize(("ctor", "kwargs"), SETUPS, ids=IDS)
def test_entries_equal_the_infos_task_errors_from_the_catch_step_on(ctor, kwargs) -> None:
    env = ctor(observe_task_error=True, **kwargs)
    hands = _hands(env)
    catches = 0
    for seed, scale in ((0, 0.0), (1, 0.02)):  # the juggler alone; small residuals
        rows = _episode(env, seed, scale)
        got = np.array([r[0][-4 * hands :] for r in rows])
        expected = _expected_tails(rows, hands, env.max_catches, env._time_limit)
        np.testing.assert_array_equal(got, expected)
        assert not got[0].any()  # zeros at the reset
        catches += rows[-1][4]["catches"]
        # the step of each catch shows ITS error (not the one before: no lag) and the
        # step before it does not (no leak)
        for k, (_, _, _, _, info) in enumerate(rows):
            if "task_error" in info:
                h = int(np.flatnonzero(~np.isnan(np.reshape(info["task_error"], (-1, 2))[:, 0]))[0])
                new = np.float32(np.reshape(info["task_error"], (-1, 2))[h, 0])
                assert got[k][4 * h] == new and got[k - 1][4 * h] != new
    assert catches >= 4  # the oracle was compared at many catches, not vacuously


@pytest.mark.parametrize(("ctor", "kwargs"), SETUPS, ids=IDS)
def test_option_changes_only_the_observations_tail(ctor, kwargs) -> None:
    """The same seeded actions with and without the option: the same observation prefix
    (bit for bit), rewards, ends, infos (catches, hand path, task errors)."""
    plain, observed = ctor(**kwargs), ctor(observe_task_error=True, **kwargs)
    n = plain.observation_space.shape[0]
    assert observed.observation_space.shape == (n + 4 * _hands(plain),)
    np.testing.assert_array_equal(observed.observation_space.low[:n], plain.observation_space.low)
    np.testing.assert_array_equal(observed.observation_space.high[:n], plain.observation_space.high)
    for seed, scale in ((3, 0.0), (4, 0.05)):
        a, b = _episode(plain, seed, scale), _episode(observed, seed, scale)
        assert len(a) == len(b)
        for (oa, ra, ta, ua, ia), (ob, rb, tb, ub, ib) in zip(a, b, strict=True):
            np.testing.assert_array_equal(ob[:n], oa)
            assert (ra, ta, ua) == (rb, tb, ub)
            assert ia.keys() == ib.keys()
            for key in ia:
                np.testing.assert_array_equal(np.asarray(ia[key]), np.asarray(ib[key]))


def test_zero_action_episode_is_the_default_envs() -> None:
    """Juggling-v2's nominal episode (the juggler alone) and Cascade-v1's ``play`` are
    unchanged by the option: the same catches, tosses, hand path and task errors."""
    kw = {"level": "medium", "controller": "juggler_mean_delay_catch"}
    a = JugglingV2Env(**kw).nominal_episode(5)
    b = JugglingV2Env(observe_task_error=True, **kw).nominal_episode(5)
    assert (a["catches"], a["tosses"], a["dropped"]) == (b["catches"], b["tosses"], b["dropped"])
    assert a["catches"] >= 3
    for key in ("time", "hand", "task_errors"):
        np.testing.assert_array_equal(a[key], b[key])
    ckw = {"level": "easy", "controller": "juggler_mean_delay_catch", "max_catches": 12}
    assert CascadeV1Env(**ckw).play(5) == CascadeV1Env(observe_task_error=True, **ckw).play(5)


@pytest.mark.parametrize(("ctor", "kwargs"), SETUPS, ids=IDS)
def test_seeded_episodes_are_deterministic_and_stay_in_the_space(ctor, kwargs) -> None:
    first, second = ctor(observe_task_error=True, **kwargs), ctor(observe_task_error=True, **kwargs)
    a, b = _episode(first, 9, 0.3), _episode(second, 9, 0.3)
    np.testing.assert_array_equal(np.array([r[0] for r in a]), np.array([r[0] for r in b]))
    assert [r[1] for r in a] == [r[1] for r in b]
    space = first.observation_space
    assert all(space.contains(r[0]) for r in a)
    hands = _hands(first)
    low, high = space.low[-4 * hands :], space.high[-4 * hands :]
    t, m = first._time_limit, first.max_catches
    np.testing.assert_array_equal(low, np.float32([-10.0, -t, 0.0, 0.0] * hands))
    np.testing.assert_array_equal(high, np.float32([10.0, t, 1.0, m] * hands))


def test_default_keeps_the_observation_size() -> None:
    assert JugglingV2Env().observation_space.shape == (V2_OBS_DIM,) == (32,)
    assert CascadeV1Env().observation_space.shape == (cascade_v1_obs_dim(3),) == (86,)
    assert JugglingV2Env(observe_task_error=True).observation_space.shape == (36,)
    assert CascadeV1Env(pattern="5", observe_task_error=True).observation_space.shape == (130,)


@pytest.mark.parametrize("env_id", ["MotionEnvs/Juggling-v2", "MotionEnvs/Cascade-v1"])
@pytest.mark.parametrize("bad", [1, 0, "true", None, 1.0])
def test_a_non_bool_is_a_one_line_error_naming_the_argument(env_id, bad) -> None:
    with pytest.raises(ValueError, match="observe_task_error") as exc:
        gym.make(env_id, observe_task_error=bad)
    assert "\n" not in str(exc.value)


@pytest.mark.parametrize("env_id", ["MotionEnvs/Juggling-v2", "MotionEnvs/Cascade-v1"])
def test_vector_entry_point_takes_the_option(env_id) -> None:
    """The ids' ``vector_entry_point`` (copies of ``gym.make``): sub-environment 0 is the
    single environment seeded alike."""
    venv = gym.make_vec(env_id, num_envs=2, observe_task_error=True, max_catches=2)
    single = gym.make(env_id, observe_task_error=True, max_catches=2).unwrapped
    obs, _ = venv.reset(seed=4)
    ref, _ = single.reset(seed=4)
    np.testing.assert_array_equal(obs[0], ref)
    zero = np.zeros(venv.action_space.shape, np.float32)
    for _ in range(300):
        obs, *_ = venv.step(zero)
        ref, _, term, trunc, _ = single.step(zero[0])
        np.testing.assert_array_equal(obs[0], ref)
        if term or trunc:
            break
    venv.close()


def test_held_errors_timing_unknown_count_capped_and_reset() -> None:
    """A catch without a planned time (NaN timing: outside the catch phase) shows timing
    0 and flag 0; a hand that did not catch (NaN row) keeps its entries; the count stops
    at ``max_catches``; a reset clears everything."""
    held = HeldTaskErrors(2, max_catches=2)
    held.record(np.array([[0.01, math.nan], [math.nan, math.nan]]))
    assert held.entries() == [0.01, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0]
    held.record(np.array([[math.nan, math.nan], [-0.02, 0.03]]))
    held.record(np.array([[0.04, -0.01], [math.nan, math.nan]]))
    held.record(np.array([[0.05, 0.02], [math.nan, math.nan]]))
    assert held.entries() == [0.05, 0.02, 1.0, 2.0, -0.02, 0.03, 1.0, 1.0]
    held.reset()
    assert held.entries() == [0.0] * 8


@pytest.mark.parametrize("bad", [10**400, None, "0.1", [0.1], True])
def test_delay_offset_that_is_not_a_number_is_a_value_error(bad) -> None:
    """Found by the fuzz once ``observe_task_error`` was listed beside it: an int beyond
    float64's range raised OverflowError, None and a list TypeError."""
    with pytest.raises(ValueError, match="delay_offset must be in") as exc:
        JugglingV2Env(controller="juggler_mean_delay", delay_offset=bad)
    assert "\n" not in str(exc.value)
