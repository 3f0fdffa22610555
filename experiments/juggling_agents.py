"""Agents on Juggling-v0 against the analytic juggler (the issue's juggling target).

For each algorithm and seed: ``motion-bench train`` (``baselines.agents.train.run``) with
``configs/agents/ALGO.yaml``'s Juggling-v0 block (5 % release noise by default), the
checkpoint chosen on the *validation* seeds (drop rate), then ``motion-bench agent`` on
the *test* seeds: catch rate of the agent and of the zero action (the analytic juggler)
on the same episodes, and the hand's deviation from the *held-out* demonstrations
relative to the zero action's (``baselines/agents/juggling_score.py``); the same for the
final policy (``final_*``; not chosen on anything, shown to see what training did). The
demonstrations are SIMULATED. Prints one row per run, the medians over seeds, the target
verdicts and, last, a JSON line.

    python experiments/juggling_agents.py [--algos ppo sac] [--seeds 0 1 2 3 4]
        [--timesteps 100000] [--noise 0.05] [--test-episodes 50] [--out DIR]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))  # _timing, shared
from _timing import machine, print_json, print_table

ENV = "MotionEnvs/Juggling-v0"


def one_run(algo: str, seed: int, args: argparse.Namespace, root: Path) -> dict[str, Any]:
    from baselines.agents.evaluate import AgentConfig
    from baselines.agents.evaluate import run as evaluate
    from baselines.agents.train import TrainConfig
    from baselines.agents.train import run as train

    env_kwargs = {} if args.noise is None else {"noise": args.noise}
    t0 = time.perf_counter()
    result = train(
        TrainConfig(
            algo=algo,
            env_id=ENV,
            out=str(root / f"{algo}-seed{seed}"),
            seed=seed,
            timesteps=args.timesteps,
            env_kwargs=env_kwargs,
            progress=False,
            tensorboard=False,
        )
    )
    test = evaluate(AgentConfig(result.run_dir, "test", args.test_episodes))
    final = evaluate(AgentConfig(result.run_dir, "test", args.test_episodes, which="final"))
    return {
        "algo": algo,
        "seed": seed,
        "best_timesteps": result.best_timesteps,
        "val_drop_rate": result.best_val_criterion,
        "val_nominal_drop_rate": result.val_nominal_criterion,
        "catch_rate": test["catch_rate"],
        "nominal_catch_rate": test["nominal_catch_rate"],
        "tosses": test["tosses"],
        "deviation_mm": 1000 * test["deviation"],
        "nominal_deviation_mm": 1000 * test["nominal_deviation"],
        "deviation_ratio": test["deviation_ratio"],
        "final_catch_rate": final["catch_rate"],
        "final_deviation_ratio": final["deviation_ratio"],
        "seconds": time.perf_counter() - t0,
    }


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--algos", nargs="+", default=["ppo"], choices=["ppo", "sac", "td3"])
    p.add_argument("--seeds", nargs="+", type=int, default=[0, 1, 2, 3, 4])
    p.add_argument("--timesteps", type=int, default=100_000)
    p.add_argument("--noise", type=float, default=None, help="release noise (config: 0.05)")
    p.add_argument("--test-episodes", type=int, default=50)
    p.add_argument("--out", type=Path, default=None, help="run folders (default: temporary)")
    args = p.parse_args(argv)
    warnings.filterwarnings("ignore", message=".*is out of date", category=DeprecationWarning)
    with tempfile.TemporaryDirectory() as tmp:
        root = args.out if args.out is not None else Path(tmp)
        rows = [one_run(a, s, args, root) for a in args.algos for s in args.seeds]
    print_table(list(rows[0]), [list(r.values()) for r in rows])
    summary = []
    for algo in args.algos:
        mine = [r for r in rows if r["algo"] == algo]
        catch = float(np.median([r["catch_rate"] for r in mine]))
        nominal = float(np.median([r["nominal_catch_rate"] for r in mine]))
        dev = float(np.median([r["deviation_ratio"] for r in mine]))
        summary.append(
            {
                "algo": algo,
                "seeds": len(mine),
                "catch_rate_median": catch,
                "nominal_catch_rate": nominal,
                "catch_rate_above_nominal": catch > nominal,
                "deviation_ratio_median": dev,
                "deviation_within_1.1": dev <= 1.1,
                "runs_keeping_initial_policy": sum(r["best_timesteps"] == 0 for r in mine),
            }
        )
    print_table(list(summary[0]), [list(r.values()) for r in summary])
    print_json({"machine": machine(), "args": vars(args) | {"out": str(args.out)}, "runs": rows,
                "summary": summary})  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
