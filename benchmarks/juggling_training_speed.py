"""PPO on Juggling-v0: SB3's SubprocVecEnv (``vec_env: subproc``) against DummyVecEnv.

Juggling-v0 has no native vector environment (one MuJoCo scene per copy), so
``motion-bench train`` steps its copies in SB3's ``DummyVecEnv`` (the anchor) or, with
``vec_env: subproc`` in the agent config, in a ``SubprocVecEnv`` (one process per copy).
The same PPO (``configs/agents/ppo.yaml``'s Juggling-v0 block, ``VecNormalize``, seed 0)
learns ``--timesteps`` steps with each, alternating, ``--repeats`` times; reported: the
wall-clock rate of ``learn`` (the workers' CPU time is not in this process's, so wall
time is the measure here), best of the repeats, and the ratio subproc / dummy. Prints a
table and, last, a JSON line.

    python benchmarks/juggling_training_speed.py [--n-envs 2 4] [--timesteps 20000] [--repeats 2]
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Sequence
from typing import Any

from _timing import machine, print_json, print_table  # benchmarks/ is on sys.path

ENV = "MotionEnvs/Juggling-v0"


def _learn(kind: str, n_envs: int, timesteps: int, seed: int) -> float:
    """Wall seconds of ``learn`` with ``vec_env=kind``."""
    import torch
    from stable_baselines3.common.vec_env import VecMonitor, VecNormalize

    from baselines.agents.config import resolve_hyperparams
    from baselines.agents.policies import build_model
    from baselines.agents.vec import make_sb3_vec_env

    hp = resolve_hyperparams("ppo", ENV, overrides={"n_envs": n_envs, "vec_env": kind})
    env: Any = VecMonitor(make_sb3_vec_env(ENV, n_envs, hp["env_kwargs"], "train", kind))
    norm = hp["normalize"]
    env = VecNormalize(env, norm_obs=norm.get("obs", False), norm_reward=norm.get("reward", False))
    torch.set_num_threads(int(hp["torch_threads"]))
    model = build_model("ppo", hp, env, seed)
    t0 = time.perf_counter()
    model.learn(timesteps)
    seconds = time.perf_counter() - t0
    env.close()
    return seconds


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--n-envs", type=int, nargs="+", default=[2, 4])
    parser.add_argument("--timesteps", type=int, default=20_000)
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    if args.timesteps < 1 or args.repeats < 1 or min(args.n_envs) < 2:
        parser.error("--timesteps and --repeats must be >= 1, --n-envs >= 2")
    info = machine()
    rows, results = [], {}
    for n in args.n_envs:
        best = {"dummy": float("inf"), "subproc": float("inf")}
        for _ in range(args.repeats):
            for kind in best:
                best[kind] = min(best[kind], _learn(kind, n, args.timesteps, args.seed))
        rates = {k: args.timesteps / v for k, v in best.items()}
        ratio = rates["subproc"] / rates["dummy"]
        results[str(n)] = {"steps_per_second": rates, "ratio": ratio}
        rows += [[n, k, rates[k]] for k in rates] + [[n, "subproc / dummy", ratio]]
    print(f"{info['date']}  {info['cpu']}, {info['cores']} cores, load {info['load_average_1min']}")
    print(f"PPO ({ENV}, configs/agents/ppo.yaml), {args.timesteps} steps, best of {args.repeats}")
    print_table(["n_envs", "vec env", "learn steps/s wall"], rows)
    print_json({"benchmark": "juggling_training_speed", "timesteps": args.timesteps,
                "repeats": args.repeats, "results": results, "machine": info})  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
