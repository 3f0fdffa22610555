"""Juggling-v1 and Cascade-v0 throughput: ``MotionEnvs/Juggling-v1`` and
``MotionEnvs/Cascade-v0`` against ``Reacher-v5`` in the same run.

Single environments from ``gym.make`` (with the registration's wrappers) step the same
pre-sampled uniform actions in ``[-1, 1]^2`` (``[-1, 1]^4`` for Cascade-v0's two hands)
and reset at episode ends; Juggling-v1 (contacts on, 5 physics steps per 5 ms step, the
actuated hand, the sensor, the analytic juggler, the human-likeness reward) is timed at
each level and under the zero action at ``medium``; Cascade-v0 (two hands, the
three-ball cascade) at ``medium`` under uniform and zero actions. Each figure is the
median over ``--repeats`` timed runs after a warm-up run; the JSON also holds the best
run of each (the machine is shared).

Prints a table, then, as its last line, one JSON object with the figures and ratios.

    python benchmarks/juggling_v1_throughput.py [--steps 20000] [--repeats 5]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from collections.abc import Callable

import gymnasium as gym
import numpy as np
from _timing import machine, print_json, print_machine, print_table  # benchmarks/ on sys.path
from tqdm import tqdm

import motion_envs  # noqa: F401  (registers the environments)

JUGGLING = "MotionEnvs/Juggling-v1"
CASCADE = "MotionEnvs/Cascade-v0"
ANCHOR = "Reacher-v5"


def _env_rate(env: gym.Env, actions: np.ndarray, cpu: dict[str, list[float]], key: str) -> float:
    """Steps per second (wall clock) of ``env`` over ``actions`` (resetting at episode
    ends); the steps per CPU second of the process are appended to ``cpu[key]``."""
    env.reset(seed=0)
    step, reset = env.step, env.reset
    t0, c0 = time.perf_counter(), time.process_time()
    for a in actions:
        _, _, terminated, truncated, _ = step(a)
        if terminated or truncated:
            reset()
    cpu.setdefault(key, []).append(actions.shape[0] / (time.process_time() - c0))
    return actions.shape[0] / (time.perf_counter() - t0)


def _median(fn: Callable[[], float], repeats: int, best: dict[str, float], key: str) -> float:
    fn()  # warm-up
    rates = [fn() for _ in range(repeats)]
    best[key] = max(rates)
    return statistics.median(rates)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--steps", type=int, default=20_000, help="env steps per timed run")
    parser.add_argument("--repeats", type=int, default=5, help="timed runs per figure")
    parser.add_argument("--seed", type=int, default=0, help="seed of the actions")
    args = parser.parse_args(argv)
    for name in ("steps", "repeats"):
        if getattr(args, name) < 1:
            parser.error(f"--{name} must be >= 1")
    rng = np.random.default_rng(args.seed)
    actions = rng.uniform(-1, 1, size=(args.steps, 2)).astype(np.float32)
    zeros = np.zeros_like(actions)
    actions4 = rng.uniform(-1, 1, size=(args.steps, 4)).astype(np.float32)
    jobs: list[tuple[str, str, dict[str, str], np.ndarray]] = [
        (f"{JUGGLING} {lv} (uniform actions)", JUGGLING, {"level": lv}, actions)
        for lv in ("easy", "medium", "hard")
    ]
    jobs.append((f"{JUGGLING} medium (zero action)", JUGGLING, {"level": "medium"}, zeros))
    jobs.append((f"{CASCADE} medium (uniform actions)", CASCADE, {"level": "medium"}, actions4))
    cascade_zero = np.zeros_like(actions4)
    jobs.append((f"{CASCADE} medium (zero action)", CASCADE, {"level": "medium"}, cascade_zero))
    jobs.append((ANCHOR, ANCHOR, {}, actions))
    best: dict[str, float] = {}
    steps: dict[str, float] = {}
    cpu_runs: dict[str, list[float]] = {}
    for key, env_id, kwargs, acts in tqdm(jobs, desc="environments", file=sys.stderr):
        env = gym.make(env_id, **kwargs)
        steps[key] = _median(
            lambda env=env, acts=acts, key=key: _env_rate(env, acts, cpu_runs, key),
            args.repeats,
            best,
            key,
        )
        env.close()
    # per CPU second (the warm-up run left out): robust to other processes on the machine
    cpu = {k: statistics.median(v[1:]) for k, v in cpu_runs.items()}
    info = machine()
    print_machine(info)
    print(f"median of {args.repeats} timed runs after a warm-up")
    reacher = steps[ANCHOR]
    print_table(
        ["environment", "steps/s", f"/ {ANCHOR}", "steps/CPU s", f"/ {ANCHOR} (CPU)"],
        [[k, v, v / reacher, cpu[k], cpu[k] / cpu[ANCHOR]] for k, v in steps.items()],
    )
    ratio = steps[f"{JUGGLING} medium (uniform actions)"] / reacher
    cascade = cpu[f"{CASCADE} medium (uniform actions)"] / cpu[ANCHOR]
    print_json(
        {
            "benchmark": "juggling_v1_throughput",
            **info,
            "gymnasium": gym.__version__,
            "repeats": args.repeats,
            "steps": args.steps,
            "steps_per_s": steps,
            "over_reacher": {k: v / reacher for k, v in steps.items()},
            "steps_per_cpu_s": cpu,
            "over_reacher_cpu": {k: v / cpu[ANCHOR] for k, v in cpu.items()},
            "best_run": best,
            "targets": {
                "juggling_v1_at_least_reacher": ratio >= 1.0,
                "cascade_v0_at_least_half_reacher_cpu": cascade >= 0.5,
            },
        }
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
