"""The contextual CEM learner: it finds a known linear context-to-action map from the
reward alone, keeps the nominal at step 0, and refuses bad settings with the argument's
name."""

from __future__ import annotations

import dataclasses
import operator

import gymnasium as gym
import numpy as np
import pytest

import motion_envs  # noqa: F401  (registers the ids)
from baselines.agents.contextual_cem import CEMConfig, train_cem


class _Bandit:
    """One-step episodes: context x, the best action a* = 0.6 tanh(A x + b) on the first
    sine term of each axis (the others best at 0); the error is the largest gap."""

    n_sines, _width = 2, 3

    def __init__(self, n: int = 400, seed: int = 0) -> None:
        rng = np.random.default_rng(seed)
        self._context = rng.normal(2.0, 0.5, (n, 4)).astype(np.float32)
        self.A = rng.normal(0.0, 0.5, (3, 4))
        self.best = np.zeros((n, 6))
        z = (self._context - self._context.mean(0)) / self._context.std(0)
        self.best[:, :3] = 0.6 * np.tanh(z @ self.A.T + 0.1)
        self._nominal_errors = self.score(np.arange(n), np.zeros((n, 6)))

    def score(self, index, actions):
        return np.abs(np.asarray(actions) - self.best[index]).max(axis=1)


def test_cem_learns_a_known_linear_map_from_the_reward():
    env = _Bandit()
    config = CEMConfig(budget=24_000, population=30, batch=40, elite=6, sigma=0.3,
                       policy_sines=1)  # fmt: skip
    res = train_cem(env, config, seed=0)
    assert res.means.shape == (config.generations, 3, 5) and config.generations == 20
    everything = np.arange(env._context.shape[0])
    nominal = np.median(env.score(everything, res.at(0).act(env._context)))
    assert nominal == np.median(env._nominal_errors)  # step 0 is the nominal
    learned = np.median(env.score(everything, res.policy.act(env._context)))
    assert learned < 0.35 * nominal  # 0.498 -> 0.131 with this seed
    assert res.elite_errors[-1] < res.elite_errors[0]
    # the same seed gives the same learner
    again = train_cem(env, config, seed=0)
    np.testing.assert_array_equal(again.means, res.means)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"population": 0}, "population must be >= 1"),
        ({"elite": 50, "population": 40}, "elite must be <= population"),
        ({"budget": 100}, "budget must hold one generation"),
        ({"sigma": 0.0}, "sigma must be > 0"),
        ({"smoothing": 1.5}, "smoothing must be in"),
    ],
)
def test_bad_settings_name_the_argument(kwargs, match):
    with pytest.raises(ValueError, match=match):
        CEMConfig(**kwargs)


# --- every choice by inner folds over the training people, the held-out person unread ---

_FOLD = 3
_GRID = [
    CEMConfig(budget=600, population=6, batch=20, elite=2, sigma=s, policy_sines=1)
    for s in (0.02, 0.1)
]


class HeldOutRead(AssertionError):
    """The held-out person's reaches were read before the choice."""


class _Watched(tuple):
    """Per-trajectory arrays that report every read of the rows in ``held`` to ``spy``
    (indexing, slicing and iteration all pass through ``__getitem__``)."""

    def __new__(cls, items, held, spy, kind):
        obj = super().__new__(cls, items)
        obj.held, obj.spy, obj.kind = frozenset(int(i) for i in held), spy, kind
        return obj

    def __getitem__(self, i):
        if isinstance(i, slice):
            return tuple(self[j] for j in range(len(self))[i])
        j = operator.index(i) % len(self)
        value = super().__getitem__(j)
        return self.spy.read(self.kind, j, value) if j in self.held else value

    def __iter__(self):
        return (self[j] for j in range(len(self)))


class _Spy:
    """Watches the held-out person's quaternions (any read before the choice raises
    :class:`HeldOutRead`) and times (read before the choice: recorded and returned
    stretched 3x, so that any use of them changes what is computed from them)."""

    def __init__(self, people, person: str) -> None:
        self.people, self.person, self.phase = list(people), person, "selection"
        self.reads: dict[tuple[str, str], set[int]] = {}

    def read(self, kind, j, value):
        self.reads.setdefault((self.phase, kind), set()).add(j)
        if self.phase != "selection":
            return value
        if kind == "quaternions":
            raise HeldOutRead(f"the held-out person's trajectory {j} read before the choice")
        return value[0] + 3.0 * (value - value[0])

    def wrap(self, dataset):
        held = np.flatnonzero(np.asarray(dataset.subjects).astype(str) == self.person)
        return dataclasses.replace(
            dataset,
            quaternions=_Watched(dataset.quaternions, held, self, "quaternions"),
            times=_Watched(dataset.times, held, self, "times"),
        )


