"""Agent hyper-parameters from zoo-style YAML files, validated (plain YAML values only).

``configs/agents/ALGO.yaml`` maps environment ids (and ``default``) to blocks of
hyper-parameters, as rl-baselines3-zoo does. An id's block overrides ``default`` key by key
(mappings such as ``env_kwargs``, ``policy_kwargs`` and ``normalize`` are merged one level
deep); ids without a block use ``default`` alone. Unlike the zoo, nothing is evaluated:
a learning-rate schedule is ``{kind: linear, start: 3.0e-4, end: 0.0}`` (linear in the
remaining progress, ``start`` at the beginning), an activation is a name (``tanh``,
``relu``, ...), a network is ``net_arch: [64, 64]`` or ``{pi: [64], vf: [64]}``. Unknown
keys, wrong types and strings that look like Python code raise ``ValueError`` naming the
file, the line and the key.

Keys of every algorithm: ``n_timesteps``, ``n_envs``, ``policy`` (``MlpPolicy``),
``env_kwargs`` (keyword arguments of the environment, plain values; not ``split``),
``normalize`` (``{obs: bool, reward: bool, clip_obs: float}``; VecNormalize),
``policy_kwargs`` (``net_arch``, ``activation``, ``log_std_init`` (PPO, SAC),
``ortho_init`` (PPO)), ``action_head_scale`` (the policy's action head is multiplied by
this at the start, 0 = the policy starts at the nominal, as residual policy learning
does), ``eval_freq`` (environment steps between validation evaluations),
``eval_episodes`` (validation episodes, null = every validation trajectory),
``torch_threads``, ``vec_env`` (``dummy`` or ``subproc``: SB3's vector environment for
an environment without a native one, Juggling-v0; ``subproc`` steps each copy in its own
process, rl-zoo's ``vec_env_type``; ignored where the native vector env is used),
``frame_stack`` (the policy observes its last ``k`` observations, flattened: Gymnasium's
``FrameStackObservation``, :mod:`baselines.agents.memory`; 1 = none; with a stack
the copies are SB3's ``DummyVecEnv`` / ``SubprocVecEnv``),
``learning_rate``, ``gamma`` and the algorithm's own keys (see :data:`ALGO_KEYS`), among
them PPO's ``use_sde`` / ``sde_sample_freq`` (SB3's generalized state-dependent
exploration: noise that is a function of the state, redrawn every ``sde_sample_freq``
steps, so that exploration survives a hand that low-passes per-step white noise).

ARS (sb3-contrib's Augmented Random Search, :mod:`baselines.agents.ars`) explores in
parameter space and plays every episode with a deterministic policy. Its keys:
``policy`` (``LinearPolicy`` or ``MlpPolicy``), ``n_delta``, ``n_top``, ``delta_std``
(a number or schedule), ``learning_rate``, ``zero_policy``, ``alive_bonus_offset``,
``n_eval_episodes`` (episodes per candidate), ``paired_seeds`` (the candidates
``w + delta`` and ``w - delta`` play episodes of the same seeds) and ``policy_kwargs``
(``with_bias``, ``squash_output``; ``net_arch`` (a list) and ``activation`` for
``MlpPolicy`` only); it takes neither ``gamma`` nor ``batch_size`` (it has no discount
and no batches), and ``normalize`` only ``obs`` and ``clip_obs`` (the candidates are
ranked by their raw returns, as the ARS paper and rl-zoo's ``ars.yml`` do).
"""

from __future__ import annotations

import copy
import re
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import yaml

from baselines.agents import config_values as V
from baselines.agents.config_values import (
    MAX_BATCH,
    MAX_BUFFER_SIZE,
    MAX_N_ENVS,
    MAX_TIMESTEPS,
    Checker,
)
from baselines.agents.yaml_files import YamlLoader, key_lines, read_yaml

__all__ = [
    "ACTIVATIONS",
    "ALGOS",
    "ALGO_KEYS",
    "COMMON_KEYS",
    "DEFAULT_CONFIG_DIR",
    "MAX_N_ENVS",
    "NOT_TAKEN",
    "SWEEP_CONFIG_DIR",
    "YamlLoader",
    "check_combination",
    "default_config_path",
    "load_hyperparams",
    "make_schedule",
    "parse_env_kwargs",
    "resolve_hyperparams",
    "validate_hyperparams",
]

