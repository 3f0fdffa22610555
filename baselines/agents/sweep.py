"""``motion-bench sweep``: many configurations x seeds of ``motion-bench train`` on Ray Tune.

A sweep file (``configs/sweeps/NAME.yaml``, plain YAML) names a search over algorithms,
environment ids, hyper-parameters and environment kwargs, and the seeds every
configuration is trained with::

    search: grid              # grid (every combination), random or optuna (num_samples)
    num_samples: 4            # random, optuna: configurations to try
    random_seed: 0            # random: numpy.random.default_rng(random_seed); optuna: TPE seed
    seeds: [0, 1, 2, 3, 4]
    timesteps: 100000         # optional overrides of the agent config
    n_envs: 8
    test_split: test
    space:
      algo: [ppo]
      env_id: [MotionEnvs/OrientationReach-v0, MotionEnvs/OrientationReach-v1]
      hyperparams: {learning_rate: [3.0e-4, 1.0e-3]}
      env_kwargs: {nominal: [bezier-null]}

Grid values are lists; a random search also takes ``{uniform: [lo, hi]}``,
``{loguniform: [lo, hi]}`` and ``{randint: [lo, hi]}`` (inclusive) and draws
``num_samples`` configurations up front, so every seed of a configuration trains the same
hyper-parameters. ``search: optuna`` takes the same space and lets Optuna's TPE sampler
(Ray Tune's ``OptunaSearch``) propose ``num_samples`` configurations one after another,
each trial training its configuration on every seed in turn and minimising the median
validation criterion over seeds. Otherwise each (configuration, seed) is one Ray Tune
trial that calls
:func:`baselines.agents.train.run`, the code path of ``motion-bench train`` (runs in
``OUT/runs/``), reports the validation criterion after every evaluation with the run
folder as its checkpoint, and at the end scores the best-on-validation policy on the test
split (:func:`baselines.agents.evaluate.run`). The summary table has one row per
configuration: median and spread over seeds of the test criterion and of its ratio to the
zero-action nominal (``n/a`` where the nominal's criterion is 0: the analytic juggler of
``Juggling-v0`` drops nothing at 5 % noise; juggling rows add the catch rates and the
hand's deviation ratio, and the plot then shows the criterion itself); the configuration
marked ``best`` has the lowest median *validation* criterion (the test split plays no
part in the choice).

Ray: by default a local instance with ``--num-cpus`` (default: the machine's cores), one
CPU per trial; ``--address ADDR`` (e.g. ``auto``) joins an existing cluster started with
``ray start``. On a cluster ``--out`` must be on storage every node sees (NFS, a shared
mount). ``--resume`` continues an interrupted sweep (Ctrl-C, which ends the command with
that advice, or a crash) in the same ``--out``: Ray Tune keeps its finished trials as they
are and starts the unfinished ones over (a trial whose run folder was finished is only
scored again: ``resumed`` in trials.csv); on an ``--out`` with no sweep it starts one.
Without ``--resume`` an ``--out`` that holds a sweep is refused, and ``--resume`` refuses a
sweep file whose settings differ from the ones recorded in ``OUT/sweep.json``.

Files: every file motion-envs writes (each trial's run folder, sweep.json, results.json,
trials.csv, table.csv, table.md, sweep.png) goes through :mod:`motion_envs._io` (atomic
replace).
Ray Tune's own experiment state, trial results and checkpoint copies under ``--out`` are
written by Ray itself (its storage layer); their consistency on interruption is Ray's
business, which is what ``--resume`` (``Tuner.restore``) relies on.
"""

from __future__ import annotations

import argparse
import itertools
import json
import os
import time
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from baselines import options
from baselines.agents import checks
from baselines.agents.config import ALGOS, validate_hyperparams
from motion_envs._io import atomic_write_text, save_figure

__all__ = ["SweepConfig", "expand_configurations", "load_sweep", "register", "run"]

