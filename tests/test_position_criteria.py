"""Position error criteria against closed forms and a brute-force DTW."""

from __future__ import annotations

import functools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from motion_envs.models import position_criteria as pc


def _brute_dtw(y, p):
    @functools.cache
    def c(i, j):
        d = float(np.linalg.norm(y[i] - p[j]))
        if i == 0 and j == 0:
            return d
        options = []
        if i > 0:
            options.append(c(i - 1, j))
        if j > 0:
            options.append(c(i, j - 1))
        if i > 0 and j > 0:
            options.append(c(i - 1, j - 1))
        return d + min(options)

    return c(len(y) - 1, len(p) - 1)


def test_parallel_lines_closed_forms():
    t = np.linspace(0, 2, 21)
    y = np.column_stack([t, np.zeros_like(t)])
    p = np.column_stack([t, np.full_like(t, 0.5)])
    assert pc.max_error(y, p) == pytest.approx(0.5)
    assert pc.rmse(y, p) == pytest.approx(0.5)
    assert pc.swept_error_area(y, p) == pytest.approx(1.0)  # 2 x 0.5 rectangle
    assert pc.dtw_distance(y, p) == pytest.approx(21 * 0.5)  # diagonal path
    # 3-D: the same rectangle tilted out of the plane keeps its area
    y3 = np.column_stack([t, np.zeros_like(t), np.zeros_like(t)])
    p3 = np.column_stack([t, np.full_like(t, 0.3), np.full_like(t, 0.4)])
    assert pc.swept_error_area(y3, p3) == pytest.approx(1.0)


def test_triangle_closed_form_area():
    # the curves meet at both ends: area of triangle (0,0), (1,0), (0.5, 1) split in steps
    y = np.array([[0.0, 0.0], [0.5, 0.0], [1.0, 0.0]])
    p = np.array([[0.0, 0.0], [0.5, 1.0], [1.0, 0.0]])
    assert pc.swept_error_area(y, p) == pytest.approx(0.5)


@settings(max_examples=20, deadline=None)
@given(seed=st.integers(0, 10_000), k=st.integers(2, 7))
def test_dtw_matches_brute_force(seed, k):
    rng = np.random.default_rng(seed)
    y = rng.normal(size=(k, 2))
    p = rng.normal(size=(k, 2))
    assert pc.dtw_distance(y, p) == pytest.approx(_brute_dtw(y, p), rel=1e-12)
    batched = pc.dtw_distance(np.stack([y, p]), np.stack([p, y]))
    np.testing.assert_allclose(batched, [_brute_dtw(y, p), _brute_dtw(p, y)], rtol=1e-12)


def test_dtw_of_time_shift_is_below_pointwise():
    t = np.linspace(0, 1, 50)
    y = np.column_stack([np.sin(2 * np.pi * t), t])
    assert pc.dtw_distance(y, y) == 0.0
    assert pc.dtw_distance(y[:-1], y[1:]) < np.sum(np.linalg.norm(y[:-1] - y[1:], axis=1))


def test_bad_input():
    with pytest.raises(ValueError, match="same shape"):
        pc.rmse(np.zeros((3, 2)), np.zeros((4, 2)))
    with pytest.raises(ValueError, match="NaN"):
        pc.max_error(np.zeros((3, 2)), np.full((3, 2), np.nan))
