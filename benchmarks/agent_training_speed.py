"""PPO training speed: the native vector env against SB3's DummyVecEnv of single envs.

The same PPO (``configs/agents/ppo.yaml``'s hyper-parameters for the environment, same
seed, ``VecNormalize`` as configured) trains for ``--timesteps`` steps twice in this run:

* ``native``: ``gym.make_vec(id, num_envs=N, vectorization_mode="vector_entry_point")``
  through :class:`baselines.sb3.GymnasiumVecEnv` (what ``motion-bench train`` uses);
* ``dummy``: SB3's ``DummyVecEnv`` of ``N`` ``gym.make(id)`` (the anchor), with
  ``VecMonitor`` on both.

Reported: environment steps per CPU second of this process (``time.process_time``;
torch runs one thread, as ``motion-bench train`` does, so on a shared machine CPU time
measures the cost where wall time measures the neighbours) for the whole ``learn`` call
and for the rollout collection alone (timed between SB3's rollout start/end callbacks,
where the environment is stepped; the rest is the gradient update, identical in both),
and the wall-clock rate of ``learn``. One step of each environment runs before timing
(numba's compilation). Repeated ``--repeats`` times, alternating, best kept. Prints a
table and, last, a JSON line.

    python benchmarks/agent_training_speed.py [--env MotionEnvs/OrientationReach-v1]
        [--n-envs 8 64] [--timesteps 20000] [--repeats 2]
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Sequence
from typing import Any

import gymnasium as gym
import numpy as np
from _timing import machine, print_json, print_table  # benchmarks/ is on sys.path

import motion_envs  # noqa: F401  (registers the environments)


def _train(kind: str, env_id: str, n_envs: int, timesteps: int, seed: int) -> dict[str, float]:
    import torch
    from stable_baselines3.common.callbacks import BaseCallback
    from stable_baselines3.common.vec_env import DummyVecEnv, VecMonitor, VecNormalize

    from baselines.agents.config import resolve_hyperparams
    from baselines.agents.policies import build_model
    from baselines.agents.vec import takes_keyword
    from baselines.sb3 import GymnasiumVecEnv

    hp = resolve_hyperparams("ppo", env_id, overrides={"n_envs": n_envs})
    kwargs = dict(hp["env_kwargs"])
    if takes_keyword(env_id, "split"):  # the reaching ids; not the juggling ones
        kwargs["split"] = "train"
    if kind == "native":
        venv = gym.make_vec(
            env_id, num_envs=n_envs, vectorization_mode="vector_entry_point", **kwargs
        )
        env: Any = VecMonitor(GymnasiumVecEnv(venv))
    else:
        env = VecMonitor(DummyVecEnv([lambda: gym.make(env_id, **kwargs)] * n_envs))
    norm = hp["normalize"]
    env = VecNormalize(env, norm_obs=norm.get("obs", False), norm_reward=norm.get("reward", False))
    torch.set_num_threads(int(hp["torch_threads"]))
    model = build_model("ppo", hp, env, seed)

    class RolloutTimer(BaseCallback):
        def __init__(self) -> None:
            super().__init__()
            self.seconds = 0.0
            self.steps = 0

        def _on_rollout_start(self) -> None:
            self._t0, self._n0 = time.process_time(), self.num_timesteps

        def _on_rollout_end(self) -> None:
            self.seconds += time.process_time() - self._t0
            self.steps += self.num_timesteps - self._n0

        def _on_step(self) -> bool:
            return True

    timer = RolloutTimer()
    env.reset()
    env.step(np.zeros((n_envs, *env.action_space.shape), dtype=np.float32))  # JIT warm-up
    t0, c0 = time.perf_counter(), time.process_time()
    model.learn(timesteps, callback=timer)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    env.close()
    return {
        "steps": float(model.num_timesteps),
        "wall_seconds": wall,
        "cpu_seconds": cpu,
        "steps_per_second": model.num_timesteps / cpu,
        "wall_steps_per_second": model.num_timesteps / wall,
        "rollout_steps_per_second": timer.steps / timer.seconds,
    }


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--env", default="MotionEnvs/OrientationReach-v1")
    parser.add_argument("--n-envs", type=int, nargs="+", default=[8, 64])
    parser.add_argument("--timesteps", type=int, default=20_000)
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    if args.timesteps < 1 or args.repeats < 1 or min(args.n_envs) < 1:
        parser.error("--timesteps, --repeats and --n-envs must be >= 1")
    info = machine()
    results: dict[str, Any] = {}
    rows = []
    for n in args.n_envs:
        best: dict[str, dict[str, float]] = {}
        for _ in range(args.repeats):
            for kind in ("native", "dummy"):
                r = _train(kind, args.env, n, args.timesteps, args.seed)
                if kind not in best or r["steps_per_second"] > best[kind]["steps_per_second"]:
                    best[kind] = r
        ratio = best["native"]["steps_per_second"] / best["dummy"]["steps_per_second"]
        ratio_rollout = (
            best["native"]["rollout_steps_per_second"] / best["dummy"]["rollout_steps_per_second"]
        )
        results[str(n)] = {**best, "ratio": ratio, "ratio_rollout": ratio_rollout}
        for kind in ("native", "dummy"):
            b = best[kind]
            rows.append(
                [
                    n,
                    kind,
                    b["steps_per_second"],
                    b["rollout_steps_per_second"],
                    b["wall_steps_per_second"],
                ]
            )
        wall_ratio = (
            best["native"]["wall_steps_per_second"] / best["dummy"]["wall_steps_per_second"]
        )
        results[str(n)]["ratio_wall"] = wall_ratio
        rows.append([n, "native / dummy", ratio, ratio_rollout, wall_ratio])
    print(f"{info['date']}  {info['cpu']}, {info['cores']} cores, load {info['load_average_1min']}")
    print(
        f"PPO ({args.env}, configs/agents/ppo.yaml), {args.timesteps} steps, best of {args.repeats}"
    )
    header = ["n_envs", "vec env", "learn steps/cpu-s", "rollout steps/cpu-s", "learn steps/s wall"]
    print_table(header, rows)
    print_json(
        {
            "benchmark": "agent_training_speed",
            "env": args.env,
            "timesteps": args.timesteps,
            "repeats": args.repeats,
            "results": results,
            "machine": info,
        }
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
