"""Bézier residual models: predictions, errors, and the JSON model format."""

from __future__ import annotations

import json
import os

import numpy as np
import pytest

from motion_envs.geometry import bezier
from motion_envs.models import serialization
from motion_envs.models.bezier_models import (
    LinearBezierModel,
    NullBezierModel,
    SubjectBezierModel,
    TaskBezierModel,
)
from motion_envs.models.estimator import NotFittedError
from motion_envs.models.serialization import ModelFileError, load_model

GRID = np.linspace(0, 1, 50)


@pytest.fixture
def curves():
    """Curves generated from known control points: task effect + subject effect + noise."""
    rng = np.random.default_rng(3)
    tasks = np.repeat(["a", "b", "c"], 8)
    subjects = np.tile(np.repeat(["s1", "s2"], 4), 3)
    task_p = {"a": [0.3, 0.0, 0.1], "b": [-0.2, 0.1, 0.0], "c": [0.0, -0.3, 0.2]}
    P = np.array([task_p[t] for t in tasks])[:, None, :] + rng.normal(0, 0.01, (24, 1, 3))
    R = bezier.evaluate(P, GRID)
    return R, P, subjects, tasks


def test_null_model_is_mean_of_fits(curves):
    R, P, _, _ = curves
    model = NullBezierModel(2).fit(R)
    assert model is not None and model.degree == 2
    np.testing.assert_allclose(model.control_points_, P.mean(axis=0), atol=1e-12)
    pred = model.predict(n=3)
    np.testing.assert_allclose(pred[1], bezier.evaluate(P.mean(axis=0), GRID), atol=1e-12)


def test_group_models_average_within_groups(curves):
    R, P, subjects, tasks = curves
    task = TaskBezierModel(2).fit(R, tasks=tasks)
    np.testing.assert_array_equal(task.groups_, ["a", "b", "c"])
    np.testing.assert_allclose(task.control_points_[1], P[tasks == "b"].mean(axis=0), atol=1e-12)
    got = task.predict_control_points(tasks=["c", "a"])
    np.testing.assert_allclose(got[0], P[tasks == "c"].mean(axis=0), atol=1e-12)
    subj = SubjectBezierModel(3).fit(R, subjects=subjects)
    assert subj.control_points_.shape == (2, 2, 3)
    with pytest.raises(ValueError, match="not seen in fit"):
        task.predict_control_points(tasks=["z"])
    lenient = TaskBezierModel(2, unseen="global").fit(R, tasks=tasks)
    np.testing.assert_allclose(lenient.predict_control_points(tasks=["z"])[0], P.mean(axis=0))


def test_linear_model_recovers_linear_relation():
    rng = np.random.default_rng(0)
    x = rng.normal(size=(40, 2))
    b0 = np.array([[0.1, -0.2, 0.3]])
    B = np.array([[[0.05, 0.0, -0.1]], [[0.0, 0.2, 0.02]]])
    P = b0 + np.einsum("lp,pkc->lkc", x, B)
    R = bezier.evaluate(P, GRID)
    model = LinearBezierModel(2).fit(R, predictors={"age": x[:, 0], "height": x[:, 1]})
    np.testing.assert_allclose(model.intercept_, b0, atol=1e-10)
    np.testing.assert_allclose(model.coef_, B, atol=1e-10)
    assert model.predictor_names_ == ["age", "height"]
    pred = model.predict_control_points(predictors={"height": x[:3, 1], "age": x[:3, 0]})
    np.testing.assert_allclose(pred, P[:3], atol=1e-10)


def test_linear_model_rejects_degenerate_design(curves):
    R = curves[0]
    with pytest.raises(ValueError, match="degenerate regression"):
        LinearBezierModel(2).fit(R, predictors={"const": np.ones(len(R))})
    x = np.arange(len(R), dtype=float)
    with pytest.raises(ValueError, match="degenerate regression"):
        LinearBezierModel(2).fit(R, predictors={"x": x, "y": 2 * x + 1})
    with pytest.raises(ValueError, match="predictors"):
        LinearBezierModel(2).fit(R, predictors={"x": x[:-1]})