@pytest.fixture
def spy(monkeypatch):
    """A spy on the dataset every environment of the test is built from (the task cache
    emptied before and after, so that every build reads the watched dataset)."""
    import motion_envs.datasets as datasets
    from motion_envs.envs._orientation_task import _build_task_cached

    original = datasets.load_orientation_dataset
    people = np.unique(np.asarray(original("vr-kitchen").subjects).astype(str))
    watcher = _Spy(people.tolist(), str(people[_FOLD]))
    monkeypatch.setattr(
        datasets, "load_orientation_dataset", lambda *a, **k: watcher.wrap(original(*a, **k))
    )
    _build_task_cached.cache_clear()
    yield watcher
    _build_task_cached.cache_clear()


def test_the_lopo_fold_never_reads_the_held_out_person_before_the_choice(spy, monkeypatch):
    import baselines.agents.contextual_cem as cem

    chosen = {}
    original = cem.choose_by_inner_folds

    def choose(*args, **kwargs):
        chosen["choice"] = original(*args, **kwargs)
        spy.phase = "after the choice"
        return chosen["choice"]

    monkeypatch.setattr(cem, "choose_by_inner_folds", choose)
    trials, choice = cem.lopo_fold(_FOLD, [0], _GRID)
    assert choice is chosen["choice"]
    # no quaternion of the held-out person before the choice (the spy raises), and their
    # times only in a form whose values do not matter (below); after it, the spy sees
    # them read: the test reads the person, so the spy is watching the right rows
    assert ("selection", "quaternions") not in spy.reads
    assert spy.reads[("after the choice", "quaternions")]
    # the inner folds: each of the 7 training people held out once, never the outer one
    assert sorted(choice.inner_people) == sorted(set(spy.people) - {spy.person})
    assert len(choice.inner_people) == 7
    assert [s.shape for s in choice.scores] == [(1, 6), (1, 6)]
    assert trials[0]["chosen_setting"] == choice.config_index
    assert trials[0]["chosen_generation"] == choice.generation(0)
    assert np.isfinite(trials[0]["test_ratio"]) and trials[0]["test_ratio"] > 0


def test_the_held_out_persons_times_do_not_change_the_choice(spy):
    """Before the choice the held-out person's times are read (the observation space's
    longest movement, the same on every split); stretched 3x they change nothing."""
    from baselines.agents.contextual_cem import ENV_ID, choose_by_inner_folds

    def make_env(split, **kwargs):
        return gym.make(ENV_ID, nominal="bezier-null", fold=_FOLD, split=split,
                        **kwargs).unwrapped  # fmt: skip

    from motion_envs.envs._orientation_task import _build_task_cached

    watched = choose_by_inner_folds(make_env, [0], _GRID)
    watched_bound = make_env("train").observation_space.high[8]
    assert spy.reads[("selection", "times")]
    spy.phase = "unwatched"
    _build_task_cached.cache_clear()
    plain = choose_by_inner_folds(make_env, [0], _GRID)
    # the stretched times were used (the duration bound is longer)...
    assert make_env("train").observation_space.high[8] < watched_bound
    # ...and the choice, every inner score, is the same to the bit
    for a, b in zip(watched.scores, plain.scores, strict=True):
        np.testing.assert_array_equal(a, b)
    assert watched.inner_people == plain.inner_people


def test_the_spy_catches_a_leak(spy):
    """The spy can fail: the held-out person's episodes built during the selection raise."""
    from baselines.agents.contextual_cem import ENV_ID

    with pytest.raises(HeldOutRead, match="read before the choice"):
        gym.make(ENV_ID, nominal="bezier-null", fold=_FOLD, split="test")


def test_the_choice_is_the_lowest_inner_score():
    from baselines.agents.contextual_cem import InnerChoice

    scores = (
        np.array([[1.0, 0.99, 0.98], [1.0, 0.97, 1.01]]),  # best per seed 0.98, 0.97
        np.array([[1.0, 0.96, 1.2], [1.0, 1.02, 1.03]]),  # 0.96, 1.0: mean 0.98 > 0.975
    )
    choice = InnerChoice(tuple(_GRID), (0, 5), scores, ("a", "b"))
    np.testing.assert_allclose(choice.setting_scores(), [0.975, 0.98])
    assert choice.config_index == 0 and choice.config is _GRID[0]
    assert (choice.generation(0), choice.generation(5)) == (2, 1)
    assert choice.inner_score(5) == 0.97