_TOP_KEYS = {
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
_SPACE_KEYS = {"algo", "env_id", "hyperparams", "env_kwargs"}
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


def _flat_space(space: Mapping[str, Any], path: str) -> dict[tuple[str, ...], Any]:
    extra = set(space) - _SPACE_KEYS
    if extra:
        raise ValueError(
            f"{path}: space has unknown keys {sorted(extra)}; expected {sorted(_SPACE_KEYS)}"
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
    flat = _flat_space(doc.get("space") or {}, path)
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


def _tune_domain(value: Any) -> Any:
    """A Ray Tune domain of a (validated) random-search value, for Optuna's sampler."""
    from ray import tune

    if isinstance(value, list):
        return tune.choice(value)
    ((kind, (lo, hi)),) = value.items()
    if kind == "uniform":
        return tune.uniform(lo, hi)
    if kind == "loguniform":
        return tune.loguniform(lo, hi)
    return tune.randint(int(lo), int(hi) + 1)


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
    extra = set(doc) - _TOP_KEYS
    if extra:
        raise ValueError(f"{p}: unknown keys {sorted(extra)}; expected {sorted(_TOP_KEYS)}")
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
        flat = _flat_space(doc["space"], str(p))
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


def _train_and_score(
    cfg: Mapping[str, Any], seed: int, run_dir: Path, sweep: SweepConfig, intermediate: bool
) -> dict[str, Any]:
    """``train.run`` for one configuration and seed (unless ``run_dir`` already holds a
    finished run), then the test split; the trial's metrics."""
    from ray import tune

    import motion_envs  # noqa: F401  (registers the environments inside the worker)
    from baselines.agents.evaluate import AgentConfig
    from baselines.agents.evaluate import run as evaluate
    from baselines.agents.train import TrainConfig
    from baselines.agents.train import run as train

    warnings.filterwarnings("ignore", message=".*is out of date", category=DeprecationWarning)
    t0 = time.perf_counter()
    resumed = (run_dir / "run.json").exists()  # finished before an interruption: rescore it
    if not resumed:
        if run_dir.exists():  # an interrupted trial: start it over
            import shutil

            shutil.rmtree(run_dir)

        def report(ev: dict[str, Any]) -> None:
            keys = ("timesteps", "val_criterion", "best_val_criterion")
            tune.report({k: ev[k] for k in keys})

        train(
            TrainConfig(
                algo=cfg["algo"],
                env_id=cfg["env_id"],
                out=str(run_dir),
                seed=seed,
                timesteps=sweep.timesteps,
                n_envs=sweep.n_envs,
                overrides=cfg["overrides"],
                progress=False,
                tensorboard=True,
            ),
            on_evaluation=report if intermediate else None,
        )
    test = evaluate(AgentConfig(str(run_dir), sweep.test_split))
    manifest = json.loads((run_dir / "run.json").read_text())
    return {
        "seed": seed,
        "timesteps": manifest["timesteps"],
        "best_val_criterion": manifest["best_val_criterion"],
        "val_nominal_criterion": manifest["val_nominal_criterion"],
        "test_criterion": test["criterion"],
        "test_nominal_criterion": test["nominal_criterion"],
        "test_ratio": test["ratio"],  # None where the nominal's criterion is 0
        # Juggling-v0 (None for the reaching environments)
        "test_catch_rate": test.get("catch_rate"),
        "test_nominal_catch_rate": test.get("nominal_catch_rate"),
        "test_deviation_ratio": test.get("deviation_ratio"),
        "train_seconds": manifest["train_seconds"],
        "trial_seconds": time.perf_counter() - t0,
        "run_dir": str(run_dir),
        "resumed": resumed,
    }


def _trial(params: dict[str, Any], sweep: SweepConfig) -> None:
    """One Ray Tune trial of a grid or random sweep: one configuration, one seed."""
    from ray import tune

    index, seed = int(params["config_index"]), int(params["seed"])
    run_dir = Path(sweep.out) / "runs" / f"config{index:03d}-seed{seed}"
    metrics = _train_and_score(sweep.configurations[index], seed, run_dir, sweep, True)
    tune.report(
        {"config_index": index, **metrics},
        checkpoint=tune.Checkpoint.from_directory(str(run_dir)),
    )


def _optuna_trial(params: dict[str, Any], sweep: SweepConfig) -> None:
    """One Ray Tune trial of an Optuna sweep: the proposed configuration on every seed
    (in turn); the objective is the median over seeds of the validation criterion."""
    from ray import tune

    point = {tuple(k.split(".", 1)): v for k, v in params.items()}
    cfg = configuration(point, sweep.path)
    trial_id = tune.get_context().get_trial_id()
    per_seed = [
        _train_and_score(
            cfg, seed, Path(sweep.out) / "runs" / f"{trial_id}-seed{seed}", sweep, False
        )
        for seed in sweep.seeds
    ]
    tune.report(
        {
            "val_criterion_median": float(np.median([m["best_val_criterion"] for m in per_seed])),
            "configuration": json.dumps(cfg),
            "per_seed": json.dumps(per_seed),
        }
    )


class SweepInterrupted(RuntimeError):
    """The sweep stopped (Ctrl-C) before every trial finished; ``--resume`` continues it."""


def _spread(values: Sequence[float | None]) -> tuple[float | None, float | None, float | None]:
    """Median, min and max over seeds; None when any seed has no value (a ratio to a
    nominal criterion of 0, or a juggling-only metric of a reaching run)."""
    if not values or any(v is None for v in values):
        return None, None, None
    a = np.asarray(values, dtype=float)
    return float(np.median(a)), float(a.min()), float(a.max())


def summarize(trials: Sequence[Mapping[str, Any]], sweep: SweepConfig) -> dict[str, Any]:
    """One row per configuration: median and spread over seeds; best by median validation."""
    rows = []
    for index, cfg in enumerate(sweep.configurations):
        mine = sorted((t for t in trials if t["config_index"] == index), key=lambda t: t["seed"])
        if not mine:
            continue
        test = np.array([t["test_criterion"] for t in mine])
        val = np.array([t["best_val_criterion"] for t in mine])
        ratio = _spread([t["test_ratio"] for t in mine])
        rows.append(
            {
                "config_index": index,
                "label": cfg["label"],
                "algo": cfg["algo"],
                "env_id": cfg["env_id"],
                "overrides": cfg["overrides"],
                "n_seeds": len(mine),
                "seeds": [int(t["seed"]) for t in mine],
                "val_criterion_median": float(np.median(val)),
                "test_criterion_median": float(np.median(test)),
                "test_criterion_min": float(test.min()),
                "test_criterion_max": float(test.max()),
                "test_criterion_iqr": float(np.subtract(*np.percentile(test, [75, 25]))),
                "test_nominal_criterion": float(mine[0]["test_nominal_criterion"]),
                "test_ratio_median": ratio[0],
                "test_ratio_min": ratio[1],
                "test_ratio_max": ratio[2],
                "test_criteria": test.tolist(),
            }
        )
        for key in ("test_catch_rate", "test_nominal_catch_rate", "test_deviation_ratio"):
            median, lo, hi = _spread([t.get(key) for t in mine])
            rows[-1].update({f"{key}_median": median, f"{key}_min": lo, f"{key}_max": hi})
    best = min(rows, key=lambda r: r["val_criterion_median"]) if rows else None
    for r in rows:
        r["best_on_validation"] = best is not None and r["config_index"] == best["config_index"]
    return {
        "configurations": rows,
        "best_config_index": None if best is None else best["config_index"],
    }


def _settings(sweep: SweepConfig) -> dict[str, Any]:
    """What a sweep trains (not where or how it runs), as JSON: ``OUT/sweep.json``."""
    keys = "configurations seeds timesteps n_envs test_split search num_samples random_seed space"
    settings: dict[str, Any] = json.loads(json.dumps({k: getattr(sweep, k) for k in keys.split()}))
    return settings


def _claim_out(sweep: SweepConfig, out: Path) -> None:
    """Refuse an ``out`` that holds a sweep unless resuming it with the same settings
    (its finished run folders would be reused as they are); record them in sweep.json."""
    stored = out / "sweep.json"
    settings = _settings(sweep)
    if not sweep.resume and ((out / "tune").exists() or (out / "runs").exists()):
        raise options.ConfigError(
            "out",
            f"{out} already holds a sweep; continue it with --resume or choose another folder",
        )
    if sweep.resume and stored.is_file() and json.loads(stored.read_text()) != settings:
        raise options.ConfigError(
            "config",
            f"{sweep.path} is not the sweep in --out {out} (its settings differ from "
            f"{stored.name}'s); resume with the same sweep file or choose another --out",
        )
    atomic_write_text(stored, json.dumps(settings, indent=2) + "\n")


def run(sweep: SweepConfig) -> dict[str, Any]:
    """Run (or resume) the sweep on Ray Tune; the summary and every trial's metrics."""
    import ray
    from ray import tune

    out = Path(sweep.out).resolve()
    out.mkdir(parents=True, exist_ok=True)
    sweep = SweepConfig(**{**sweep.__dict__, "out": str(out)})
    _claim_out(sweep, out)
    started_here = False
    if not ray.is_initialized():
        if sweep.address is not None:
            ray.init(address=sweep.address, log_to_driver=False)
        else:
            ray.init(
                num_cpus=sweep.num_cpus or os.cpu_count(),
                log_to_driver=False,
                include_dashboard=False,
            )
        started_here = True
    t0 = time.perf_counter()
    try:
        optuna = sweep.search == "optuna"
        fn = _optuna_trial if optuna else _trial
        trainable = tune.with_resources(tune.with_parameters(fn, sweep=sweep), {"cpu": 1})
        name = "tune"
        run_config = tune.RunConfig(
            name=name, storage_path=str(out), verbose=1 if sweep.progress else 0
        )
        if sweep.resume and tune.Tuner.can_restore(str(out / name)):
            tuner = tune.Tuner.restore(str(out / name), trainable, resume_errored=True)
        elif optuna:
            from ray.tune.search.optuna import OptunaSearch

            assert sweep.space is not None
            metric = "val_criterion_median"
            tuner = tune.Tuner(
                trainable,
                param_space={k: _tune_domain(v) for k, v in sweep.space.items()},
                tune_config=tune.TuneConfig(
                    search_alg=OptunaSearch(metric=metric, mode="min", seed=sweep.random_seed),
                    num_samples=sweep.num_samples,
                    metric=metric,
                    mode="min",
                ),
                run_config=run_config,
            )
        else:
            tuner = tune.Tuner(
                trainable,
                param_space={
                    "config_index": tune.grid_search(list(range(len(sweep.configurations)))),
                    "seed": tune.grid_search(list(sweep.seeds)),
                },
                tune_config=tune.TuneConfig(metric="best_val_criterion", mode="min"),
                run_config=run_config,
            )
        grid = tuner.fit()
    finally:
        wall = time.perf_counter() - t0
        if started_here:
            ray.shutdown()
    if grid.errors:
        raise RuntimeError(
            f"a sweep trial failed: {grid.errors[0]}; once fixed, --resume --out {out} "
            "runs the failed trials again"
        )
    # Ctrl-C: Ray Tune saves its state, stops the running trials and returns; a trial
    # finished if it made its last report (Ray marks the stopped ones terminated too)
    expected = sweep.num_samples if optuna else len(sweep.configurations) * len(sweep.seeds)
    last = "per_seed" if optuna else "config_index"
    finished = sum(last in (grid[i].metrics or {}) for i in range(len(grid)))
    if finished != expected:
        raise SweepInterrupted(
            f"the sweep was interrupted with {finished} of {expected} trials finished; "
            f"continue it with --resume --out {out}"
        )
    trials = []
    # optuna: the configurations are the ones the sampler proposed, one per trial
    configurations = [] if sweep.search == "optuna" else list(sweep.configurations)
    for i in range(len(grid)):
        m: dict[str, Any] = grid[i].metrics or {}
        if sweep.search == "optuna":  # one configuration per trial, every seed inside
            configurations.append(json.loads(m["configuration"]))
            for t in json.loads(m["per_seed"]):
                trials.append({"config_index": len(configurations) - 1, **t})
        else:
            trials.append({k: m[k] for k in _TRIAL_KEYS})
    sweep = SweepConfig(**{**sweep.__dict__, "configurations": tuple(configurations)})
    trials.sort(key=lambda t: (t["config_index"], t["seed"]))
    summary = summarize(trials, sweep)
    return {
        "sweep": sweep.path,
        "seeds": list(sweep.seeds),
        "test_split": sweep.test_split,
        "n_trials": len(trials),
        "wall_seconds": wall,
        "num_cpus": sweep.num_cpus or os.cpu_count(),
        "address": sweep.address,
        **summary,
        "trials": trials,
    }


_TRIAL_KEYS = (
    "config_index",
    "seed",
    "timesteps",
    "best_val_criterion",
    "val_nominal_criterion",
    "test_criterion",
    "test_nominal_criterion",
    "test_ratio",
    "test_catch_rate",
    "test_nominal_catch_rate",
    "test_deviation_ratio",
    "train_seconds",
    "trial_seconds",
    "run_dir",
    "resumed",
)


def format_table(results: Mapping[str, Any]) -> str:
    """The summary as a Markdown table (the README's agent table)."""
    rows = results["configurations"]
    juggling = any(r.get("test_catch_rate_median") is not None for r in rows)
    head = (
        "| configuration | seeds | val median | test median | test min-max | nominal (test) | "
        "x nominal (median, min-max) |"
    )
    rule = "|---|--:|--:|--:|--:|--:|--:|"
    if juggling:
        head += " catch rate (median, min-max) | nominal catch rate | deviation x nominal |"
        rule += "--:|--:|--:|"
    lines = [head, rule]

    def spread(r: Mapping[str, Any], key: str) -> str:
        if r.get(f"{key}_median") is None:
            return "n/a"
        return f"{r[f'{key}_median']:.3f} ({r[f'{key}_min']:.3f}-{r[f'{key}_max']:.3f})"

    for r in rows:
        mark = " **(best on val)**" if r["best_on_validation"] else ""
        line = (
            f"| {r['label']}{mark} | {r['n_seeds']} | {r['val_criterion_median']:.4f} | "
            f"{r['test_criterion_median']:.4f} | {r['test_criterion_min']:.4f}-"
            f"{r['test_criterion_max']:.4f} | {r['test_nominal_criterion']:.4f} | "
            f"{spread(r, 'test_ratio')} |"
        )
        if juggling:
            nominal = r.get("test_nominal_catch_rate_median")
            line += (
                f" {spread(r, 'test_catch_rate')} | "
                f"{'n/a' if nominal is None else f'{nominal:.3f}'} | "
                f"{spread(r, 'test_deviation_ratio')} |"
            )
        lines.append(line)
    return "\n".join(lines)


def write_results(results: Mapping[str, Any], out: Path) -> None:
    """results.json, trials.csv, table.csv, table.md and sweep.png in ``out``."""
    import pandas as pd

    from baselines.agents.rundir import write_json

    write_json(out / "results.json", dict(results))
    trials = pd.DataFrame(results["trials"]).to_csv(index=False, float_format="%.17g")
    atomic_write_text(out / "trials.csv", trials)
    table = pd.DataFrame(results["configurations"]).drop(
        columns=["overrides", "test_criteria", "seeds"]
    )
    atomic_write_text(out / "table.csv", table.to_csv(index=False, float_format="%.17g"))
    atomic_write_text(out / "table.md", format_table(results) + "\n")
    plot_sweep(results, out / "sweep.png")


def plot_sweep(results: Mapping[str, Any], path: Path) -> None:
    """Test criterion / nominal per seed (points) and median (bar) for each configuration."""
    import textwrap

    from baselines.plots import new_figure

    rows = results["configurations"]
    fig = new_figure(max(6.0, 2.2 * len(rows) + 1.5), 4.5)
    ax = fig.subplots()
    if any(r["test_ratio_median"] is None for r in rows):
        _plot_criteria(ax, rows, results["test_split"])
        save_figure(fig, path, dpi=120)
        return
    for i, r in enumerate(rows):
        ratios = np.asarray(r["test_criteria"]) / r["test_nominal_criterion"]
        color = "C1" if r["best_on_validation"] else "C0"
        ax.bar(i, r["test_ratio_median"], color=color, alpha=0.5, width=0.6)
        ax.scatter(np.full(ratios.size, i), ratios, color="k", s=14, zorder=3)
    ax.axhline(1.0, color="k", ls="--", lw=1, label="zero-action nominal")
    ax.set_xticks(range(len(rows)))
    ax.set_xticklabels([textwrap.fill(r["label"], 24) for r in rows], fontsize=8)
    ax.set_ylabel(f"{results['test_split']} criterion / nominal's")
    ax.set_title("median over seeds (bar), each seed (dot); orange: best on validation", fontsize=9)
    all_ratios = np.concatenate(
        [np.asarray(r["test_criteria"]) / r["test_nominal_criterion"] for r in rows]
    )
    lo, hi = float(all_ratios.min()), float(all_ratios.max())
    pad = max(0.02, 0.1 * (max(hi, 1.0) - min(lo, 1.0)))
    ax.set_ylim(min(lo, 1.0) - pad, max(hi, 1.0) + pad)
    ax.legend(loc="upper right", fontsize=8)
    save_figure(fig, path, dpi=120)


def _plot_criteria(ax: Any, rows: Sequence[Mapping[str, Any]], split: str) -> None:
    """The test criterion itself per seed and configuration, with the nominal's: where a
    nominal's criterion is 0 (the analytic juggler drops nothing) there is no ratio."""
    import textwrap

    for i, r in enumerate(rows):
        crit = np.asarray(r["test_criteria"], dtype=float)
        color = "C1" if r["best_on_validation"] else "C0"
        ax.bar(i, r["test_criterion_median"], color=color, alpha=0.5, width=0.6)
        ax.scatter(np.full(crit.size, i), crit, color="k", s=14, zorder=3)
        label = "zero-action nominal" if i == 0 else None
        ax.plot([i - 0.4, i + 0.4], [r["test_nominal_criterion"]] * 2, "k--", lw=1, label=label)
    ax.set_xticks(range(len(rows)))
    ax.set_xticklabels([textwrap.fill(r["label"], 24) for r in rows], fontsize=8)
    ax.set_ylabel(f"{split} criterion (lower is better; Juggling-v0: drop rate per toss)")
    ax.set_title("median over seeds (bar), each seed (dot); orange: best on validation", fontsize=9)
    ax.set_ylim(bottom=0.0, top=max(0.05, 1.1 * max(max(r["test_criteria"]) for r in rows)))
    ax.legend(loc="upper right", fontsize=8)


def _cli(args: argparse.Namespace) -> int:
    warnings.filterwarnings("ignore", message=".*is out of date", category=DeprecationWarning)
    if args.address is not None and args.num_cpus is not None:
        raise options.ConfigError("num_cpus", "applies to a local Ray only; omit it with --address")
    name = Path(args.config).stem
    sweep = load_sweep(
        args.config,
        out=str(args.out) if args.out is not None else f"sweeps/{name}",
        address=args.address,
        num_cpus=args.num_cpus,
        resume=args.resume,
        progress=not args.no_progress,
    )
    try:
        results = run(sweep)
    except SweepInterrupted as exc:
        return options.fail("motion-bench sweep", str(exc), status=130)
    out = Path(sweep.out)
    write_results(results, out)
    print(format_table(results))
    print(
        f"{results['n_trials']} trials in {results['wall_seconds']:.0f} s; wrote "
        f"{out / 'results.json'}, trials.csv, table.csv, table.md, sweep.png"
    )
    return 0


def register(subparsers: Any) -> None:
    """Add ``motion-bench sweep``."""
    p = options.add_subcommand(
        subparsers,
        "sweep",
        help="configurations x seeds of motion-bench train on Ray Tune (local or a cluster)",
        description=__doc__.split("\n\n")[0].replace("``", ""),
    )
    p.add_argument(
        "--config", required=True, type=checks.yaml_file, metavar="PATH",
        help="sweep file, e.g. configs/sweeps/orientation_ppo.yaml",
    )  # fmt: skip
    p.add_argument("--address", default=None, help="existing Ray cluster (e.g. auto)")
    p.add_argument(
        "--num-cpus", type=options.positive_int, default=None,
        help="local Ray's CPUs (default: all)",
    )  # fmt: skip
    p.add_argument(
        "--out", default=None, type=options.output_folder, metavar="DIR",
        help="results folder (default: sweeps/NAME)",
    )  # fmt: skip
    p.add_argument(
        "--resume", action="store_true",
        help="continue the interrupted sweep in --out (or start it if --out holds none)",
    )  # fmt: skip
    p.add_argument("--no-progress", action="store_true", help="no Ray Tune status table")
    p.set_defaults(func=_cli)