def test_errors_name_the_argument(curves):
    R, _, subjects, _ = curves
    with pytest.raises(ValueError, match="residuals"):
        NullBezierModel(2).fit(R[:, :, :2])
    with pytest.raises(ValueError, match="tasks"):
        TaskBezierModel(2).fit(R)
    with pytest.raises(ValueError, match="subjects"):
        SubjectBezierModel(2).fit(R, subjects=subjects[:-1])
    with pytest.raises(ValueError, match="degree"):
        NullBezierModel(0)
    with pytest.raises(NotFittedError, match="not fitted"):
        NullBezierModel(2).predict(n=2)


def fitted_models(curves):
    R, _, subjects, tasks = curves
    x = np.linspace(-1, 1, len(R))
    return [
        NullBezierModel(3).fit(R),
        SubjectBezierModel(2).fit(R, subjects=subjects),
        TaskBezierModel(4, unseen="global").fit(R, tasks=tasks),
        LinearBezierModel(2).fit(R, predictors={"x": x, "x2": x**2}),
    ]


def predict_any(model, curves):
    R, _, subjects, tasks = curves
    x = np.linspace(-1, 1, len(R))
    return model.predict(n=len(R), subjects=subjects, tasks=tasks, predictors={"x": x, "x2": x**2})


def test_save_load_roundtrip_is_exact(curves, tmp_path):
    for model in fitted_models(curves):
        path = model.save(tmp_path / f"{type(model).__name__}.json")
        loaded = type(model).load(path)
        assert type(loaded) is type(model)
        assert vars(loaded).keys() == vars(model).keys()
        for key, value in vars(model).items():
            np.testing.assert_array_equal(getattr(loaded, key), value, err_msg=key)
        np.testing.assert_array_equal(predict_any(loaded, curves), predict_any(model, curves))
        assert type(load_model(path)) is type(model)


def test_corrupt_truncated_and_wrong_version_files(curves, tmp_path):
    model = NullBezierModel(2).fit(curves[0])
    path = model.save(tmp_path / "m.json")
    text = path.read_text()
    (tmp_path / "trunc.json").write_text(text[: len(text) // 2])
    with pytest.raises(ModelFileError, match="corrupt or truncated"):
        load_model(tmp_path / "trunc.json")
    doc = json.loads(text)
    doc["format_version"] = 99
    (tmp_path / "v99.json").write_text(json.dumps(doc))
    with pytest.raises(ModelFileError, match="format_version 99"):
        load_model(tmp_path / "v99.json")
    (tmp_path / "other.json").write_text('{"hello": 1}')
    with pytest.raises(ModelFileError, match="not a motion-envs model"):
        load_model(tmp_path / "other.json")
    doc = json.loads(text)
    doc["arrays"]["control_points_"]["shape"] = [7, 7]
    (tmp_path / "shape.json").write_text(json.dumps(doc))
    with pytest.raises(ModelFileError, match="control_points_"):
        load_model(tmp_path / "shape.json")
    with pytest.raises(ModelFileError, match="does not exist"):
        load_model(tmp_path / "missing.json")
    with pytest.raises(ModelFileError, match="not a TaskBezierModel"):
        TaskBezierModel.load(path)
    assert isinstance(ModelFileError("x"), ValueError)


def test_failed_write_leaves_no_partial_file(curves, tmp_path, monkeypatch):
    model = NullBezierModel(2).fit(curves[0])
    target = tmp_path / "m.json"
    model.save(target)
    before = target.read_bytes()

    def boom(*args, **kwargs):
        raise OSError("disk full")

    monkeypatch.setattr(os, "fsync", boom)
    with pytest.raises(OSError, match="disk full"):
        NullBezierModel(3).fit(curves[0]).save(target)
    assert target.read_bytes() == before  # the old file is intact
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.json"]  # no temp file left


def test_refuses_to_save_nan(curves, tmp_path):
    model = NullBezierModel(2).fit(curves[0])
    model.control_points_ = model.control_points_ * np.nan
    with pytest.raises(ValueError, match="NaN"):
        serialization.save_model(model, tmp_path / "nan.json")
    assert not (tmp_path / "nan.json").exists()
