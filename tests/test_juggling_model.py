"""The pure-model juggling world and the analytic juggler (eq. 9 toss, catch planner, eq. 10)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from motion_envs.datasets.juggling import (
    JugglingNoise,
    JugglingTask,
    ballistic_position,
    generate_demonstrations,
)
from motion_envs.geometry import sine_series as ss
from motion_envs.geometry.minimum_jerk import minimum_jerk
from motion_envs.models.juggling import (
    AnalyticJuggler,
    BallisticWorld,
    cycle_rngs,
    plan_catch,
    run_cycle,
    run_cycles,
    run_cycles_fast,
)


@pytest.fixture(scope="module")
def juggler():
    demos = generate_demonstrations(n_cycles=40, seed=3)
    return AnalyticJuggler(n_sines=8).fit(demos)


def test_ballistic_world_follows_the_closed_form_parabola():
    task = JugglingTask()
    world = BallisticWorld(task)
    world.reset([0.0, 1.0])
    hand = [np.array([0.0, 1.0])]
    v = np.array([-0.3, 0.8])
    dt = task.dt
    hand.append(hand[-1] + v * dt)
    state = world.step(hand[-1], False)
    hand.append(hand[-1] + v * dt * 0.9)  # decelerate: a_z = -0.1 v_z / dt = -16 m/s^2
    state = world.step(hand[-1], True)
    assert state.released and not state.held
    p0, v0 = state.ball_pos.copy(), state.ball_vel.copy()
    np.testing.assert_allclose(v0, v * 0.9)  # the hand's velocity at the release
    sol = solve_ivp(
        lambda t, y: [y[2], y[3], 0.0, -task.gravity],
        (0, 1.2),
        [*p0, *v0],
        t_eval=np.arange(1, 241) * dt,
        rtol=1e-12,
        atol=1e-12,
    )
    far = np.array([2.0, 2.0])  # hand parked away: no catch
    for k in range(240):
        state = world.step(far, False)
        np.testing.assert_allclose(state.ball_pos, sol.y[:2, k], atol=1e-6)
        np.testing.assert_allclose(state.ball_vel, sol.y[2:, k], atol=1e-6)
    assert not state.caught


def test_world_catch_drop_and_bad_input():
    task = JugglingTask()
    world = BallisticWorld(task)
    world.reset([0.0, 1.0])
    world.step([0.0, 1.005], False)
    state = world.step([0.0, 1.006], True)  # a_z = (1e-3 - 5e-3) / dt^2 = -160
    assert state.released
    s = world.step([0.3, 1.0], False)  # leave the radius
    assert not s.caught
    # put the hand on the ball's next position: caught, held again
    nxt = ballistic_position(state.ball_pos, state.ball_vel, 2 * task.dt, task.gravity)
    s = world.step(nxt + np.array([0.0, 0.01]), False)
    assert s.caught and s.held
    np.testing.assert_allclose(s.ball_pos, s.hand_pos)
    with pytest.raises(ValueError, match="hand_target"):
        world.step([np.nan, 1.0], False)
    with pytest.raises(ValueError, match=r"shape \(2,\)"):
        world.step([1.0, 2.0, 3.0], False)
    # a dropped ball
    world.reset([0.0, 1.0])
    world.step([0.0, 1.005], False)
    world.step([0.0, 1.006], True)
    for _ in range(400):
        s = world.step([1.0, 1.0], False)
    assert s.dropped and s.ball_pos[1] < task.floor_z


def test_eq9_toss_ends_with_zero_vertical_velocity(juggler):
    state = BallisticWorld(juggler.task).reset(juggler.home_)
    juggler.reset(state, np.random.default_rng(0))
    phase, _, duration, p = juggler.plans[0]
    assert phase == "toss"
    v_end = ss.velocity(p, np.array([1.0]), duration)[0]
    assert abs(v_end[1]) < 1e-9
    # from a training release point, the unconstrained plan would not stop: eq. 9 acts
    fit = juggler.phases_["toss"]
    start, end = p[0], fit.model.conditions_[0, 2:] - [0.0, 0.1]
    q = np.concatenate([start, end])
    free = fit.model.plan(q, duration, start, end)
    assert abs(ss.velocity(free, np.array([1.0]), duration)[0][1]) > 1e-2
    held = fit.model.plan(q, duration, start, end, final_velocity=np.zeros(2), axes=[1])
    assert abs(ss.velocity(held, np.array([1.0]), duration)[0][1]) < 1e-9
    np.testing.assert_allclose(held[0], start)  # the start does not move


def test_catch_planner_hits_a_known_flight():
    g = 1.0
    p0, v0 = np.array([0.1, 1.3]), np.array([-0.3, 0.4])
    t_best, end = plan_catch(np.zeros(2), p0, v0, g, (0.7, 0.9), np.array([-0.1, 1.2]))
    # independent closed form of the flight at t_best
    exact = np.array([p0[0] + v0[0] * t_best, p0[1] + v0[1] * t_best - g * t_best**2 / 2])
    np.testing.assert_allclose(end, exact, atol=1e-6)
    assert 0.7 <= t_best <= 0.9


def test_juggler_catch_plan_reaches_the_ball(juggler):
    """Unperturbed: the catch plan's end point is where the ball is at t0 + T (1e-6 m)."""
    world = BallisticWorld(juggler.task)
    res = run_cycle(juggler, world, JugglingNoise(), cycle_rngs(5, 1)[0], record=True)
    assert res.caught
    catch = next(p for p in juggler.plans if p[0] == "catch")
    _, t0, duration, coef = catch
    release = np.flatnonzero(res.phase == "go_down")[0]  # first go-down sample
    k_rel = release - 1  # the world released at the last toss step
    t_rel = res.times[k_rel]
    ball_at_end = ballistic_position(
        res.ball[k_rel], res.release_velocity, t0 + duration - t_rel, juggler.task.gravity
    )
    np.testing.assert_allclose(coef[0] + coef[1], ball_at_end, atol=1e-6)
    assert juggler.corrections == []  # nothing to correct without noise


