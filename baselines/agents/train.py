"""``motion-bench train``: train an SB3 agent on top of the nominal, choose it on validation.

``run(TrainConfig) -> TrainResult`` is the one training code path (``motion-bench
train`` and every trial of ``motion-bench sweep`` call it):

1. hyper-parameters from ``configs/agents/ALGO.yaml`` (or ``--config``), the command's
   overrides on top (:func:`~baselines.agents.config.resolve_hyperparams`);
2. the native vector environment of ``split="train"``
   (``gym.make_vec(..., vectorization_mode="vector_entry_point")``) through
   :class:`baselines.sb3.GymnasiumVecEnv`, ``VecMonitor`` and, where the config says so,
   ``VecNormalize``;
3. the model starts at the nominal (:func:`~baselines.agents.policies.start_at_nominal`);
   ``--algo ars`` is sb3-contrib's ARS (:mod:`baselines.agents.ars`: parameter-space
   exploration, every episode played by a deterministic policy), the rest unchanged;
4. every ``eval_freq`` steps (and at the start and the end) the deterministic policy is
   scored on the *validation* split (``split="val"``: training subjects/demonstrations
   held out by ``val_fraction``) with the papers' criterion, the median over episodes of
   ``info["max_error"]``; the best policy so far is saved as ``agent.zip``. The test split
   is never touched. A *refit* (``keep_timesteps``, the last step of a nested
   evaluation: :mod:`baselines.agents.sweep.nested`) has no validation split: it trains
   on all the training data and keeps the policy at the first point of the same
   evaluation schedule at or after ``keep_timesteps`` (a step chosen by inner folds),
   then stops (ARS, whose evaluation loop ignores a callback's stop, trains on to
   ``n_timesteps``; the kept policy is the same). ``Juggling-v0`` (no native vector
   environment: SB3's ``DummyVecEnv``) is validated on its own seed range by the drop
   rate per toss (:mod:`baselines.agents.juggling_score`);
5. the run folder (:mod:`baselines.agents.rundir`) gets the final policy, the resolved
   config, the manifest and TensorBoard logs.
"""

from __future__ import annotations

import argparse
import dataclasses
import functools
import json
import shlex
import sys
import time
import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from baselines import options
from baselines.agents import checks
from baselines.agents.config import (
    ALGOS,
    parse_env_kwargs,
    resolve_hyperparams,
    unknown_env_id,
)
from motion_envs._io import atomic_write_text

__all__ = [
    "TrainConfig",
    "TrainResult",
    "equivalent_command",
    "preflight",
    "register",
    "run",
]

#: Called after every validation: ``{"timesteps", "val_criterion", "best_val_criterion",
#: "is_best", "run_dir"}``.
EvaluationHook = Callable[[dict[str, Any]], None]


@dataclass(frozen=True)
class TrainConfig:
    """Everything ``motion-bench train`` needs (None: from the config file)."""

    algo: str
    env_id: str
    out: str
    seed: int = 0
    config_path: str | None = None
    timesteps: int | None = None
    n_envs: int | None = None
    env_kwargs: Mapping[str, Any] = field(default_factory=dict)
    overrides: Mapping[str, Any] = field(default_factory=dict)
    progress: bool = True
    tensorboard: bool = True
    command: tuple[str, ...] = ()
    #: A refit: no validation; keep the policy at this step of the evaluation schedule.
    keep_timesteps: int | None = None
    #: How ``keep_timesteps`` was chosen (stored in run.json as ``selection``); its
    #: ``val_criterion`` and ``val_nominal_criterion`` stand for the validation's.
    selection: Mapping[str, Any] | None = None


@dataclass(frozen=True)
class TrainResult:
    """What a training run produced (also in ``DIR/run.json``)."""

    run_dir: str
    best_val_criterion: float
    best_timesteps: int
    val_nominal_criterion: float
    evaluations: list[dict[str, float]]
    timesteps: int
    train_seconds: float
    steps_per_second: float
    hyperparams: dict[str, Any]


def _check_config(config: TrainConfig) -> None:
    if config.algo not in ALGOS:
        raise ValueError(f"--algo must be one of {list(ALGOS)}; got {config.algo!r}")
    import gymnasium as gym

    import motion_envs  # noqa: F401  (registers the ids, also inside Ray workers)

    if config.env_id not in gym.registry:
        raise ValueError(f"--env {unknown_env_id(config.env_id)}")
    if isinstance(config.seed, bool) or not isinstance(config.seed, int) or config.seed < 0:
        raise ValueError(f"--seed must be an integer >= 0; got {config.seed!r}")