#: Algorithms ``motion-bench train`` knows.
ALGOS: tuple[str, ...] = ("ppo", "sac", "td3", "ars")
#: The agent configs shipped in the package (``baselines/configs/agents``, package data),
#: so that a wheel install finds them; the repository's ``configs/agents`` is a link to
#: this folder, one file on disk (``tests/test_packaged_configs.py``).
DEFAULT_CONFIG_DIR = Path(__file__).resolve().parents[1] / "configs" / "agents"
#: The sweep files shipped in the package (``configs/sweeps`` links here, as above).
SWEEP_CONFIG_DIR = Path(__file__).resolve().parents[1] / "configs" / "sweeps"
#: The longest frame stack (observations) a config may ask for.
MAX_FRAME_STACK = 256
#: Activation names and their ``torch.nn`` classes.
ACTIVATIONS: tuple[str, ...] = ("tanh", "relu", "elu", "leaky_relu", "gelu", "silu")

#: A learning rate: in (0, 1]; a linear schedule may end at 0.
_LR = V.schedule_or(V.float_in(0.0, 1.0, open_lo=True), V.float_in(0.0, 1.0))

#: Keys every algorithm takes.
COMMON_KEYS: dict[str, Checker] = {
    "n_timesteps": V.int_in(1, MAX_TIMESTEPS),
    "n_envs": V.int_in(1, MAX_N_ENVS),
    "policy": V.choice("MlpPolicy"),
    "env_kwargs": V.env_kwargs,
    "normalize": V.sub(
        {
            "obs": V.bool_value,
            "reward": V.bool_value,
            "clip_obs": V.float_in(0.0, open_lo=True),
            "gamma": V.float_in(0.0, 1.0),  # 0: a one-step (episodic) environment
        }
    ),
    "action_head_scale": V.float_in(0.0, 1.0),
    "eval_freq": V.int_in(1),
    "eval_episodes": V.optional(V.int_in(1)),
    "torch_threads": V.int_in(1, 1024),
    "vec_env": V.choice("dummy", "subproc"),
    "frame_stack": V.int_in(1, MAX_FRAME_STACK),
    "learning_rate": _LR,
    "gamma": V.float_in(0.0, 1.0),  # 0: a one-step (episodic) environment
    "batch_size": V.int_in(1, MAX_BATCH),
}

_OFF_POLICY: dict[str, Checker] = {
    "buffer_size": V.int_in(1, MAX_BUFFER_SIZE),
    "learning_starts": V.int_in(0),
    "tau": V.float_in(0.0, 1.0),
    "train_freq": V.int_in(1),
    "gradient_steps": V.int_in(-1),
}

#: Keys of each algorithm (beyond :data:`COMMON_KEYS`).
ALGO_KEYS: dict[str, dict[str, Checker]] = {
    "ppo": {
        "n_steps": V.int_in(2, MAX_BATCH),
        "n_epochs": V.int_in(1),
        "gae_lambda": V.float_in(0.0, 1.0),
        "clip_range": V.schedule_or(V.float_in(0.0)),
        "ent_coef": V.float_in(0.0),
        "vf_coef": V.float_in(0.0),
        "max_grad_norm": V.float_in(0.0),
        "target_kl": V.optional(V.float_in(0.0)),
        "normalize_advantage": V.bool_value,
        "use_sde": V.bool_value,
        "sde_sample_freq": V.int_in(-1),
        "policy_kwargs": V.sub(
            {
                "net_arch": V.net_arch,
                "activation": V.choice(*ACTIVATIONS),
                "log_std_init": V.float_in(-20.0, 2.0),
                "ortho_init": V.bool_value,
            }
        ),
    },
    "sac": {
        **_OFF_POLICY,
        "ent_coef": lambda v, w: v if v == "auto" else V.float_in(0.0)(v, w),
        "target_entropy": lambda v, w: v if v == "auto" else V.float_in()(v, w),
        "policy_kwargs": V.sub(
            {
                "net_arch": V.net_arch,
                "activation": V.choice(*ACTIVATIONS),
                "log_std_init": V.float_in(-20.0, 2.0),
            }
        ),
    },
    "td3": {
        **_OFF_POLICY,
        "policy_delay": V.int_in(1),
        "target_policy_noise": V.float_in(0.0),
        "target_noise_clip": V.float_in(0.0),
        "action_noise_sigma": V.float_in(0.0),
        "policy_kwargs": V.sub({"net_arch": V.net_arch, "activation": V.choice(*ACTIVATIONS)}),
    },
    "ars": {
        "policy": V.choice("LinearPolicy", "MlpPolicy"),
        "normalize": V.sub({"obs": V.bool_value, "clip_obs": V.float_in(0.0, open_lo=True)}),
        "n_delta": V.int_in(1, MAX_BATCH),
        "n_top": V.int_in(1, MAX_BATCH),
        "delta_std": V.schedule_or(V.float_in(0.0, open_lo=True), V.float_in(0.0)),
        "zero_policy": V.bool_value,
        "alive_bonus_offset": V.float_in(),
        "n_eval_episodes": V.int_in(1, MAX_BATCH),
        "paired_seeds": V.bool_value,
        "policy_kwargs": V.sub(
            {
                "net_arch": V.net_arch_list,
                "activation": V.choice(*ACTIVATIONS),
                "with_bias": V.bool_value,
                "squash_output": V.bool_value,
            }
        ),
    },
}
#: Keys of :data:`COMMON_KEYS` an algorithm does not take.
NOT_TAKEN: dict[str, frozenset[str]] = {"ars": frozenset({"gamma", "batch_size"})}

