"""The sweep file and its search space: :class:`SweepConfig`, :func:`load_sweep`,
:func:`expand_configurations` (grid, random draws) and :func:`configuration` (one point
of the flat space, validated). No Ray here."""

from __future__ import annotations

import itertools
import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from baselines.agents.config import ALGOS, validate_hyperparams

TOP_KEYS = {
    "search",
    "num_samples",
    "random_seed",
    "seeds",
    "timesteps",
    "n_envs",
    "test_split",
    "space",
    "description",
}
SPACE_KEYS = {"algo", "env_id", "hyperparams", "env_kwargs"}
#: Searches of a sweep file.
SEARCHES: tuple[str, ...] = ("grid", "random", "optuna")


@dataclass(frozen=True)
class SweepConfig:
    """A validated sweep: the configurations (dicts with ``algo``, ``env_id``,
    ``overrides``), the seeds, and where/how to run."""

    path: str
    configurations: tuple[dict[str, Any], ...]
    seeds: tuple[int, ...]
    out: str
    test_split: str = "test"
    timesteps: int | None = None
    n_envs: int | None = None
    address: str | None = None
    num_cpus: int | None = None
    resume: bool = False
    progress: bool = False
    search: str = "grid"
    num_samples: int = 1
    random_seed: int = 0
    space: Mapping[str, Any] | None = None  # optuna: the flat space, keys "hyperparams.lr"


def _draw(value: Any, rng: np.random.Generator, where: str) -> Any:
    if isinstance(value, list):
        if not value:
            raise ValueError(f"{where}: an empty list of choices")
        return value[int(rng.integers(len(value)))]
    if isinstance(value, Mapping) and len(value) == 1:
        ((kind, bounds),) = value.items()
        if kind in ("uniform", "loguniform", "randint") and (
            isinstance(bounds, list) and len(bounds) == 2
        ):
            lo, hi = bounds
            if kind == "uniform":
                return float(rng.uniform(lo, hi))
            if kind == "loguniform":
                return float(np.exp(rng.uniform(np.log(lo), np.log(hi))))
            return int(rng.integers(int(lo), int(hi) + 1))
    raise ValueError(
        f"{where}: expected a list of values or {{uniform|loguniform|randint: [lo, hi]}}; "
        f"got {value!r}"
    )


def flat_space(space: Mapping[str, Any], path: str) -> dict[tuple[str, ...], Any]:
    """The ``space`` block as one mapping: keys ``("algo",)``, ``("env_id",)``,
    ``("hyperparams", name)`` and ``("env_kwargs", name)``."""
    extra = set(space) - SPACE_KEYS
    if extra:
        raise ValueError(
            f"{path}: space has unknown keys {sorted(extra)}; expected {sorted(SPACE_KEYS)}"
        )
    flat: dict[tuple[str, ...], Any] = {}
    for key in ("algo", "env_id"):
        if key not in space:
            raise ValueError(f"{path}: space.{key} is required (a list)")
        flat[(key,)] = space[key]
    for group in ("hyperparams", "env_kwargs"):
        block = space.get(group) or {}
        if not isinstance(block, Mapping):
            raise ValueError(f"{path}: space.{group} must be a mapping of lists")
        for name, value in block.items():
            flat[(group, str(name))] = value
    return flat


def expand_configurations(doc: Mapping[str, Any], path: str = "sweep") -> list[dict[str, Any]]:
    """The configurations of a sweep document (grid: every combination; random: draws)."""
    search = doc.get("search", "grid")
    if search not in SEARCHES:
        raise ValueError(f"{path}: search must be one of {list(SEARCHES)}; got {search!r}")
    flat = flat_space(doc.get("space") or {}, path)
    points: list[dict[tuple[str, ...], Any]] = []
    if search == "grid":
        for key, value in flat.items():
            if not isinstance(value, list) or not value:
                raise ValueError(f"{path}: space.{'.'.join(key)} must be a non-empty list (grid)")
        for combo in itertools.product(*flat.values()):
            points.append(dict(zip(flat, combo, strict=True)))
    else:
        n = doc.get("num_samples")
        if isinstance(n, bool) or not isinstance(n, int) or n < 1:
            raise ValueError(f"{path}: num_samples must be an integer >= 1 for a {search} search")
        rng = np.random.default_rng(int(doc.get("random_seed", 0)))
        for _ in range(n):
            points.append(
                {k: _draw(v, rng, f"{path}: space.{'.'.join(k)}") for k, v in flat.items()}
            )
    # optuna: the draws only validate the space; Optuna's sampler proposes the trials
    return [configuration(point, path) for point in points]


