"""``motion-bench train --algo ars`` (sb3-contrib's ARS, :mod:`baselines.agents.ars`).

* the shipped ``configs/agents/ars.yaml`` blocks resolve, and keys ARS does not take (or
  does not take together) are one line naming the key;
* an untrained ARS policy (``zero_policy``; an ``MlpPolicy`` with ``action_head_scale 0``)
  plays the controller exactly: its validation episodes equal the zero action's;
* ``paired_seeds``: the two candidates of a direction play the same episodes (equal
  candidates, equal returns), different directions different ones, and the seeds stay
  below the validation seeds;
* a tiny training run writes a run folder that reloads to the same actions as the model
  that trained (through the saved normalisation), without unpickling the zip's data.
"""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pytest

pytest.importorskip("sb3_contrib")

from baselines.agents.config import resolve_hyperparams, validate_hyperparams

ENV = "MotionEnvs/Juggling-v2"
#: The shipped block's env, one catch per episode (short episodes for the tests).
SHORT = {"max_catches": 1}


def _hp(**overrides: Any) -> dict[str, Any]:
    env_kwargs = overrides.pop("env_kwargs", SHORT)
    return resolve_hyperparams("ars", ENV, overrides={"env_kwargs": env_kwargs, **overrides})


def _model(hp: dict[str, Any], seed: int = 0, seed_bound: int | None = None) -> Any:
    from stable_baselines3.common.vec_env import VecMonitor, VecNormalize

    from baselines.agents.policies import build_model
    from baselines.agents.vec import make_sb3_vec_env

    env = VecNormalize(
        VecMonitor(make_sb3_vec_env(ENV, int(hp["n_envs"]), hp["env_kwargs"])), norm_reward=False
    )
    return build_model("ars", hp, env, seed, seed_bound=seed_bound)


def test_shipped_blocks_resolve() -> None:
    juggling = resolve_hyperparams("ars", ENV)
    assert juggling["env_kwargs"]["level"] == "drift"
    assert juggling["env_kwargs"]["controller"] == "juggler_mean_delay_catch"
    cascade = resolve_hyperparams("ars", "MotionEnvs/Cascade-v1")
    assert cascade["env_kwargs"]["pattern"] == "3" and cascade["env_kwargs"]["level"] == "medium"
    for hp in (juggling, cascade):
        assert hp["policy"] == "LinearPolicy" and hp["zero_policy"] and hp["paired_seeds"]
        assert hp["frame_stack"] == 1 and hp["normalize"] == {"obs": True}
        assert "gamma" not in hp and "batch_size" not in hp


@pytest.mark.parametrize(
    ("block", "message"),
    [
        ({"gamma": 0.99}, "gamma: unknown key for ars"),
        ({"normalize": {"reward": True}}, "normalize.reward: unknown key"),
        ({"policy_kwargs": {"net_arch": {"pi": [8]}}}, "must be a list of layer sizes"),
        ({"delta_std": 0.0}, "delta_std: must be in (0.0, inf]"),
    ],
)
def test_keys_ars_does_not_take_are_refused(block: dict[str, Any], message: str) -> None:
    with pytest.raises(ValueError, match=None) as info:
        validate_hyperparams("ars", block, "f.yaml, line 3")
    assert str(info.value).startswith("f.yaml, line 3: ") and message in str(info.value)
    assert "\n" not in str(info.value)


def test_keys_that_do_not_go_together_are_refused() -> None:
    with pytest.raises(ValueError, match=r"policy_kwargs.net_arch: LinearPolicy has no hidden"):
        _hp(policy_kwargs={"net_arch": [16]})
    with pytest.raises(ValueError, match=r"n_top: must be <= n_delta \(8\); got 9"):
        _hp(n_top=9)
    assert _hp(policy="MlpPolicy", policy_kwargs={"net_arch": [16]})["policy"] == "MlpPolicy"


