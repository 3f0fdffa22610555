"""Juggling throughput: ``MotionEnvs/Juggling-v0`` against ``Reacher-v5`` in the same run,
and the analytic juggler's cycles per second in pure-model mode.

Single environments (``gym.make``, with the registration's wrappers) step the same
pre-sampled uniform actions in ``[-1, 1]^2`` and reset at episode ends; Juggling-v0 is also
timed under the zero action (the analytic juggler's own run, episodes of ``max_cycles``
catches). Pure-model mode: the fitted analytic juggler drives
``motion_envs.models.juggling.BallisticWorld`` (no MuJoCo, no Gymnasium) step by step
for ``--cycles`` cycles (a cycle ends with a catch or a drop; a drop restarts at home), the
same loop in the MuJoCo scene (``JugglingScene``), and ``run_cycles_fast`` (the vectorised
pure-model runner of ``motion-bench juggling``: its own seeded cycles, each from home).
Each figure is the median over ``--repeats`` timed runs after one warm-up run; the JSON
also holds the best run of each (the machine is shared).

Prints a table, then, as its last line, one JSON object with the figures and ratios.

    python benchmarks/juggling_throughput.py [--steps 20000] [--cycles 200] [--repeats 5]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from collections.abc import Callable
from typing import Any

import gymnasium as gym
import numpy as np
from _timing import machine, print_json, print_machine, print_table  # benchmarks/ on sys.path
from tqdm import tqdm

import motion_envs  # noqa: F401  (registers the environments)

JUGGLING = "MotionEnvs/Juggling-v0"
ANCHOR = "Reacher-v5"


def _env_rate(env: gym.Env, actions: np.ndarray) -> float:
    """Steps per second of ``env`` over ``actions`` (resetting at episode ends)."""
    env.reset(seed=0)
    step, reset = env.step, env.reset
    t0 = time.perf_counter()
    for a in actions:
        _, _, terminated, truncated, _ = step(a)
        if terminated or truncated:
            reset()
    return actions.shape[0] / (time.perf_counter() - t0)


def _cycle_rate(
    world: Any, juggler: Any, task: Any, cycles: int, seed: int, counts: dict[str, int]
) -> float:
    """Cycles per second of the juggler driving ``world``; a drop restarts at home.

    ``counts`` receives the control steps, catches and drops of the run."""
    rng = np.random.default_rng(seed)
    done = n_steps = drops = 0
    t0 = time.perf_counter()
    while done < cycles:
        state = world.reset(task.home, rng=rng)
        juggler.reset(state, rng=rng)
        command, step = juggler.command, world.step
        while done < cycles:
            target, armed = command(state)
            state = step(target, armed)
            n_steps += 1
            if state.caught:
                done += 1
            elif state.dropped:
                done += 1
                drops += 1
                break
    elapsed = time.perf_counter() - t0
    counts.update(control_steps=n_steps, catches=cycles - drops, drops=drops)
    return cycles / elapsed


def _median(fn: Callable[[], float], repeats: int, best: dict[str, float], key: str) -> float:
    fn()  # warm-up
    rates = [fn() for _ in range(repeats)]
    best[key] = max(rates)
    return statistics.median(rates)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--steps", type=int, default=20_000, help="env steps per timed run")
    parser.add_argument("--cycles", type=int, default=200, help="juggling cycles per timed run")
    parser.add_argument("--repeats", type=int, default=5, help="timed runs per figure")
    parser.add_argument("--seed", type=int, default=0, help="seed of the actions and the runs")
    args = parser.parse_args(argv)
    for name in ("steps", "cycles", "repeats"):
        if getattr(args, name) < 1:
            parser.error(f"--{name} must be >= 1")

    from motion_envs.datasets.juggling import JugglingTask
    from motion_envs.envs.juggling import JugglingScene
    from motion_envs.models.juggling import BallisticWorld, load_juggler, run_cycles_fast

    rng = np.random.default_rng(args.seed)
    actions = rng.uniform(-1, 1, size=(args.steps, 2)).astype(np.float32)
    zeros = np.zeros_like(actions)
    best: dict[str, float] = {}
    steps: dict[str, float] = {}
    jobs = [
        (f"{JUGGLING} (uniform actions)", JUGGLING, actions),
        (f"{JUGGLING} (zero action)", JUGGLING, zeros),
        (ANCHOR, ANCHOR, actions),
    ]
    for key, env_id, acts in tqdm(jobs, desc="environments", file=sys.stderr):
        env = gym.make(env_id)
        steps[key] = _median(
            lambda env=env, acts=acts: _env_rate(env, acts), args.repeats, best, key
        )
        env.close()
    task = JugglingTask()
    juggler = load_juggler(None, task)
    cycles: dict[str, float] = {}
    counts: dict[str, dict[str, int]] = {}
    for key, world in tqdm(
        (
            ("pure model (BallisticWorld)", BallisticWorld(task)),
            ("MuJoCo scene", JugglingScene(task)),
        ),
        desc="juggler",
        file=sys.stderr,
    ):
        counts[key] = {}
        cycles[key] = _median(
            lambda world=world, c=counts[key]: _cycle_rate(
                world, juggler, task, args.cycles, args.seed, c
            ),
            args.repeats,
            best,
            key,
        )
    # the vectorised pure-model runner motion-bench juggling uses (same cycles, all at once)
    key = "pure model, vectorised (run_cycles_fast)"
    fast_counts: dict[str, int] = {}

    def fast() -> float:
        t0 = time.perf_counter()
        res = run_cycles_fast(juggler, args.cycles, seed=args.seed)
        elapsed = time.perf_counter() - t0
        caught = sum(r.caught for r in res)
        fast_counts.update(
            control_steps=sum(r.steps for r in res), catches=caught, drops=args.cycles - caught
        )
        return args.cycles / elapsed

    cycles[key] = _median(fast, args.repeats, best, key)
    counts[key] = fast_counts

    info = machine()
    print_machine(info)
    print(f"median of {args.repeats} timed runs after a warm-up")
    reacher = steps[ANCHOR]
    print_table(
        ["environment", "steps/s", f"/ {ANCHOR}"],
        [[k, v, v / reacher] for k, v in steps.items()],
    )
    print()
    print_table(
        ["analytic juggler", "cycles/s", "control steps/s", "catches", "drops"],
        [
            [
                k,
                v,
                v * counts[k]["control_steps"] / args.cycles,
                counts[k]["catches"],
                counts[k]["drops"],
            ]
            for k, v in cycles.items()
        ],
    )
    ratio = steps[f"{JUGGLING} (uniform actions)"] / reacher
    print_json(
        {
            "benchmark": "juggling_throughput",
            **info,
            "gymnasium": gym.__version__,
            "repeats": args.repeats,
            "steps": args.steps,
            "cycles": args.cycles,
            "steps_per_s": steps,
            "over_reacher": {k: v / reacher for k, v in steps.items()},
            "juggler_cycles_per_s": cycles,
            "juggler_run_counts": counts,
            "best_run": best,
            "targets": {"juggling_at_least_reacher": ratio >= 1.0},
        }
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