def preflight(config: TrainConfig) -> dict[str, Any]:
    """Every check of a run that needs no training: algorithm, registered id, seed, the
    resolved hyper-parameters, the constructor's keywords and the validation split (with
    ``n_envs``); the resolved hyper-parameters. ``run`` calls it first, ``motion-bench
    sweep`` for every configuration and seed before Ray starts."""
    from baselines.agents.scorers import check_validation_split

    _check_config(config)
    overrides: dict[str, Any] = dict(config.overrides)
    if config.timesteps is not None:
        overrides["n_timesteps"] = config.timesteps
    if config.n_envs is not None:
        overrides["n_envs"] = config.n_envs
    if config.env_kwargs:
        overrides["env_kwargs"] = {**overrides.get("env_kwargs", {}), **config.env_kwargs}
    hp = resolve_hyperparams(config.algo, config.env_id, config.config_path, overrides)
    checks.check_env_kwargs(config.env_id, hp["env_kwargs"])
    if config.keep_timesteps is None:  # a refit has no validation split
        check_validation_split(config.env_id, hp["env_kwargs"], config.seed, int(hp["n_envs"]))
    elif isinstance(config.keep_timesteps, bool) or not isinstance(config.keep_timesteps, int):
        raise ValueError(f"keep_timesteps must be an integer >= 0; got {config.keep_timesteps!r}")
    elif not 0 <= config.keep_timesteps <= int(hp["n_timesteps"]):
        raise ValueError(
            f"keep_timesteps must be in [0, {hp['n_timesteps']}]; got {config.keep_timesteps}"
        )
    return hp


def _make_train_env(env_id: str, hp: Mapping[str, Any]) -> Any:
    from stable_baselines3.common.vec_env import VecMonitor, VecNormalize

    from baselines.agents.vec import make_sb3_vec_env

    env: Any = VecMonitor(
        make_sb3_vec_env(
            env_id,
            hp["n_envs"],
            hp["env_kwargs"],
            "train",
            hp["vec_env"],
            int(hp.get("frame_stack", 1)),
        )
    )
    norm = hp.get("normalize", {})
    if norm.get("obs") or norm.get("reward"):
        env = VecNormalize(
            env,
            norm_obs=bool(norm.get("obs", False)),
            norm_reward=bool(norm.get("reward", False)),
            clip_obs=float(norm.get("clip_obs", 10.0)),
            gamma=float(norm.get("gamma", hp.get("gamma", 0.99))),
        )
    return env


def run(config: TrainConfig, on_evaluation: EvaluationHook | None = None) -> TrainResult:
    """Train, validate, save the run folder; see the module docstring.

    ``--out`` must not exist or be an empty folder. The run is written into a fresh
    staging folder beside it (``.NAME.partial-*``, removed if training fails or is
    interrupted) and renamed to ``--out`` once complete, so a run folder holds exactly one
    run's files; of two runs into one folder the second to finish is refused.
    """
    from baselines.agents.rundir import staged_run_folder

    hp = preflight(config)
    out = Path(config.out)
    # a fresh staging folder beside --out, renamed into place once complete: nothing of an
    # interrupted or concurrent run (a stale normalization.npz) can end up in the run
    with staged_run_folder(out) as staging:
        result = _train(config, hp, staging, on_evaluation)
    return dataclasses.replace(result, run_dir=str(out))


