"""The value checkers of the agent configs (:mod:`baselines.agents.config`).

A checker takes ``(value, where)`` and returns the cleaned value or raises a one-line
``ValueError`` that starts with ``where`` (the file, the line and the key); the bounds
(:data:`MAX_N_ENVS`, :data:`MAX_TIMESTEPS`, ...) keep every count within what a run can
allocate. Plain YAML values only: a string that looks like Python code is refused.
"""

from __future__ import annotations

import itertools
import math
import re
from collections.abc import Callable, Mapping
from typing import Any

__all__ = [
    "MAX_BATCH",
    "MAX_BUFFER_SIZE",
    "MAX_HIDDEN_WEIGHTS",
    "MAX_INT",
    "MAX_LAYERS",
    "MAX_LAYER_SIZE",
    "MAX_N_ENVS",
    "MAX_TIMESTEPS",
    "Checker",
    "bool_value",
    "choice",
    "env_kwargs",
    "fail",
    "float_in",
    "int_in",
    "integral",
    "net_arch",
    "net_arch_list",
    "no_python",
    "optional",
    "plain_mapping",
    "schedule_or",
    "sub",
]

# A checker takes (value, where) and returns the cleaned value or raises ValueError.
Checker = Callable[[Any, str], Any]

_PYTHON = re.compile(r"(\(|\)|lambda|\bnn\.|\bth\.|torch\.|__|import|dict\(|\blin_)")


def fail(where: str, message: str) -> ValueError:
    return ValueError(f"{where}: {message}")


