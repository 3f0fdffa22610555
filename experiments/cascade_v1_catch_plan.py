"""Choose Cascade-v1's catch-plan leads on TRAINING seeds only.

For each catch-plan controller (``juggler_oracle_catch``, ``juggler_mean_delay_catch``;
:data:`motion_envs.models.juggling.CASCADE_CATCH_PLANS`), each juggler (the fitted
cascade juggler on pattern ``"3"``, the siteswap juggler on ``"5"``) and each lead of
``CASCADE_LEAD_GRID`` (no descent: the view tells the ball ``lead`` s ahead, the
hand waits), the controller alone (the zero action) plays ``--episodes`` TRAINING
episodes (seeds ``SPLIT_SEEDS["train"] + i``; never a validation or test seed) of
``MotionEnvs/Cascade-v1`` on each level, ``--max-catches`` catches at most. The lead with
the most mean catches before the first drop pooled over the levels is the choice (ties:
the smaller lead); ``CASCADE_CATCH_PLANS`` quotes it. Prints a table per controller and
pattern and, as its last line, one JSON object (``--out FILE`` also writes it). The
demonstrations are SIMULATED.

    python experiments/cascade_v1_catch_plan.py [--episodes 12] [--max-catches 10]
        [--patterns 3,5] [--out FILE]
"""

from __future__ import annotations

import argparse
import json
import time
from dataclasses import replace

from tqdm import tqdm

from motion_envs._io import atomic_write_text
from motion_envs.datasets.juggling import SIMULATED_LABEL, episode_seeds
from motion_envs.envs.juggling import CascadeV1Env
from motion_envs.models.juggling import CASCADE_CATCH_PLANS, CASCADE_V1_LEVELS
from motion_envs.models.juggling._cascade_v1 import CASCADE_LEAD_GRID as LEAD_GRID


def score(
    controller: str, pattern: str, lead: float, episodes: int, max_catches: int
) -> dict[str, float]:
    """Per level the mean catches before the first drop of ``episodes`` TRAINING episodes
    with the catch plan's lead set to ``lead``."""
    out = {}
    for level in CASCADE_V1_LEVELS:
        env = CascadeV1Env(level=level, pattern=pattern, controller=controller,
                           max_catches=max_catches)  # fmt: skip
        assert env.catch_plan is not None
        env.catch_plan = replace(env.catch_plan, lead=lead)  # the candidate
        env.view.lead = lead
        catches = [env.play(int(seed))[0] for seed in episode_seeds("train", episodes).tolist()]
        out[level] = sum(catches) / len(catches)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=12)
    parser.add_argument("--max-catches", type=int, default=10)
    parser.add_argument("--patterns", default="3,5")
    parser.add_argument("--out", default=None)
    args = parser.parse_args()
    if args.episodes < 1 or args.max_catches < 1:
        parser.error("--episodes and --max-catches must be >= 1")
    t0 = time.process_time()
    patterns = args.patterns.split(",")
    doc: dict[str, object] = {"demonstrations": SIMULATED_LABEL, "split": "train",
                              "patterns": patterns, "leads_s": list(LEAD_GRID),
                              "episodes_per_level": args.episodes,
                              "max_catches": args.max_catches, "results": {}}  # fmt: skip
    for controller in CASCADE_CATCH_PLANS:
        for pattern in patterns:
            rows = []
            best, best_mean = LEAD_GRID[0], -1.0
            for lead in tqdm(LEAD_GRID, desc=f"{controller} {pattern}"):
                levels = score(controller, pattern, lead, args.episodes, args.max_catches)
                pooled = sum(levels.values()) / len(levels)
                rows.append({"lead_s": lead, "pooled": pooled, "levels": levels})
                if pooled > best_mean:
                    best, best_mean = lead, pooled
            print(f"\n{controller}, pattern {pattern} (TRAINING seeds, {args.episodes} per level;"
                  " mean catches before the first drop)")  # fmt: skip
            print(
                f"{'lead s':>7s} {'pooled':>7s} " + " ".join(f"{k:>7s}" for k in CASCADE_V1_LEVELS)
            )
            for r in rows:
                lv = " ".join(f"{r['levels'][k]:7.2f}" for k in CASCADE_V1_LEVELS)
                print(f"{r['lead_s']:7.2f} {r['pooled']:7.2f} {lv}")
            print(f"choice: lead {best} s (pooled {best_mean:.2f})")
            key = f"{controller} {pattern}"
            doc["results"][key] = {"grid": rows, "choice": {"lead_s": best, "pooled": best_mean}}  # type: ignore[index]
    doc["cpu_s"] = time.process_time() - t0
    if args.out:
        atomic_write_text(args.out, json.dumps(doc, indent=2) + "\n")
    print(json.dumps(doc))


if __name__ == "__main__":
    main()
