"""The sweep file and its search space: :class:`SweepConfig`, :func:`load_sweep`,
:func:`expand_configurations` (grid, random draws) and :func:`configuration` (one point
of the flat space, validated). No Ray here."""

from __future__ import annotations

import itertools
import math
import os
from collections import Counter
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any, Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator

from baselines import options
from baselines.agents.config import ALGOS, MAX_N_ENVS, validate_hyperparams
from baselines.agents.yaml_files import key_lines, read_yaml

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
    "inner_folds",
}
SPACE_KEYS = {"algo", "env_id", "hyperparams", "env_kwargs"}
#: Searches of a sweep file.
SEARCHES: tuple[str, ...] = ("grid", "random", "optuna")
#: Most configurations of a sweep (grid points or random/Optuna samples).
MAX_CONFIGURATIONS = 10_000
#: Most seeds of a sweep.
MAX_SEEDS = 1_000
#: Most choices of one list of the space.
MAX_CHOICES = 1_000
#: Most inner folds over people of a nested trial.
MAX_INNER_FOLDS = 1_000
#: Most environment steps of one trial.
MAX_TIMESTEPS = 10**10


class SweepFile(BaseModel):
    """The top level of a sweep file (pydantic schema, strict types: ``random_seed: [1]``
    or ``num_samples: true`` are refused, bounds checked)."""

    model_config = ConfigDict(extra="forbid", strict=True)

    search: Literal["grid", "random", "optuna"] = "grid"
    num_samples: int | None = Field(None, ge=1, le=MAX_CONFIGURATIONS)
    random_seed: int = Field(0, ge=0, le=2**32 - 1)
    seeds: list[Annotated[int, Field(ge=0, le=2**32 - 1)]] = Field(
        default_factory=lambda: [0], min_length=1, max_length=MAX_SEEDS
    )
    timesteps: int | None = Field(None, ge=1, le=MAX_TIMESTEPS)
    n_envs: int | None = Field(None, ge=1, le=MAX_N_ENVS)
    test_split: Literal["test", "val", "train"] = "test"
    space: dict[str, Any]
    description: str | None = Field(None, max_length=10_000)
    inner_folds: int | None = Field(None, ge=2, le=MAX_INNER_FOLDS)

    @field_validator("seeds")
    @classmethod
    def _distinct_seeds(cls, seeds: list[int]) -> list[int]:
        repeated = sorted(s for s, k in Counter(seeds).items() if k > 1)
        if repeated:
            raise ValueError(
                f"seeds must be distinct (a repeated seed runs the same trial twice): {repeated}"
            )
        return seeds


def _schema_error(exc: ValidationError, path: str, lines: Mapping[tuple[str, ...], int]) -> str:
    """One line of the first error of a pydantic validation: file, line, key, message."""
    err = exc.errors()[0]
    loc = tuple(str(x) for x in err["loc"])
    line = lines.get(loc[:1]) if loc else None
    where = f"{path}: line {line}" if line is not None else path
    key = ".".join(loc) or "sweep file"
    got = err.get("input")
    if isinstance(got, int) and not isinstance(got, bool) and abs(got) >= 10**30:
        shown = f"a {len(str(got))}-digit integer"
    else:
        shown = repr(got)
        shown = shown if len(shown) <= 80 else shown[:77] + "..."
    if err["type"] == "missing":
        return f"{where}: {key} is required"
    if err["type"] == "extra_forbidden":
        return f"{where}: unknown key {key!r}; expected {sorted(TOP_KEYS)}"
    return f"{where}: {key}: {err['msg']}; got {shown}"


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
    inner_folds: int | None = None  # checkpoints by inner folds over people, then a refit


def check_domain(value: Any, where: str) -> None:
    """Refuse a random-search value that cannot be drawn from: an empty list, bounds that
    are not finite numbers with ``lo <= hi`` (``loguniform``: ``0 < lo``; ``randint``:
    integers)."""
    if isinstance(value, list):
        if not value:
            raise ValueError(f"{where}: an empty list of choices")
        if len(value) > MAX_CHOICES:
            raise ValueError(f"{where}: more than {MAX_CHOICES} choices")
        return
    if isinstance(value, Mapping) and len(value) == 1:
        ((kind, bounds),) = value.items()
        if kind in ("uniform", "loguniform", "randint") and (
            isinstance(bounds, list) and len(bounds) == 2
        ):
            lo, hi = bounds
            numbers = all(
                not isinstance(b, bool)
                and isinstance(b, (int, float))
                and abs(b) < 1e300
                and math.isfinite(b)
                for b in (lo, hi)
            )
            if not numbers:
                raise ValueError(f"{where}: {kind} bounds must be finite numbers; got {bounds!r}")
            if kind == "randint" and not all(isinstance(b, int) for b in (lo, hi)):
                raise ValueError(f"{where}: randint bounds must be integers; got {bounds!r}")
            if kind == "loguniform" and lo <= 0:
                raise ValueError(f"{where}: loguniform bounds must be > 0; got {bounds!r}")
            if lo > hi:
                raise ValueError(f"{where}: {kind} needs lo <= hi; got {bounds!r}")
            return
    raise ValueError(
        f"{where}: expected a list of values or {{uniform|loguniform|randint: [lo, hi]}}; "
        f"got {value!r}"
    )


