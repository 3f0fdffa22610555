"""Choose Juggling-v2's catch plans (lead, descent) on TRAINING seeds only.

For each catch-plan controller (``juggler_oracle_catch``, ``juggler_mean_delay_catch``;
:mod:`motion_envs.models.juggling._v2_catch`) and each pair of ``LEAD_GRID x
DESCENT_GRID``, the controller alone (the zero action) plays ``--episodes`` TRAINING
episodes (seeds ``SPLIT_SEEDS["train"] + i``; never a validation or test seed) of
``MotionEnvs/Juggling-v2`` on each of the four levels, ``--max-catches`` catches per
episode (the benchmark's 3). The pair with the highest catch rate (catches per toss)
pooled over the levels is the choice (ties: the first in grid order, the smaller lead,
then the smaller descent); ``CATCH_PLANS`` in the module quotes it. Prints a table per
controller and, as its last line, one JSON object (``--out FILE`` also writes it). The
demonstrations the juggler is fitted on are SIMULATED.

    python experiments/juggling_v2_catch_plan.py [--episodes 50] [--max-catches 3] [--out FILE]
        [--controllers juggler_oracle_catch,juggler_mean_delay_catch]
"""

from __future__ import annotations

import argparse
import json
import time
from itertools import product

import gymnasium as gym
from tqdm import tqdm

import motion_envs  # noqa: F401  (registers the environments)
from motion_envs._io import atomic_write_text
from motion_envs.datasets.juggling import SIMULATED_LABEL, episode_seeds
from motion_envs.models.juggling import CATCH_PLANS, V2_LEVELS, CatchPlan
from motion_envs.models.juggling._v2_catch import DESCENT_GRID, LEAD_GRID


def score(
    controller: str, plan: CatchPlan, episodes: int, max_catches: int
) -> dict[str, list[int]]:
    """Per level ``[catches, tosses]`` of ``episodes`` training episodes under ``plan``."""
    out = {}
    for level in V2_LEVELS:
        env = gym.make(
            "MotionEnvs/Juggling-v2", level=level, controller=controller, max_catches=max_catches
        ).unwrapped
        env.controller.plan = plan  # the candidate (the env built the declared one)
        catches = tosses = 0
        for seed in episode_seeds("train", episodes).tolist():
            played = env.nominal_episode(int(seed))
            catches += played["catches"]
            tosses += played["tosses"]
        env.close()
        out[level] = [catches, tosses]
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=50)
    parser.add_argument("--max-catches", type=int, default=3)
    parser.add_argument("--out", default=None)
    parser.add_argument(
        "--controllers", default=",".join(CATCH_PLANS), help="comma-separated; default: all"
    )
    args = parser.parse_args()
    t0 = time.process_time()
    doc: dict[str, object] = {
        "demonstrations": SIMULATED_LABEL,
        "split": "train",
        "episodes_per_level": args.episodes,
        "max_catches": args.max_catches,
        "controllers": {},
    }
    pairs = list(product(LEAD_GRID, DESCENT_GRID))
    for controller in args.controllers.split(","):
        if controller not in CATCH_PLANS:
            parser.error(f"--controllers: {controller!r} is not one of {list(CATCH_PLANS)}")
        rows = []
        best, best_rate = pairs[0], -1.0
        for lead, descent in tqdm(pairs, desc=controller):
            per_level = score(controller, CatchPlan(lead, descent), args.episodes, args.max_catches)
            catches = sum(c for c, _ in per_level.values())
            tosses = sum(t for _, t in per_level.values())
            rate = catches / max(tosses, 1)
            levels = {k: c / max(t, 1) for k, (c, t) in per_level.items()}
            rows.append({"lead_s": lead, "descent_m_s": descent, "pooled": rate, "levels": levels})
            if rate > best_rate:
                best, best_rate = (lead, descent), rate
        print(f"\n{controller} (TRAINING seeds, {args.episodes} episodes per level)")
        print(
            f"{'lead s':>7s} {'descent':>8s} {'pooled':>7s} "
            + " ".join(f"{k:>7s}" for k in V2_LEVELS)
        )
        for r in rows:
            lv = " ".join(f"{r['levels'][k]:7.3f}" for k in V2_LEVELS)
            print(f"{r['lead_s']:7.2f} {r['descent_m_s']:8.1f} {r['pooled']:7.3f} {lv}")
        print(f"choice: lead {best[0]} s, descent {best[1]} m/s (pooled {best_rate:.3f})")
        choice = {"lead_s": best[0], "descent_m_s": best[1], "pooled": best_rate}
        doc["controllers"][controller] = {"grid": rows, "choice": choice}  # type: ignore[index]
    doc["cpu_s"] = time.process_time() - t0
    text = json.dumps(doc)
    if args.out:
        atomic_write_text(args.out, json.dumps(doc, indent=2) + "\n")
    print(text)


if __name__ == "__main__":
    main()
