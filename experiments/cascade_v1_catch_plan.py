"""Choose Cascade-v1's catch plans on TRAINING seeds only.

For each catch-plan controller (``juggler_oracle_catch``, ``juggler_mean_delay_catch``;
:data:`motion_envs.models.juggling.CASCADE_CATCH_PLANS`) and each juggler, the
controller alone (the zero action) plays ``--episodes`` TRAINING episodes (seeds
``SPLIT_SEEDS["train"] + i``; never a validation or test seed) of ``MotionEnvs/Cascade-v1``
on each level, ``--max-catches`` catches at most, for every candidate plan:

* the fitted cascade juggler (pattern ``"3"``): each lead of ``CASCADE_LEAD_GRID``, no
  descent (the view tells the ball ``lead`` s ahead, the hand waits);
* the siteswap juggler (pattern ``"5"``): its own catch
  (:class:`~motion_envs.models.juggling.SiteswapCatchController`), each pair of
  ``CASCADE_LEAD_GRID`` x ``SITESWAP_DESCENT_GRID`` (the reach ends ``lead`` before the
  meeting, the palm then descends at ``descent``).

The plan with the most mean catches before the first drop pooled over the levels is the
choice (ties: the first in grid order, the smaller lead, then the smaller descent);
``CASCADE_CATCH_PLANS`` quotes it, for each controller and juggler (on pattern ``"5"``
each controller's own run: ``--controllers`` one at a time, leads 80-160 ms).
Prints a table per controller and pattern and, as its last line, one JSON
object (``--out FILE`` also writes it). The demonstrations are SIMULATED.

    python experiments/cascade_v1_catch_plan.py [--episodes 12] [--max-catches 10]
        [--patterns 3,5] [--controllers juggler_oracle_catch,...] [--leads 0.1,0.12]
        [--out FILE]

``--leads`` plays a part of the lead grid (a run split over processes; ``--merge
A.json,B.json`` then prints the choice over the parts, :func:`choose_from`).
"""

from __future__ import annotations

import argparse
import itertools
import json
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

from tqdm import tqdm

from motion_envs._io import atomic_write_text
from motion_envs.datasets.juggling import SIMULATED_LABEL, episode_seeds
from motion_envs.envs.juggling import CascadeV1Env
from motion_envs.models.juggling import (
    CASCADE_CATCH_PLANS,
    CASCADE_V1_LEVELS,
    CatchPlan,
    SiteswapCatchController,
    SiteswapController,
    pattern_spec,
)
from motion_envs.models.juggling._cascade_v1 import CASCADE_LEAD_GRID as LEAD_GRID
from motion_envs.models.juggling._cascade_v1 import SITESWAP_DESCENT_GRID


def candidates(pattern: str, leads: tuple[float, ...] = LEAD_GRID) -> list[CatchPlan]:
    """The plans tried for ``pattern``'s juggler (module docstring), in grid order, with
    the leads ``leads`` (a part of the grid: a run split over processes)."""
    if pattern_spec(pattern).fitted:
        return [CatchPlan(lead, 0.0) for lead in leads]
    return [CatchPlan(a, d) for a, d in itertools.product(leads, SITESWAP_DESCENT_GRID)]


def score(
    controller: str, pattern: str, plan: CatchPlan, episodes: int, max_catches: int
) -> dict[str, float]:
    """Per level the mean catches before the first drop of ``episodes`` TRAINING episodes
    with the catch plan ``plan``."""
    out = {}
    for level in CASCADE_V1_LEVELS:
        env = CascadeV1Env(level=level, pattern=pattern, controller=controller,
                           max_catches=max_catches)  # fmt: skip
        if env.pattern.fitted:
            assert env.catch_plan is not None
            env.catch_plan = replace(env.catch_plan, lead=plan.lead)  # the candidate
            env.view.lead = plan.lead
        else:  # the siteswap juggler's own catch, the view untouched
            assert isinstance(env.controller, SiteswapController)
            env.controller = SiteswapCatchController(
                env.controller.plan, plan, env.controller.variant
            )
            env.catch_plan = plan
        catches = [env.play(int(seed))[0] for seed in episode_seeds("train", episodes).tolist()]
        out[level] = sum(catches) / len(catches)
    return out


