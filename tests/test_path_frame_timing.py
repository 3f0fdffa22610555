"""Path frame (exact inverse, degenerate cases, scipy oracle) and the speed-profile model."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from scipy.special import betainc

from motion_envs.geometry import quaternion as quat
from motion_envs.models.bezier_models import NullBezierModel, TaskBezierModel
from motion_envs.models.estimator import NotFittedError
from motion_envs.models.path_frame import MIN_SCALE, from_path_frame, path_frames, to_path_frame
from motion_envs.models.serialization import load_model
from motion_envs.models.timing_model import SpeedProfileModel, timing_features


def _random_pairs(rng: np.random.Generator, L: int) -> tuple[np.ndarray, np.ndarray]:
    starts = quat.from_rotation(Rotation.random(L, random_state=rng.integers(1 << 30)))
    rel = rng.normal(size=(L, 3))
    rel *= rng.uniform(0.05, 2.5, size=(L, 1)) / np.linalg.norm(rel, axis=1, keepdims=True)
    return starts, quat.multiply(starts, quat.expmap(rel))


def test_path_frame_inverse_is_exact_and_orthonormal():
    rng = np.random.default_rng(0)
    S, E = _random_pairs(rng, 200)
    R = rng.normal(scale=0.2, size=(200, 50, 3))
    up = (0.3, 1.0, -0.2)
    back = from_path_frame(to_path_frame(R, S, E, up), S, E, up)
    assert np.max(np.abs(back - R)) < 1e-12
    F, _ = path_frames(S, E, up)
    assert np.allclose(np.einsum("lji,ljk->lik", F, F), np.eye(3), atol=1e-12)
    assert np.allclose(np.linalg.det(F), 1.0)


def test_path_frame_axes_match_scipy_oracle():
    rng = np.random.default_rng(1)
    S, E = _random_pairs(rng, 50)
    up = np.array([0.0, 0.0, 1.0])
    F, s = path_frames(S, E, up)
    rs = Rotation.from_quat(S[:, [1, 2, 3, 0]])
    re = Rotation.from_quat(E[:, [1, 2, 3, 0]])
    rotvec = (rs.inv() * re).as_rotvec()
    angle = np.linalg.norm(rotvec, axis=1)
    assert np.allclose(s, angle, atol=1e-12)
    assert np.allclose(F[:, :, 0], rotvec / angle[:, None], atol=1e-10)
    up_body = rs.inv().apply(up)
    # u is up made perpendicular to the axis, with a positive up component
    assert np.allclose(np.einsum("li,li->l", F[:, :, 1], F[:, :, 0]), 0.0, atol=1e-12)
    assert np.all(np.einsum("li,li->l", F[:, :, 1], up_body) > 0)


def test_path_frame_near_zero_rotation_and_vertical_axis():
    S = quat.expmap(np.array([[0.3, -0.2, 0.1]] * 4))
    tiny = quat.expmap(np.array([[0, 0, 0], [1e-12, 0, 0], [0, 1e-7, 0], [0, 0, 0.5]]))
    E = quat.multiply(S, tiny)
    F, s = path_frames(S, E, (0, 0, 1))
    assert np.all(np.isfinite(F))
    assert np.allclose(np.einsum("lji,ljk->lik", F, F), np.eye(3), atol=1e-12)
    assert np.all(s >= MIN_SCALE)
    P = np.ones((4, 50, 3))
    body = from_path_frame(P, S, E)
    # predictions vanish with the rotation: |r| <= min_scale |p| for rotations under it
    assert np.all(np.linalg.norm(body[:3], axis=2) <= MIN_SCALE * np.sqrt(3) + 1e-15)
    R = np.random.default_rng(2).normal(size=(4, 50, 3))
    assert np.max(np.abs(from_path_frame(to_path_frame(R, S, E), S, E) - R)) < 1e-12
    # rotation about the vertical axis itself (start = identity, up = z)
    S2 = np.array([[1.0, 0, 0, 0]])
    E2 = quat.expmap(np.array([[0, 0, 0.8]]))
    F2, _ = path_frames(S2, E2, (0, 0, 1))
    assert np.allclose(F2[0].T @ F2[0], np.eye(3), atol=1e-12)
    assert np.allclose(F2[0][:, 0], [0, 0, 1])


def test_path_frame_rejects_bad_up():
    S = np.array([[1.0, 0, 0, 0]])
    with pytest.raises(ValueError, match="up"):
        path_frames(S, S, (0, 0, 0))
    with pytest.raises(ValueError, match="up"):
        path_frames(S, S, (0, 1))


def test_bezier_models_in_the_path_frame(tmp_path):
    rng = np.random.default_rng(3)
    S, E = _random_pairs(rng, 40)
    R = rng.normal(scale=0.1, size=(40, 50, 3))
    R[:, 0] = R[:, -1] = 0
    up = (0, 1, 0)
    model = NullBezierModel(2, frame="path", up=up).fit(R, starts=S, ends=E)
    manual = NullBezierModel(2).fit(to_path_frame(R, S, E, up))
    expected = from_path_frame(manual.predict(n=40), S, E, up)
    assert np.allclose(model.predict(starts=S, ends=E), expected, atol=1e-14)
    with pytest.raises(ValueError, match="starts and ends"):
        model.predict(n=40)
    task = TaskBezierModel(2, frame="path", up=up).fit(R, tasks=np.arange(40) % 3, starts=S, ends=E)
    path = tmp_path / "task.json"
    task.save(path)
    again = load_model(path)
    assert again.frame == "path" and tuple(again.up) == tuple(task.up)
    t = np.arange(40) % 3
    assert np.array_equal(
        again.predict(tasks=t, starts=S, ends=E), task.predict(tasks=t, starts=S, ends=E)
    )
    with pytest.raises(ValueError, match="frame"):
        NullBezierModel(2, frame="world")


def _beta_curves(a: np.ndarray, n: int = 50) -> np.ndarray:
    tau = np.linspace(0, 1, n)
    return betainc(a[:, None], 2.5, tau[None, :])


def test_timing_model_monotone_pinned_and_mean_at_centre():
    rng = np.random.default_rng(4)
    x = rng.uniform(-1, 1, size=(120, 2))
    A = _beta_curves(2.0 + 0.8 * x[:, 0])
    model = SpeedProfileModel().fit(x, A)
    extreme = np.array([[-1e3, 1e3], [1e3, -1e3], [0.0, 0.0], [5.0, 5.0]])
    pred = model.predict(extreme)
    assert np.all(pred[:, 0] == 0.0) and np.all(pred[:, -1] == 1.0)
    assert np.all(np.diff(pred, axis=1) >= 0)
    # at the training mean of the features it is the average profile exactly
    centre = model.predict(x.mean(axis=0, keepdims=True))[0]
    assert np.allclose(centre, A.mean(axis=0), atol=1e-12)


def test_timing_model_recovers_a_known_dependence():
    rng = np.random.default_rng(5)
    x = rng.uniform(-1, 1, size=(200, 2))
    A = _beta_curves(2.0 + 0.8 * x[:, 0])
    model = SpeedProfileModel().fit(x[:150], A[:150])
    err_model = np.abs(model.predict(x[150:]) - A[150:]).max(axis=1).mean()
    err_mean = np.abs(A[:150].mean(axis=0) - A[150:]).max(axis=1).mean()
    assert err_model < 0.3 * err_mean
    assert model.lam_ in model.lambdas


def test_timing_features_and_errors():
    X = timing_features([1.0, 2.0], [0.5, 1.0])
    assert np.allclose(X, [[0.0, 0.5], [np.log(2), 1.0]])
    with pytest.raises(ValueError, match="durations"):
        timing_features([0.0, 1.0], [0.1, 0.2])
    with pytest.raises(NotFittedError, match="not fitted"):
        SpeedProfileModel().predict([[0.0, 0.0]])


def test_import_motion_envs_does_not_import_torch():
    code = (
        "import sys, motion_envs, motion_envs.models.path_frame, motion_envs.models.timing_model,"
        " motion_envs.models.bezier_models, baselines.learned, baselines.learned.rows;"
        " sys.exit('torch' in sys.modules)"
    )
    assert subprocess.run([sys.executable, "-c", code], check=False).returncode == 0


def test_dataset_up_attribute_and_override(tmp_path):
    from motion_envs.datasets import load_orientation_dataset, load_vr_kitchen
    from motion_envs.datasets.orientation import DEFAULT_UP, read_orientation_csv

    ds = load_vr_kitchen()
    assert ds.up == (0.0, 1.0, 0.0)
    assert load_orientation_dataset("vr-kitchen", up=(0, 0, 2)).up == (0.0, 0.0, 1.0)
    path = ds.subset(np.arange(5)).to_csv(tmp_path / "five.csv")
    assert read_orientation_csv(path).up == DEFAULT_UP
    assert read_orientation_csv(path, up=(1.0, 0.0, 0.0)).up == (1.0, 0.0, 0.0)
    with pytest.raises(ValueError, match="up"):
        load_orientation_dataset(str(path), up=(0, 0, 0))
