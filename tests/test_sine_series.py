"""Sine-series basis, DST and least-squares coefficients against closed forms."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from motion_envs.geometry import sine_series as ss


def test_basis_closed_form_values():
    phi = ss.basis([0.0, 0.5, 1.0], 3)
    expected = np.array(
        [
            [1.0, 0.0, 0.0, 0.0, 0.0],
            [1.0, 0.5, 1.0, 0.0, -1.0],
            [1.0, 1.0, 0.0, 0.0, 0.0],
        ]
    )
    np.testing.assert_allclose(phi, expected, atol=1e-15)
    dphi = ss.basis_derivative([0.0, 1.0], 3)
    np.testing.assert_allclose(
        dphi,
        [[0, 1, np.pi, 2 * np.pi, 3 * np.pi], [0, 1, -np.pi, 2 * np.pi, -3 * np.pi]],
        atol=1e-12,
    )


def test_derivatives_match_finite_differences():
    tau = np.linspace(0.05, 0.95, 7)
    h = 1e-6
    fd = (ss.basis(tau + h, 4) - ss.basis(tau - h, 4)) / (2 * h)
    np.testing.assert_allclose(ss.basis_derivative(tau, 4), fd, atol=1e-7)
    fd2 = (ss.basis_derivative(tau + h, 4) - ss.basis_derivative(tau - h, 4)) / (2 * h)
    np.testing.assert_allclose(ss.basis_second_derivative(tau, 4), fd2, atol=1e-5)


def test_dst_scaling_closed_form():
    # Y = 3 + 2 tau + sin(2 pi tau) - 0.5 sin(5 pi tau): P = [3, 2, 0, 1, 0, 0, -0.5, 0]
    m = 40
    tau = np.linspace(0, 1, m + 1)
    y = (3 + 2 * tau + np.sin(2 * np.pi * tau) - 0.5 * np.sin(5 * np.pi * tau))[:, None]
    p = ss.dst_coefficients(y, 6)
    np.testing.assert_allclose(p[:, 0], [3, 2, 0, 1, 0, 0, -0.5, 0], atol=1e-12)
    np.testing.assert_allclose(ss.evaluate(p, tau), y, atol=1e-12)


def test_dst_hand_worked_three_interior_points():
    # M = 4, D = [0, 1, 2, 1, 0] (linear part zero): b_n = (2/4) sum_k D_k sin(n pi k/4)
    y = np.array([[0.0], [1.0], [2.0], [1.0], [0.0]])
    s = np.sqrt(0.5)
    b1 = 0.5 * (s + 2 + s)
    b2 = 0.5 * (1 + 0 - 1)
    b3 = 0.5 * (s - 2 + s)
    p = ss.dst_coefficients(y, 3)
    np.testing.assert_allclose(p[2:, 0], [b1, b2, b3], atol=1e-14)
    # full set (N = M - 1) interpolates every sample
    np.testing.assert_allclose(ss.evaluate(p, np.linspace(0, 1, 5)), y, atol=1e-14)


@settings(max_examples=30, deadline=None)
@given(
    m=st.integers(min_value=3, max_value=40),
    frac=st.floats(min_value=0.0, max_value=1.0),
    seed=st.integers(min_value=0, max_value=2**31 - 1),
    dims=st.integers(min_value=1, max_value=3),
)
def test_dst_equals_least_squares_on_uniform_samples(m, frac, seed, dims):
    rng = np.random.default_rng(seed)
    n = round(frac * (m - 1))
    y = rng.normal(size=(2, m + 1, dims))
    tau = np.linspace(0, 1, m + 1)
    np.testing.assert_allclose(
        ss.dst_coefficients(y, n), ss.lstsq_coefficients(tau, y, n), atol=1e-9
    )


def test_least_squares_on_nonuniform_samples_recovers_series():
    rng = np.random.default_rng(1)
    tau = np.concatenate([[0.0], np.sort(rng.uniform(0, 1, 50)), [1.0]])
    p_true = rng.normal(size=(7, 3))
    y = ss.evaluate(p_true, tau)
    assert not ss.is_uniform(tau)
    np.testing.assert_allclose(ss.fit_coefficients(tau, y, 5), p_true, atol=1e-10)


def test_velocity_scales_with_duration():
    p = np.array([[0.0], [1.0], [0.5]])
    v = ss.velocity(p, [1.0], duration=2.0)
    np.testing.assert_allclose(v, [[(1.0 - 0.5 * np.pi) / 2.0]], atol=1e-14)


def test_odd_extension_period_two():
    # The series with these coefficients reproduces the odd period-2 extension -D(2 - tau).
    p = np.array([[0.0], [0.0], [0.7], [-0.2], [0.1]])
    tau = np.linspace(0, 1, 9)
    d = ss.evaluate(p, tau)[:, 0]
    ext = ss.evaluate(p, 2 - tau)[:, 0]
    np.testing.assert_allclose(ext, -d, atol=1e-14)


def test_bad_input():
    with pytest.raises(ValueError, match="n_sines"):
        ss.dst_coefficients(np.zeros((5, 1)), 4)
    with pytest.raises(ValueError, match="NaN"):
        ss.dst_coefficients(np.array([[0.0], [np.nan], [1.0], [2.0]]), 1)
    with pytest.raises(ValueError, match="cannot determine"):
        ss.lstsq_coefficients([0.0, 0.5, 1.0], np.zeros((3, 1)), 2)
    with pytest.raises(ValueError, match="strictly increasing"):
        ss.normalised_time([0.0, 1.0, 1.0])
    with pytest.raises(ValueError, match="n_sines"):
        ss.basis([0.5], -1)
