"""The cascade juggler before and after a change, paired by seed, on TRAINING or
VALIDATION seeds only.

``play`` runs the zero-action Cascade-v0 episodes of
:func:`baselines.juggling_bench.cascade.cascade_episode` (at most ``--max-catches``
catches) on seeds ``SPLIT_SEEDS[split] + i`` for the easy juggler, the medium juggler and
the medium latency-aware juggler, and writes the catches before the first drop per seed
to a JSON file; run it once on each commit (the test seeds are refused: they are
measured once, by ``motion-bench juggling --pattern 3``). ``compare`` prints, per split and
run, the median, the episodes reaching the cap, the mean and the paired difference of
the means (after minus before) with its standard error (the standard deviation of the
per-seed differences over ``sqrt(n)``), its 95 % paired bootstrap interval, the verdict
in words and the power line (:func:`baselines.stats.paired_mean_difference`). The
demonstrations are SIMULATED.

    python experiments/cascade_paired.py play --split train --out before_train.json
    python experiments/cascade_paired.py compare before_train.json after_train.json
"""

from __future__ import annotations

import argparse
import json
import math
import time
from typing import Any

import numpy as np

from baselines.juggling_bench.cascade import cascade_episode
from baselines.stats import paired_mean_difference
from motion_envs.datasets.juggling import SIMULATED_LABEL, SPLIT_SEEDS

#: ``(level, controller)`` pairs played.
RUNS: tuple[tuple[str, str], ...] = (
    ("easy", "juggler"),
    ("medium", "juggler"),
    ("medium", "juggler_latency_aware"),
)


def play(split: str, episodes: int, max_catches: int) -> dict[str, Any]:
    """Catches before the first drop per seed, for each of :data:`RUNS`."""
    if split not in ("train", "val"):
        raise ValueError(f"split must be 'train' or 'val'; got {split!r}")
    t0 = time.process_time()
    seeds = [SPLIT_SEEDS[split] + i for i in range(episodes)]
    catches = {
        f"{level}/{method}": [cascade_episode(level, method, s, max_catches)[0] for s in seeds]
        for level, method in RUNS
    }
    return {
        "demonstrations": SIMULATED_LABEL,
        "split": split,
        "first_seed": seeds[0],
        "max_catches": max_catches,
        "catches": catches,
        "cpu_s": time.process_time() - t0,
    }


def compare(before: dict[str, Any], after: dict[str, Any]) -> list[dict[str, Any]]:
    """Per run: both sides' summaries and the paired difference of the means."""
    if (before["split"], before["first_seed"]) != (after["split"], after["first_seed"]):
        raise ValueError("the two files were played on different seeds")
    rows = []
    cap = after["max_catches"]
    for run, b in before["catches"].items():
        x, y = np.asarray(b, dtype=float), np.asarray(after["catches"][run], dtype=float)
        d = y - x
        rows.append({
            "run": run,
            "n": int(d.size),
            "before": {"median": float(np.median(x)), "at_cap": int((x >= cap).sum()),
                       "mean": float(x.mean())},
            "after": {"median": float(np.median(y)), "at_cap": int((y >= cap).sum()),
                      "mean": float(y.mean())},
            "diff": float(d.mean()),
            "se": float(d.std(ddof=1) / math.sqrt(d.size)),
            "paired": paired_mean_difference(y, x, "after", "before").to_dict(),
        })  # fmt: skip
    return rows


def main(argv: list[str] | None = None) -> None:
    """``play`` or ``compare``."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    p = sub.add_parser("play", help="play the runs on one split, write JSON")
    p.add_argument("--split", choices=["train", "val"], default="train")
    p.add_argument("--episodes", type=int, default=80)
    p.add_argument("--max-catches", type=int, default=100)
    p.add_argument("--out", required=True)
    c = sub.add_parser("compare", help="paired differences of two play files")
    c.add_argument("before")
    c.add_argument("after")
    args = ap.parse_args(argv)
    if args.cmd == "play":
        if args.episodes < 2:
            ap.error(f"--episodes must be >= 2; got {args.episodes}")
        doc = play(args.split, args.episodes, args.max_catches)
        with open(args.out, "w") as f:
            json.dump(doc, f)
        print(json.dumps({k: v for k, v in doc.items() if k != "catches"}))
        return
    with open(args.before) as f:
        before = json.load(f)
    with open(args.after) as f:
        after = json.load(f)
    rows = compare(before, after)
    for r in rows:
        b, a = r["before"], r["after"]
        lo, hi = r["paired"]["ci95"]
        print(
            f"{before['split']:5s} {r['run']:28s} before: median {b['median']:5.1f}, "
            f"{b['at_cap']:2d} of {r['n']} at cap, mean {b['mean']:6.2f} | after: median "
            f"{a['median']:5.1f}, {a['at_cap']:2d} at cap, mean {a['mean']:6.2f} | "
            f"{r['diff']:+.2f} [SE {r['se']:.2f}; 95% CI {lo:+.2f} to {hi:+.2f}]: "
            f"{r['paired']['sentence']}; {r['paired']['power_line']}"
        )
    print(json.dumps(rows))


if __name__ == "__main__":
    main()