def _train(
    config: TrainConfig,
    hp: dict[str, Any],
    run_dir: Path,
    on_evaluation: EvaluationHook | None,
) -> TrainResult:
    """Train into the (empty, staging) ``run_dir``; see :func:`run`."""
    import torch
    from stable_baselines3.common.utils import set_random_seed

    from baselines.agents.callbacks import (
        EvaluationHookCallback,
        KeepAtCallback,
        SaveBestCallback,
        ValidationCallback,
    )
    from baselines.agents.evaluate import split_criterion
    from baselines.agents.policies import build_model
    from baselines.agents.rundir import ObsNormalizer, save_model, write_json, write_manifest
    from baselines.agents.scorers import scorer_for
    from baselines.sb3 import TqdmCallback

    torch.set_num_threads(int(hp["torch_threads"]))
    set_random_seed(config.seed)
    env = _make_train_env(config.env_id, hp)
    tb = None
    if config.tensorboard:
        try:
            import tensorboard  # noqa: F401

            tb = str(run_dir / "tb")
        except ImportError:
            print(
                "motion-bench train: tensorboard is not installed; no TensorBoard logs",
                file=sys.stderr,
            )
    # ARS's paired episode seeds stay below the validation seeds (a seed-range split)
    seed_bound = scorer_for(config.env_id).first_val_seed
    model = build_model(
        config.algo, hp, env, config.seed, tensorboard_log=tb, seed_bound=seed_bound
    )
    selection = dict(config.selection or {})
    validation: ValidationCallback
    if config.keep_timesteps is not None:  # a refit: the validation's schedule, no split
        val_nominal = float(selection.get("val_nominal_criterion", float("nan")))
        validation = KeepAtCallback(
            config.keep_timesteps, int(hp["eval_freq"]), SaveBestCallback(run_dir)
        )
    else:
        val_nominal = split_criterion(
            None, config.env_id, hp["env_kwargs"], "val", hp.get("eval_episodes")
        )
        validation = ValidationCallback(
            functools.partial(
                split_criterion,
                env_id=config.env_id,
                env_kwargs=hp["env_kwargs"],
                split="val",
                episodes=hp.get("eval_episodes"),
                frame_stack=int(hp.get("frame_stack", 1)),
            ),
            eval_freq=int(hp["eval_freq"]),
            callback_on_new_best=SaveBestCallback(run_dir),
            callback_after_eval=None
            if on_evaluation is None
            else EvaluationHookCallback(on_evaluation, run_dir),
        )
    callbacks: list[Any] = [validation]
    total = int(hp["n_timesteps"])
    if config.progress:
        callbacks.append(TqdmCallback(total, f"{config.algo} {config.env_id.split('/')[-1]}"))
    t0 = time.perf_counter()
    model.learn(total_timesteps=total, callback=callbacks, tb_log_name=config.algo)
    seconds = time.perf_counter() - t0
    steps = int(model.num_timesteps)
    best = validation.best
    if config.keep_timesteps is not None:
        if not getattr(validation, "kept", False):
            raise RuntimeError(
                f"keep_timesteps {config.keep_timesteps} was not reached in {steps} steps"
            )
        best = float(selection.get("val_criterion", float("nan")))

    save_model(model, run_dir / "final_agent.zip")
    vn = model.get_vec_normalize_env()
    if vn is not None:
        ObsNormalizer.save_vec_normalize(vn, run_dir / "final_normalization.npz")
    env.close()
    write_json(
        run_dir / "config.json",
        {"algo": config.algo, "env_id": config.env_id, "seed": config.seed, "hyperparams": hp},
    )
    rows = [f"{e['timesteps']},{e['val_criterion']!r}\n" for e in validation.evaluations]
    atomic_write_text(run_dir / "evaluations.csv", "timesteps,val_criterion\n" + "".join(rows))
    command = list(config.command) or equivalent_command(config)
    write_manifest(
        run_dir,
        {
            "algo": config.algo,
            "env_id": config.env_id,
            "seed": config.seed,
            "command": shlex.join(command),
            "torch_version": torch.__version__,
            "timesteps": steps,
            "train_seconds": seconds,
            "best_val_criterion": best,
            "best_timesteps": validation.best_timesteps,
            "val_nominal_criterion": val_nominal,
            **({"selection": selection} if config.keep_timesteps is not None else {}),
        },
        [
            "config.json",
            "agent.zip",
            "normalization.npz",
            "final_agent.zip",
            "final_normalization.npz",
            "evaluations.csv",
        ],
    )
    return TrainResult(
        run_dir=str(run_dir),
        best_val_criterion=best,
        best_timesteps=validation.best_timesteps,
        val_nominal_criterion=val_nominal,
        evaluations=validation.evaluations,
        timesteps=steps,
        train_seconds=seconds,
        steps_per_second=steps / seconds if seconds > 0 else float("nan"),
        hyperparams=hp,
    )


