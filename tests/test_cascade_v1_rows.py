"""Cascade-v1's rows taken from Juggling-v2's bench: the hand-written delay estimator
(``juggler_delay_estimator``: a known delay recovered from hand-worked frames and pooled
over the balls; on real episodes near the true delay), the best constant and
``velocity x mean delay`` (hand-worked observations), the estimator with the mean-delay
catch plan (``juggler_delay_estimator_catch``: its parts, determinism, and with the pool
pinned the mean-delay catch plan told that delay, episode for episode), and every new
choice made on validation seeds only (a spy that can fail)."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from _helpers import rollout_digest

from baselines.juggling_bench.cascade import CascadeEpisodes
from baselines.juggling_bench.cascade_v1 import (
    CONSTANT_GRID,
    FRESH_FRAME,
    REFERENCES,
    ROWS,
    CascadeV1Config,
    CascadeVelocityTimesDelay,
    _Constant,
    choose_constant,
    choose_late_offset,
    run_cascade_v1,
)
from motion_envs.datasets.juggling import episode_seeds
from motion_envs.envs.juggling import CascadeV1Env, cascade_v1_obs_dim
from motion_envs.models.juggling import (
    CASCADE_CATCH_PLANS,
    CASCADE_V1_CONTROLLERS,
    CameraFrame,
    CascadeBallView,
    PooledReleaseEstimator,
    SiteswapCatchController,
    catch_plan,
)
from tests.test_cascade_v1 import Spy as CascadeSpy

G = 9.81


def _flight(t0: float, p0: tuple[float, float], v0: tuple[float, float], t: float) -> np.ndarray:
    s = t - t0
    return np.array([p0[0] + v0[0] * s, p0[1] + v0[1] * s - 0.5 * G * s * s])


def _frames(
    t0: float, p0: tuple[float, float], v0: tuple[float, float], delay: float, n: int
) -> list[CameraFrame]:
    """``n`` noiseless frames of the ballistic flight from ``p0`` at ``t0``, captured
    every 10 ms from 10 ms after ``t0`` and arriving ``delay`` later."""
    out = []
    for j in range(1, n + 1):
        c = t0 + 0.01 * j
        x, z = _flight(t0, p0, v0, c)
        out.append(CameraFrame(c, c + delay, float(x), float(z)))
    return out


def test_a_known_delay_is_recovered_from_the_release_and_pooled_over_the_balls() -> None:
    """Hand-worked: ball 0 thrown by a hand at 0.3 s from (0.05, 1.33) m at (-0.5, 3.0)
    m/s, its frames arriving 135 ms after capture; ball 1 in flight at the start (no
    hand released it), its frames 135 ms late too. Before any release tells the delay
    both are fitted with the prior (150 ms: the frames placed 15 ms early); after ball
    0's eighth frame the pool holds 135 ms, and both balls' states are exact (the
    ballistic flight; no drag). Ball 1's start tells nothing; a second release of ball 0
    whose frames are 145 ms late makes the pooled delay their mean, 140 ms."""
    pool: list[float] = []
    est = [PooledReleaseEstimator(G, pool, 0.15) for _ in range(2)]
    for e in est:
        e.reset()
    p1, v1 = (-0.2, 1.6), (0.6, 1.0)
    est[1].flying_at_start(0.0, *p1)
    for f in _frames(0.0, p1, v1, 0.135, 10):
        est[1].add([f])
    assert pool == [] and est[1].delay_estimate is None
    # the prior places the newest frame (captured 0.10, arrived 0.235) at 0.085 s
    fit = est[1].fit()
    assert fit is not None and fit[0] == pytest.approx(0.235 - 0.15)
    p0, v0 = (0.05, 1.33), (-0.5, 3.0)
    est[0].released(0.3, *p0)
    frames = _frames(0.3, p0, v0, 0.135, 12)
    for j, f in enumerate(frames):
        est[0].add([f])
        assert len(pool) == (1 if j >= 7 else 0)  # the eighth frame tells the delay
    assert pool == [pytest.approx(0.135)]
    now = 0.6
    for e, (t0, p, v) in zip(est, ((0.3, p0, v0), (0.0, p1, v1)), strict=True):
        got = e.estimate(now)
        assert got is not None
        np.testing.assert_allclose(got[0], _flight(t0, p, v, now), atol=1e-9)
        np.testing.assert_allclose(got[1], [v[0], v[1] - G * (now - t0)], atol=1e-9)
    est[0].released(1.0, *p0)
    for f in _frames(1.0, p0, v0, 0.145, 8):
        est[0].add([f])
    assert pool == [pytest.approx(0.135), pytest.approx(0.145)]
    assert est[1].delay_estimate == pytest.approx(0.140)


def test_the_env_offers_the_estimator_with_one_pool_per_episode() -> None:
    env = CascadeV1Env(level="easy", pattern="5", controller="juggler_delay_estimator")
    assert CASCADE_V1_CONTROLLERS["juggler_delay_estimator"] == ("juggler", "release")
    assert all(isinstance(e, PooledReleaseEstimator) for e in env.view.estimators)
    assert all(e.pool is env.view.pool for e in env.view.estimators)  # type: ignore[attr-defined]
    with pytest.raises(ValueError, match="delay_offset is for"):
        CascadeV1Env(controller="juggler_delay_estimator", delay_offset=0.02)
    view = CascadeBallView(3, "arrival", G, 0.15, 1.3)
    assert view.delay_estimate is None and not view.pool


@pytest.mark.parametrize(("pattern", "level"), [("3", "easy"), ("5", "medium")])
def test_on_real_episodes_the_pooled_delay_is_near_the_true_one(pattern: str, level: str) -> None:
    """Zero-action episodes (seeds 100-105, not the bench's): after the episode the
    pooled estimate is within 25 ms of the hidden delay, 12 ms on average (measured
    before: within 18 ms on these levels, jitter 5-10 ms, frames every 10 ms)."""
    env = CascadeV1Env(level=level, pattern=pattern, controller="juggler_delay_estimator",
                       max_catches=8)  # fmt: skip
    errors = []
    for seed in range(100, 106):
        env.play(seed)
        assert env.view.delay_estimate is not None
        errors.append(env.view.delay_estimate - env.delay)
        assert env.view.delay_estimate == pytest.approx(float(np.mean(env.view.pool)))
    assert np.abs(errors).max() < 0.025 and np.abs(errors).mean() < 0.012


def _obs(balls: int) -> np.ndarray:
    obs = np.zeros(cascade_v1_obs_dim(balls))
    return obs


def test_velocity_times_delay_reads_the_ball_each_hand_is_about_to_catch() -> None:
    """Hand-worked, three balls: the right hand in its catch phase with its planned catch
    at (0.3, 1.3) m; ball 0 held (its old frames nearest), ball 1 falling toward the
    plan, ball 2 rising, a fourth frame set (ball 1's twin) stale; the left hand not
    catching. Ball 1's frames: newest (0.31, 1.50) age 0, oldest valid (0.30, 1.60) age
    0.03 s: v = (1/3, -10/3) m/s; times 15 ms / 0.1 m per unit: (0.05, -0.5)."""
    n = 3
    obs = _obs(n)
    obs[7] = 1.0  # right hand: catch phase
    obs[13:15] = (0.3, 1.3)
    obs[16 + 5] = 1.0  # left hand: toss phase
    obs[32 + 0] = 1.0  # ball 0 held by the right hand
    base = 32 + 2 * n
    frames = obs[base:].reshape(n, 4, 4)
    frames[0, :2] = [(0.3, 1.31, 0.0, 1.0), (0.3, 1.4, 0.01, 1.0)]  # held: ignored
    frames[1, :2] = [(0.31, 1.50, 0.0, 1.0), (0.30, 1.60, 0.03, 1.0)]
    frames[2, :3] = [(0.1, 1.9, 0.0, 1.0), (0.1, 1.8, 0.01, 1.0), (0.1, 1.7, 0.02, 1.0)]
    policy = CascadeVelocityTimesDelay(n, 0.015, 0.1)
    out = policy(obs.astype(np.float32).copy())
    np.testing.assert_allclose(out, [0.05, -0.5, 0.0, 0.0], atol=1e-6)
    # ball 1's frames too old: nothing to read, no residual
    frames[1, :2, 2] += FRESH_FRAME
    np.testing.assert_allclose(policy(obs.astype(np.float32)), 0.0)
    # out of the catch phase: no residual
    obs[7], frames[1, :2, 2] = 0.0, (0.0, 0.03)
    np.testing.assert_allclose(policy(obs.astype(np.float32)), 0.0)
    # large velocities are clipped to the action box
    obs[7] = 1.0
    np.testing.assert_allclose(CascadeVelocityTimesDelay(n, 0.15, 0.1)(obs), [0.5, -1, 0, 0])


def test_a_constant_is_mirrored_for_the_left_hand() -> None:
    assert (0.0, 0.0) in CONSTANT_GRID and len(CONSTANT_GRID) == 9
    np.testing.assert_array_equal(_Constant((0.5, -0.5))(_obs(3)), [0.5, -0.5, -0.5, -0.5])


# -- the new choices: a spy ----------------------------------------------------------------


class Spy(CascadeSpy):
    """:class:`tests.test_cascade_v1.Spy` (fails when a test seed is played while a
    choice is made) with other synthetic episodes, whose ranking differs between splits:
    on validation the constant (+0.5, 0) and the delay estimator are best, on test the
    constant (-0.5, -0.5) and ``velocity_x_mean_delay``, so a choice read from test seeds
    is told apart."""

    def catches(self, policy: Any, kwargs: dict[str, Any], split: str) -> int:
        if isinstance(policy, _Constant):
            best = (0.5, 0.0, -0.5, 0.0) if split == "val" else (-0.5, -0.5, 0.5, -0.5)
            return 6 if tuple(policy.action) == best else 2
        if isinstance(policy, CascadeVelocityTimesDelay):
            return 3 if split == "val" else 20
        if kwargs["controller"] == "juggler_delay_estimator":
            return 10 if split == "val" else 4
        return 1


def test_the_constant_and_the_best_row_are_chosen_on_validation_seeds() -> None:
    spy = Spy()
    config = CascadeV1Config(levels=("medium", "hard"), episodes=5, val_episodes=4, ilc=False)
    doc = run_cascade_v1(config, spy.play, spy.chooser(choose_late_offset),
                         spy.chooser(choose_constant))  # fmt: skip
    during = [split for _, split, choosing in spy.calls if choosing]
    assert during == ["val"] * (2 * (len(CONSTANT_GRID) + 7))  # 9 constants, 7 offsets
    for level in ("medium", "hard"):  # per level every validation play before any test play
        splits = [s for lv, s, _ in spy.calls if lv == level]
        assert "test" in splits and "val" not in splits[splits.index("test") :]
    for lv in doc["levels"]:
        assert lv["constant"] == [0.5, 0.0]  # test would pick (-0.5, -0.5)
        assert lv["constant_val_mean_catches"]["+0.5,+0.0"] == 6.0
        assert lv["val_mean_catches"]["best_constant"] == 6.0
        # the grid's zero is the juggler (the zero action, played once and reused)
        assert lv["val_mean_catches"]["juggler"] == lv["constant_val_mean_catches"]["+0.0,+0.0"]
        assert lv["val_mean_catches"]["juggler"] == 1.0
        assert lv["val_mean_catches"]["velocity_x_mean_delay"] == 3.0
        assert lv["best_non_oracle"] == "delay_estimator"  # 10 on validation, 4 on test
        assert lv["rows"]["velocity_x_mean_delay"]["catches_mean"] == 20.0
        assert lv["rows"]["best_constant"]["catches_mean"] == 2.0  # (+0.5, 0) on test
        assert lv["room"]["value"] == 1.0 - 4.0


def test_the_spy_catches_a_constant_chosen_on_test_seeds() -> None:
    def leaky(level: str, config: CascadeV1Config, play: Any) -> Any:
        play(None, {"level": level, "controller": "juggler"}, "test", 3)
        return (0.0, 0.0), {}

    spy = Spy()
    with pytest.raises(AssertionError, match="before the choice"):
        run_cascade_v1(CascadeV1Config(levels=("medium",), episodes=5, val_episodes=4, ilc=False),
                       spy.play, spy.chooser(choose_late_offset), spy.chooser(leaky))  # fmt: skip


# -- the task-error learner ------------------------------------------------------------------


class _OneCatchEnv:
    """A scripted Cascade-v1: the left hand in its catch phase with ball 1 falling toward
    its plan (the velocity test's frames), then a catch by the left hand with the task
    error ``(e_x, e_t) = (4 mm, 10 ms)``; the episode ends."""

    def __init__(self) -> None:
        obs = _obs(3)
        obs[16 + 7], obs[16 + 13 : 16 + 15] = 1.0, (0.3, 1.3)
        frames = obs[38:].reshape(3, 4, 4)
        frames[1, :2] = [(0.31, 1.50, 0.0, 1.0), (0.30, 1.60, 0.03, 1.0)]
        self.obs, self.actions = obs.astype(np.float32), []

    def reset(self, *, seed: int) -> tuple[np.ndarray, dict[str, Any]]:
        return self.obs, {}

    def step(self, a: np.ndarray) -> tuple[Any, ...]:
        self.actions.append(np.asarray(a, dtype=np.float64))
        err = np.array([[np.nan, np.nan], [0.004, 0.01]])
        info = {"caught": 1, "task_error": err, "time": 0.5, "tosses": 1, "catches": 1}
        return self.obs, 0.0, True, False, info


def test_the_learner_acts_and_learns_in_each_hands_own_frame_hand_worked() -> None:
    """Left hand (own frame: x mirrored), ball velocity (1/3, -10/3) m/s, c = (0.02,
    -0.01) m, d = 15 ms, 0.1 m per unit: the world residual S c + d v = (-0.015, -0.06) m,
    action (0, 0, -0.15, -0.6). The catch's error (4 mm, 10 ms) asks for r* = r + (e_x,
    v_z e_t) = (-0.011, -0.09333) m; in the hand's own frame the sample is (v'_x, v_z,
    r*'_x, r*'_z) = (-1/3, -10/3, 0.011, -0.09333)."""
    from baselines.juggling_bench.cascade_v1_ilc import CascadeTaskErrorILC

    ilc = CascadeTaskErrorILC("easy", "3", 0.1, 0.015)
    ilc.c = np.array([0.02, -0.01])
    env = _OneCatchEnv()
    assert ilc.play(env, 0, learn=True) == (0.5, 1, 1, True)  # type: ignore[arg-type]
    np.testing.assert_allclose(env.actions[0], [0.0, 0.0, -0.15, -0.6], atol=1e-6)
    (sample,) = ilc.samples
    np.testing.assert_allclose(sample, [-1 / 3, -10 / 3, 0.011, -0.06 - 0.1 / 3], atol=1e-6)
    ilc.play(env, 0, learn=False)
    assert len(ilc.samples) == 1


def test_the_learner_trains_on_training_seeds_only(monkeypatch: pytest.MonkeyPatch) -> None:
    from baselines.juggling_bench.cascade_v1_ilc import CascadeTaskErrorILC
    from baselines.juggling_bench.ilc import ILCConfig

    seeds: list[int] = []
    make = CascadeTaskErrorILC._env

    def spying_env(self: Any) -> Any:
        env = make(self)
        reset = env.reset

        def spy_reset(*, seed: int, **kw: Any) -> Any:
            seeds.append(seed)
            return reset(seed=seed, **kw)

        env.reset = spy_reset
        return env

    monkeypatch.setattr(CascadeTaskErrorILC, "_env", spying_env)
    ilc = CascadeTaskErrorILC("easy", "3", 0.1, 0.125, ILCConfig(2, 3, max_catches=3))
    ilc.train()
    np.testing.assert_array_equal(seeds, episode_seeds("train", 6))
    assert len(ilc.history) == 2


def test_the_learner_is_chosen_on_validation_and_played_on_test_after(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A stand-in learner recording when it trains and plays: per level it trains, then
    plays validation, before any test seed is played; its validation mean (15) makes it
    the best row although its test mean (0) is the lowest."""
    from baselines.juggling_bench import cascade_v1_ilc

    spy = Spy()

    class Fake:
        c, d, history = np.zeros(2), 0.1, []

        def __init__(self, level: str, *args: Any) -> None:
            self.level = level

        def train(self) -> None:
            spy.calls.append((self.level, "train", spy.choosing))

        def evaluate(self, split: str, n: int) -> CascadeEpisodes:
            spy.calls.append((self.level, split, spy.choosing))
            c = 15 if split == "val" else 0
            return CascadeEpisodes(episode_seeds(split, n), np.full(n, c), np.full(n, c + 1),
                                   np.ones(n, bool), np.ones(n))  # fmt: skip

    monkeypatch.setattr(cascade_v1_ilc, "CascadeTaskErrorILC", Fake)
    config = CascadeV1Config(levels=("easy",), episodes=5, val_episodes=4)
    (lv,) = run_cascade_v1(config, spy.play, spy.chooser(choose_late_offset),
                           spy.chooser(choose_constant))["levels"]  # fmt: skip
    splits = [s for _, s, _ in spy.calls]
    first_test = splits.index("test")
    assert splits.index("train") < first_test and "val" not in splits[first_test:]
    assert splits[splits.index("train") + 1] == "val"
    assert (
        lv["best_non_oracle"] == "task_error_ilc" and lv["val_mean_catches"]["task_error_ilc"] == 15
    )
    assert lv["rows"]["task_error_ilc"]["catches_mean"] == 0.0
    assert lv["ilc"]["budget_train_episodes"] == 60


# -- the two hand-written fixes together: juggler_delay_estimator_catch --------------------

ESTCATCH = "juggler_delay_estimator_catch"


def test_the_estimator_with_the_catch_plan_is_the_two_fixes_together() -> None:
    """The delay estimator's mode (``"release"``, one pool per episode) and the mean-delay
    catch plan on either juggler (the same declared objects): on three balls each ball
    told ``lead`` ahead, on five the siteswap juggler's own catch; no ``tracker_gain``
    (its ``delay_offset``, a correction of the estimate: ``tests/test_estimator_offset.py``)."""
    assert CASCADE_V1_CONTROLLERS[ESTCATCH] == CASCADE_V1_CONTROLLERS["juggler_delay_estimator"]
    plans = CASCADE_CATCH_PLANS["juggler_mean_delay_catch"]
    for pattern, fitted in (("3", True), ("5", False)):
        plan = plans["fitted" if fitted else "siteswap"]
        assert plan is not None and catch_plan(ESTCATCH, fitted) is plan
        env = CascadeV1Env(level="medium", pattern=pattern, controller=ESTCATCH)
        assert all(isinstance(e, PooledReleaseEstimator) for e in env.view.estimators)
        assert all(e.pool is env.view.pool for e in env.view.estimators)  # type: ignore[attr-defined]
        assert env.catch_plan is plan
        if fitted:
            assert not isinstance(env.controller, SiteswapCatchController)
            assert env.view.lead == plan.lead == 0.02
        else:
            assert isinstance(env.controller, SiteswapCatchController)
            assert env.controller.catch is plan and env.view.lead == 0.0
    with pytest.raises(ValueError, match="tracker_gain is for"):
        CascadeV1Env(controller=ESTCATCH, tracker_gain=0.5)


def _digest(controller: str, pattern: str, seed: int, max_catches: int = 6) -> str:
    """The zero-action episode's observations, rewards and true balls, hashed."""
    env = CascadeV1Env(level="medium", pattern=pattern, controller=controller,
                       max_catches=max_catches)  # fmt: skip
    return rollout_digest(env, seed)


@pytest.mark.parametrize("pattern", ["3", "5"])
def test_the_estimator_with_the_catch_plan_is_deterministic_and_its_own_row(
    pattern: str,
) -> None:
    """The same seed gives the same episode (fresh envs), another seed another one; and
    on these seeds it is neither of the two rows it combines."""
    a = _digest(ESTCATCH, pattern, 11)
    assert a == _digest(ESTCATCH, pattern, 11)
    assert a != _digest(ESTCATCH, pattern, 12)
    for seed in (11, 12):
        mine = _digest(ESTCATCH, pattern, seed)
        assert mine != _digest("juggler_delay_estimator", pattern, seed)
        assert mine != _digest("juggler_mean_delay_catch", pattern, seed)


def _pinned(pattern: str, delay: float, monkeypatch: pytest.MonkeyPatch) -> CascadeV1Env:
    """``juggler_delay_estimator_catch`` whose pool holds ``delay`` alone from every
    reset on (the releases tell nothing: their anchor adds no delay)."""
    env = CascadeV1Env(level="medium", pattern=pattern, controller=ESTCATCH, max_catches=6)
    reset = env.view.reset

    def pinned_reset(*args: Any) -> None:
        reset(*args)
        env.view.pool.append(delay)

    monkeypatch.setattr(env.view, "reset", pinned_reset)
    for est in env.view.estimators:
        monkeypatch.setattr(est, "_anchor", lambda: None)
    return env


@pytest.mark.parametrize("pattern", ["3", "5"])
def test_with_the_pool_pinned_it_is_the_mean_delay_catch_plan_told_that_delay(
    pattern: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    """With the pool pinned at 185 ms the row is ``juggler_mean_delay_catch`` whose fixed
    delay is 185 ms (not the level's mean, 150 ms) exactly, episode for episode: the row
    is the mean-delay catch plan on the estimator's delay, nothing else. The pinning
    matters (unpinned, or the mean delay's own 150 ms, other episodes on some seed)."""
    delay = 0.185
    pinned = _pinned(pattern, delay, monkeypatch)
    told = CascadeV1Env(level="medium", pattern=pattern, controller="juggler_mean_delay_catch",
                        max_catches=6)  # fmt: skip
    for est in told.view.estimators:
        est.fixed_delay = delay
    same = [rollout_digest(pinned, s) == rollout_digest(told, s) for s in range(3)]
    assert all(same)
    assert pinned.view.pool == [delay]
    differ = [
        rollout_digest(pinned, s) != _digest(name, pattern, s)
        for s in range(3)
        for name in (ESTCATCH, "juggler_mean_delay_catch")
    ]
    assert any(differ[0::2]) and any(differ[1::2])


class EstimatorCatchSpy(Spy):
    """:class:`Spy` whose ``juggler_delay_estimator_catch`` is the best row on validation
    (15 catches) and the worst on test (0)."""

    def catches(self, policy: Any, kwargs: dict[str, Any], split: str) -> int:
        if kwargs["controller"] == ESTCATCH:
            return 15 if split == "val" else 0
        return super().catches(policy, kwargs, split)


def test_the_estimator_with_the_catch_plan_is_a_competitor_chosen_on_validation() -> None:
    spy = EstimatorCatchSpy()
    config = CascadeV1Config(levels=("medium",), episodes=5, val_episodes=4, ilc=False)
    doc = run_cascade_v1(config, spy.play, spy.chooser(choose_late_offset),
                         spy.chooser(choose_constant))  # fmt: skip
    assert [s for _, s, choosing in spy.calls if choosing] == ["val"] * (len(CONSTANT_GRID) + 7)
    (lv,) = doc["levels"]
    assert "delay_estimator_catch" in ROWS and "delay_estimator_catch" not in REFERENCES
    assert lv["val_mean_catches"]["delay_estimator_catch"] == 15.0
    assert lv["best_non_oracle"] == "delay_estimator_catch"  # 0 on test: not read there
    assert lv["rows"]["delay_estimator_catch"]["catches_mean"] == 0.0
    assert lv["room"]["value"] == 1.0 - 0.0  # oracle_catch 1 on test
    assert lv["delay_tracker_minus"]["rival"] == "delay_estimator_catch"