def _draw(value: Any, rng: np.random.Generator, where: str) -> Any:
    check_domain(value, where)
    if isinstance(value, list):
        return value[int(rng.integers(len(value)))]
    ((kind, (lo, hi)),) = value.items()
    if kind == "uniform":
        return float(rng.uniform(lo, hi))
    if kind == "loguniform":
        return float(np.exp(rng.uniform(np.log(lo), np.log(hi))))
    return int(rng.integers(int(lo), int(hi) + 1))


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
        n_points = 1
        for key, value in flat.items():
            if not isinstance(value, list) or not value:
                raise ValueError(f"{path}: space.{'.'.join(key)} must be a non-empty list (grid)")
            n_points *= len(value)
        if n_points > MAX_CONFIGURATIONS:
            raise ValueError(
                f"{path}: the grid has {n_points} configurations; at most {MAX_CONFIGURATIONS}"
            )
        for combo in itertools.product(*flat.values()):
            points.append(dict(zip(flat, combo, strict=True)))
    else:
        n = doc.get("num_samples")
        if isinstance(n, bool) or not isinstance(n, int) or not 1 <= n <= MAX_CONFIGURATIONS:
            raise ValueError(
                f"{path}: num_samples must be an integer in [1, {MAX_CONFIGURATIONS}] for a "
                f"{search} search"
            )
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


def _preflight_configurations(
    top: SweepFile, configs: list[dict[str, Any]], path: str
) -> list[dict[str, Any]]:
    """The configurations whose training setup the pre-flight checks: the grid's own; for
    a random or Optuna search, every combination of the values of ``algo``, ``env_id``,
    ``env_kwargs.*`` and ``hyperparams.n_envs`` (a range by its two bounds), the other
    hyper-parameters at their first draw."""
    if top.search == "grid":
        return configs
    flat = flat_space(top.space, path)
    setup = {("algo",), ("env_id",), ("hyperparams", "n_envs")}
    first = expand_configurations({**top.model_dump(), "num_samples": 1}, path)[0]
    axes: dict[tuple[str, ...], list[Any]] = {}
    for key, value in flat.items():
        if key in setup or key[0] == "env_kwargs":
            axes[key] = value if isinstance(value, list) else list(next(iter(value.values())))
    out = []
    for combo in itertools.islice(itertools.product(*axes.values()), MAX_CONFIGURATIONS):
        point = dict(zip(axes, combo, strict=True))
        point.update(
            {
                ("hyperparams", k): v
                for k, v in first["overrides"].items()
                if k != "env_kwargs" and ("hyperparams", k) not in point
            }
        )
        out.append(configuration(point, path))
    return out


def _check_inner_folds(env_id: str, env_kwargs: Mapping[str, Any]) -> None:
    """Build the validation split of the last inner fold (``inner_folds`` larger than the
    training people fails here, naming ``val_folds``)."""
    import gymnasium as gym

    import motion_envs  # noqa: F401  (registers the ids)

    gym.make(env_id, **{**env_kwargs, "split": "val"}).close()


def preflight_sweep(top: SweepFile, configs: list[dict[str, Any]], path: str) -> None:
    """``motion-bench train``'s checks (:func:`baselines.agents.train.preflight`: registered
    id, constructor keywords, ``n_envs`` and the validation split) for every configuration
    and seed the sweep can run, before Ray starts; a ``ValueError`` naming the file and the
    configuration."""
    from baselines.agents.sweep.nested import inner_overrides
    from baselines.agents.train import TrainConfig, preflight

    for cfg in _preflight_configurations(top, configs, path):
        overrides = cfg["overrides"]
        if top.inner_folds:  # the last inner fold's setup (the refit's differs in val only)
            overrides = inner_overrides(overrides, top.inner_folds, top.inner_folds - 1)
        for i, seed in enumerate(top.seeds):
            try:
                hp = preflight(
                    TrainConfig(
                        algo=cfg["algo"],
                        env_id=cfg["env_id"],
                        out="",
                        seed=seed,
                        timesteps=top.timesteps,
                        n_envs=top.n_envs,
                        overrides=overrides,
                    )
                )
                if top.inner_folds and i == 0:  # the people can be cut into K groups
                    _check_inner_folds(cfg["env_id"], hp["env_kwargs"])
            except ValueError as exc:
                message = str(exc).removeprefix("--env ")
                if isinstance(exc, options.ConfigError):
                    message = f"{exc.field}: {exc.message}"
                raise ValueError(f"{path}: {cfg['label']} (seed {seed}): {message}") from None


def load_sweep(path: str | os.PathLike[str], **kwargs: Any) -> SweepConfig:
    """Read and validate a sweep file; ``kwargs`` set the run options (``out``, ...)."""
    p = Path(path)
    if not p.exists():
        raise FileNotFoundError(f"sweep file {p} does not exist")
    doc, node = read_yaml(p)
    if not isinstance(doc, Mapping):
        raise ValueError(f"{p}: a sweep file is a mapping (search, seeds, space, ...)")
    try:
        top = SweepFile.model_validate(doc)
    except ValidationError as exc:
        raise ValueError(_schema_error(exc, str(p), key_lines(node))) from None
    if top.search != "grid" and top.num_samples is None:
        raise ValueError(f"{p}: num_samples is required for a {top.search} search")
    if top.search != "grid":
        for key, value in flat_space(top.space, str(p)).items():
            check_domain(value, f"{p}: space.{'.'.join(key)}")
    n_points = top.num_samples if top.search != "grid" else None
    if n_points is not None and n_points * len(top.seeds) > MAX_CONFIGURATIONS * 10:
        raise ValueError(f"{p}: num_samples x seeds is more than {MAX_CONFIGURATIONS * 10} trials")
    configs = expand_configurations(doc, str(p))
    seeds = top.seeds
    split = top.test_split
    preflight_sweep(top, configs, str(p))
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
        timesteps=top.timesteps,
        n_envs=top.n_envs,
        inner_folds=top.inner_folds,
        **kwargs,
    )
