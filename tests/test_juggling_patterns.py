"""Patterns as registrations: a pattern is a spec (siteswap, dwell ratio, tunables) plus
``register_pattern``; Cascade-v0 plays any registered one single and vector (native vector
= SyncVectorEnv, bit for bit); anything else is refused with the reason; the controller's
tunables are a frozen dataclass (no module globals); the zero-action episode has one home
(``CascadeEnv.play``), equal to stepping the env."""

from __future__ import annotations

import dataclasses

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode

import motion_envs  # noqa: F401
from baselines.juggling_bench.cascade import cascade_episode
from motion_envs.envs._kernels import numba_available
from motion_envs.envs.juggling import CascadeEnv, cascade_obs_dim
from motion_envs.models.juggling import (
    DEFAULT_TUNABLES,
    PATTERNS,
    CascadeTunables,
    PatternSpec,
    pattern_reasons,
    pattern_spec,
    register_pattern,
)
from tests.test_env_juggling_vector import run_both

CASCADE = "MotionEnvs/Cascade-v0"

# a pattern added inside this file: the three-ball cascade held longer in the hands (the
# spec and the registration are all it takes)
SLOW = "3-test-slow"
if SLOW not in PATTERNS:
    register_pattern(
        PatternSpec(SLOW, "3", 0.62, "test pattern", dataclasses.replace(DEFAULT_TUNABLES))
    )


def test_registered_pattern_plays_single_and_its_timing_is_its_own():
    env = CascadeEnv(level="easy", pattern=SLOW, max_catches=6)
    base = CascadeEnv(level="easy", max_catches=6)
    assert env.balls == 3 and env.dwell_ratio == 0.62
    assert env.controller.beat > base.controller.beat  # a longer dwell, the same flight
    assert env.observation_space.shape == (cascade_obs_dim(3),)
    catches, tosses, dropped, _ = env.play(2_000_000_000)
    assert catches == 6 and not dropped and tosses >= catches


@pytest.mark.skipif(not numba_available(), reason="needs numba")
def test_registered_pattern_vector_equals_sync():
    kw = {"level": "medium", "pattern": SLOW, "max_catches": 3}
    vec = gym.make_vec(CASCADE, 2, autoreset_mode=AutoresetMode.NEXT_STEP, **kw)
    run_both(CASCADE, vec, 2, AutoresetMode.NEXT_STEP, 160, "random", **kw)


@pytest.mark.parametrize(
    ("siteswap", "why"),
    [
        ("4", "not a cascade"),
        ("441", "not a cascade"),
        ("531", "not a cascade"),
        ("423", "not a cascade"),
        ("51", "not a cascade"),
        ("7", "demonstrations exist for"),
        ("45", "land on the same beat"),
        ("3!", "is not a throw"),
    ],
)
def test_other_patterns_are_refused_with_the_reason(siteswap, why):
    with pytest.raises(ValueError, match=why) as info:
        gym.make(CASCADE, pattern=siteswap)
    assert "\n" not in str(info.value)


def test_pattern_reasons_and_registration_errors():
    assert pattern_reasons("3") == ()
    assert pattern_spec("3").balls == 3
    with pytest.raises(ValueError, match="already registered"):
        register_pattern(PatternSpec("3", "3"))
    with pytest.raises(ValueError, match="dwell_ratio"):
        register_pattern(PatternSpec("3-bad", "3", 0.95))
    with pytest.raises(ValueError, match="not a cascade"):
        register_pattern(PatternSpec("fountain", "4"))
    assert "3-bad" not in PATTERNS and "fountain" not in PATTERNS


def test_tunables_are_a_frozen_dataclass_passed_to_the_controller():
    with pytest.raises(dataclasses.FrozenInstanceError):
        DEFAULT_TUNABLES.catch_window = 1.0  # type: ignore[misc]
    with pytest.raises(ValueError, match="release_armed"):
        CascadeTunables(release_armed=1.5)
    with pytest.raises(ValueError, match="toss_clearance"):
        CascadeTunables(toss_clearance=float("nan"))
    t = CascadeTunables(release_armed=0.9, reaim_after=0.2)
    env = CascadeEnv(level="easy", tunables=t)
    c = env.controller
    env.reset(seed=0)
    assert c.tunables is t and all(h.tunables is t for h in c.hands)
    assert c.options.release_after == pytest.approx(0.9 * c.pattern.lead)
    default = CascadeEnv(level="easy").controller
    assert default.options.release_after == pytest.approx(0.75 * default.pattern.lead)
    with pytest.raises(ValueError, match="tunables"):
        CascadeEnv(tunables={"catch_window": 1.0})  # type: ignore[arg-type]


def test_play_is_the_zero_action_episode_of_step():
    """The one home of the episode loop: ``play`` equals reset + step(0) to the end."""
    for level, method in (("medium", "juggler"), ("easy", "fixed_point")):
        env = CascadeEnv(level=level, controller=method, max_catches=4)
        got = env.play(7)
        env.reset(seed=7)
        terminated = truncated = False
        while not (terminated or truncated):
            _, _, terminated, truncated, info = env.step(np.zeros(4, np.float32))
        assert got == (info["catches"], info["tosses"], terminated, info["time"])
        assert cascade_episode(level, method, 7, 4) == got