def no_python(value: Any, where: str) -> None:
    if isinstance(value, str) and _PYTHON.search(value):
        raise fail(
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


def integral(v: Any) -> Any:
    """``v`` as an int when it is a float holding an integer (YAML's ``1e3``, ``64.0``)."""
    if isinstance(v, float) and math.isfinite(v) and v.is_integer():
        return int(v)
    return v


def int_in(lo: int = 0, hi: int = MAX_INT) -> Checker:
    def check(v: Any, where: str) -> int:
        no_python(v, where)
        v = integral(v)
        if isinstance(v, bool) or not isinstance(v, int) or not lo <= v <= hi:
            shown = (
                v if not isinstance(v, int) or abs(v) < 10**30 else f"a {len(str(v))}-digit integer"
            )
            raise fail(where, f"must be an integer in [{lo}, {hi}]; got {shown!r}")
        return int(v)

    return check


def float_in(lo: float = -math.inf, hi: float = math.inf, *, open_lo: bool = False) -> Checker:
    """A finite number in ``[lo, hi]`` (``(lo, hi]`` with ``open_lo``); an integer too
    large for a float is refused like ``inf``, not with an ``OverflowError``."""
    interval = f"{'(' if open_lo else '['}{lo}, {hi}]"

    def check(v: Any, where: str) -> float:
        no_python(v, where)
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            raise fail(where, f"must be a finite number; got {v!r}")
        if isinstance(v, int) and abs(v) >= 10**300:
            raise fail(
                where, f"must be a finite number in {interval}; got a {len(str(v))}-digit integer"
            )
        x = float(v)
        if not math.isfinite(x):
            raise fail(where, f"must be a finite number; got {v!r}")
        if not (lo < x <= hi if open_lo else lo <= x <= hi):
            raise fail(where, f"must be in {interval}; got {v!r}")
        return x

    return check


def bool_value(v: Any, where: str) -> bool:
    no_python(v, where)
    if not isinstance(v, bool):
        raise fail(where, f"must be true or false; got {v!r}")
    return v


def optional(check: Checker) -> Checker:
    return lambda v, where: None if v is None else check(v, where)


def choice(*choices: str) -> Checker:
    def check(v: Any, where: str) -> str:
        no_python(v, where)
        if v not in choices:
            raise fail(where, f"must be one of {list(choices)}; got {v!r}")
        return str(v)

    return check


def schedule_or(check_value: Checker, check_end: Checker | None = None) -> Checker:
    """A number, or ``{kind: linear|constant, start: x, end: y}`` (``end`` checked by
    ``check_end``, default ``check_value``)."""
    check_end = check_value if check_end is None else check_end

    def check(v: Any, where: str) -> Any:
        if not isinstance(v, Mapping):
            return check_value(v, where)
        extra = set(v) - {"kind", "start", "end"}
        if extra:
            raise fail(where, f"unknown schedule keys {sorted(extra)}; expected kind, start, end")
        kind = choice("linear", "constant")(v.get("kind"), f"{where}.kind")
        if "start" not in v:
            raise fail(where, "a schedule needs 'start'")
        out: dict[str, Any] = {"kind": kind, "start": check_value(v["start"], f"{where}.start")}
        if kind == "linear":
            out["end"] = check_end(v.get("end", 0.0), f"{where}.end")
        elif "end" in v:
            raise fail(where, "a constant schedule has no 'end'")
        return out

    return check


def net_arch(v: Any, where: str) -> Any:
    def layers(x: Any, w: str) -> list[int]:
        if isinstance(x, list):
            x = [integral(n) for n in x]
        if not isinstance(x, list) or not all(
            isinstance(n, int) and not isinstance(n, bool) and n > 0 for n in x
        ):
            raise fail(w, f"must be a list of positive layer sizes; got {x!r}")
        if len(x) > MAX_LAYERS or any(n > MAX_LAYER_SIZE for n in x):
            raise fail(
                w,
                f"at most {MAX_LAYERS} layers of at most {MAX_LAYER_SIZE} units each; got "
                f"{len(x)} layer(s), the largest {max(x)}",
            )
        weights = sum(a * b for a, b in itertools.pairwise(x))
        if weights > MAX_HIDDEN_WEIGHTS:
            raise fail(
                w,
                f"{weights} weights between hidden layers, more than {MAX_HIDDEN_WEIGHTS} "
                f"({MAX_HIDDEN_WEIGHTS * 16 / 1e9:g} GB with gradients and Adam's moments)",
            )
        return [int(n) for n in x]

    no_python(v, where)
    if isinstance(v, Mapping):
        extra = set(v) - {"pi", "vf", "qf"}
        if extra:
            raise fail(where, f"unknown keys {sorted(extra)}; expected pi, vf (PPO) or pi, qf")
        return {k: layers(x, f"{where}.{k}") for k, x in v.items()}
    return layers(v, where)


def net_arch_list(v: Any, where: str) -> list[int]:
    """:func:`net_arch` as one list of layer sizes (a network without separate heads)."""
    no_python(v, where)
    if isinstance(v, Mapping):
        raise fail(where, f"must be a list of layer sizes (one network, no pi/vf heads); got {v!r}")
    out: list[int] = net_arch(v, where)
    return out


def plain_mapping(v: Any, where: str) -> dict[str, Any]:
    """A mapping of plain YAML values (numbers, strings, booleans, lists, mappings)."""
    if not isinstance(v, Mapping):
        raise fail(where, f"must be a mapping; got {v!r}")

    def walk(x: Any, w: str) -> Any:
        if isinstance(x, Mapping):
            return {str(k): walk(y, f"{w}.{k}") for k, y in x.items()}
        if isinstance(x, list):
            return [walk(y, f"{w}[{i}]") for i, y in enumerate(x)]
        if x is None or isinstance(x, (bool, int, float)):
            return x
        if isinstance(x, str):
            no_python(x, w)
            return x
        raise fail(w, f"must be a plain YAML value; got {type(x).__name__}")

    out: dict[str, Any] = walk(v, where)
    return out


def env_kwargs(v: Any, where: str) -> dict[str, Any]:
    out = plain_mapping(v, where)
    for key in ("split", "render_mode"):
        if key in out:
            raise fail(
                f"{where}.{key}", "is set by the command (train: 'train', validation: 'val')"
            )
    return out


def sub(schema: Mapping[str, Checker]) -> Checker:
    def check(v: Any, where: str) -> dict[str, Any]:
        no_python(v, where)
        if not isinstance(v, Mapping):
            raise fail(where, f"must be a mapping; got {v!r}")
        extra = [k for k in v if k not in schema]
        if extra:
            raise fail(f"{where}.{extra[0]}", f"unknown key; expected one of {sorted(schema)}")
        return {k: schema[k](x, f"{where}.{k}") for k, x in v.items()}

    return check
