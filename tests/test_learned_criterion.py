"""``motion-bench agent``'s learned row: scored like the environment, fitted on its training data.

* plumbing: the scorer given the environment's own nominal reproduces the zero-action
  episodes' ``info["max_error"]`` (so ``nominal_criterion``) to 1e-9, for every reaching
  environment and version;
* the orientation scorer agrees with the formula written with the geometry module
  (independent of the environments' kernels) on the learned residuals;
* out of sample: the regressor is fitted on exactly the environment's training split
  (the trajectories its nominal was fitted on), never on a test trajectory.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import motion_envs  # noqa: F401
from baselines.agents import learned_criterion as LC
from baselines.agents.evaluate import episode_max_errors
from motion_envs.geometry import quaternion as quat

pytest.importorskip("sklearn")
pytestmark = pytest.mark.filterwarnings("ignore:.*out of date.*:DeprecationWarning")

SHAPES = ["Angle", "GShape", "Sine"]
CASES = [
    ("MotionEnvs/OrientationReach-v0", {"nominal": "bezier-null"}, "test"),
    ("MotionEnvs/OrientationReach-v1", {"nominal": "bezier-task", "val_fraction": 0.2}, "val"),
    ("MotionEnvs/PositionReach-v0", {"shapes": SHAPES}, "test"),
    ("MotionEnvs/PositionReach-v1", {"shapes": SHAPES, "nominal": "null"}, "test"),
]


def _task(env_id, kwargs, split):
    return gym.make(env_id, split=split, **kwargs).unwrapped.task


@pytest.mark.parametrize(("env_id", "kwargs", "split"), CASES)
def test_scorer_given_the_nominal_reproduces_nominal_criterion(env_id, kwargs, split):
    task = _task(env_id, kwargs, split)
    if "Orientation" in env_id:
        errs = LC.orientation_max_errors(task, task.grids.predicted_residuals)
    else:
        errs = LC.position_max_errors(task, task.grids.nominal)
    nominal = episode_max_errors(None, env_id, kwargs, split)
    np.testing.assert_allclose(errs, nominal.max_errors, rtol=0, atol=1e-9)
    assert abs(float(np.median(errs)) - nominal.criterion) <= 1e-9


@pytest.mark.parametrize(("env_id", "kwargs", "split"), CASES)
def test_learned_errors_are_the_env_criterion_of_the_prediction(env_id, kwargs, split):
    got = LC.learned_episode_errors(env_id, kwargs, split)
    task = _task(env_id, kwargs, split)
    np.testing.assert_array_equal(got.errors.trajectory_ids, task.trajectory_ids)
    assert got.errors.criterion == float(np.median(got.errors.max_errors))
    assert np.all(np.isfinite(got.errors.max_errors)) and np.all(got.errors.max_errors > 0)
    few = LC.learned_episode_errors(env_id, kwargs, split, episodes=4)
    np.testing.assert_array_equal(few.errors.max_errors, got.errors.max_errors[:4])


def test_orientation_scorer_matches_the_geometry_formula():
    env_id, kwargs, split = CASES[0]
    task = _task(env_id, kwargs, split)
    rng = np.random.default_rng(0)
    rhat = 0.3 * rng.normal(size=task.grids.residuals.shape)
    # independent oracle: residual chart at the base slerp, |logmap(conj(e) q) - r|
    q = quat.multiply(task.grids.base, quat.expmap(rhat))
    chart = quat.logmap(quat.multiply(quat.conjugate(task.grids.base), q))
    oracle = np.linalg.norm(chart - task.grids.residuals, axis=2).max(axis=1)
    np.testing.assert_allclose(LC.orientation_max_errors(task, rhat), oracle, atol=1e-9)
    with pytest.raises(ValueError, match="predicted_residuals must have shape"):
        LC.orientation_max_errors(task, rhat[:, :10])


@pytest.mark.parametrize("version", ["v0", "v1"])
def test_orientation_regressor_is_fitted_on_the_train_split_only(monkeypatch, version):
    env_id = f"MotionEnvs/OrientationReach-{version}"
    seen = {}
    real = LC.orientation_learned_residuals

    def spy(fit, part, *args, **kw):
        seen["fit"] = np.asarray(fit.trajectory_ids).astype(str)
        seen["part"] = np.asarray(part.trajectory_ids).astype(str)
        return real(fit, part, *args, **kw)

    monkeypatch.setattr(LC, "orientation_learned_residuals", spy)
    LC.learned_episode_errors(env_id, {}, "test")
    train = _task(env_id, {}, "train").trajectory_ids.astype(str)
    test = _task(env_id, {}, "test").trajectory_ids.astype(str)
    np.testing.assert_array_equal(seen["fit"], train)
    np.testing.assert_array_equal(seen["part"], test)
    assert not set(seen["fit"]) & set(test)


def test_orientation_prediction_depends_on_a_trajectorys_own_conditions_only():
    from motion_envs.envs.orientation_reach import orientation_split_parts

    _, fit, part = orientation_split_parts("vr-kitchen", "test", 0.25, 0, 10.0)
    rhat, chosen = LC.orientation_learned_residuals(fit, part)
    assert rhat.shape == (len(part), 50, 3) and np.all(np.isfinite(rhat))
    assert chosen and "alpha" in chosen[0]
    # the scored trajectories' targets are never read (they are NaN inside) and their
    # number does not change the fit: one test trajectory alone gets the same curve
    alone, _ = LC.orientation_learned_residuals(fit, part.subset([3]))
    np.testing.assert_allclose(alone[0], rhat[3], rtol=0, atol=1e-12)


def test_position_regressor_is_fitted_on_the_train_split_only(monkeypatch):
    import baselines.learned.position as P

    env_id, kwargs = "MotionEnvs/PositionReach-v0", {"shapes": SHAPES}
    seen = {}
    real = P.learned_position_predictions

    def spy(y_all, durations, folds, *args, **kw):
        seen["train"] = np.sort(np.concatenate([t for _, t, _ in folds]))
        seen["scored"] = np.concatenate([s for _, _, s in folds])
        return real(y_all, durations, folds, *args, **kw)

    monkeypatch.setattr(P, "learned_position_predictions", spy)
    LC.learned_episode_errors(env_id, kwargs, "test")
    train = _task(env_id, kwargs, "train").grids.index
    test = _task(env_id, kwargs, "test").grids.index
    np.testing.assert_array_equal(seen["train"], np.sort(train))
    np.testing.assert_array_equal(seen["scored"], test)
    assert not set(seen["train"].tolist()) & set(test.tolist())


def test_no_regressor_for_juggling():
    assert LC.learned_skip_reason("MotionEnvs/Juggling-v0") is not None
    with pytest.raises(ValueError, match="no learned regressor"):
        LC.learned_episode_errors("MotionEnvs/Juggling-v0", {}, "test")