def test_eq10_correction_retargets_the_catch(juggler):
    noise = JugglingNoise(release=0.1)
    rngs = cycle_rngs(11, 30)
    world = BallisticWorld(juggler.task)
    with_c = [run_cycle(juggler, world, noise, r) for r in cycle_rngs(11, 30)]
    assert sum(r.corrections for r in with_c) > 0
    off = juggler.variant(correction=False)
    without = [run_cycle(off, world, noise, r) for r in rngs]
    assert juggler.correction and off.model is juggler.model  # shared, unchanged
    assert np.mean([r.caught for r in with_c]) >= np.mean([r.caught for r in without])
    assert np.mean([r.caught for r in with_c]) >= 0.95


def test_correction_plan_meets_the_observed_intercept(juggler):
    noise = JugglingNoise(release=0.1)
    world = BallisticWorld(juggler.task)
    for rngs in cycle_rngs(2, 10):
        res = run_cycle(juggler, world, noise, rngs, record=True)
        if not juggler.corrections:
            continue
        t_fix, _ = juggler.corrections[0]
        k = round(t_fix / juggler.task.dt)
        plan = juggler.episode  # the cycle's controller: its current (corrected) plan
        s = plan.t_start + plan.duration - res.times[k]
        target = ballistic_position(res.ball[k], _vel(res, k), s, juggler.task.gravity)
        np.testing.assert_allclose(plan.end, target, atol=1e-9)
        p = plan.coefficients
        np.testing.assert_allclose(p[0] + p[1], plan.end, atol=1e-9)
        return
    pytest.fail("no correction happened in 10 noisy cycles")


def _vel(res, k):
    """Ball velocity at sample k: central difference, exact on the recorded parabola."""
    return (res.ball[k + 1] - res.ball[k - 1]) / (2 * 0.005)