def choose_from(parts: list[dict[str, Any]], key: str) -> dict[str, Any]:
    """The choice over the parts of a split run (their JSON documents; ``key`` e.g.
    ``"juggler_oracle_catch 5"``): the grid rows of every part in grid order (smaller
    lead, then smaller descent), the one with the most pooled mean catches the choice
    (ties: the first)."""
    rows = sorted(
        (r for doc in parts for r in doc["results"][key]["grid"]),
        key=lambda r: (r["lead_s"], r.get("descent_m_s", 0.0)),
    )
    best = rows[0]
    for r in rows[1:]:
        if r["pooled"] > best["pooled"]:
            best = r
    return {"grid": rows, "choice": best}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=12)
    parser.add_argument("--max-catches", type=int, default=10)
    parser.add_argument("--patterns", default="3,5")
    parser.add_argument("--controllers", default=",".join(CASCADE_CATCH_PLANS))
    parser.add_argument("--leads", default=None, help="a part of the lead grid (s, comma list)")
    parser.add_argument("--out", default=None)
    parser.add_argument("--merge", default=None, help="the parts' JSON files (comma list)")
    args = parser.parse_args()
    if args.merge is not None:  # a split run's choice
        parts = [json.loads(Path(f).read_text(encoding="utf-8")) for f in args.merge.split(",")]
        for key in parts[0]["results"]:
            got = choose_from(parts, key)
            for r in got["grid"]:
                print(key, r["lead_s"], r.get("descent_m_s", 0.0), round(r["pooled"], 2),
                      {k: round(v, 2) for k, v in r["levels"].items()})  # fmt: skip
            print(f"{key} choice: {json.dumps(got['choice'])}")
        return
    if args.episodes < 1 or args.max_catches < 1:
        parser.error("--episodes and --max-catches must be >= 1")
    t0 = time.process_time()
    patterns = args.patterns.split(",")
    leads = LEAD_GRID if args.leads is None else tuple(float(x) for x in args.leads.split(","))
    if not set(leads) <= set(LEAD_GRID):
        parser.error(f"--leads must be among {list(LEAD_GRID)}; got {list(leads)}")
    doc: dict[str, object] = {"demonstrations": SIMULATED_LABEL, "split": "train",
                              "patterns": patterns, "leads_s": list(leads),
                              "siteswap_descents_m_s": list(SITESWAP_DESCENT_GRID),
                              "episodes_per_level": args.episodes,
                              "max_catches": args.max_catches, "results": {}}  # fmt: skip
    for controller in args.controllers.split(","):
        if controller not in CASCADE_CATCH_PLANS:
            parser.error(f"--controllers: {controller!r} has no catch plan")
        for pattern in patterns:
            rows = []
            grid = candidates(pattern, leads)
            best, best_mean = grid[0], -1.0
            for plan in tqdm(grid, desc=f"{controller} {pattern}"):
                levels = score(controller, pattern, plan, args.episodes, args.max_catches)
                pooled = sum(levels.values()) / len(levels)
                rows.append({"lead_s": plan.lead, "descent_m_s": plan.descent,
                             "pooled": pooled, "levels": levels})  # fmt: skip
                if pooled > best_mean:
                    best, best_mean = plan, pooled
            print(f"\n{controller}, pattern {pattern} (TRAINING seeds, {args.episodes} per level;"
                  " mean catches before the first drop)")  # fmt: skip
            head = " ".join(f"{k:>7s}" for k in CASCADE_V1_LEVELS)
            print(f"{'lead s':>7s} {'descent':>7s} {'pooled':>7s} {head}")
            for r in rows:
                lv = " ".join(f"{r['levels'][k]:7.2f}" for k in CASCADE_V1_LEVELS)
                print(f"{r['lead_s']:7.2f} {r['descent_m_s']:7.2f} {r['pooled']:7.2f} {lv}")
            print(
                f"choice: lead {best.lead} s, descent {best.descent} m/s (pooled {best_mean:.2f})"
            )
            key = f"{controller} {pattern}"
            choice = {"lead_s": best.lead, "descent_m_s": best.descent, "pooled": best_mean}
            doc["results"][key] = {"grid": rows, "choice": choice}  # type: ignore[index]
    doc["cpu_s"] = time.process_time() - t0
    if args.out:
        atomic_write_text(args.out, json.dumps(doc, indent=2) + "\n")
    print(json.dumps(doc))


if __name__ == "__main__":
    main()
