"""Issue 23 (second pass): one model of a hand's position and orientation together.

Oracles: the two parts fitted on their own (the combined model must equal them), the
prescribed end points, scikit-learn's ``clone`` and a save/load round trip.
"""

from __future__ import annotations

import numpy as np
import pytest

from motion_envs.geometry import expmap, slerp
from motion_envs.geometry import quaternion as quat
from motion_envs.models import (
    NotFittedError,
    OrientationModel,
    PoseModel,
    SineSeriesRegression,
    load_model,
)

RATE = 120.0


def _recordings(seed: int = 8):
    """SIMULATED reaches with a turning wrist, 2 subjects, varied lengths, sign flips."""
    rng = np.random.default_rng(seed)
    ys, qs, subjects = [], [], []
    for i in range(12):
        n = int(rng.integers(100, 140))
        tau = np.linspace(0.0, 1.0, n)
        s5 = 10 * tau**3 - 15 * tau**4 + 6 * tau**5
        start = rng.normal(0, 0.03, 3)
        end = start + np.array([0.3, 0.1 * (i % 3), 0.0]) + rng.normal(0, 0.02, 3)
        ys.append(start + (end - start) * s5[:, None] + rng.normal(0, 5e-4, (n, 3)))
        q = slerp(expmap([0, 0, 0.1]), expmap([0.6 + 0.1 * (i % 3), 0.1, 0.0]), s5)
        wobble = expmap((0.04 if i % 2 else 0.1) * np.sin(np.pi * tau)[:, None] * [1, 0, 0])
        q = quat.multiply(q, wobble)
        qs.append(q * np.where(rng.random(n) < 0.1, -1.0, 1.0)[:, None])
        subjects.append("a" if i % 2 else "b")
    return ys, qs, np.array(subjects)


@pytest.fixture(scope="module")
def fitted():
    ys, qs, subjects = _recordings()
    poses = [np.hstack([y, q]) for y, q in zip(ys, qs, strict=True)]  # positions, quaternion
    model = PoseModel(n_sines=4, degree=3, by="subject").fit(subjects, poses, rate=RATE)
    return model, ys, qs, subjects


def test_pose_model_equals_its_two_parts_fitted_alone(fitted):
    model, ys, qs, subjects = fitted
    q_cond = np.array([np.r_[y[0], y[-1]] for y in ys])
    position = SineSeriesRegression(n_sines=4).fit(q_cond, ys, rate=RATE)
    orientation = OrientationModel(degree=3, by="subject").fit(subjects, qs, rate=RATE)
    t = np.linspace(0.0, 0.9, 37)
    y_s, y_e, q_s, q_e = ys[0][0], ys[0][-1], qs[0][0], qs[0][-1]
    pos, ori = model.predict(y_s, y_e, q_s, q_e, t, subjects=["b"])
    assert pos.shape == (37, 3) and ori.shape == (37, 4)
    np.testing.assert_array_equal(
        pos, position.predict(np.r_[y_s, y_e], 0.9, t, start=y_s, end=y_e)
    )
    np.testing.assert_array_equal(ori, orientation.predict(q_s, q_e, t, subjects=["b"]))
    np.testing.assert_allclose(pos[[0, -1]], [y_s, y_e], atol=1e-12)  # the end points held
    assert quat.angle(ori[0], q_s) < 1e-9 and quat.angle(ori[-1], q_e) < 1e-9
    # a training recording is reproduced at its own times (noise 0.5 mm, wobble by subject)
    times = np.arange(len(ys[3])) / RATE
    pos3, ori3 = model.predict(ys[3][0], ys[3][-1], qs[3][0], qs[3][-1], times, subjects=["a"])
    assert np.sqrt(np.mean(np.sum((pos3 - ys[3]) ** 2, axis=1))) < 2e-3
    assert np.max(quat.angle(ori3, qs[3])) < 0.02


def test_pose_model_predicts_a_batch_with_durations(fitted):
    model, ys, qs, _ = fitted
    starts, ends = np.stack([y[0] for y in ys[:3]]), np.stack([y[-1] for y in ys[:3]])
    q_s, q_e = np.stack([q[0] for q in qs[:3]]), np.stack([q[-1] for q in qs[:3]])
    t = np.linspace(0.0, 0.5, 11)
    pos, ori = model.predict(
        starts, ends, q_s, q_e, t, duration=[1.0, 1.2, 0.5], subjects=["b", "a", "b"]
    )
    assert pos.shape == (3, 11, 3) and ori.shape == (3, 11, 4)
    one, one_q = model.predict(starts[1], ends[1], q_s[1], q_e[1], t, duration=1.2, subjects=["a"])
    np.testing.assert_allclose(pos[1], one, atol=1e-12)
    np.testing.assert_allclose(ori[1], one_q, atol=1e-12)
    with pytest.raises(ValueError, match="same movements"):
        model.predict(starts, ends, q_s[0], q_e[0], t, subjects=["b"])


def test_pose_model_follows_scikit_learn_and_saves(fitted, tmp_path):
    from sklearn.base import clone

    model, ys, qs, subjects = fitted
    assert model.get_params() == {
        "by": "subject", "degree": 3, "n_points": 50, "n_sines": 4, "normalize": False,
        "unseen": "global",
    }  # fmt: skip
    fresh = clone(model)
    assert fresh.get_params() == model.get_params() and not hasattr(fresh, "position_model_")
    with pytest.raises(NotFittedError, match="PoseModel"):
        fresh.predict(ys[0][0], ys[0][-1], qs[0][0], qs[0][-1], [0.0, 0.5])
    assert fresh.set_params(n_sines=2).n_sines == 2
    with pytest.raises(ValueError, match="by"):
        fresh.set_params(by="weekday")
    poses = [np.hstack([y, q]) for y, q in zip(ys, qs, strict=True)]
    assert fresh.fit(subjects, poses, rate=RATE) is fresh
    with pytest.raises(ValueError, match=r"times=.*rate="):
        PoseModel().fit(None, poses)
    with pytest.raises(ValueError, match=r"y\[0\] must be \(n, D \+ 4\)"):
        PoseModel().fit(subjects, qs, rate=RATE)
    path = model.save(tmp_path / "pose.json")
    again = load_model(path)
    assert isinstance(again, PoseModel) and again.get_params() == model.get_params()
    t = np.linspace(0.0, 1.0, 9)
    args = (ys[5][0], ys[5][-1], qs[5][0], qs[5][-1], t)
    for a, b in zip(
        again.predict(*args, subjects=["a"]), model.predict(*args, subjects=["a"]), strict=True
    ):
        np.testing.assert_array_equal(a, b)
    assert PoseModel.load(path).durations_.shape == (12,)


def test_a_corrupt_pose_model_file_names_the_field(fitted, tmp_path):
    import json

    from motion_envs.models import ModelFileError

    model = fitted[0]
    doc = json.loads(model.save(tmp_path / "pose.json").read_text())
    assert {"position_F", "orientation_average_alpha_"} <= set(doc["arrays"])
    doc["arrays"]["position_conditions"] = {
        "dtype": "float64",
        "shape": [12, 2],
        "data": [0.0] * 24,
    }
    (tmp_path / "bad.json").write_text(json.dumps(doc))  # test fixture, not library output
    with pytest.raises(ModelFileError, match=r"arrays\.position_F"):
        load_model(tmp_path / "bad.json")
