"""v1 observations (duration, elapsed time) and the validation split of the reaching envs."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import motion_envs  # noqa: F401  (registers the ids)
from motion_envs.datasets import load_orientation_dataset
from motion_envs.datasets.splits import split_by_replicate, split_by_subject

SHAPES = ["Angle", "CShape", "GShape"]
CASES = [("OrientationReach", {}), ("PositionReach", {"shapes": SHAPES})]


@pytest.mark.parametrize(("name", "kwargs"), CASES)
@pytest.mark.parametrize("split", ["train", "test"])
def test_v1_observation_is_v0_plus_duration_and_elapsed_time(name, kwargs, split):
    v0 = gym.make(f"MotionEnvs/{name}-v0", split=split, **kwargs)
    v1 = gym.make(f"MotionEnvs/{name}-v1", split=split, **kwargs)
    assert v1.observation_space.shape[0] == v0.observation_space.shape[0] + 2
    task = v1.unwrapped.task
    dataset = load_orientation_dataset("vr-kitchen") if name == "OrientationReach" else None
    rng = np.random.default_rng(0)
    for trajectory in (0, task.n_trajectories - 1):
        o0, _ = v0.reset(options={"trajectory": trajectory})
        o1, info = v1.reset(options={"trajectory": trajectory})
        if dataset is not None:  # the duration of the recorded trajectory, in seconds
            i = list(dataset.trajectory_ids).index(info["trajectory_id"])
            assert o1[-2] == np.float32(dataset.times[i][-1] - dataset.times[i][0])
        duration = o1[-2]
        for k in range(50):
            np.testing.assert_array_equal(o1[:-2], o0)
            assert o1[-2] == duration
            assert o1[-1] == pytest.approx(duration * k / 49, rel=1e-6)
            assert v1.observation_space.contains(o1)
            a = rng.uniform(-1, 1, v0.action_space.shape).astype(np.float32)
            o0, r0, *_ = v0.step(a)
            o1, r1, *_ = v1.step(a)
            assert r0 == r1
        assert o1[-1] == duration  # tau = 1 after the last step


def test_orientation_validation_subjects_are_carved_from_training():
    kw = {"val_fraction": 0.2}
    train = gym.make("MotionEnvs/OrientationReach-v1", split="train", **kw).unwrapped.task
    val = gym.make("MotionEnvs/OrientationReach-v1", split="val", **kw).unwrapped.task
    test = gym.make("MotionEnvs/OrientationReach-v1", split="test", **kw).unwrapped.task
    test_v0 = gym.make("MotionEnvs/OrientationReach-v0", split="test").unwrapped.task
    s_train, s_val, s_test = (set(t.subjects.tolist()) for t in (train, val, test))
    assert s_val and not (s_val & s_train) and not (s_val & s_test) and not (s_train & s_test)
    assert len(s_val) == 1  # round(0.2 * 6 training subjects)
    # the test split (and its nominal, fitted on every training subject) is unchanged
    assert test.criterion == test_v0.criterion
    # the validation nominal never saw the validation subjects: refit by hand
    ds = load_orientation_dataset("vr-kitchen")
    full_train, _ = split_by_subject(ds, 0.25, 0)
    fit, held = split_by_subject(full_train, 0.2, 0)
    assert set(held.subjects.tolist()) == s_val
    assert set(fit.subjects.tolist()) == s_train
    from motion_envs.models.orientation_nominal import OrientationNominal

    expected = OrientationNominal("slerp", 2, 50).fit(fit).criterion(held)
    assert val.criterion == pytest.approx(expected, abs=1e-12)


def test_position_validation_demonstrations_are_carved_from_training():
    from motion_envs.datasets import load_position_dataset

    kw = {"val_fraction": 0.2, "shapes": SHAPES, "nominal": "null"}
    tasks = {
        s: gym.make("MotionEnvs/PositionReach-v0", split=s, **kw).unwrapped.task
        for s in ("train", "val", "test")
    }
    ids = {s: set(t.trajectory_ids.tolist()) for s, t in tasks.items()}
    assert ids["val"] and not ids["val"] & ids["train"] and not ids["val"] & ids["test"]
    ds = load_position_dataset("lasa", tuple(SHAPES))
    train, test = split_by_replicate(ds, 0.25, 0)
    assert ids["test"] == set(test.trajectory_ids)
    assert ids["train"] | ids["val"] == set(train.trajectory_ids)
    assert len(ids["val"]) == len(SHAPES)  # one of the 5 training demonstrations per shape


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"split": "val"}, "val_fraction > 0"),
        ({"val_fraction": 1.0}, "val_fraction must be in"),
        ({"val_fraction": "0.2"}, "val_fraction must be a number"),
    ],
)
@pytest.mark.parametrize("name", ["OrientationReach", "PositionReach"])
def test_bad_validation_arguments(name, kwargs, match):
    with pytest.raises(ValueError, match=match):
        gym.make(f"MotionEnvs/{name}-v1", **kwargs)
