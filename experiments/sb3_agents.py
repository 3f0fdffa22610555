"""A stable-baselines3 PPO agent against the analytic nominal, on the papers' criterion.

For each environment, PPO (``MlpPolicy``, SB3's default hyper-parameters, seeded) is
trained on ``split="train"`` for ``--timesteps`` steps on the native vector environment
(``gym.make_vec(..., vectorization_mode="vector_entry_point")``, adapted to SB3's
``VecEnv`` interface by :class:`baselines.sb3.GymnasiumVecEnv`, with ``VecMonitor``),
then evaluated deterministically on
``split="test"``: one episode per test trajectory (``reset(options={"trajectory": i})``),
``info["max_error"]`` at the episode's end. Three policies are scored:

* ``nominal``: the zero action, i.e. the analytic model. Its criterion is checked against
  ``motion-bench orientation --split test --nominal bezier-null`` /
  ``motion-bench position --split test --n-points 50`` (computed in the same run; the
  script raises if they differ by more than 1e-9);
* ``random``: uniform actions in ``[-1, 1]`` (seeded);
* ``ppo``: the trained agent's deterministic (mean) action.

Criteria: ``MotionEnvs/OrientationReach-v0`` (``nominal="bezier-null"``, vr-kitchen, split
by subject): the median over test trajectories of the max residual error (radians), Faraway
& Choe's criterion. ``MotionEnvs/PositionReach-v0`` (``nominal="null"``, LASA ``--shapes``,
split by replicate): the median over shapes of the per-shape medians of the max distance
(mm), ``motion-bench position``'s aggregation, and the plain median over test episodes.
A ratio PPO / nominal below 1 means the agent beats the analytic model out of sample.

Prints a table, then, as its last line, one JSON object with the figures and ratios.
Training progress (a tqdm bar per environment) goes to stderr.

    python experiments/sb3_agents.py [--timesteps 100000] [--n-envs 4] [--seed 0]
"""

from __future__ import annotations

import argparse
import contextlib
import json
import sys
import tempfile
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

import motion_envs  # noqa: F401  (registers the environments)

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))  # _timing, shared
from _timing import machine, print_json, print_table

ORIENTATION_ID = "MotionEnvs/OrientationReach-v0"
POSITION_ID = "MotionEnvs/PositionReach-v0"
DEFAULT_SHAPES = ("Angle", "CShape", "GShape", "Sine", "Worm")
TOLERANCE = 1e-9  # nominal criterion vs motion-bench


def train_ppo(env_id: str, kwargs: dict[str, Any], timesteps: int, n_envs: int, seed: int):
    """PPO (MlpPolicy, default hyper-parameters) on the train split; (model, seconds)."""
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import VecMonitor

    from baselines.sb3 import GymnasiumVecEnv, TqdmCallback

    venv = gym.make_vec(
        env_id,
        num_envs=n_envs,
        vectorization_mode="vector_entry_point",
        split="train",
        **kwargs,
    )
    env = VecMonitor(GymnasiumVecEnv(venv))
    model = PPO("MlpPolicy", env, seed=seed, verbose=0, device="cpu")
    t0 = time.perf_counter()
    model.learn(timesteps, callback=TqdmCallback(timesteps, env_id.split("/")[-1]))
    seconds = time.perf_counter() - t0
    env.close()
    return model, seconds


def evaluate(
    env_id: str, kwargs: dict[str, Any], policy: Callable[[np.ndarray], np.ndarray]
) -> tuple[np.ndarray, np.ndarray]:
    """``info["max_error"]`` of one episode per test trajectory, and the trajectories' tasks."""
    env = gym.make(env_id, split="test", **kwargs)
    task = env.unwrapped.task
    maxima = np.empty(task.n_trajectories)
    for i in range(task.n_trajectories):
        obs, _ = env.reset(options={"trajectory": i})
        done = False
        while not done:
            obs, _, terminated, truncated, info = env.step(policy(obs))
            done = terminated or truncated
        maxima[i] = info["max_error"]
    env.close()
    return maxima, np.asarray(task.tasks).astype(str)


def _motion_bench(argv: list[str]) -> dict[str, Any]:
    """Run ``motion-bench`` in-process (its report to stderr); its results.json."""
    from baselines.cli import main

    with tempfile.TemporaryDirectory() as tmp, contextlib.redirect_stdout(sys.stderr):
        if main([*argv, "--out", tmp]) != 0:
            raise RuntimeError(f"motion-bench {' '.join(argv)} failed")
        return json.loads((Path(tmp) / "results.json").read_text())


def _criteria(maxima: np.ndarray, tasks: np.ndarray, per_shape: bool) -> dict[str, float]:
    out = {"median": float(np.median(maxima))}
    if per_shape:
        out["median_of_shape_medians"] = float(
            np.median([np.median(maxima[tasks == s]) for s in np.unique(tasks)])
        )
    return out


