"""SB3 models built from validated hyper-parameters, starting at the nominal.

Residual policy learning starts the policy at the base controller: here the action is a
residual on top of the analytic nominal, so an action head scaled by
``action_head_scale = 0`` makes the initial deterministic policy the nominal itself
(the weights still get gradients, so learning proceeds), and a small ``log_std_init``
keeps the initial exploration near it. ARS (:mod:`baselines.agents.ars`, sb3-contrib)
starts there too: ``zero_policy`` zeroes every weight, and ``action_head_scale = 0`` zeroes
the last layer of an ``MlpPolicy`` whose hidden layers keep their random start (so that a
perturbation of the output layer changes the action at first order).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import torch
from stable_baselines3 import PPO, SAC, TD3
from stable_baselines3.common.base_class import BaseAlgorithm
from stable_baselines3.common.noise import NormalActionNoise
from stable_baselines3.common.vec_env import VecEnv

from baselines.agents.config import COMMAND_KEYS, make_schedule

__all__ = ["ALGO_CLASSES", "algo_class", "build_model", "start_at_nominal"]

ALGO_CLASSES: dict[str, type[BaseAlgorithm]] = {"ppo": PPO, "sac": SAC, "td3": TD3}

_ACTIVATIONS: dict[str, type[torch.nn.Module]] = {
    "tanh": torch.nn.Tanh,
    "relu": torch.nn.ReLU,
    "elu": torch.nn.ELU,
    "leaky_relu": torch.nn.LeakyReLU,
    "gelu": torch.nn.GELU,
    "silu": torch.nn.SiLU,
}


def algo_class(algo: str) -> type[BaseAlgorithm]:
    """The model class of ``algo`` (ARS imported only when asked for: sb3-contrib)."""
    if algo == "ars":
        from baselines.agents.ars import ARS

        return ARS
    return ALGO_CLASSES[algo]


def _policy_kwargs(algo: str, spec: Mapping[str, Any]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key, value in spec.items():
        if key == "activation":
            out["activation_fn"] = _ACTIVATIONS[value]
        elif key == "log_std_init" and algo != "ppo":
            continue  # SAC: set on the log_std head by start_at_nominal
        else:
            out[key] = value
    return out


def build_model(
    algo: str,
    hp: Mapping[str, Any],
    env: VecEnv,
    seed: int,
    tensorboard_log: str | None = None,
    seed_bound: int | None = None,
) -> BaseAlgorithm:
    """The SB3 model of ``algo`` with hyper-parameters ``hp`` (validated), at the nominal.

    ``seed_bound``: ARS's paired episode seeds stay below it (the environment's first
    validation seed; None: any seed)."""
    cls = algo_class(algo)
    kwargs = {k: v for k, v in hp.items() if k not in COMMAND_KEYS}
    if algo == "ars" and seed_bound is not None:
        kwargs["seed_bound"] = int(seed_bound)
    for key in ("learning_rate", "clip_range", "delta_std"):
        if key in kwargs:
            kwargs[key] = make_schedule(kwargs[key])
    kwargs["policy_kwargs"] = _policy_kwargs(algo, hp.get("policy_kwargs", {}))
    if algo == "td3":
        dim = int(np.prod(env.action_space.shape or (1,)))
        sigma = float(hp.get("action_noise_sigma", 0.1))
        kwargs["action_noise"] = NormalActionNoise(np.zeros(dim), sigma * np.ones(dim))
    model = cls(
        hp.get("policy", "MlpPolicy"),
        env,
        seed=seed,
        device="cpu",
        verbose=0,
        tensorboard_log=tensorboard_log,
        **kwargs,
    )
    start_at_nominal(model, algo, float(hp.get("action_head_scale", 0.0)), hp)
    return model


@torch.no_grad()
def start_at_nominal(
    model: BaseAlgorithm, algo: str, scale: float, hp: Mapping[str, Any] | None = None
) -> None:
    """Scale the action head's weights by ``scale`` and zero its bias (``scale = 0``: the
    deterministic policy is the zero action, i.e. the nominal); SAC's ``log_std`` head
    starts at ``log_std_init`` (weights scaled likewise); ARS's search starts from the
    scaled weights."""
    policy: Any = model.policy
    if algo == "ars":
        head = [m for m in policy.action_net if isinstance(m, torch.nn.Linear)][-1]
        head.weight.mul_(scale)
        if head.bias is not None:
            head.bias.zero_()
        ars: Any = model  # sb3-contrib's ARS keeps its search point in ``weights``
        ars.weights = torch.nn.utils.parameters_to_vector(policy.parameters()).detach()
        return
    if algo == "ppo":
        heads = [policy.action_net]
    elif algo == "sac":
        heads = [policy.actor.mu]
        log_std = (hp or {}).get("policy_kwargs", {}).get("log_std_init")
        if log_std is not None:
            policy.actor.log_std.weight.mul_(scale)
            policy.actor.log_std.bias.fill_(float(log_std))
    else:  # td3: the last Linear before the Tanh of the actor (and its target)
        heads = [next(m for m in reversed(policy.actor.mu) if isinstance(m, torch.nn.Linear))]
    for head in heads:
        head.weight.mul_(scale)
        head.bias.zero_()
    if algo == "td3":
        policy.actor_target.load_state_dict(policy.actor.state_dict())
