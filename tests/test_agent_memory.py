"""An agent's memory (``frame_stack``, :mod:`baselines.agents.memory`) and the shipped
Juggling-v2 block.

The policy-side stack the scorers use equals Gymnasium's ``FrameStackObservation`` +
``FlattenObservation`` (what training sees) step by step on Juggling-v2 episodes; a bad
``frame_stack`` is one line naming the key; a tiny training run of the shipped block's
keys trains on stacked observations, reloads, and is scored on the test seeds with the
same stack (the smoke test of ``experiments/juggling_v2_agents.py``'s path).
"""

from __future__ import annotations

import dataclasses
import warnings

import gymnasium as gym
import numpy as np
import pytest

import motion_envs  # noqa: F401
from baselines.agents.config import resolve_hyperparams, validate_hyperparams
from baselines.agents.memory import StackedPolicy, stack_env, stacked_policy

pytest.importorskip("stable_baselines3")

ENV = "MotionEnvs/Juggling-v2"
KW = {"level": "medium", "controller": "juggler_delay_estimator", "max_catches": 1}


@pytest.mark.parametrize("k", [1, 3, 8])
def test_stacked_policy_sees_what_the_wrapper_gives(k: int) -> None:
    """Two episodes played together (as ``play_until_ended`` plays them): each row's
    stacked input equals FrameStackObservation+Flatten's observation of the same episode
    under the same actions, at every step."""
    rng = np.random.default_rng(0)
    weights = rng.normal(0.0, 0.3, (k * 32, 2))
    seen: list[np.ndarray] = []

    def inner(stacked: np.ndarray) -> np.ndarray:
        seen.append(stacked.copy())
        return np.tanh(np.nan_to_num(stacked) @ weights / 50.0)

    seeds = [11, 12]
    raw = [gym.make(ENV, **KW) for _ in seeds]
    wrapped = [stack_env(gym.make(ENV, **KW), k) for _ in seeds]
    policy = stacked_policy(inner, k)
    assert isinstance(policy, StackedPolicy) == (k > 1)
    obs = np.stack([e.reset(seed=s)[0] for e, s in zip(raw, seeds, strict=True)])
    expected = np.stack([e.reset(seed=s)[0] for e, s in zip(wrapped, seeds, strict=True)])
    assert expected.shape == (2, k * 32)
    ended = False
    steps = 0
    while not ended:
        actions = policy(obs)
        np.testing.assert_array_equal(seen[-1], expected)
        for i in range(2):
            obs[i], _, terminated, truncated, _ = raw[i].step(actions[i])
            expected[i], _, w_terminated, w_truncated, _ = wrapped[i].step(actions[i])
            assert (terminated, truncated) == (w_terminated, w_truncated)
            ended = ended or terminated or truncated
        steps += 1
    assert steps > 2 * k  # the stacks were full of real observations for a while


def test_bad_frame_stack_is_one_line() -> None:
    for bad in (0, -1, 2.5, "8", True, 10_000):
        with pytest.raises(ValueError, match="frame_stack") as info:
            validate_hyperparams("ppo", {"frame_stack": bad})
        assert "\n" not in str(info.value)
    with pytest.raises(ValueError, match="frame_stack"):
        StackedPolicy(lambda o: o, 0)


def test_shipped_block_resolves() -> None:
    hp = resolve_hyperparams("ppo", ENV)
    assert hp["frame_stack"] == 8
    assert hp["env_kwargs"]["controller"] == "juggler_delay_estimator"
    assert hp["env_kwargs"]["residual_phases"] == ["catch"]
    # every other id keeps no memory
    assert resolve_hyperparams("ppo", "MotionEnvs/Juggling-v1")["frame_stack"] == 1


def test_tiny_stacked_run_trains_reloads_and_scores(tmp_path) -> None:
    from baselines.agents.evaluate import AgentConfig, split_criterion
    from baselines.agents.evaluate import run as evaluate_run
    from baselines.agents.rundir import load_run
    from baselines.agents.train import TrainConfig
    from baselines.agents.train import run as train_run

    cfg = TrainConfig(
        algo="ppo",
        env_id=ENV,
        out=str(tmp_path / "run"),
        seed=0,
        timesteps=400,
        n_envs=2,
        env_kwargs={"max_catches": 1},
        overrides={
            "frame_stack": 3,
            "eval_freq": 200,
            "eval_episodes": 2,
            "n_steps": 100,
            "batch_size": 100,
            "n_epochs": 1,
        },
        progress=False,
        tensorboard=False,
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = train_run(cfg)
    loaded = load_run(result.run_dir)
    assert loaded.frame_stack == 3
    assert loaded.normalizer.mean is not None and loaded.normalizer.mean.shape == (96,)
    assert loaded.model.observation_space.shape == (96,)
    # the callback's validation of the kept policy is what a fresh stack scores
    val = split_criterion(loaded.predict, ENV, loaded.env_kwargs, "val", 2, frame_stack=3)
    assert val == pytest.approx(result.best_val_criterion)
    # without the stack the policy cannot even read the observations
    with pytest.raises(ValueError):
        split_criterion(loaded.predict, ENV, loaded.env_kwargs, "val", 2)
    out = evaluate_run(AgentConfig(result.run_dir, "test", 2))
    assert out["n_episodes"] == 2 and 0.0 <= out["catch_rate"] <= 1.0
    # an older run folder without the key keeps no memory
    plain = dataclasses.replace(loaded, config={**loaded.config, "hyperparams": {}})
    assert plain.frame_stack == 1