@pytest.mark.parametrize(
    "overrides",
    [
        {},  # LinearPolicy, zero_policy: every weight 0
        # MlpPolicy keeping its random hidden layers, its output layer zeroed
        {"policy": "MlpPolicy", "zero_policy": False, "policy_kwargs": {"net_arch": [16]}},
    ],
    ids=["linear-zero", "mlp-head-zeroed"],
)
def test_untrained_ars_plays_the_controller_exactly(overrides: dict[str, Any]) -> None:
    """Validation episodes of the untrained policy (as the validation plays it) equal
    those of the zero action: the same tosses, catches, drops and hand deviations."""
    from baselines.agents.scorers import scorer_for

    hp = _hp(**overrides)
    model = _model(hp)
    weights = [p.detach().numpy() for p in model.policy.parameters()]
    if overrides:  # the hidden layer is not zero: the zeroed head is what makes it nominal
        assert np.abs(weights[0]).max() > 0
    else:
        assert all(not w.any() for w in weights)

    def policy(obs: np.ndarray) -> np.ndarray:
        return np.asarray(model.predict(obs, deterministic=True)[0])

    def zero(obs: np.ndarray) -> np.ndarray:
        return np.zeros((len(obs), 2), dtype=np.float32)

    score = scorer_for(ENV).episodes
    ours, nominal = (score(p, ENV, hp["env_kwargs"], "val", 3) for p in (policy, zero))
    for field in ("seeds", "tosses", "catches", "dropped", "segment_deviation"):
        np.testing.assert_array_equal(getattr(ours, field), getattr(nominal, field))
    assert ours.tosses.sum() > 0 and ours.segment_deviation.size > 0


def test_paired_seeds_give_both_candidates_of_a_direction_the_same_episodes() -> None:
    """``evaluate_candidates`` on equal candidate weights: with ``paired_seeds`` the
    candidates ``i`` and ``i + n_delta`` get equal returns and the directions differ;
    without, the two candidates of a direction play different episodes."""
    import torch as th

    returns = {}
    for paired in (True, False):
        model = _model(_hp(n_delta=3, n_top=1, paired_seeds=paired))
        _, callback = model._setup_learn(10, None)
        candidates = th.zeros(model.pop_size, model.n_params)
        returns[paired] = model.evaluate_candidates(candidates, callback, None).numpy()
    np.testing.assert_array_equal(returns[True][:3], returns[True][3:])
    assert len(set(returns[True][:3].tolist())) == 3  # three directions, three draws
    assert not np.array_equal(returns[False][:3], returns[False][3:])


def test_paired_seeds_stay_below_the_bound() -> None:
    model = _model(_hp(n_delta=50, n_top=1), seed_bound=12)
    seeds = np.array([model.pair_seeds() for _ in range(20)])
    assert seeds.min() >= 0 and seeds.max() <= 12 - 1  # one copy: s + 0 < 12
    assert len(np.unique(seeds)) == 12  # the whole range is used
    default = _model(_hp(n_delta=50, n_top=1), seed_bound=10**9)
    assert max(default.pair_seeds()) < 10**9


def test_tiny_run_round_trips(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """``run`` with ARS writes the run folder of any algorithm; ``load_run`` (best and
    final) gives the actions of the model that trained (its final normalisation), reads
    no pickled data, and the trained policy is not the zero one."""
    import stable_baselines3.common.save_util as save_util

    from baselines.agents import policies
    from baselines.agents.rundir import ObsNormalizer, load_run
    from baselines.agents.train import TrainConfig, run

    built: list[Any] = []
    build = policies.build_model

    def spy(*args: Any, **kwargs: Any) -> Any:
        built.append(build(*args, **kwargs))
        return built[-1]

    monkeypatch.setattr(policies, "build_model", spy)
    out = tmp_path / "run"
    overrides = {"n_delta": 2, "n_top": 1, "eval_freq": 1500, "eval_episodes": 2}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = run(
            TrainConfig(
                algo="ars",
                env_id=ENV,
                out=str(out),
                timesteps=1500,
                env_kwargs=SHORT,
                overrides=overrides,
                progress=False,
                tensorboard=False,
            )
        )
    assert result.timesteps >= 1500 and len(result.evaluations) >= 2
    files = {p.name for p in out.iterdir()}
    assert {"agent.zip", "final_agent.zip", "normalization.npz", "run.json"} <= files
    trained = built[0]
    assert np.abs(trained.policy.action_net[0].weight.detach().numpy()).max() > 0

    def unpickle(*args: Any, **kwargs: Any) -> Any:
        raise AssertionError("load_run read the zip's pickled data")

    monkeypatch.setattr(save_util, "json_to_data", unpickle)
    final = load_run(out, "final")
    assert load_run(out).manifest["algo"] == "ars"
    rng = np.random.default_rng(0)
    obs = rng.normal(0.0, 1.0, (16, trained.observation_space.shape[0])).astype(np.float32)
    normalizer = ObsNormalizer.from_vec_normalize(trained.get_vec_normalize_env())
    expected = trained.predict(normalizer(obs), deterministic=True)[0]
    np.testing.assert_array_equal(final.predict(obs), expected)
    assert np.abs(expected).max() > 0
    # an independent oracle of the linear policy: clip(W x) on the normalised input
    w = trained.policy.action_net[0].weight.detach().numpy()
    np.testing.assert_allclose(
        final.predict(obs), np.clip(normalizer(obs) @ w.T, -1, 1), rtol=1e-5, atol=1e-6
    )
