"""Environment throughput: our envs against Pendulum-v1 and Reacher-v5, same run, same actions.

Single environments (``gym.make``, with the registration's wrappers): steps per second
of ``MotionEnvs/OrientationReach-v0`` and ``MotionEnvs/PositionReach-v0`` against
``Pendulum-v1`` and ``Reacher-v5``, each stepping the same pre-sampled uniform actions in
``[-1, 1]`` (cut to its action dimension) and resetting at episode ends. Vector
environments: the native vector envs
(``gym.make_vec(..., vectorization_mode="vector_entry_point")``) at N = 1, 8, 64, 1024
against, in the same run, the same env's single environment and its ``SyncVectorEnv``
(N = 1, 8, 64) and ``Reacher-v5`` under ``SyncVectorEnv`` with 8 copies, in env-steps
per second (N x vector steps / s). Each figure is the median over ``--repeats`` timed runs, after
one warm-up run; the JSON also holds the best run of each (the machine is shared, so the
spread says how much other load there was). Reacher-v5 needs ``imageio``
(``pip install "gymnasium[mujoco]"``).

Prints a table, then, as its last line, one JSON object with the figures and ratios.

    python benchmarks/env_throughput.py [--steps 20000] [--vector-steps 300] [--repeats 5]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import sys
import time
from datetime import datetime, timezone

import gymnasium as gym
import numpy as np
from _timing import cpu_model  # benchmarks/ is on sys.path when run as a script
from tqdm import tqdm

import motion_envs  # noqa: F401  (registers the environments)

OURS = ("MotionEnvs/OrientationReach-v0", "MotionEnvs/PositionReach-v0")
ANCHORS = ("Pendulum-v1", "Reacher-v5")
VECTOR_SIZES = (1, 8, 64, 1024)
SYNC_SIZES = (1, 8, 64)


def _single_rate(env: gym.Env, actions: np.ndarray) -> float:
    dim = env.action_space.shape[0]
    acts = np.ascontiguousarray(actions[:, :dim])
    env.reset(seed=0)
    step, reset = env.step, env.reset
    t0 = time.perf_counter()
    for a in acts:
        _, _, terminated, truncated, _ = step(a)
        if terminated or truncated:
            reset()
    return acts.shape[0] / (time.perf_counter() - t0)


def _vector_rate(env: gym.vector.VectorEnv, actions: np.ndarray) -> float:
    n, dim = env.num_envs, env.single_action_space.shape[0]
    acts = np.ascontiguousarray(actions[:, :n, :dim])
    env.reset(seed=0)
    step = env.step
    t0 = time.perf_counter()
    for a in acts:
        step(a)
    return acts.shape[0] * n / (time.perf_counter() - t0)


def _median_rate(fn, repeats: int, best: dict[str, float], key: str) -> float:
    """Median rate over ``repeats`` timed runs after a warm-up; the best run into ``best``."""
    fn()  # warm-up
    rates = [fn() for _ in range(repeats)]
    best[key] = max(rates)
    return statistics.median(rates)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--steps", type=int, default=20_000, help="single-env steps per run")
    parser.add_argument("--vector-steps", type=int, default=300, help="vector steps per run")
    parser.add_argument("--repeats", type=int, default=5, help="timed runs per figure")
    parser.add_argument("--seed", type=int, default=0, help="seed of the pre-sampled actions")
    args = parser.parse_args(argv)
    rng = np.random.default_rng(args.seed)
    single_actions = rng.uniform(-1, 1, size=(args.steps, 3)).astype(np.float32)
    vector_actions = rng.uniform(-1, 1, size=(args.vector_steps, max(VECTOR_SIZES), 3)).astype(
        np.float32
    )

    best: dict[str, float] = {}
    single: dict[str, float] = {}
    for env_id in tqdm((*OURS, *ANCHORS), desc="single envs", file=sys.stderr):
        env = gym.make(env_id)
        single[env_id] = _median_rate(
            lambda env=env: _single_rate(env, single_actions), args.repeats, best, env_id
        )
        env.close()

    vector: dict[str, dict[str, float]] = {env_id: {} for env_id in OURS}
    jobs = [(env_id, n) for env_id in OURS for n in VECTOR_SIZES]
    for env_id, n in tqdm(jobs, desc="vector envs", file=sys.stderr):
        venv = gym.make_vec(env_id, num_envs=n, vectorization_mode="vector_entry_point")
        vector[env_id][str(n)] = _median_rate(
            lambda venv=venv: _vector_rate(venv, vector_actions),
            args.repeats,
            best,
            f"{env_id} N={n}",
        )
        venv.close()
    sync: dict[str, dict[str, float]] = {env_id: {} for env_id in OURS}
    jobs = [(env_id, n) for env_id in OURS for n in SYNC_SIZES]
    for env_id, n in tqdm(jobs, desc="SyncVectorEnv", file=sys.stderr):
        venv = gym.make_vec(env_id, num_envs=n, vectorization_mode="sync")
        sync[env_id][str(n)] = _median_rate(
            lambda venv=venv: _vector_rate(venv, vector_actions[: max(20, 2000 // n)]),
            args.repeats,
            best,
            f"{env_id} Sync N={n}",
        )
        venv.close()
    reacher = gym.make_vec("Reacher-v5", num_envs=8, vectorization_mode="sync")
    reacher_sync8 = _median_rate(
        lambda: _vector_rate(reacher, vector_actions), args.repeats, best, "Reacher-v5 Sync N=8"
    )
    reacher.close()

    pendulum = single["Pendulum-v1"]
    print(f"steps per second, median of {args.repeats} runs ({cpu_model()})")
    print()
    print(f"{'single environment':<34} {'steps/s':>12} {'/ Pendulum-v1':>14}")
    for env_id, rate in single.items():
        print(f"{env_id:<34} {rate:>12,.0f} {rate / pendulum:>14.2f}")
    print()
    head = f"{'vector environment':<34} {'N':>6} {'env-steps/s':>14} {'/ single':>9}"
    print(f"{head} {'/ Sync':>7} {'/ Reacher Sync x8':>18}")
    for env_id in OURS:
        for kind, rates in (("native", vector[env_id]), ("Sync", sync[env_id])):
            for n, rate in rates.items():
                ref = sync[env_id].get(n)
                vs_sync = f"{rate / ref:>7.2f}" if ref else f"{'':>7}"
                print(
                    f"{env_id + f' ({kind})':<34} {n:>6} {rate:>14,.0f} "
                    f"{rate / single[env_id]:>9.2f} {vs_sync} {rate / reacher_sync8:>18.1f}"
                )
    print(f"{'Reacher-v5 (SyncVectorEnv)':<34} {8:>6} {reacher_sync8:>14,.0f} {1.0:>37.1f}")
    doc = {
        "benchmark": "env_throughput",
        "date": datetime.now(timezone.utc).date().isoformat(),
        "cpu": cpu_model(),
        "cores": os.cpu_count(),
        "load_average_1min": os.getloadavg()[0],
        "python": platform.python_version(),
        "gymnasium": gym.__version__,
        "numpy": np.__version__,
        "repeats": args.repeats,
        "single_steps_per_s": single,
        "single_over_pendulum": {k: v / pendulum for k, v in single.items()},
        "vector_env_steps_per_s": vector,
        "sync_env_steps_per_s": sync,
        "vector_over_single": {
            env_id: {n: r / single[env_id] for n, r in rates.items()}
            for env_id, rates in vector.items()
        },
        "reacher_sync8_env_steps_per_s": reacher_sync8,
        "vector_over_reacher_sync8": {
            env_id: {n: r / reacher_sync8 for n, r in rates.items()}
            for env_id, rates in vector.items()
        },
        "best_run_steps_per_s": best,
        "targets": {
            "single_at_least_pendulum": {env_id: single[env_id] >= pendulum for env_id in OURS},
            "vector_1_at_least_single": {
                env_id: vector[env_id]["1"] >= single[env_id] for env_id in OURS
            },
            "vector_64_at_least_1e6": {env_id: vector[env_id]["64"] >= 1e6 for env_id in OURS},
            "vector_1024_at_least_3e6_orientation_1e7_position": {
                env_id: vector[env_id]["1024"] >= (3e6 if "Orientation" in env_id else 1e7)
                for env_id in OURS
            },
        },
    }
    print(json.dumps(doc))
    return 0


if __name__ == "__main__":
    sys.exit(main())