def equivalent_command(config: TrainConfig) -> list[str]:
    """The ``motion-bench train`` command line of ``config`` (hyper-parameter overrides,
    which the command line cannot set, follow as a comment)."""
    cmd = ["motion-bench", "train", "--algo", config.algo, "--env", config.env_id]
    cmd += ["--seed", str(config.seed), "--out", str(config.out)]
    if config.config_path is not None:
        cmd += ["--config", str(config.config_path)]
    if config.timesteps is not None:
        cmd += ["--timesteps", str(config.timesteps)]
    if config.n_envs is not None:
        cmd += ["--n-envs", str(config.n_envs)]
    if config.env_kwargs:
        cmd += ["--env-kwargs", *(f"{k}={json.dumps(v)}" for k, v in config.env_kwargs.items())]
    if config.overrides:
        cmd.append(f"# overrides {json.dumps(dict(config.overrides), sort_keys=True)}")
    return cmd


def _cli(args: argparse.Namespace) -> int:
    # the user chose the id; Gymnasium's "vN is out of date" notice would repeat per env
    warnings.filterwarnings("ignore", message=".*is out of date", category=DeprecationWarning)
    try:
        env_kwargs = parse_env_kwargs(args.env_kwargs)
    except ValueError as exc:
        raise options.ConfigError("env_kwargs", str(exc).removeprefix("--env-kwargs: ")) from None
    checks.check_env_kwargs(args.env, env_kwargs)
    from baselines.agents.scorers import check_validation_split, scorer_for

    if scorer_for(args.env).first_val_seed is not None:  # seed-range splits: checked
        hp = resolve_hyperparams(args.algo, args.env, args.config)  # before anything is built
        n_envs = args.n_envs if args.n_envs is not None else int(hp["n_envs"])
        check_validation_split(args.env, {}, args.seed, n_envs)
    default_out = f"runs/{args.algo}-{args.env.split('/')[-1]}-seed{args.seed}"
    config = TrainConfig(
        algo=args.algo,
        env_id=args.env,
        out=str(args.out) if args.out is not None else default_out,
        seed=args.seed,
        config_path=None if args.config is None else str(args.config),
        timesteps=args.timesteps,
        n_envs=args.n_envs,
        env_kwargs=env_kwargs,
        progress=not args.no_progress,
        tensorboard=not args.no_tensorboard,
        command=("motion-bench", *sys.argv[1:]) if sys.argv[1:2] == ["train"] else (),
    )
    result = run(config)
    nominal = result.val_nominal_criterion
    ratio = f", ratio {result.best_val_criterion / nominal:.4f}" if nominal > 0 else ""
    print(
        f"{config.algo} on {config.env_id}, seed {config.seed}: {result.timesteps} steps in "
        f"{result.train_seconds:.0f} s ({result.steps_per_second:.0f} steps/s); validation "
        f"criterion {result.best_val_criterion:.6g} at step {result.best_timesteps} "
        f"(nominal {nominal:.6g}{ratio})"
    )
    print(
        f"wrote {result.run_dir} (evaluate on the test split: motion-bench agent {result.run_dir})"
    )
    return 0


def register(subparsers: Any) -> None:
    """Add ``motion-bench train``."""
    p = options.add_subcommand(
        subparsers,
        "train",
        help="train an agent (SB3's ppo, sac, td3; sb3-contrib's ars) on top of the nominal; "
        "zoo-style YAML configs",
        description=__doc__.split("\n\n")[0].replace("``", ""),
    )
    p.add_argument("--algo", required=True, choices=ALGOS)
    p.add_argument(
        "--env", required=True, type=checks.env_id, metavar="ID",
        help="e.g. MotionEnvs/OrientationReach-v1",
    )  # fmt: skip
    p.add_argument(
        "--config", default=None, type=checks.yaml_file, metavar="PATH",
        help="hyper-parameters (default: configs/agents/ALGO.yaml)",
    )  # fmt: skip
    p.add_argument(
        "--timesteps", type=options.positive_int, default=None, help="override n_timesteps"
    )
    p.add_argument("--seed", type=options.non_negative_int, default=0)
    p.add_argument("--n-envs", type=options.positive_int, default=None, help="override n_envs")
    p.add_argument(
        "--env-kwargs",
        nargs="*",
        type=checks.env_kwarg,
        default=None,
        metavar="K=V",
        help="environment kwargs (plain YAML values), e.g. nominal=bezier-task",
    )
    p.add_argument(
        "--out", default=None, type=options.output_folder, metavar="DIR",
        help="run folder (default: runs/ALGO-ENV-seedS)",
    )  # fmt: skip
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("--no-tensorboard", action="store_true", help="no TensorBoard logs")
    p.set_defaults(func=_cli)