def run_env(
    name: str,
    env_id: str,
    kwargs: dict[str, Any],
    reference: float,
    key: str,
    args: argparse.Namespace,
) -> dict[str, Any]:
    """Train, evaluate the three policies, check the nominal against motion-bench."""
    per_shape = key == "median_of_shape_medians"
    dim = gym.make(env_id, split="test", **kwargs).action_space.shape[0]
    zero = np.zeros(dim, dtype=np.float32)
    rng = np.random.default_rng(args.seed)
    policies: dict[str, Callable[[np.ndarray], np.ndarray]] = {
        "nominal": lambda obs: zero,
        "random": lambda obs: rng.uniform(-1.0, 1.0, dim).astype(np.float32),
    }
    model, seconds = train_ppo(env_id, kwargs, args.timesteps, args.n_envs, args.seed)
    policies["ppo"] = lambda obs: model.predict(obs, deterministic=True)[0]
    results: dict[str, Any] = {"env": env_id, "kwargs": kwargs, "train_seconds": seconds}
    for label, policy in policies.items():
        maxima, tasks = evaluate(env_id, kwargs, policy)
        results[label] = _criteria(maxima, tasks, per_shape)
    results["n_test_episodes"] = int(maxima.size)
    nominal = results["nominal"][key]
    results["motion_bench"] = reference
    results["nominal_minus_motion_bench"] = nominal - reference
    if not abs(nominal - reference) <= TOLERANCE:
        raise RuntimeError(
            f"{name}: zero-action criterion {nominal!r} != motion-bench's {reference!r}"
        )
    results["criterion"] = key
    results["ratio_ppo_to_nominal"] = results["ppo"][key] / nominal
    results["ratio_random_to_nominal"] = results["random"][key] / nominal
    return results


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--timesteps", type=int, default=100_000, help="PPO training steps per environment"
    )
    parser.add_argument("--n-envs", type=int, default=4, help="sub-environments of the vector env")
    parser.add_argument("--seed", type=int, default=0, help="seed of PPO, its envs and 'random'")
    parser.add_argument(
        "--shapes", nargs="+", default=list(DEFAULT_SHAPES), help="LASA shapes of PositionReach"
    )
    parser.add_argument(
        "--envs",
        nargs="+",
        choices=("orientation", "position"),
        default=["orientation", "position"],
        help="which environments to run",
    )
    args = parser.parse_args(argv)
    if args.timesteps < 1:
        parser.error(f"--timesteps must be >= 1; got {args.timesteps}")
    if args.n_envs < 1:
        parser.error(f"--n-envs must be >= 1; got {args.n_envs}")

    import torch

    torch.manual_seed(args.seed)
    info = machine()
    t_start = time.perf_counter()
    results: dict[str, Any] = {}
    if "orientation" in args.envs:
        doc = _motion_bench(["orientation", "--split", "test", "--nominal", "bezier-null"])
        results["orientation"] = run_env(
            "orientation",
            ORIENTATION_ID,
            {"nominal": "bezier-null"},
            doc["nominal"]["criterion"],
            "median",
            args,
        )
    if "position" in args.envs:
        doc = _motion_bench(
            [
                *("position", "--split", "test", "--n-points", "50"),
                *("--no-peers", "--no-progress", "--shapes", *args.shapes),
            ]
        )
        results["position"] = run_env(
            "position",
            POSITION_ID,
            {"nominal": "null", "shapes": list(args.shapes)},
            doc["summary_median_across_shapes"]["null"]["max_error"],
            "median_of_shape_medians",
            args,
        )
    total = time.perf_counter() - t_start

    print(f"{info['date']}  {info['cpu']}, {info['cores']} cores, load {info['load_average_1min']}")
    print(
        f"PPO MlpPolicy, SB3 defaults, {args.timesteps} steps, {args.n_envs} envs, seed {args.seed}"
    )
    rows = []
    for name, r in results.items():
        unit = "rad" if name == "orientation" else "mm"
        for label in ("nominal", "random", "ppo"):
            c = r[label]
            rows.append(
                [
                    f"{name} ({unit}, {r['n_test_episodes']} test eps)",
                    label,
                    c["median"],
                    c.get("median_of_shape_medians", float("nan")),
                    c[r["criterion"]] / r["nominal"][r["criterion"]],
                ]
            )
        print_table(
            ["env", "policy", "median max err", "median of shape medians", "x nominal"],
            rows[-3:],
        )
        print(
            f"  nominal vs motion-bench: {r['nominal'][r['criterion']]:.9f} vs "
            f"{r['motion_bench']:.9f} (diff {r['nominal_minus_motion_bench']:.1e}); "
            f"PPO trained {r['train_seconds']:.0f} s"
        )
    print_json(
        {
            "benchmark": "sb3_agents",
            "timesteps": args.timesteps,
            "n_envs": args.n_envs,
            "seed": args.seed,
            "total_seconds": total,
            "results": results,
            "machine": info,
        }
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
