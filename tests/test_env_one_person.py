"""OrientationReach on a one-person recording: the split by subject cannot be made, so
``split_by="replicate"`` holds out trials of the person (datasets.splits.split_by_replicate)."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import motion_envs  # noqa: F401  (registers the ids)
from motion_envs.datasets import load_orientation_dataset, load_vr_kitchen
from motion_envs.datasets.splits import split_by_replicate
from motion_envs.models.orientation_nominal import OrientationNominal

ENV = "MotionEnvs/OrientationReach-v1"


@pytest.fixture(scope="module")
def one_person(tmp_path_factory):
    """One person's 41 reaches of 10 tasks (vr-kitchen's subject 10), as the users' CSV."""
    ds = load_vr_kitchen()
    path = tmp_path_factory.mktemp("one") / "me.csv"
    ds.subset(ds.subjects == "10").to_csv(path)
    return str(path)


def test_one_person_split_by_trial(one_person):
    with pytest.raises(ValueError, match=r"needs at least 2 subjects.*split_by='replicate'"):
        gym.make(ENV, data=one_person, split="test")
    dataset = load_orientation_dataset(one_person)
    train, test = split_by_replicate(dataset, test_fraction=0.25, seed=3)
    episodes = {}
    for split in ("train", "test"):
        env = gym.make(ENV, data=one_person, split=split, split_by="replicate", split_seed=3)
        episodes[split] = env.unwrapped.task.trajectory_ids
        env.close()
    # the episodes are the trials split_by_replicate holds out, and all others in training
    assert list(episodes["test"]) == list(test.trajectory_ids) and len(test) > 0
    assert list(episodes["train"]) == list(train.trajectory_ids)
    assert set(episodes["train"]).isdisjoint(episodes["test"])
    assert len(episodes["train"]) + len(episodes["test"]) == len(dataset)
    # the nominal is fitted on the training trials: the zero action scores its criterion
    env = gym.make(ENV, data=one_person, split="test", split_by="replicate", split_seed=3,
                   nominal="bezier-null")  # fmt: skip
    expected = OrientationNominal("bezier-null", 2, 50).fit(train).grids(test).criterion()
    assert env.unwrapped.task.criterion == pytest.approx(expected, rel=1e-12)
    env.reset(seed=0)
    _, reward, *_ = env.step(np.zeros(env.action_space.shape, dtype=np.float32))
    assert np.isfinite(reward)
    env.close()


def test_validation_trials_and_refusals(one_person):
    kwargs = {"data": one_person, "split_by": "replicate", "val_fraction": 0.3}
    train = gym.make(ENV, split="train", **kwargs).unwrapped.task.trajectory_ids
    val = gym.make(ENV, split="val", **kwargs).unwrapped.task.trajectory_ids
    test = gym.make(ENV, split="test", **kwargs).unwrapped.task.trajectory_ids
    assert len(val) > 0 and len({*train, *val, *test}) == len(train) + len(val) + len(test)
    with pytest.raises(
        ValueError, match=r"split_by must be one of \[.subject., .replicate.\]; got .trial."
    ):
        gym.make(ENV, data=one_person, split_by="trial")
    with pytest.raises(ValueError, match=r"split_by='replicate' holds out trials; fold"):
        gym.make(ENV, data=one_person, split_by="replicate", fold=0)
    venv = gym.make_vec(ENV, num_envs=2, data=one_person, split="test", split_by="replicate")
    assert list(venv.unwrapped.task.trajectory_ids) == list(test)
    venv.close()