def configuration(point: Mapping[tuple[str, ...], Any], path: str = "sweep") -> dict[str, Any]:
    """One configuration (``algo``, ``env_id``, ``overrides``, ``label``) from a point of
    the flat space (keys ``("algo",)``, ``("env_id",)``, ``("hyperparams", name)``,
    ``("env_kwargs", name)``), validated."""
    algo, env_id = point[("algo",)], point[("env_id",)]
    if algo not in ALGOS:
        raise ValueError(f"{path}: space.algo {algo!r} is not one of {list(ALGOS)}")
    overrides: dict[str, Any] = {}
    env_kwargs: dict[str, Any] = {}
    for key, value in point.items():
        if key[0] == "hyperparams":
            overrides[key[1]] = value
        elif key[0] == "env_kwargs":
            env_kwargs[key[1]] = value
    if env_kwargs:
        overrides["env_kwargs"] = env_kwargs
    validate_hyperparams(algo, overrides, f"{path}: {algo} {env_id}")
    label = " ".join(
        [algo, str(env_id).split("/")[-1]]
        + [f"{k[-1]}={v}" for k, v in point.items() if k[0] != "algo" and k[0] != "env_id"]
    )
    return {"algo": algo, "env_id": str(env_id), "overrides": overrides, "label": label}


def load_sweep(path: str | os.PathLike[str], **kwargs: Any) -> SweepConfig:
    """Read and validate a sweep file; ``kwargs`` set the run options (``out``, ...)."""
    from baselines.agents.config import YamlLoader

    p = Path(path)
    if not p.is_file():
        raise FileNotFoundError(f"sweep file {p} does not exist")
    try:
        doc = yaml.load(p.read_text(encoding="utf-8"), Loader=YamlLoader)
    except yaml.YAMLError as exc:
        raise ValueError(f"{p}: not valid YAML: {exc}".replace("\n", " ")) from None
    if not isinstance(doc, Mapping):
        raise ValueError(f"{p}: a sweep file is a mapping (search, seeds, space, ...)")
    extra = set(doc) - TOP_KEYS
    if extra:
        raise ValueError(f"{p}: unknown keys {sorted(extra)}; expected {sorted(TOP_KEYS)}")
    seeds = doc.get("seeds", [0])
    if (
        not isinstance(seeds, list)
        or not seeds
        or not all(isinstance(s, int) and not isinstance(s, bool) and s >= 0 for s in seeds)
    ):
        raise ValueError(f"{p}: seeds must be a non-empty list of integers >= 0; got {seeds!r}")
    configs = expand_configurations(doc, str(p))
    for key in ("timesteps", "n_envs"):
        v = doc.get(key)
        if v is not None and (isinstance(v, bool) or not isinstance(v, int) or v < 1):
            raise ValueError(f"{p}: {key} must be an integer >= 1; got {v!r}")
    split = doc.get("test_split", "test")
    if split not in ("test", "val", "train"):
        raise ValueError(f"{p}: test_split must be 'test', 'val' or 'train'; got {split!r}")
    search = doc.get("search", "grid")
    space = None
    if search == "optuna":
        flat = flat_space(doc["space"], str(p))
        space = {".".join(k): v for k, v in flat.items()}
    return SweepConfig(
        path=str(p),
        configurations=tuple(configs),
        search=search,
        num_samples=int(doc.get("num_samples", 1)),
        random_seed=int(doc.get("random_seed", 0)),
        space=space,
        seeds=tuple(int(s) for s in seeds),
        test_split=split,
        timesteps=doc.get("timesteps"),
        n_envs=doc.get("n_envs"),
        **kwargs,
    )
