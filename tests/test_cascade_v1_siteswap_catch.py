"""The siteswap juggler's catch plan (``SiteswapCatchController``, Cascade-v1's
``juggler_oracle_catch``, ``juggler_mean_delay_catch`` and ``juggler_delay_tracker`` on five
balls): the meeting point of a ballistic ball (hand-worked), the reach ending ``lead``
early ``descent lead`` above it and the palm passing through it at ``t_m`` (closed form),
no re-plan in the reach's last periods, a palm that is not rising at the catches,
determinism, which controllers carry it, and that the mean-delay plan changes five balls
only."""

from __future__ import annotations

import math

import numpy as np
import pytest
from _helpers import rollout_digest

from motion_envs.envs.juggling import CascadeV1Env
from motion_envs.geometry.minimum_jerk import quintic_evaluate
from motion_envs.models.juggling import (
    CASCADE_CATCH_PLANS,
    CatchPlan,
    SiteswapCatchController,
    SiteswapController,
    catch_plan,
    pattern_controller,
    pattern_spec,
)
from motion_envs.models.juggling._cascade_siteswap_catch import FREEZE, meeting_point
from motion_envs.models.juggling._cascade_v1 import CASCADE_LEAD_GRID, SITESWAP_DESCENT_GRID


def test_the_meeting_point_of_a_ballistic_ball_hand_worked() -> None:
    """Thrown at t = 0.1 s from (0, 1) m at (1, 4) m/s, g = 10: at t_m = 0.9 s (0.8 s of
    flight) it is at (0.8, 1 + 3.2 - 3.2) = (0.8, 1) m moving at (1, -4) m/s; the planned
    meeting speed of a palm descending at 1 m/s is |(1, -3)| = sqrt(10) m/s."""
    m, v = meeting_point((0.1, np.array([0.0, 1.0]), np.array([1.0, 4.0])), 0.9, 10.0)
    np.testing.assert_allclose(m, [0.8, 1.0], atol=1e-12)
    np.testing.assert_allclose(v, [1.0, -4.0], atol=1e-12)
    assert CatchPlan(0.1, 1.0).meeting_speed(v) == pytest.approx(math.sqrt(10.0))


@pytest.mark.parametrize("plan", [CatchPlan(0.12, 0.0), CatchPlan(0.08, 1.0)])
def test_the_reach_ends_lead_early_above_the_meeting_point(plan: CatchPlan) -> None:
    """The reach's quintic ends at ``t_e = t_m - lead`` at ``E = M + (0, descent lead)``
    moving at ``(0, -descent)`` with no acceleration; the commanded palm then passes
    through ``M`` at ``t_m`` (``E - descent lead``); ``M`` is the told ball's ballistic
    position at ``t_m`` (recomputed here from the state the controller was given)."""
    env = CascadeV1Env(level="easy", pattern="5", controller="juggler_oracle_catch")
    c = env.controller
    assert isinstance(c, SiteswapCatchController)
    c.catch = plan
    seed = 3
    env.reset(seed=seed)
    checked = 0
    for _ in range(400):
        given = env._state
        assert given is not None
        _, _, terminated, truncated, _ = env.step(np.zeros(4, np.float32))
        if terminated or truncated:
            seed += 1
            env.reset(seed=seed)
            continue
        for h, hand in enumerate(c.hands):
            m = c._meet[h]
            t_m = hand.t_star
            if hand.mode != "vacant" or m is None or hand.t0 != given.time:
                continue  # only a reach planned at this step
            b = c.ball_of[hand.landing]
            sign = np.array((1.0, 1.0)) if h == 0 else np.array((-1.0, 1.0))
            p, v = given.ball_pos[b] * sign, given.ball_vel[b] * sign
            s = t_m - given.time
            expect = p + v * s - np.array((0.0, 0.5 * 9.81 * s * s))
            np.testing.assert_allclose(m, expect, atol=1e-9)
            assert hand.t0 + hand.T == pytest.approx(t_m - plan.lead, abs=1e-9)
            end = quintic_evaluate(hand.c, hand.T)
            np.testing.assert_allclose(
                end, m + np.array((0.0, plan.descent * plan.lead)), atol=1e-9
            )
            np.testing.assert_allclose(
                quintic_evaluate(hand.c, hand.T, 1), (0.0, -plan.descent), atol=1e-9
            )
            np.testing.assert_allclose(quintic_evaluate(hand.c, hand.T, 2), (0.0, 0.0), atol=1e-6)
            np.testing.assert_allclose(hand.state(t_m)[0], m, atol=1e-9)
            np.testing.assert_allclose(c.plan_end(h), m * sign, atol=1e-12)
            checked += 1
    assert checked >= 20


