"""Choose the cascade juggler's hand-set constants on TRAINING seeds only.

The analytic cascade juggler (:class:`motion_envs.models.juggling.CascadeController`) has
four hand-set tunables, the fields of
:class:`~motion_envs.models.juggling.CascadeTunables`: ``catch_window`` (beats a catch may
last beyond the longest training catch), ``release_armed`` (share of the nominal toss's
release time after which a release is armed), ``reaim_after`` (beats after its catch
plan's end at which an empty hand re-aims) and ``toss_clearance`` (m a hand's own falling
ball must keep from its toss's column, else the toss moves aside). This script plays the
juggler's zero-action Cascade-v0 episodes of ``--pattern`` (default ``3``)
(:func:`baselines.juggling_bench.cascade.cascade_episode`, controller ``"juggler"``) on the
TRAINING seeds ``SPLIT_SEEDS["train"] + i`` (never the test seeds), levels ``easy`` and
``medium``, ``--episodes`` episodes per level, at most ``--max-catches`` catches (default
100: the easy target, issue 20, is 100 catches before the first drop; with a cap of 10
almost every easy episode reached the cap, so the objective could not see the long-run
drops), for a one-at-a-time grid around each constant (the other two at their current
values).

A value is passed as the controller's tunables (``dataclasses.replace`` of the pattern's
current :class:`~motion_envs.models.juggling.CascadeTunables`; the env's ``tunables=``).

Objective (fixed before the results were read): the mean over episodes of the catches
before the first drop (each episode censored at ``--max-catches``), summed over the levels
(easy + medium; on medium the juggler without latency compensation drops within a few
catches, so easy dominates the sum). Noise: the episodes share their seeds across values, so each
value's difference from the current value is paired by seed; its standard error is the
standard deviation of the per-seed differences (summed over the levels) over
``sqrt(episodes)``. A value replaces the current one only if it beats it by more than
two standard errors; otherwise the current value is kept (a tie within noise). If more
than one constant changes, the combination is played too and reported.

    python experiments/cascade_constants.py [--episodes 80] [--max-catches 100]
        [--levels easy medium] [--pattern 3]

Prints a table and, as its last line, one JSON object with every value's figures, the
choices and the CPU seconds. The demonstrations the juggler is fitted on are SIMULATED.
"""

from __future__ import annotations

import argparse
import json
import math
import time
from dataclasses import asdict
from typing import Any

import numpy as np

from baselines.juggling_bench.cascade import cascade_episode
from motion_envs.datasets.juggling import SIMULATED_LABEL, SPLIT_SEEDS
from motion_envs.models.juggling import CascadeTunables, pattern_spec

#: The grid: each tunable's candidate values (the current value is played too).
GRID: dict[str, tuple[float, ...]] = {
    "catch_window": (0.3, 0.5, 0.7, 1.0),
    "release_armed": (0.6, 0.75, 0.9),
    "reaim_after": (0.1, 0.2, 0.3, 0.5),
    "toss_clearance": (0.08, 0.1, 0.12),
}
#: A value must beat the current one by this many paired standard errors to replace it.
MARGIN_SE = 2.0


def play(
    values: dict[str, float], levels: list[str], episodes: int, max_catches: int, pattern: str
) -> dict[str, np.ndarray]:
    """Catches before the first drop per training seed and level, at ``values``."""
    seeds = SPLIT_SEEDS["train"] + np.arange(episodes, dtype=np.int64)
    tunables = CascadeTunables(**values)
    out: dict[str, np.ndarray] = {}
    for level in levels:
        out[level] = np.array(
            [
                cascade_episode(level, "juggler", int(s), max_catches, 9.81, pattern, tunables)[0]
                for s in seeds
            ],
            dtype=np.float64,
        )
    return out


def objective(catches: dict[str, np.ndarray]) -> float:
    """Mean catches before the first drop, summed over the levels."""
    return float(sum(c.mean() for c in catches.values()))


