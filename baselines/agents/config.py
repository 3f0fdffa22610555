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
``learning_rate``, ``gamma`` and the algorithm's own keys (see :data:`ALGO_KEYS`), among
them PPO's ``use_sde`` / ``sde_sample_freq`` (SB3's generalized state-dependent
exploration: noise that is a function of the state, redrawn every ``sde_sample_freq``
steps, so that exploration survives a hand that low-passes per-step white noise).
"""

from __future__ import annotations

import copy
import itertools
import math
import re
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import yaml

from baselines.agents.yaml_files import YamlLoader, key_lines, read_yaml

__all__ = [
    "ACTIVATIONS",
    "ALGOS",
    "ALGO_KEYS",
    "COMMON_KEYS",
    "DEFAULT_CONFIG_DIR",
    "SWEEP_CONFIG_DIR",
    "YamlLoader",
    "default_config_path",
    "load_hyperparams",
    "make_schedule",
    "parse_env_kwargs",
    "resolve_hyperparams",
    "validate_hyperparams",
]

#: Algorithms ``motion-bench train`` knows.
ALGOS: tuple[str, ...] = ("ppo", "sac", "td3")
#: The agent configs shipped in the package (``baselines/configs/agents``, package data),
#: so that a wheel install finds them; the repository's ``configs/agents`` is a link to
#: this folder, one file on disk (``tests/test_packaged_configs.py``).
DEFAULT_CONFIG_DIR = Path(__file__).resolve().parents[1] / "configs" / "agents"
#: The sweep files shipped in the package (``configs/sweeps`` links here, as above).
SWEEP_CONFIG_DIR = Path(__file__).resolve().parents[1] / "configs" / "sweeps"
#: Activation names and their ``torch.nn`` classes.
ACTIVATIONS: tuple[str, ...] = ("tanh", "relu", "elu", "leaky_relu", "gelu", "silu")

# A checker takes (value, where) and returns the cleaned value or raises ValueError.
Checker = Callable[[Any, str], Any]

_PYTHON = re.compile(r"(\(|\)|lambda|\bnn\.|\bth\.|torch\.|__|import|dict\(|\blin_)")


def _fail(where: str, message: str) -> ValueError:
    return ValueError(f"{where}: {message}")


def _no_python(value: Any, where: str) -> None:
    if isinstance(value, str) and _PYTHON.search(value):
        raise _fail(
            where,
            f"{value!r} looks like Python code; write plain YAML values "
            "(e.g. learning_rate: {kind: linear, start: 3.0e-4}, activation: relu)",
        )


#: Largest integer any count of a config may take (steps, buffer and batch sizes, seeds).
MAX_INT = 2**31 - 1
#: Most environment copies of a run (``n_envs``).
MAX_N_ENVS = 256
#: Most environment steps of a run (``n_timesteps``).
MAX_TIMESTEPS = 10**10
#: Most hidden layers of a network and units of one layer (``net_arch``).
MAX_LAYERS = 64
MAX_LAYER_SIZE = 2**16
#: Most weights between a network's hidden layers: float32 weights, their gradients and
#: Adam's two moments take 16 bytes each, 1.6 GB at this bound.
MAX_HIDDEN_WEIGHTS = 10**8
#: Most transitions of an off-policy replay buffer (``buffer_size``; SB3's default is
#: 10^6) and samples of a rollout or a batch (``n_steps``, ``batch_size``): bounds of the
#: memory they allocate up front.
MAX_BUFFER_SIZE = 10**7
MAX_BATCH = 2**20


def _integral(v: Any) -> Any:
    """``v`` as an int when it is a float holding an integer (YAML's ``1e3``, ``64.0``)."""
    if isinstance(v, float) and math.isfinite(v) and v.is_integer():
        return int(v)
    return v


def _int(lo: int = 0, hi: int = MAX_INT) -> Checker:
    def check(v: Any, where: str) -> int:
        _no_python(v, where)
        v = _integral(v)
        if isinstance(v, bool) or not isinstance(v, int) or not lo <= v <= hi:
            shown = (
                v if not isinstance(v, int) or abs(v) < 10**30 else f"a {len(str(v))}-digit integer"
            )
            raise _fail(where, f"must be an integer in [{lo}, {hi}]; got {shown!r}")
        return int(v)

    return check


def _float(lo: float = -math.inf, hi: float = math.inf, *, open_lo: bool = False) -> Checker:
    """A finite number in ``[lo, hi]`` (``(lo, hi]`` with ``open_lo``); an integer too
    large for a float is refused like ``inf``, not with an ``OverflowError``."""
    interval = f"{'(' if open_lo else '['}{lo}, {hi}]"

    def check(v: Any, where: str) -> float:
        _no_python(v, where)
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            raise _fail(where, f"must be a finite number; got {v!r}")
        if isinstance(v, int) and abs(v) >= 10**300:
            raise _fail(
                where, f"must be a finite number in {interval}; got a {len(str(v))}-digit integer"
            )
        x = float(v)
        if not math.isfinite(x):
            raise _fail(where, f"must be a finite number; got {v!r}")
        if not (lo < x <= hi if open_lo else lo <= x <= hi):
            raise _fail(where, f"must be in {interval}; got {v!r}")
        return x

    return check


def _bool(v: Any, where: str) -> bool:
    _no_python(v, where)
    if not isinstance(v, bool):
        raise _fail(where, f"must be true or false; got {v!r}")
    return v


def _optional(check: Checker) -> Checker:
    return lambda v, where: None if v is None else check(v, where)


def _choice(*choices: str) -> Checker:
    def check(v: Any, where: str) -> str:
        _no_python(v, where)
        if v not in choices:
            raise _fail(where, f"must be one of {list(choices)}; got {v!r}")
        return str(v)

    return check


def _schedule_or(check_value: Checker, check_end: Checker | None = None) -> Checker:
    """A number, or ``{kind: linear|constant, start: x, end: y}`` (``end`` checked by
    ``check_end``, default ``check_value``)."""
    check_end = check_value if check_end is None else check_end

    def check(v: Any, where: str) -> Any:
        if not isinstance(v, Mapping):
            return check_value(v, where)
        extra = set(v) - {"kind", "start", "end"}
        if extra:
            raise _fail(where, f"unknown schedule keys {sorted(extra)}; expected kind, start, end")
        kind = _choice("linear", "constant")(v.get("kind"), f"{where}.kind")
        if "start" not in v:
            raise _fail(where, "a schedule needs 'start'")
        out: dict[str, Any] = {"kind": kind, "start": check_value(v["start"], f"{where}.start")}
        if kind == "linear":
            out["end"] = check_end(v.get("end", 0.0), f"{where}.end")
        elif "end" in v:
            raise _fail(where, "a constant schedule has no 'end'")
        return out

    return check


def _net_arch(v: Any, where: str) -> Any:
    def layers(x: Any, w: str) -> list[int]:
        if isinstance(x, list):
            x = [_integral(n) for n in x]
        if not isinstance(x, list) or not all(
            isinstance(n, int) and not isinstance(n, bool) and n > 0 for n in x
        ):
            raise _fail(w, f"must be a list of positive layer sizes; got {x!r}")
        if len(x) > MAX_LAYERS or any(n > MAX_LAYER_SIZE for n in x):
            raise _fail(
                w,
                f"at most {MAX_LAYERS} layers of at most {MAX_LAYER_SIZE} units each; got "
                f"{len(x)} layer(s), the largest {max(x)}",
            )
        weights = sum(a * b for a, b in itertools.pairwise(x))
        if weights > MAX_HIDDEN_WEIGHTS:
            raise _fail(
                w,
                f"{weights} weights between hidden layers, more than {MAX_HIDDEN_WEIGHTS} "
                f"({MAX_HIDDEN_WEIGHTS * 16 / 1e9:g} GB with gradients and Adam's moments)",
            )
        return [int(n) for n in x]

    _no_python(v, where)
    if isinstance(v, Mapping):
        extra = set(v) - {"pi", "vf", "qf"}
        if extra:
            raise _fail(where, f"unknown keys {sorted(extra)}; expected pi, vf (PPO) or pi, qf")
        return {k: layers(x, f"{where}.{k}") for k, x in v.items()}
    return layers(v, where)


def _plain_mapping(v: Any, where: str) -> dict[str, Any]:
    """A mapping of plain YAML values (numbers, strings, booleans, lists, mappings)."""
    if not isinstance(v, Mapping):
        raise _fail(where, f"must be a mapping; got {v!r}")

    def walk(x: Any, w: str) -> Any:
        if isinstance(x, Mapping):
            return {str(k): walk(y, f"{w}.{k}") for k, y in x.items()}
        if isinstance(x, list):
            return [walk(y, f"{w}[{i}]") for i, y in enumerate(x)]
        if x is None or isinstance(x, (bool, int, float)):
            return x
        if isinstance(x, str):
            _no_python(x, w)
            return x
        raise _fail(w, f"must be a plain YAML value; got {type(x).__name__}")

    out: dict[str, Any] = walk(v, where)
    return out


def _env_kwargs(v: Any, where: str) -> dict[str, Any]:
    out = _plain_mapping(v, where)
    for key in ("split", "render_mode"):
        if key in out:
            raise _fail(
                f"{where}.{key}", "is set by the command (train: 'train', validation: 'val')"
            )
    return out


def _sub(schema: Mapping[str, Checker]) -> Checker:
    def check(v: Any, where: str) -> dict[str, Any]:
        _no_python(v, where)
        if not isinstance(v, Mapping):
            raise _fail(where, f"must be a mapping; got {v!r}")
        extra = [k for k in v if k not in schema]
        if extra:
            raise _fail(f"{where}.{extra[0]}", f"unknown key; expected one of {sorted(schema)}")
        return {k: schema[k](x, f"{where}.{k}") for k, x in v.items()}

    return check


#: A learning rate: in (0, 1]; a linear schedule may end at 0.
_LR = _schedule_or(_float(0.0, 1.0, open_lo=True), _float(0.0, 1.0))

#: Keys every algorithm takes.
COMMON_KEYS: dict[str, Checker] = {
    "n_timesteps": _int(1, MAX_TIMESTEPS),
    "n_envs": _int(1, MAX_N_ENVS),
    "policy": _choice("MlpPolicy"),
    "env_kwargs": _env_kwargs,
    "normalize": _sub(
        {
            "obs": _bool,
            "reward": _bool,
            "clip_obs": _float(0.0, open_lo=True),
            "gamma": _float(0.0, 1.0),  # 0: a one-step (episodic) environment
        }
    ),
    "action_head_scale": _float(0.0, 1.0),
    "eval_freq": _int(1),
    "eval_episodes": _optional(_int(1)),
    "torch_threads": _int(1, 1024),
    "vec_env": _choice("dummy", "subproc"),
    "learning_rate": _LR,
    "gamma": _float(0.0, 1.0),  # 0: a one-step (episodic) environment
    "batch_size": _int(1, MAX_BATCH),
}

_OFF_POLICY: dict[str, Checker] = {
    "buffer_size": _int(1, MAX_BUFFER_SIZE),
    "learning_starts": _int(0),
    "tau": _float(0.0, 1.0),
    "train_freq": _int(1),
    "gradient_steps": _int(-1),
}

#: Keys of each algorithm (beyond :data:`COMMON_KEYS`).
ALGO_KEYS: dict[str, dict[str, Checker]] = {
    "ppo": {
        "n_steps": _int(2, MAX_BATCH),
        "n_epochs": _int(1),
        "gae_lambda": _float(0.0, 1.0),
        "clip_range": _schedule_or(_float(0.0)),
        "ent_coef": _float(0.0),
        "vf_coef": _float(0.0),
        "max_grad_norm": _float(0.0),
        "target_kl": _optional(_float(0.0)),
        "normalize_advantage": _bool,
        "use_sde": _bool,
        "sde_sample_freq": _int(-1),
        "policy_kwargs": _sub(
            {
                "net_arch": _net_arch,
                "activation": _choice(*ACTIVATIONS),
                "log_std_init": _float(-20.0, 2.0),
                "ortho_init": _bool,
            }
        ),
    },
    "sac": {
        **_OFF_POLICY,
        "ent_coef": lambda v, w: v if v == "auto" else _float(0.0)(v, w),
        "target_entropy": lambda v, w: v if v == "auto" else _float()(v, w),
        "policy_kwargs": _sub(
            {
                "net_arch": _net_arch,
                "activation": _choice(*ACTIVATIONS),
                "log_std_init": _float(-20.0, 2.0),
            }
        ),
    },
    "td3": {
        **_OFF_POLICY,
        "policy_delay": _int(1),
        "target_policy_noise": _float(0.0),
        "target_noise_clip": _float(0.0),
        "action_noise_sigma": _float(0.0),
        "policy_kwargs": _sub({"net_arch": _net_arch, "activation": _choice(*ACTIVATIONS)}),
    },
}

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
        raise _fail(where, f"must be a mapping of hyper-parameters; got {block!r}")
    schema = {**COMMON_KEYS, **ALGO_KEYS[algo]}
    out: dict[str, Any] = {}
    for key, value in block.items():
        if key not in schema:
            raise _fail(
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
    return _env_kwargs(out, "--env-kwargs")


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
    return hp


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