def test_no_replan_in_the_last_periods_of_the_reach() -> None:
    """Within ``FREEZE`` periods of ``t_e`` and while the hand waits (until ``t_m +
    lead``) its quintic is not replaced."""
    env = CascadeV1Env(level="medium", pattern="5", controller="juggler_oracle_catch")
    c = env.controller
    assert isinstance(c, SiteswapCatchController) and c.catch.lead > 0
    seed = 5
    env.reset(seed=seed)
    frozen = 0
    for _ in range(400):
        before = [(id(hand.c), hand.t_star) for hand in c.hands]
        t = env._state.time if env._state else math.nan
        _, _, terminated, truncated, _ = env.step(np.zeros(4, np.float32))
        if terminated or truncated:
            seed += 1
            env.reset(seed=seed)
            continue
        for h, hand in enumerate(c.hands):
            waiting = hand.mode == "vacant" and c._meet[h] is not None
            late = hand.t_star - c.catch.lead - t <= FREEZE * env.dt
            if waiting and late and before[h][1] == hand.t_star:
                assert id(hand.c) == before[h][0]
                frozen += 1
    assert frozen >= 10


def _catch_palm_vz(controller: str, level: str, seeds: range) -> list[float]:
    env = CascadeV1Env(level=level, pattern="5", controller=controller)
    out = []
    for seed in seeds:
        env.reset(seed=seed)
        done = False
        while not done:
            vz = env.data.qvel[[1, 3]].copy()
            _, _, te, tr, info = env.step(np.zeros(4, np.float32))
            done = te or tr
            if info["caught"]:
                out += [float(vz[h]) for h in range(2) if np.isfinite(info["catch_speed"][h])]
    return out


def test_the_palm_is_not_rising_at_the_catches() -> None:
    """Measured (easy, 4 seeds): at the step before each catch the oracle's planned palm
    moves down or rests (median vertical velocity <= 0.05 m/s, upper quartile below
    0.3 m/s), not up into the ball as the plain juggler's often does."""
    vz = _catch_palm_vz("juggler_oracle_catch", "easy", range(4))
    assert len(vz) >= 20
    assert np.median(vz) <= 0.05 and np.percentile(vz, 75) < 0.3, vz


def _digest(controller: str, seed: int) -> str:
    env = CascadeV1Env(level="hard", pattern="5", controller=controller, max_catches=6)
    return rollout_digest(env, seed)


def test_deterministic() -> None:
    """The same seed gives the same episode (fresh envs), another seed another one."""
    a = _digest("juggler_oracle_catch", 11)
    assert a == _digest("juggler_oracle_catch", 11)
    assert a != _digest("juggler_oracle_catch", 12)


def test_which_controllers_carry_the_siteswap_plan() -> None:
    """``juggler_oracle_catch`` and ``juggler_mean_delay_catch`` on the siteswap juggler:
    each its declared plan, from the declared grids, the view telling the ball as it is;
    ``juggler_delay_tracker`` and ``juggler_delay_estimator_catch``: the mean-delay one
    (the same object); the other controllers: none (the plain juggler); the fitted
    juggler refuses a controller-side plan."""
    carriers = ("juggler_delay_tracker", "juggler_delay_estimator_catch")
    for name in ("juggler_oracle_catch", "juggler_mean_delay_catch", *carriers):
        base = "juggler_mean_delay_catch" if name in carriers else name
        plan = CASCADE_CATCH_PLANS[base]["siteswap"]
        assert plan is not None and plan.lead in CASCADE_LEAD_GRID
        assert plan.descent in SITESWAP_DESCENT_GRID
        assert catch_plan(name, False) is plan
        env = CascadeV1Env(level="easy", pattern="5", controller=name)
        assert isinstance(env.controller, SiteswapCatchController)
        assert env.controller.catch is plan and env.view.lead == 0.0
    for name in ("juggler", "juggler_mean_delay", "juggler_oracle", "juggler_delay_estimator"):
        assert catch_plan(name, False) is None
        env = CascadeV1Env(level="easy", pattern="5", controller=name)
        assert type(env.controller) is SiteswapController and env.view.lead == 0.0
    with pytest.raises(ValueError, match="catch must be None"):
        pattern_controller(pattern_spec("3"), "juggler", 9.81, catch=CatchPlan(0.02, 0.0))


def test_the_mean_delay_plan_changes_five_balls_only() -> None:
    """On five balls ``juggler_mean_delay_catch`` (and the delay tracker built on it) is no
    longer ``juggler_mean_delay``: the same seeds give other episodes (each controller
    deterministic, so a difference is the plan's). On three balls the catch-plan
    controllers keep the fitted juggler's plan told through the view (lead 20 ms, no
    controller-side plan)."""
    for seed in (11, 12):
        plain = _digest("juggler_mean_delay", seed)
        assert plain == _digest("juggler_mean_delay", seed)
        assert _digest("juggler_mean_delay_catch", seed) != plain
        assert _digest("juggler_delay_tracker", seed) != plain
    fitted = CASCADE_CATCH_PLANS["juggler_mean_delay_catch"]["fitted"]
    assert fitted == CatchPlan(0.02, 0.0)
    for name in ("juggler_mean_delay_catch", "juggler_delay_tracker"):
        env = CascadeV1Env(level="easy", pattern="3", controller=name)
        assert not isinstance(env.controller, SiteswapController)
        assert catch_plan(name, True) is fitted and env.view.lead == fitted.lead
