"""Bézier curves with end points at the origin."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from motion_envs.geometry import bezier

GRID = np.linspace(0, 1, 50)


def de_casteljau(points: np.ndarray, t: float) -> np.ndarray:
    """Independent oracle: repeated linear interpolation of the full control polygon."""
    pts = points.copy()
    while len(pts) > 1:
        pts = (1 - t) * pts[:-1] + t * pts[1:]
    return pts[0]


@settings(max_examples=50, deadline=None)
@given(st.integers(2, 7), st.data())
def test_evaluate_matches_de_casteljau(degree, data):
    P = data.draw(arrays(np.float64, (degree - 1, 3), elements=st.floats(-2, 2)))
    full = np.vstack([np.zeros(3), P, np.zeros(3)])
    ours = bezier.evaluate(P, GRID)
    ref = np.stack([de_casteljau(full, t) for t in GRID])
    np.testing.assert_allclose(ours, ref, atol=1e-12)
    np.testing.assert_array_equal(ours[[0, -1]], 0.0)


def test_quadratic_passes_through_half_control_point():
    # d = 2: the residual reaches P1/2 at t = 1/2 (Faraway & Choe, section 3.4)
    P = np.array([[0.4, -0.2, 0.6]])
    np.testing.assert_allclose(bezier.evaluate(P, [0.5]), [[0.2, -0.1, 0.3]])


def test_bernstein_interior_hand_worked():
    B = bezier.bernstein_interior([0.25], 3)
    np.testing.assert_allclose(B, [[3 * 0.25 * 0.75**2, 3 * 0.25**2 * 0.75]])
    assert bezier.bernstein_interior(GRID, 1).shape == (50, 0)


@settings(max_examples=30, deadline=None)
@given(st.integers(2, 6), st.data())
def test_fit_recovers_exact_curves_batched(degree, data):
    P = data.draw(arrays(np.float64, (4, 2, degree - 1, 3), elements=st.floats(-1, 1)))
    curves = bezier.evaluate(P, GRID)
    np.testing.assert_allclose(bezier.fit(curves, GRID, degree), P, atol=1e-9)


def test_fit_equals_per_curve_lstsq():
    rng = np.random.default_rng(0)
    curves = rng.normal(size=(20, 50, 3))
    curves[:, [0, -1]] = 0
    B = np.array([[math.comb(3, i) * t**i * (1 - t) ** (3 - i) for i in (1, 2)] for t in GRID])
    ref = np.stack([np.linalg.lstsq(B, c, rcond=None)[0] for c in curves])
    np.testing.assert_allclose(bezier.fit(curves, GRID, 3), ref, atol=1e-12)


def test_mean_of_fits_is_fit_of_mean():
    rng = np.random.default_rng(1)
    curves = rng.normal(size=(30, 50, 3))
    np.testing.assert_allclose(
        bezier.fit(curves, GRID, 4).mean(axis=0), bezier.fit(curves.mean(axis=0), GRID, 4)
    )


@pytest.mark.parametrize("degree", [0, -1, 2.5, True])
def test_bad_degree(degree):
    with pytest.raises(ValueError, match="degree"):
        bezier.bernstein_interior(GRID, degree)


def test_bad_shapes_and_values():
    with pytest.raises(ValueError, match="curves"):
        bezier.fit(np.zeros((3, 49, 3)), GRID, 2)
    with pytest.raises(ValueError, match="curves"):
        bezier.fit(np.full((3, 50, 3), np.nan), GRID, 2)
    with pytest.raises(ValueError, match="control_points"):
        bezier.evaluate(np.zeros(3), GRID)
    with pytest.raises(ValueError, match="degree 5 needs"):
        bezier.fit_operator(np.array([0.0, 0.5, 1.0]), 5)
