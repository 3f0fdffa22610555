"""Cascade-v1's bench with its TEST episodes kept, and one row replayed against them.

``motion-bench juggling --version v2 --pattern P`` plays every row; when a commit
changes ONE row (here the five-ball ``oracle_catch``: the siteswap juggler's own catch
plan) the others' episodes are unchanged (their rollouts are bit-identical), so the row
can be replayed alone and paired with them on the same test seeds.

* ``--bench DIR``: :func:`baselines.juggling_bench.cascade_v1.run_cascade_v1` for
  ``--pattern`` and ``--levels`` (every choice on validation seeds as the bench makes
  it), writing ``results.json`` and ``episodes.json`` (per level and row the test seeds,
  catches, tosses, drops and times) in ``DIR``;
* ``--replay DIR``: plays ``--row`` (default ``oracle_catch``, a zero-action row without
  a tracker) with the code as it is now on the test seeds of ``DIR``'s episodes and
  prints, per level, its summary and its paired differences (mean catches, 95 %
  bootstrap over the seeds) from every other row of ``DIR``, the best non-oracle row
  (chosen on validation in ``DIR``) and the row with the highest test mean among the
  non-oracle ones; ``--out FILE`` writes them.

The demonstrations are SIMULATED.

    python experiments/cascade_v1_replay_row.py --bench DIR --pattern 5 --levels easy
    python experiments/cascade_v1_replay_row.py --replay DIR [--row oracle_catch] [--out F]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

import numpy as np

from baselines.juggling_bench.cascade import CascadeEpisodes
from baselines.juggling_bench.cascade_v1 import (
    REFERENCES,
    CascadeV1Config,
    _kwargs,
    _paired,
    _players,
    cascade_v1_episodes,
    row_summary,
    run_cascade_v1,
)
from motion_envs._io import atomic_write_text


def _episodes_doc(eps: CascadeEpisodes) -> dict[str, list[Any]]:
    return {
        "seeds": eps.seeds.tolist(),
        "catches": eps.catches.tolist(),
        "tosses": eps.tosses.tolist(),
        "dropped": eps.dropped.tolist(),
        "time": eps.time.tolist(),
    }


def _episodes(doc: dict[str, list[Any]]) -> CascadeEpisodes:
    rows = list(zip(doc["catches"], doc["tosses"], doc["dropped"], doc["time"], strict=True))
    return CascadeEpisodes.from_rows(np.asarray(doc["seeds"]), rows)


def bench(out: Path, pattern: str, levels: tuple[str, ...]) -> None:
    """The bench with its test episodes kept (module docstring)."""
    keep: dict[str, dict[str, Any]] = {}
    doc = run_cascade_v1(CascadeV1Config(pattern=pattern, levels=levels), keep=keep)
    out.mkdir(parents=True, exist_ok=True)
    atomic_write_text(out / "results.json", json.dumps(doc, indent=2) + "\n")
    eps = {lv: {row: _episodes_doc(e) for row, e in rows.items()} for lv, rows in keep.items()}
    atomic_write_text(out / "episodes.json", json.dumps(eps) + "\n")


def replay(folder: Path, row: str) -> dict[str, Any]:
    """``row`` replayed on ``folder``'s test seeds and paired with its other rows."""
    doc = json.loads((folder / "results.json").read_text(encoding="utf-8"))
    kept = json.loads((folder / "episodes.json").read_text(encoding="utf-8"))
    config = CascadeV1Config(**{**doc["config"], "levels": tuple(doc["config"]["levels"])})
    out: dict[str, Any] = {}
    for lv in doc["levels"]:
        level = lv["level"]
        players = _players(level, config, lv["late_offset_s"], tuple(lv["constant"]))
        ctl, policy, off, gain = players[row]
        others = {name: _episodes(e) for name, e in kept[level].items() if name != row}
        seeds = next(iter(others.values())).seeds
        kwargs = _kwargs(level, config, ctl, off, gain)
        new = cascade_v1_episodes(policy, kwargs, "test", seeds.size)
        if not np.array_equal(new.seeds, seeds):
            raise ValueError(f"{folder}: the kept test seeds differ from the replayed ones")
        rivals = [name for name in others if name not in REFERENCES]
        top = max(rivals, key=lambda name: float(others[name].catches.mean()))
        out[level] = {
            "row": row_summary(new),
            "minus": {name: _paired(new, e) for name, e in others.items()},
            "best_non_oracle": lv["best_non_oracle"],
            "top_test_mean_non_oracle": top,
            "means": {name: float(e.catches.mean()) for name, e in others.items()},
        }
        m = out[level]["row"]
        print(f"{level}: {row} mean {m['catches_mean']:.2f} {m['catches_mean_ci']}, median "
              f"{m['catches_median']} {m['catches_median_ci']}, catch rate {m['catch_rate']:.3f}, "
              f"censored {m['censored']}")  # fmt: skip
        for name in sorted(others, key=lambda n: -out[level]["means"][n]):
            d = out[level]["minus"][name]
            print(f"  {row} - {name:24s} {d['value']:+6.2f} [{d['ci'][0]:+.2f}, {d['ci'][1]:+.2f}]"
                  f"  ({name} mean {out[level]['means'][name]:.2f})")  # fmt: skip
        print(f"  best non-oracle (validation): {lv['best_non_oracle']}; highest test mean: {top}")
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bench", type=Path, default=None)
    ap.add_argument("--replay", type=Path, default=None)
    ap.add_argument("--pattern", default="5")
    ap.add_argument("--levels", default="easy,medium,hard")
    ap.add_argument("--row", default="oracle_catch")
    ap.add_argument("--out", default=None)
    args = ap.parse_args()
    if (args.bench is None) == (args.replay is None):
        ap.error("give one of --bench DIR and --replay DIR")
    if args.bench is not None:
        bench(args.bench, args.pattern, tuple(args.levels.split(",")))
        return
    got = replay(args.replay, args.row)
    if args.out:
        atomic_write_text(args.out, json.dumps(got, indent=2) + "\n")


if __name__ == "__main__":
    main()
