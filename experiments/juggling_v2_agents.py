"""The shipped agent block on Juggling-v2 (medium, hard) against the reference rows (issue 34).

For each level and seed: ``motion-bench train`` (``baselines.agents.train.run``) with
``configs/agents/ppo.yaml``'s Juggling-v2 block (the residual on top of the hand-written
delay estimator, a frame stack of 8 observations; ``level`` overridden), the checkpoint
chosen on the VALIDATION seeds (drop rate per toss, 40 episodes), then the kept policy
played on the TEST seeds (``SPLIT_SEEDS["test"] + i``). The reference rows are
``motion-bench juggling --version v2``'s (:func:`baselines.juggling_bench.v2.run_v2`:
every choice on validation seeds, the same test seeds); the best non-oracle row and the
UPPER REFERENCE (``oracle_catch``: the true delay and drag with the catch planned for the
capture rule) are replayed on the same test seeds for paired differences.

Per run: the agent's catch rate with its 95 % bootstrap interval, its hand deviation
from the HELD-OUT SIMULATED demonstrations (the rows' likeness criterion), ``agent -
best non-oracle row`` and ``oracle - agent`` (paired bootstrap intervals over episodes).
Per level: the median over seeds (the run whose difference is the median) and the
validation pick (the seed with the lowest validation drop rate), and the issue's targets
in words: ``agent - best row >= +0.05`` with the interval above 0, deviation <= the
juggler's + 5 mm, the oracle above the agent (the room left reported).

    python experiments/juggling_v2_agents.py [--levels medium hard] [--seeds 0 1 2]
        [--algo ppo] [--timesteps N] [--controller NAME] [--test-episodes 100] [--runs DIR]
        [--reuse-only] [--out results.json]

``--timesteps`` defaults to the config's (2.5e6, the full budget: about 21 min of CPU per
seed at the measured 2,000 steps per CPU-second; the issue allows 30). Existing complete
run folders in ``--runs`` are reused (not retrained; with ``--reuse-only`` a missing one is
an error; a reused folder of another environment, algorithm, level or seed is refused).
The parts shared with ``experiments/cascade_v1_agents.py`` are in
:mod:`baselines.agents.against_rows`. Writes ``results.json`` and
``juggling_v2_agents.png`` (the rows' catch rate against deviation with the agent).
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))  # _timing, shared
from _timing import machine, print_json

from baselines.agents.against_rows import (
    DEVIATION_SLACK_MM,
    MARGIN,
    add_arguments,
    check_run,
    check_same_seeds,
    format_difference,
    likeness_met,
    margin_met,
    median_run,
    run_fields,
    save_plot,
    train_all,
    validation_pick,
    write_results,
)

ENV = "MotionEnvs/Juggling-v2"


def level_rows(
    level: str, episodes: int, every_row: bool = False
) -> tuple[dict[str, Any], dict[str, Any]]:
    """The rows' document of ``level`` (:func:`run_v2`) and the test episodes of its best
    non-oracle row, its juggler and its upper reference, replayed on the same seeds
    (``every_row``: every row :func:`row_players` can replay)."""
    from baselines.agents.juggling_score import juggling_episodes
    from baselines.juggling_bench.v2 import (
        ENV_ID_V2,
        RESIDUAL_SCALE,
        UPPER_REFERENCE,
        V2Config,
        row_players,
        run_v2,
    )

    config = V2Config(levels=(level,), episodes=episodes)
    doc = run_v2(config)
    lv = doc["levels"][0]
    best = lv["best_non_oracle"]
    trk = lv.get("tracker", {"gain": 0.0, "offset_s": 0.0})
    players = row_players(
        level, tuple(lv["constant"]), lv.get("late_offset_s", 0.0), (trk["gain"], trk["offset_s"]),
        lv.get("estimator_offset_s", 0.0),
    )  # fmt: skip
    if best not in players:
        raise RuntimeError(f"the best non-oracle row {best!r} cannot be replayed")
    played = {}
    names = ("juggler", UPPER_REFERENCE, best, *(players if every_row else ()))
    for name in dict.fromkeys(names):
        controller, policy, extra = players[name]
        kwargs = {
            "level": level,
            "controller": controller,
            "max_catches": config.max_catches,
            "residual_scale": RESIDUAL_SCALE,
            **extra,
        }
        played[name] = juggling_episodes(policy, ENV_ID_V2, kwargs, "test", episodes)
    for name, eps in played.items():  # the replay is the rows' own episodes
        if not math.isclose(eps.catch_rate, lv["rows"][name]["catch_rate"]):
            raise RuntimeError(f"{level} {name}: the replay differs from run_v2's row")
    return lv, played


def score_run(
    run_dir: Path, played: dict[str, Any], best: str, args: argparse.Namespace, job: tuple[str, int]
) -> dict[str, Any]:
    """The kept policy of ``run_dir`` on the test seeds against the replayed rows."""
    from baselines.agents.juggling_score import (
        catch_rate_difference,
        catch_rate_interval,
        deviation_interval,
        juggling_episodes,
    )
    from baselines.agents.rundir import load_run

    loaded = load_run(run_dir)
    check_run(loaded, ENV, args.algo, *job)
    eps = juggling_episodes(loaded.policy(), ENV, loaded.env_kwargs, "test", args.test_episodes)
    check_same_seeds(eps.seeds, played[best].seeds)
    rate, lo, hi = catch_rate_interval(eps)
    dev, dlo, dhi = deviation_interval(eps)
    diff, diff_lo, diff_hi = catch_rate_difference(eps, played[best])
    from baselines.juggling_bench.v2 import UPPER_REFERENCE

    room, room_lo, room_hi = catch_rate_difference(played[UPPER_REFERENCE], eps)
    return {
        **run_fields(loaded, "drop_rate"),
        "catch_rate": rate,
        "catch_rate_ci": [lo, hi],
        "deviation_mm": 1000 * dev,
        "deviation_ci_mm": [1000 * dlo, 1000 * dhi],
        "minus_best_row": diff,
        "minus_best_row_ci": [diff_lo, diff_hi],
        "oracle_minus_agent": room,
        "oracle_minus_agent_ci": [room_lo, room_hi],
    }


def verdict(run: dict[str, Any], juggler_mm: float) -> dict[str, bool]:
    """The issue's three targets for one run."""
    return {
        "margin": margin_met(run["minus_best_row"], run["minus_best_row_ci"]),
        "likeness": bool(likeness_met(run["deviation_mm"], juggler_mm)),
        "oracle_above": run["oracle_minus_agent"] > 0,
    }


