"""Do trivial policies lose to the juggler in the shipped Juggling-v1 agents' action space?

Not a timing: the floor under the agent's win. ``MotionEnvs/Juggling-v1`` with the shipped
PPO block's environment keywords (read from ``configs/agents/ppo.yaml``: level, catches
per episode, ``residual_scale``, ``residual_phases``) on VALIDATION seeds
``SPLIT_SEEDS["val"] + i`` (``--split train`` for the training seeds; never the test
seeds), ``--episodes`` episodes per policy, each policy on the same seeds:

* ``zero``: the analytic juggler itself (the reference the agent must beat);
* ``uniform random``: an action drawn uniformly in the box every step;
* ``constant up`` / ``constant down``: the vertical residual at +1 / -1 every step.

Prints, per policy, the catch rate (catches per toss, pooled over the episodes) with a
95 % bootstrap interval resampling episodes (:func:`baselines.stats.group_bootstrap`),
then, as its last line, one JSON object with the figures. The demonstrations the juggler
is fitted on are SIMULATED.

    python experiments/juggling_v1_trivial_residuals.py [--episodes 80] [--split val]
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from pathlib import Path

import gymnasium as gym
import numpy as np
from tqdm import tqdm

import motion_envs  # noqa: F401  (registers the environments)
from baselines.agents.config import resolve_hyperparams
from baselines.stats import group_bootstrap
from motion_envs.datasets.juggling import SPLIT_SEEDS

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))  # _timing, shared
from _timing import machine, print_json, print_machine, print_table

ENV_ID = "MotionEnvs/Juggling-v1"
#: The shipped agents' environment (read from ``configs/agents/ppo.yaml``).
SHIPPED: dict[str, object] = dict(resolve_hyperparams("ppo", ENV_ID)["env_kwargs"])
#: Trivial policies: a name and the action of a step given a generator.
POLICIES: dict[str, Callable[[np.random.Generator], np.ndarray]] = {
    "zero": lambda rng: np.zeros(2),
    "uniform random": lambda rng: rng.uniform(-1.0, 1.0, 2),
    "constant up": lambda rng: np.array([0.0, 1.0]),
    "constant down": lambda rng: np.array([0.0, -1.0]),
}


def play(policy: str, split: str, episodes: int) -> tuple[np.ndarray, np.ndarray]:
    """Catches and tosses per episode of ``policy`` on ``split``'s first seeds."""
    env = gym.make(ENV_ID, **SHIPPED)
    rng = np.random.default_rng(0)
    act = POLICIES[policy]
    catches, tosses = np.zeros(episodes), np.zeros(episodes)
    for i in range(episodes):
        env.reset(seed=SPLIT_SEEDS[split] + i)
        done, info = False, {}
        while not done:
            _, _, terminated, truncated, info = env.step(act(rng).astype(np.float32))
            done = terminated or truncated
        catches[i], tosses[i] = info["catches"], info["tosses"]
    env.close()
    return catches, tosses


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--episodes", type=int, default=80, help="episodes per policy")
    parser.add_argument("--split", choices=("train", "val"), default="val")
    args = parser.parse_args(argv)
    if args.episodes < 2:
        parser.error("--episodes must be >= 2")
    info = machine()
    print_machine(info)
    print(f"{ENV_ID}, {SHIPPED}, {args.episodes} {args.split} episodes (SIMULATED demonstrations)")
    rows, figures = [], []
    for name in tqdm(POLICIES, desc="policies", file=sys.stderr):
        c, t = play(name, args.split, args.episodes)
        rate, low, high = group_bootstrap(
            lambda r, c=c, t=t: float(c[r].sum() / max(t[r].sum(), 1.0)), np.arange(c.size)
        )
        rows.append([name, f"{rate:.3f} [{low:.3f}, {high:.3f}]", int(t.sum())])
        figures.append({"policy": name, "catch_rate": rate, "ci": [low, high], "tosses": t.sum()})
    print_table(["policy", "catch rate [95 % CI]", "tosses"], rows)
    print_json({"machine": info, "env_kwargs": SHIPPED, "split": args.split, "figures": figures})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