#: Keys the training command consumes itself (not passed to the SB3 constructor).
COMMAND_KEYS: tuple[str, ...] = (
    "n_timesteps",
    "n_envs",
    "policy",
    "env_kwargs",
    "normalize",
    "action_head_scale",
    "eval_freq",
    "eval_episodes",
    "torch_threads",
    "vec_env",
    "frame_stack",
    "action_noise_sigma",
)

#: Values of the command keys when no block sets them.
COMMAND_DEFAULTS: dict[str, Any] = {
    "n_timesteps": 100_000,
    "n_envs": 8,
    "policy": "MlpPolicy",
    "env_kwargs": {},
    "normalize": {},
    "action_head_scale": 0.0,
    "eval_freq": 10_000,
    "eval_episodes": None,
    "torch_threads": 1,
    "vec_env": "dummy",
    "frame_stack": 1,
}


def default_config_path(algo: str) -> Path:
    """``configs/agents/ALGO.yaml`` (the package's file, :data:`DEFAULT_CONFIG_DIR`)."""
    return DEFAULT_CONFIG_DIR / f"{algo}.yaml"


def registered_env_ids() -> list[str]:
    """Every environment id Gymnasium knows once ``motion_envs`` registered its own."""
    import gymnasium as gym

    import motion_envs  # noqa: F401  (registers the environments)

    return sorted(gym.envs.registry)


def unknown_env_id(name: str) -> str:
    """The message for an unregistered id ``name``, with the closest registered ids."""
    import difflib

    ids = registered_env_ids()
    close = difflib.get_close_matches(name, ids, n=3, cutoff=0.6)
    hint = f"; did you mean {' or '.join(repr(c) for c in close)}?" if close else ""
    ours = [i for i in ids if i.startswith("MotionEnvs/")]
    return f"{name!r} is not a registered environment id{hint} (motion-envs ids: {ours})"


def validate_hyperparams(algo: str, block: Any, where: str = "config") -> dict[str, Any]:
    """Check one block of hyper-parameters of ``algo``; the cleaned dict.

    ``where`` prefixes the errors (``"FILE, line N: KEY: ..."`` when called by
    :func:`load_hyperparams`).
    """
    if algo not in ALGOS:
        raise ValueError(f"algo must be one of {list(ALGOS)}; got {algo!r}")
    if block is None:
        return {}
    if not isinstance(block, Mapping):
        raise V.fail(where, f"must be a mapping of hyper-parameters; got {block!r}")
    schema = {**COMMON_KEYS, **ALGO_KEYS[algo]}
    for key in NOT_TAKEN.get(algo, ()):
        del schema[key]
    out: dict[str, Any] = {}
    for key, value in block.items():
        if key not in schema:
            raise V.fail(
                f"{where}: {key}", f"unknown key for {algo}; expected one of {sorted(schema)}"
            )
        out[str(key)] = schema[key](value, f"{where}: {key}")
    return out


def _merge(base: Mapping[str, Any], over: Mapping[str, Any]) -> dict[str, Any]:
    out = copy.deepcopy(dict(base))
    for key, value in over.items():
        if isinstance(value, Mapping) and isinstance(out.get(key), Mapping):
            out[key] = {**out[key], **copy.deepcopy(dict(value))}
        else:
            out[key] = copy.deepcopy(value)
    return out


