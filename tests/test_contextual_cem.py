"""The contextual CEM learner: it finds a known linear context-to-action map from the
reward alone, keeps the nominal at step 0, and refuses bad settings with the argument's
name."""

from __future__ import annotations

import numpy as np
import pytest

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