def test_fast_runner_equals_the_step_by_step_runner(juggler):
    for noise in (JugglingNoise(), JugglingNoise(release=0.1, tracking=5e-4)):
        for corr in (True, False):
            variant = juggler.variant(correction=corr)
            a = run_cycles(variant, 25, noise, seed=4)
            b = run_cycles_fast(variant, 25, noise, seed=4)
            for x, y in zip(a, b, strict=True):
                assert (x.caught, x.dropped, x.released, x.steps, x.corrections) == (
                    y.caught,
                    y.dropped,
                    y.released,
                    y.steps,
                    y.corrections,
                )
                np.testing.assert_allclose(x.release_velocity, y.release_velocity, atol=1e-12)


def test_runs_are_deterministic_under_a_seed(juggler):
    noise = JugglingNoise(release=0.05, tracking=5e-4)
    a = run_cycles_fast(juggler, 40, noise, seed=9)
    b = run_cycles_fast(juggler, 40, noise, seed=9)
    assert [r.steps for r in a] == [r.steps for r in b]
    c = run_cycles_fast(juggler, 40, noise, seed=10)
    assert [r.steps for r in a] != [r.steps for r in c]


def test_minimum_jerk_closed_form():
    tau = np.linspace(0, 1, 11)
    y = minimum_jerk([0.0, 1.0], [1.0, 3.0], tau)
    np.testing.assert_allclose(y[[0, -1]], [[0, 1], [1, 3]])
    np.testing.assert_allclose(y[5], [0.5, 2.0])  # symmetric profile
    # oracle: the quintic with rest end states (solved as a linear system)
    from motion_envs.geometry.minimum_jerk import quintic

    z = np.zeros(2)
    c = quintic(np.array([0.0, 1.0]), z, z, np.array([1.0, 3.0]), z, z, 1.0)
    np.testing.assert_allclose(y, np.vander(tau, 6, increasing=True) @ c, atol=1e-12)


def test_unfitted_juggler_raises():
    with pytest.raises(ValueError, match="not fitted"):
        AnalyticJuggler().reset(BallisticWorld().reset([0.2, 1.0]))


def test_real_gravity_is_the_same_gesture_faster():
    """Under 9.81 m/s^2 the person's movements are time-scaled; the juggler still catches."""
    from motion_envs.models.juggling import fit_juggler

    task = JugglingTask(gravity=9.81)
    assert task.toss_threshold == pytest.approx(3.0 * 9.81)
    demos = generate_demonstrations(n_cycles=30, seed=1, task=task)
    lengths = [len(s.times) for s in demos.segments("toss")]
    assert 40 <= np.median(lengths) <= 80  # about sqrt(1 / 9.81) of the default sizes
    juggler, train, test = fit_juggler(demos, seed=0, n_sines=6)
    assert not train & test
    res = run_cycles_fast(juggler, 50, JugglingNoise(), seed=0)
    assert np.mean([r.caught for r in res]) >= 0.95


def test_juggler_pickles_mid_cycle(juggler):
    """Juggling-v0 pickles its juggler: a copy taken mid-cycle continues identically."""
    import pickle

    world = BallisticWorld(juggler.task)
    state = world.reset(juggler.home_)
    juggler.reset(state, np.random.default_rng(3))
    for _ in range(250):  # into the go-down phase
        state = world.step(*juggler.command(state))
    twin = pickle.loads(pickle.dumps(juggler))
    world2 = pickle.loads(pickle.dumps(world))
    s1, s2 = state, state
    for _ in range(200):
        t1, a1 = juggler.command(s1)
        t2, a2 = twin.command(s2)
        np.testing.assert_array_equal(t1, t2)
        assert a1 == a2
        s1, s2 = world.step(t1, a1), world2.step(t2, a2)
    assert juggler.phase == twin.phase
