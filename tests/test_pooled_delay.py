"""The pooled release-anchored delay (:func:`pooled_flight_delay`): the parabola's vertex
against a hand-worked quadratic, the pooled curve against each flight's, the estimate
against an independent oracle (per flight numpy's least squares of the velocity, the
joint residual minimised by scipy's bounded scalar minimiser and on a 0.05 ms brute-force
grid), a hypothesis property over random flight sets, and the rule as the envs use it."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from _helpers import P0, T_R, G, release_frames
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import minimize_scalar

import motion_envs  # noqa: F401  (registers the ids)
from motion_envs.models.juggling import (
    DELAY_GRID,
    mean_flight_delay,
    parabolic_minimum,
    pooled_flight_delay,
    pooled_residuals,
    release_residuals,
)

H = 0.005  # the grid step


def _flight(
    delay: float, n: int, v: tuple[float, float] = (-0.8, 3.5), noise: float = 0.0,
    rng: np.random.Generator | None = None, start: float = 0.01,
) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """An anchored flight of ``n`` frames captured every 10 ms from ``start`` s after the
    release at velocity ``v``, arriving ``delay`` s later, with white noise (m)."""
    s = start + 0.01 * np.arange(n)
    q = np.stack([v[0] * s, v[1] * s - 0.5 * G * s * s], axis=1)
    if noise:
        assert rng is not None
        q = q + rng.normal(0.0, noise, q.shape)
    return s + delay, q


def _joint_residual(flights: list[tuple[np.ndarray, np.ndarray]], d: float) -> float:
    """The oracle: per flight numpy's least squares of ``y = v s`` (s = arrival - d),
    summed; inf where a frame would precede its release."""
    total = 0.0
    for s0, q in flights:
        s = s0 - d
        if (s <= 0).any():
            return np.inf
        y = q + np.stack([np.zeros_like(s), 0.5 * G * s * s], axis=1)
        v, *_ = np.linalg.lstsq(s[:, None], y, rcond=None)
        total += float(((y - s[:, None] * v) ** 2).sum())
    return total


def _oracle(flights: list[tuple[np.ndarray, np.ndarray]]) -> float:
    """The joint residual's minimiser: a 0.05 ms brute-force grid, then scipy's bounded
    minimiser within one fine step of its best point."""
    fine = np.arange(0.0, 0.4, 0.00005)
    values = np.array([_joint_residual(flights, d) for d in fine])
    best = float(fine[int(np.argmin(values))])
    got = minimize_scalar(lambda d: _joint_residual(flights, d),
                          bounds=(best - 0.00005, best + 0.00005), method="bounded",
                          options={"xatol": 1e-8})  # fmt: skip
    return float(got.x)


# -- the parabola -------------------------------------------------------------------------
def test_the_vertex_of_a_sampled_parabola_is_found_exactly_hand_worked() -> None:
    # R(d) = 3 (d - 0.1234)^2 + 1: least grid point 0.125, neighbours 0.120 and 0.130;
    # R = 1 + 3 (0.0034^2, 0.0016^2, 0.0066^2); the vertex 0.125 + 0.0025 (R- - R+) /
    # (R- - 2 R0 + R+) = 0.125 + 0.0025 (0.00001156 - 0.00004356) / 0.00005 = 0.1234.
    values = 3.0 * (DELAY_GRID - 0.1234) ** 2 + 1.0
    assert parabolic_minimum(DELAY_GRID, values) == pytest.approx(0.1234, abs=1e-12)


def test_the_grid_point_stands_at_an_end_next_to_inf_or_on_a_flat() -> None:
    grid = np.array([0.0, 0.005, 0.01, 0.015])
    assert parabolic_minimum(grid, np.array([1.0, 2.0, 3.0, 4.0])) == 0.0
    assert parabolic_minimum(grid, np.array([4.0, 3.0, 2.0, 1.0])) == 0.015
    assert parabolic_minimum(grid, np.array([2.0, 1.0, np.inf, np.inf])) == 0.005
    assert parabolic_minimum(grid, np.array([2.0, 2.0, 2.0, 2.0])) == 0.0
    assert parabolic_minimum(grid, np.full(4, np.inf)) is None


def test_a_bad_grid_is_a_one_line_error() -> None:
    with pytest.raises(ValueError, match="grid and values") as err:
        parabolic_minimum(np.arange(3.0), np.arange(4.0))
    assert "\n" not in str(err.value)


# -- the pooled curve -----------------------------------------------------------------------
def test_the_pooled_curve_is_the_sum_of_the_flights_without_the_impossible_ones() -> None:
    rng = np.random.default_rng(0)
    a = _flight(0.13, 8, noise=0.004, rng=rng)
    b = _flight(0.13, 12, v=(0.6, 4.0), noise=0.004, rng=rng)
    never = (a[0] - 1.0, a[1])  # every frame before its release
    got = pooled_residuals([a, never, b], G)
    assert got is not None
    want = release_residuals(*a, G) + release_residuals(*b, G)
    np.testing.assert_array_equal(np.isinf(got), np.isinf(want))
    ok = np.isfinite(want)
    np.testing.assert_allclose(got[ok], want[ok], rtol=1e-12)
    assert pooled_residuals([never], G) is None and pooled_flight_delay([never], G) is None
    assert pooled_flight_delay([], G) is None


def test_a_flight_bounds_the_delay_by_its_first_arrival() -> None:
    s0, q = _flight(0.13, 8)
    r = release_residuals(s0, q, G)
    assert np.isinf(r[DELAY_GRID >= s0[0]]).all() and np.isfinite(r[DELAY_GRID < s0[0]]).all()


# -- the estimate against the oracle ------------------------------------------------------
@pytest.mark.parametrize("delay", [0.1327, 0.145, 0.1913])
def test_noiseless_flights_give_their_delay_below_the_grid(delay: float) -> None:
    flights = [_flight(delay, 8), _flight(delay, 8, v=(0.7, 4.2)), _flight(delay, 16)]
    assert _oracle(flights) == pytest.approx(delay, abs=2e-6)  # the oracle finds it
    got = pooled_flight_delay(flights, G)
    assert got is not None and abs(got - delay) < 0.5e-3  # the parabola's own error
    # through the estimator's path too (release_frames: a known flight, 10 ms frames)
    frames = release_frames(delay, 8)
    s0 = np.array([f.arrival - T_R for f in frames])
    q = np.array([[f.x - P0[0], f.z - P0[1]] for f in frames])
    single = pooled_flight_delay([(s0, q)], G)
    assert single is not None and abs(single - delay) < 0.5e-3


@pytest.mark.parametrize("seed", range(6))
def test_noisy_flights_match_the_joint_least_squares_oracle(seed: int) -> None:
    rng = np.random.default_rng(seed)
    delay = float(rng.uniform(0.1, 0.25))
    flights = [
        _flight(delay + float(rng.normal(0, 0.003)), int(rng.integers(6, 17)),
                v=(float(rng.uniform(-1.5, 1.5)), float(rng.uniform(3.0, 5.0))),
                noise=0.004, rng=rng, start=float(rng.uniform(0.0, 0.06)) + 0.005)
        for _ in range(int(rng.integers(1, 6)))
    ]  # fmt: skip
    got = pooled_flight_delay(flights, G)
    assert got is not None
    # the parabola through three 5 ms points of a curve that is not exactly quadratic:
    # within 1 ms of the exact minimiser (the grid alone: up to 2.5 ms)
    assert abs(got - _oracle(flights)) < 1e-3


@settings(max_examples=40, deadline=None)
@given(
    delay=st.floats(0.08, 0.3),
    n=st.lists(st.integers(4, 16), min_size=1, max_size=5),
    noise=st.floats(0.0, 0.01),
    seed=st.integers(0, 2**31 - 1),
)
def test_property_the_estimate_lies_within_half_a_step_of_the_pooled_grid_minimum(
    delay: float, n: list[int], noise: float, seed: int
) -> None:
    """Whatever the flights: within ``h / 2`` of the brute-force joint residual's best
    5 ms grid point, the same for the flights in any order, and for one flight within
    ``h / 2`` of the default rule's grid delay."""
    rng = np.random.default_rng(seed)
    flights = [
        _flight(delay, k, v=(float(rng.uniform(-1.5, 1.5)), float(rng.uniform(3.0, 5.0))),
                noise=noise, rng=rng)
        for k in n
    ]  # fmt: skip
    got = pooled_flight_delay(flights, G)
    assert got is not None
    brute = np.array([_joint_residual(flights, d) for d in DELAY_GRID])
    best = float(DELAY_GRID[int(np.argmin(brute))])
    assert abs(got - best) <= H / 2 + 1e-12
    again = pooled_flight_delay(flights[::-1], G)
    assert again == pytest.approx(got, abs=1e-9)
    one = pooled_flight_delay(flights[:1], G)
    default = mean_flight_delay(flights[:1], G)
    assert one is not None and default is not None and abs(one - default) <= H / 2 + 1e-12


# -- the rule in the envs --------------------------------------------------------------------
def test_the_pooled_rule_places_cascade_v1s_frames() -> None:
    env = gym.make("MotionEnvs/Cascade-v1", level="medium", pattern="3", max_catches=4,
                   controller="juggler_delay_estimator_catch", delay_rule=pooled_flight_delay,
                   anchor_frames=12)  # fmt: skip
    env.reset(seed=3)
    done = False
    while not done:  # the episode's anchors stay in the view until the next reset
        _, _, te, tr, _ = env.step(np.zeros(env.action_space.shape, np.float32))
        done = te or tr
    view = env.unwrapped.view  # type: ignore[attr-defined]
    assert len(view.anchors) >= 2 and all(len(s0) == 12 for s0, _ in view.anchors)
    got = view.delay_estimate
    assert got == pooled_flight_delay(view.anchors, 9.81)
    assert abs(got - env.unwrapped.delay) < 0.03  # type: ignore[attr-defined]
    assert not np.isclose(got % H, 0.0) and not np.isclose(got % H, H)  # below the grid
