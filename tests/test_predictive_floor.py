"""The predictive floor (motion_envs.models.criteria) on hand-worked cases: each reach
predicted from the other replicates of its person and task, in the body frame and in the
path frame, and the replicate-count correction."""

from __future__ import annotations

import math

import numpy as np
import pytest

from motion_envs.models.criteria import (
    predictive_floor_errors,
    replicate_loo_errors,
    within_subject_error,
)


def _constant(vectors: list[tuple[float, float, float]], n: int = 5) -> np.ndarray:
    return np.repeat(np.asarray(vectors, dtype=np.float64)[:, None, :], n, axis=1)


def test_leave_one_out_by_hand():
    # person p, task A: x = 0, 1, 2 on the first axis; task B: (0, 0, 0) and (0, 3, 0);
    # task C: a single reach (left out)
    R = _constant([(0, 0, 0), (1, 0, 0), (2, 0, 0), (0, 0, 0), (0, 3, 0), (5, 5, 5)])
    subjects = ["p"] * 6
    tasks = ["A", "A", "A", "B", "B", "C"]
    loo, sizes = replicate_loo_errors(R, subjects, tasks)
    # reach 0 against (1 + 2) / 2, reach 1 against (0 + 2) / 2, reach 2 against 0.5
    np.testing.assert_allclose(loo[:5], [1.5, 0.0, 1.5, 3.0, 3.0])
    assert math.isnan(loo[5]) and sizes.tolist() == [3, 3, 3, 2, 2, 1]
    loo2, floor = predictive_floor_errors(R, subjects, tasks)
    np.testing.assert_allclose(loo2, loo)
    root = [math.sqrt(2 / 3)] * 3 + [math.sqrt(1 / 2)] * 2
    np.testing.assert_allclose(floor[:5], loo[:5] * np.array(root))
    # the paper's in-sample row is (n - 1) / n of the leave-one-out deviation
    in_sample = [1.0, 0.0, 1.0, 1.5, 1.5]
    assert within_subject_error(R, subjects, tasks) == np.median(in_sample)
    assert np.nanmedian(loo) == 1.5 and np.nanmedian(floor) == pytest.approx(1.5 * root[0])


def _about(axis: str, angle: float) -> np.ndarray:
    half = angle / 2
    v = {"x": (1, 0, 0), "y": (0, 1, 0)}[axis]
    return np.array([math.cos(half), *(math.sin(half) * np.array(v))])


def test_path_frame_leave_one_out_by_hand():
    """Reach 1 turns 0.4 rad about x, reach 2 0.8 rad about y (up = z). Path frames
    (axis, up, axis x up): F1 = [x, z, -y], F2 = [y, z, x]. Residuals r1 = 0.4 x (path
    (1, 0, 0)) and r2 = 0.8 z (path (0, 1, 0)). Path-frame prediction of reach 1 from
    reach 2: 0.4 F1 (0, 1, 0) = 0.4 z, error 0.4 sqrt(2); of reach 2: 0.8 F2 (1, 0, 0) =
    0.8 y, error 0.8 sqrt(2). Body frame: |0.4 x - 0.8 z| for both."""
    t1, t2 = 0.4, 0.8
    R = _constant([(t1, 0, 0), (0, 0, t2)])
    starts = np.array([[1.0, 0, 0, 0]] * 2)
    ends = np.stack([_about("x", t1), _about("y", t2)])
    frame = (starts, ends, np.array([0.0, 0.0, 1.0]))
    loo, floor = predictive_floor_errors(R, ["p", "p"], ["A", "A"], frame)
    np.testing.assert_allclose(loo, [t1 * math.sqrt(2), t2 * math.sqrt(2)], atol=1e-12)
    np.testing.assert_allclose(floor, loo / math.sqrt(2))
    body, _ = predictive_floor_errors(R, ["p", "p"], ["A", "A"])
    np.testing.assert_allclose(body, [math.hypot(t1, t2)] * 2)


def test_floor_correction_recovers_the_noise_of_a_known_mean():
    """Gaussian replicates around a mean known to the oracle: the corrected floor's median
    is the median max error of predicting each reach by the true mean; the uncorrected
    leave-one-out is above it, the in-sample row below."""
    rng = np.random.default_rng(0)
    n_groups, n = 4000, 3
    means = rng.normal(0.0, 1.0, (n_groups, 1, 6, 3))
    noise = rng.normal(0.0, 0.1, (n_groups, n, 6, 3))
    R = (means + noise).reshape(-1, 6, 3)
    groups = np.repeat(np.arange(n_groups), n).astype(str)
    truth = np.median(np.linalg.norm(noise, axis=-1).max(axis=-1))
    loo, floor = predictive_floor_errors(R, groups, ["t"] * groups.size)
    assert np.median(floor) == pytest.approx(truth, rel=0.02)
    assert np.median(loo) > 1.1 * truth > 1.2 * within_subject_error(R, groups, ["t"] * groups.size)