def words(lv: dict[str, Any]) -> str:
    """The level's verdict on the issue's targets, for the median seed, in words."""
    run = next(r for r in lv["runs"] if r["seed"] == lv["median_seed"])
    t = run["targets"]
    margin = "met" if t["margin"] else "NOT met"
    like = "met" if t["likeness"] else "NOT met"
    above = "the oracle is above the agent" if t["oracle_above"] else "the agent reaches the oracle"
    return (
        f"agent - {lv['best_non_oracle']} "
        f"{format_difference(run['minus_best_row'], run['minus_best_row_ci'])} "
        f"(target >= +{MARGIN:.2f}, interval above 0: {margin}); deviation "
        f"{run['deviation_mm']:.1f} mm against the juggler's {lv['juggler_deviation_mm']:.1f} "
        f"+ {DEVIATION_SLACK_MM:.0f} mm ({like}); {above} (room "
        f"{run['oracle_minus_agent']:+.3f})"
    )


def write_plot(levels: list[dict[str, Any]], path: Path, algo: str = "ppo") -> Path:
    """The rows' catch rate against deviation (``plot_v2``) with the median seed's agent
    as a star, a panel per level."""
    from baselines.juggling_bench.v2 import plot_v2

    panels = []
    for lv in levels:
        run = next(r for r in lv["runs"] if r["seed"] == lv["median_seed"])
        agent = {
            "catch_rate": run["catch_rate"],
            "catch_rate_ci": run["catch_rate_ci"],
            "deviation_m": run["deviation_mm"] / 1000,
            "deviation_ci": [v / 1000 for v in run["deviation_ci_mm"]],
        }
        name = f"{algo.upper()} agent, frame stack (median of {len(lv['runs'])} seeds)"
        panels.append({"level": lv["level"], "rows": {**lv["rows"], name: agent}})
    return save_plot(plot_v2({"levels": panels}), path)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    add_arguments(
        p,
        levels=["medium", "hard"],
        runs="juggling_v2_agent_runs",
        timesteps_help="default: the config's (2.5e6)",
        controller_help="the controller the residual acts on (default: the config's, "
        "juggler_delay_estimator); e.g. juggler_mean_delay_catch",
    )
    args = p.parse_args(argv)
    root = Path(args.runs)
    t0 = time.process_time()
    levels = []
    runs_dirs = train_all(ENV, args)
    for level in tqdm(args.levels, desc="score"):
        lv, played = level_rows(level, args.test_episodes)
        best = lv["best_non_oracle"]
        juggler_mm = 1000 * lv["rows"]["juggler"]["deviation_m"]
        runs = [score_run(runs_dirs[level, s], played, best, args, (level, s)) for s in args.seeds]
        for run in runs:
            run["targets"] = verdict(run, juggler_mm)
        median = median_run(runs, "minus_best_row")
        pick = validation_pick(runs, "val_drop_rate")
        levels.append(
            {
                "level": level,
                "rows": lv["rows"],
                "best_non_oracle": best,
                "juggler_deviation_mm": juggler_mm,
                "runs": runs,
                "median_seed": median["seed"],
                "median": {k: median[k] for k in ("catch_rate", "minus_best_row", "targets")},
                "median_catch_rate_over_seeds": float(np.median([r["catch_rate"] for r in runs])),
                "median_deviation_mm_over_seeds": float(
                    np.median([r["deviation_mm"] for r in runs])
                ),
                "validation_pick_seed": pick["seed"],
            }
        )
    doc = {
        "benchmark": f"agents on {ENV} (SIMULATED demonstrations)",
        "test_episodes": args.test_episodes,
        "seeds": args.seeds,
        "timesteps": args.timesteps,
        "levels": levels,
        "machine": machine(),
        "cpu_s_scoring_and_training_in_process": time.process_time() - t0,
    }
    for lv in levels:
        best, rows = lv["best_non_oracle"], lv["rows"]
        print(
            f"{lv['level']}: best non-oracle row {best} {rows[best]['catch_rate']:.3f}, "
            f"juggler deviation {lv['juggler_deviation_mm']:.1f} mm, "
            f"upper reference oracle_catch {rows['oracle_catch']['catch_rate']:.3f}"
        )
        for r in lv["runs"]:
            print(
                f"  seed {r['seed']}: {r['timesteps']} steps (best at {r['best_timesteps']}), "
                f"catch {r['catch_rate']:.3f} [{r['catch_rate_ci'][0]:.3f}, "
                f"{r['catch_rate_ci'][1]:.3f}], deviation {r['deviation_mm']:.1f} mm, "
                f"- best row {r['minus_best_row']:+.3f} [{r['minus_best_row_ci'][0]:+.3f}, "
                f"{r['minus_best_row_ci'][1]:+.3f}], oracle - agent "
                f"{r['oracle_minus_agent']:+.3f} [{r['oracle_minus_agent_ci'][0]:+.3f}, "
                f"{r['oracle_minus_agent_ci'][1]:+.3f}], targets {r['targets']}"
            )
        print(
            f"  median seed {lv['median_seed']}, validation pick seed "
            f"{lv['validation_pick_seed']}: {words(lv)}"
        )
    out = Path(args.out) if args.out else root / "results.json"
    print(f"wrote {write_results(doc, out)}")
    print(f"wrote {write_plot(levels, out.with_name('juggling_v2_agents.png'), args.algo)}")
    print_json(doc)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