def load_hyperparams(path: str | Path, algo: str, env_id: str) -> dict[str, Any]:
    """The validated ``default`` block of ``path`` merged with ``env_id``'s block.

    Errors name the file and the line of the offending key.
    """
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"config file {path} does not exist")
    doc, node = read_yaml(path)
    if doc is None:
        doc = {}
    if not isinstance(doc, Mapping):
        raise ValueError(f"{path}: must map environment ids (and 'default') to hyper-parameters")
    lines = key_lines(node)
    ids = None
    blocks: dict[str, dict[str, Any]] = {}
    for name, block in doc.items():
        name = str(name)
        if name != "default" and not re.fullmatch(r"[\w.:/-]+-v\d+", name):
            raise ValueError(
                f"{path}, line {lines.get((name,), '?')}: top-level key {name!r} is neither "
                "'default' nor an environment id (NAMESPACE/Name-vN)"
            )
        if name != "default":
            ids = registered_env_ids() if ids is None else ids
            if name not in ids:  # a misspelt id's block would be silently ignored
                raise ValueError(
                    f"{path}, line {lines.get((name,), '?')}: top-level key {unknown_env_id(name)}"
                )
        try:
            blocks[name] = validate_hyperparams(algo, block, name)
        except ValueError as exc:
            key = str(exc).split(":")[1].strip() if ":" in str(exc) else ""
            line = lines.get((name, key), lines.get((name,), "?"))
            raise ValueError(f"{path}, line {line}: {exc}") from None
    return _merge(blocks.get("default", {}), blocks.get(env_id, {}))


def parse_env_kwargs(items: list[str] | None) -> dict[str, Any]:
    """``["k=v", ...]`` from the command line; values read as plain YAML scalars/lists.

    ``nominal=bezier-null`` gives a string, ``val_fraction=0.2`` a float,
    ``shapes=[Angle, GShape]`` a list; ``nominal=null`` the string ``"null"``.
    """
    out: dict[str, Any] = {}
    for item in items or []:
        key, sep, raw = item.partition("=")
        if not sep or not key.isidentifier():
            raise ValueError(f"--env-kwargs: expected KEY=VALUE; got {item!r}")
        try:
            value = yaml.load(raw, Loader=YamlLoader)
        except yaml.YAMLError:
            raise ValueError(f"--env-kwargs: cannot read the value of {item!r}") from None
        out[key] = raw if value is None and raw else value  # nominal=null is the null model
    return V.env_kwargs(out, "--env-kwargs")


def resolve_hyperparams(
    algo: str,
    env_id: str,
    config_path: str | Path | None = None,
    overrides: Mapping[str, Any] | None = None,
) -> dict[str, Any]:
    """The complete hyper-parameters of a run: command defaults, the file's ``default``
    and ``env_id`` blocks, then ``overrides`` (validated, ``env_kwargs`` merged)."""
    path = default_config_path(algo) if config_path is None else Path(config_path)
    hp = _merge(COMMAND_DEFAULTS, load_hyperparams(path, algo, env_id))
    if overrides:
        hp = _merge(hp, validate_hyperparams(algo, dict(overrides), "overrides"))
    check_combination(algo, hp, f"{path} ({env_id})")
    return hp


def check_combination(algo: str, hp: Mapping[str, Any], where: str) -> None:
    """Refuse keys that are valid one by one but not together (one-line ``ValueError``
    starting with ``where``): ARS's ``LinearPolicy`` has no hidden layers, and its
    ``n_top`` best directions are among its ``n_delta``."""
    if algo != "ars":
        return
    if hp.get("policy") == "LinearPolicy":
        hidden = sorted({"net_arch", "activation"} & set(hp.get("policy_kwargs", {})))
        if hidden:
            raise V.fail(
                f"{where}: policy_kwargs.{hidden[0]}",
                "LinearPolicy has no hidden layers (use policy: MlpPolicy for net_arch)",
            )
    n_delta, n_top = int(hp.get("n_delta", 8)), hp.get("n_top")  # 8: sb3-contrib's default
    if n_top is not None and int(n_top) > n_delta:
        raise V.fail(f"{where}: n_top", f"must be <= n_delta ({n_delta}); got {n_top}")


def make_schedule(value: Any) -> float | Callable[[float], float]:
    """A number, or SB3's schedule ``f(progress_remaining)`` of a validated schedule.

    ``linear``: ``end + progress_remaining (start - end)`` (``start`` when training starts).
    """
    if not isinstance(value, Mapping):
        return float(value)
    start = float(value["start"])
    if value["kind"] == "constant":
        return start
    end = float(value["end"])
    return _Linear(start, end)


class _Linear:
    """``end + p (start - end)`` for the remaining progress ``p`` (a picklable callable)."""

    def __init__(self, start: float, end: float) -> None:
        self.start, self.end = start, end

    def __call__(self, progress_remaining: float) -> float:
        return self.end + progress_remaining * (self.start - self.end)