def paired(a: dict[str, np.ndarray], b: dict[str, np.ndarray]) -> tuple[float, float]:
    """``(difference, standard error)`` of objective(a) - objective(b), paired by seed."""
    d = sum(a[lv] - b[lv] for lv in a)
    assert isinstance(d, np.ndarray)
    return float(d.mean()), float(d.std(ddof=1) / math.sqrt(d.size))


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Run the grid; print the table and the JSON line."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--episodes", type=int, default=80, help="training episodes per level")
    ap.add_argument("--max-catches", type=int, default=100, help="episode ends after this")
    ap.add_argument("--levels", nargs="+", default=["easy", "medium"], help="levels played")
    ap.add_argument("--pattern", default="3", help="a registered pattern's name")
    args = ap.parse_args(argv)
    try:
        spec = pattern_spec(args.pattern)
    except ValueError as exc:
        ap.error(f"--pattern: {exc}")
    if args.episodes < 2:
        ap.error(f"--episodes must be >= 2; got {args.episodes}")
    if args.max_catches < 1:
        ap.error(f"--max-catches must be >= 1; got {args.max_catches}")

    t0 = time.process_time()
    current = {name: float(v) for name, v in asdict(spec.tunables).items()}
    runs: dict[tuple[str, float], dict[str, np.ndarray]] = {}
    pat = args.pattern
    base = play(current, args.levels, args.episodes, args.max_catches, pat)
    rows: list[dict[str, Any]] = []
    chosen = dict(current)
    for name, grid in GRID.items():
        best, best_diff = current[name], 0.0
        for v in grid:
            c = (
                base
                if v == current[name]
                else play({**current, name: v}, args.levels, args.episodes, args.max_catches, pat)
            )
            runs[(name, v)] = c
            diff, se = paired(c, base)
            rows.append({
                "constant": name,
                "value": v,
                "current": v == current[name],
                "objective": objective(c),
                "per_level_mean": {lv: float(x.mean()) for lv, x in c.items()},
                "per_level_reached_max": {
                    lv: int((x >= args.max_catches).sum()) for lv, x in c.items()
                },
                "diff_vs_current": diff,
                "diff_se": se,
            })  # fmt: skip
            if diff > MARGIN_SE * se and diff > best_diff:
                best, best_diff = v, diff
        chosen[name] = best
    combined = None
    if sum(chosen[n] != current[n] for n in GRID) > 1:
        c = play(chosen, args.levels, args.episodes, args.max_catches, pat)
        diff, se = paired(c, base)
        combined = {"values": chosen, "objective": objective(c), "diff_vs_current": diff,
                    "diff_se": se}  # fmt: skip
    cpu = time.process_time() - t0

    print(
        f"Cascade juggler tunables, pattern {pat}, on TRAINING seeds {SPLIT_SEEDS['train']}.."
        f"{SPLIT_SEEDS['train'] + args.episodes - 1}, levels {' + '.join(args.levels)}, "
        f"at most {args.max_catches} catches ({SIMULATED_LABEL} demonstrations)"
    )
    print("objective: mean catches before the first drop, summed over the levels")
    print(f"{'constant':14s} {'value':>6s} {'objective':>9s} {'per level':44s} {'diff [SE]':>16s}")
    for r in rows:
        per = ", ".join(
            f"{lv} {m:.2f} ({r['per_level_reached_max'][lv]} at max)"
            for lv, m in r["per_level_mean"].items()
        )
        mark = " (current)" if r["current"] else ""
        print(
            f"{r['constant']:14s} {r['value']:6.2f} {r['objective']:9.2f} {per:44s} "
            f"{r['diff_vs_current']:+7.2f} [{r['diff_se']:.2f}]{mark}"
        )
    for name in GRID:
        kept = "kept" if chosen[name] == current[name] else "changed"
        print(f"chosen {name} = {chosen[name]} ({kept}; current {current[name]})")
    if combined is not None:
        print(
            f"combination {combined['values']}: objective {combined['objective']:.2f}, "
            f"{combined['diff_vs_current']:+.2f} [{combined['diff_se']:.2f}] vs current"
        )
    print(f"CPU {cpu:.1f} s")
    doc = {
        "benchmark": f"cascade juggler tunables, pattern {pat} (training seeds)",
        "demonstrations": SIMULATED_LABEL,
        "seeds": {"split": "train", "first": SPLIT_SEEDS["train"], "count": args.episodes},
        "levels": args.levels,
        "max_catches": args.max_catches,
        "objective": "sum over levels of the mean catches before the first drop",
        "margin_se": MARGIN_SE,
        "current": current,
        "rows": rows,
        "chosen": chosen,
        "combined": combined,
        "cpu_s": cpu,
    }
    print(json.dumps(doc))
    return doc


if __name__ == "__main__":
    main()
