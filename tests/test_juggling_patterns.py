"""Patterns as registrations: a pattern is a spec (siteswap, dwell ratio, tunables) plus
``register_pattern``; Cascade-v0 plays any registered one single and vector (native vector
= SyncVectorEnv, bit for bit); anything else is refused with the reason; the controller's
tunables are a frozen dataclass (no module globals); the zero-action episode has one home
(``CascadeEnv.play``), equal to stepping the env."""

from __future__ import annotations

import dataclasses
import itertools

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
    SiteswapStyle,
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
        ("50505", "empty beats"),
        ("7", "the world holds at most 5"),
        ("1", "two hands juggle 2 to 5"),
        ("522", "it is not registered"),
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
        register_pattern(PatternSpec("fountain", "4"))  # the fitted juggler has one toss
    with pytest.raises(ValueError, match="dwell_ratio"):  # the siteswap juggler needs one
        register_pattern(PatternSpec("fountain", "4", None, "", SiteswapStyle()))
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


def test_five_ball_demonstrations_are_simulated_and_keep_the_five_ball_beat():
    """The five-ball population (Kalvan's dwell ratio ~2/3): SIMULATED, the hands in
    turn on the beat of Shannon's theorem with N = 5; each hand catches the ball thrown
    three beats before its own next beat (tested by the hands' release times); the
    ball count is refused where no population exists."""
    from motion_envs.datasets.juggling import (
        CASCADE_STYLES,
        JugglingTask,
        draw_cascade_person,
        generate_cascade_demonstrations,
        style_timing,
    )

    task = JugglingTask(gravity=9.81)
    demos = generate_cascade_demonstrations(n_cycles=8, seed=3, task=task, balls=5)
    assert demos.simulated and "cascade5" in demos.name
    assert all("cascade5" in r.name for r in demos.recordings)
    style = draw_cascade_person(np.random.default_rng(np.random.SeedSequence(3).spawn(1)[0]), 5)
    assert 0.64 <= style.dwell_ratio <= 0.69
    _, timing = style_timing(style, task, 5)
    assert 0.18 < timing.beat < 0.23 and 0.65 < timing.flight < 0.8
    # releases: where a toss run ends (toss -> go_down); the two hands alternate a beat apart
    ends = sorted(
        (float(r.t[k + 1]), i)
        for i, r in enumerate(demos.recordings)
        for k in np.flatnonzero((r.phase[:-1] == "toss") & (r.phase[1:] == "go_down"))
    )
    gaps = np.diff([t for t, _ in ends])
    assert np.median(gaps) == pytest.approx(timing.beat, abs=0.02)
    assert all(a != b for (_, a), (_, b) in itertools.pairwise(ends))
    assert sorted(CASCADE_STYLES) == [3, 5]
    with pytest.raises(ValueError, match="balls must be one of"):
        generate_cascade_demonstrations(n_cycles=2, balls=4)


def test_five_ball_cascade_plays_single_and_vector():
    """Five balls in the world, two held and three flying at the start (ball L lands on
    beat L, thrown on beat L - 5 by that beat's hand), the observation sized for five;
    the native vector env is SyncVectorEnv's."""
    env = CascadeEnv(level="easy", pattern="5")
    obs, info = env.reset(seed=0)
    assert env.balls == 5 and obs.shape == (cascade_obs_dim(5),) == (120,)
    assert env.world.spec.balls == 5 and info["balls"].shape == (5, 2)
    start = env.controller.start()
    assert start.holder == (0, 1, -1, -1, -1) and start.thrower == (-1, -1, 1, 0, 1)
    if numba_available():
        kw = {"level": "medium", "pattern": "5", "max_catches": 2}
        vec = gym.make_vec(CASCADE, 2, autoreset_mode=AutoresetMode.NEXT_STEP, **kw)
        run_both(CASCADE, vec, 2, AutoresetMode.NEXT_STEP, 60, "random", **kw)


def test_pattern_cli_runs_every_registered_pattern(tmp_path):
    import json

    from baselines.cli import main

    for name, spec in list(PATTERNS.items()):
        if name.startswith("3-"):
            continue
        out = tmp_path / name
        argv = ["juggling", "--pattern", name, "--levels", "easy", "--episodes", "2",
                "--max-catches", "1", "--out", str(out)]  # fmt: skip
        assert main(argv) == 0
        doc = json.loads((out / "results.json").read_text())
        assert doc["pattern"]["balls"] == spec.balls and "SIMULATED" in doc["demonstrations"]
        assert doc["pattern"]["dwell_ratio"] == spec.dwell_ratio or name == "3"


def test_cascade_style_catch_follow_and_toss_to_top():
    """``CascadeStyle.catch_follow``: the hand meets the ball moving down with a share of
    its velocity (the catch -> return boundary); ``toss_to_top``: the toss phase lasts
    past the release to the plan's top, where the hand is vertically at rest (the
    toss -> go_down boundary, within one period of its braking); off (both
    populations), the go-down starts at the release speed and the five-ball hand still
    rises into the falling ball when it meets it."""
    from motion_envs.datasets.juggling import (
        JugglingTask,
        draw_cascade_person,
        generate_cascade_demonstrations,
    )

    task = JugglingTask(gravity=9.81)
    base = draw_cascade_person(np.random.default_rng(5), 5)
    moving = dataclasses.replace(
        base, catch_follow=0.2, toss_to_top=True, catch_drop=-0.06, wait=(-0.02, 0.04)
    )

    def boundary_vz(style, before, after):
        demos = generate_cascade_demonstrations(
            n_cycles=6, seed=1, task=task, balls=5, sensor_noise=0.0, styles=[style]
        )
        out = []
        for r in demos.recordings:
            vz = np.diff(r.hand[:, 1]) / task.dt
            ks = np.flatnonzero((r.phase[:-1] == before) & (r.phase[1:] == after))
            out.extend(vz[ks])
        return np.asarray(out)

    assert np.all(np.abs(boundary_vz(moving, "toss", "go_down")) < 1.0)
    assert np.all(boundary_vz(base, "toss", "go_down") > 2.5)
    met = boundary_vz(moving, "catch", "return")
    assert np.all((met < -0.3) & (met > -2.0)), met
    assert np.all(boundary_vz(base, "catch", "return") > 0.5)
