"""Native vector environments of the juggling ids against ``SyncVectorEnv``, same run.

For ``MotionEnvs/Juggling-v1`` and ``MotionEnvs/Cascade-v0`` (each of ``--patterns``,
default the three- and the five-ball cascade) at ``--level`` and each ``N`` in
``--num-envs``: ``gym.make_vec(id, N)`` (the native vector environment) against
``gymnasium.vector.SyncVectorEnv`` of ``N`` ``gym.make(id)`` copies (the anchor), both
stepping the same pre-sampled actions (the zero action, and ``0.3 N(0, 1)`` residuals),
autoresetting (NEXT_STEP). The native env runs with each ``--threads`` count (default:
1, and every CPU this process may use; its worlds' control periods are split among the
threads, see ``motion_envs.envs.juggling._vector``). A figure is the median env-steps per
second over ``--repeats`` timed runs after a warm-up run, per wall-clock second and per
CPU second of the process (all its threads: a threaded run's CPU figure is what it costs,
its wall figure what a user waits); the ratio is native / sync.

Prints a table, then, as its last line, one JSON object with the figures and ratios.

    python benchmarks/juggling_vector_throughput.py [--num-envs 64 256] [--steps 16384]
        [--threads 1 2] [--patterns 3 5]
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from typing import Any

import gymnasium as gym
import numpy as np
from _timing import machine, print_json, print_machine, print_table  # benchmarks/ on sys.path
from tqdm import tqdm

import motion_envs  # noqa: F401  (registers the environments)

IDS = ("MotionEnvs/Juggling-v1", "MotionEnvs/Cascade-v0")


def _rate(env: gym.vector.VectorEnv, actions: np.ndarray) -> tuple[float, float]:
    """Env-steps per second of ``env`` over ``actions (T, N, ...)``: per wall-clock second
    and per CPU second of this process (the CPU figure does not count the time another
    process took from this one)."""
    env.reset(seed=0)
    step = env.step
    t0, c0 = time.perf_counter(), time.process_time()
    for a in actions:
        step(a)
    n = actions.shape[0] * actions.shape[1]
    return n / (time.perf_counter() - t0), n / (time.process_time() - c0)


def _median_rate(
    env: gym.vector.VectorEnv, actions: np.ndarray, repeats: int
) -> tuple[float, float]:
    _rate(env, actions[: max(100, actions.shape[0] // 4)])  # warm-up (numba loads its code)
    runs = [_rate(env, actions) for _ in range(repeats)]
    return statistics.median(r[0] for r in runs), statistics.median(r[1] for r in runs)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--num-envs", type=int, nargs="+", default=[64, 256])
    parser.add_argument("--steps", type=int, default=16_384, help="env-steps per timed run")
    parser.add_argument("--repeats", type=int, default=3, help="timed runs per figure")
    parser.add_argument("--level", default="medium", help="the envs' level")
    parser.add_argument("--ids", nargs="+", default=list(IDS), help="env ids")
    parser.add_argument(
        "--patterns", nargs="+", default=["3", "5"], help="Cascade-v0's patterns played"
    )
    cpus = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else 1
    parser.add_argument(
        "--threads",
        type=int,
        nargs="+",
        default=sorted({1, cpus}),
        help="thread counts of the native env (default: 1 and the CPUs available)",
    )
    args = parser.parse_args(argv)
    if any(t < 1 for t in args.threads):
        parser.error("--threads must be >= 1")
    for name in ("steps", "repeats"):
        if getattr(args, name) < 1:
            parser.error(f"--{name} must be >= 1")
    if any(n < 1 for n in args.num_envs):
        parser.error("--num-envs must be >= 1")
    rows: list[list[Any]] = []
    out: dict[str, Any] = {"machine": machine(), "level": args.level, "figures": []}
    settings: list[tuple[str, dict[str, Any]]] = []
    for env_id in args.ids:
        if "Cascade" in env_id:
            settings += [(env_id, {"pattern": p}) for p in args.patterns]
        else:
            settings.append((env_id, {}))
    jobs = [
        (env_id, extra, n, policy)
        for env_id, extra in settings
        for n in args.num_envs
        for policy in ("zero", "residual 0.3 N(0,1)")
    ]
    for env_id, extra, n, policy in tqdm(jobs, desc="settings", file=sys.stderr):
        kw = {"level": args.level, **extra}
        label = env_id + "".join(f" {k}={v}" for k, v in extra.items())
        sync = gym.vector.SyncVectorEnv(
            [lambda env_id=env_id, kw=kw: gym.make(env_id, **kw) for _ in range(n)]
        )
        shape = (max(1, args.steps // n), n, *sync.single_action_space.shape)
        rng = np.random.default_rng(0)
        actions = (
            np.zeros(shape, dtype=np.float32)
            if policy == "zero"
            else (0.3 * rng.standard_normal(shape)).astype(np.float32)
        )
        figures = {"sync": _median_rate(sync, actions, args.repeats)}
        sync.close()
        for threads in args.threads:
            env = gym.make_vec(env_id, n, threads=threads, **kw)
            figures[f"native, {threads} thread{'s' if threads > 1 else ''}"] = _median_rate(
                env, actions, args.repeats
            )
            env.close()
        for name, (wall, cpu) in figures.items():
            ratio, ratio_cpu = wall / figures["sync"][0], cpu / figures["sync"][1]
            rows.append(
                [label, n, policy, name, f"{wall:,.0f}", f"{ratio:.2f}", f"{ratio_cpu:.2f}"]
            )
            out["figures"].append(
                {
                    "id": env_id,
                    **extra,
                    "num_envs": n,
                    "policy": policy,
                    "variant": name,
                    "env_steps_per_s": round(wall, 1),
                    "env_steps_per_cpu_s": round(cpu, 1),
                    "ratio_to_sync": round(ratio, 3),
                    "ratio_to_sync_cpu": round(ratio_cpu, 3),
                }
            )
    print_machine(out["machine"])
    header = ["id", "N", "actions", "vector env", "env-steps/s", "x sync", "x sync (CPU)"]
    print_table(header, rows)
    print_json(out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
