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
  prints, per level, its summary and its paired differences (mean catches and catch
  rate, 95 % bootstrap over the seeds) from every other row of ``DIR``, the best
  non-oracle row (chosen on validation in ``DIR``) and the row with the highest test
  mean among the non-oracle ones; ``--out FILE`` writes them. A competitor row that
  ``DIR``'s bench did not choose among (a row added since) is also played on the
  validation seeds, and the best non-oracle row is chosen again with it
  (``best_non_oracle_with_row``). ``estimator_offset_catch`` in a ``DIR`` made before
  it existed first gets its offset chosen on the validation seeds as the bench chooses
  it (:func:`~baselines.juggling_bench.cascade_v1.choose_estimator_offset`; its table
  in ``estimator_offset_val_mean_catches``; the 0 ms candidate, ``delay_estimator_catch``
  itself, is checked against ``DIR``'s validation mean of that row,
  ``zero_offset_equals_kept_val``); ``pooled_estimator_catch`` likewise first gets its
  anchor frames and start anchor chosen on the validation seeds
  (:func:`~baselines.juggling_bench.cascade_v1.choose_pooled_anchor`; its table in
  ``pooled_val_mean_catches``). A row ``DIR`` holds is compared with its kept
  episodes (``equals_kept``: the replay plays what the bench played);
* ``--replay DIR --kept``: the same pairing of ``DIR``'s own episodes of ``--row``,
  nothing played (a bench run with the row in it; its summary, with the hand
  deviation, as the bench wrote it);
* ``--pick DIR --rows A,B,... --val-episodes N``: how sure the bench's choice of the
  best non-oracle row is. The named rows, each with the parameters ``DIR``'s bench chose
  on validation (``pooled_estimator_catch`` with ``--pooled-anchor`` frames, and with
  ``--pooled-start`` the start anchored on its throws), are played
  on ``N`` VALIDATION episodes (the bench's own are the first of them: ``DIR``'s
  ``pick_episodes``, or ``val_episodes`` for a bench made before it, checked against
  ``DIR``'s validation means: ``first_equal_bench``); per row the mean
  catches with a 95 % bootstrap interval, the pick on the bench's episodes and on all
  ``N``, and every row minus the pick on ``N`` (paired). No test seed is played.

The demonstrations are SIMULATED.

    python experiments/cascade_v1_replay_row.py --bench DIR --pattern 5 --levels easy
    python experiments/cascade_v1_replay_row.py --replay DIR [--row oracle_catch] [--out F]
    python experiments/cascade_v1_replay_row.py --replay DIR --kept --row delay_estimator_catch
    python experiments/cascade_v1_replay_row.py --pick DIR \
        --rows late_meeting,pooled_estimator_catch --val-episodes 200 \
        [--pooled-anchor 20] [--pooled-start]
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
    ROWS,
    CascadeV1Config,
    _kwargs,
    _paired,
    _players,
    cascade_v1_episodes,
    choose_estimator_offset,
    choose_pooled_anchor,
    pooled_key,
    row_summary,
    run_cascade_v1,
)
from baselines.juggling_bench.v2 import offset_key
from motion_envs._io import atomic_write_text
from motion_envs.models.juggling import ANCHOR_FRAMES


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


def _rate_difference(a: CascadeEpisodes, b: CascadeEpisodes, names: tuple[str, str]) -> Any:
    """The paired catch-rate difference ``a - b`` (catches per toss pooled over the
    episodes; 95 % bootstrap over the shared seeds)."""
    from baselines.agents.cascade_score import catch_rate_comparison

    d = catch_rate_comparison(a, b, names=names)
    return {"value": d.difference, "ci": list(d.ci95)}


def _pick_episodes(doc: dict[str, Any]) -> int:
    """The validation episodes ``doc``'s bench picked its best row on (``val_episodes``
    for a bench made before ``pick_episodes``)."""
    return int(doc["config"].get("pick_episodes", doc["config"]["val_episodes"]))


def replay(folder: Path, row: str, kept_row: bool = False) -> dict[str, Any]:
    """``row`` replayed on ``folder``'s test seeds (or, ``kept_row``, its kept episodes)
    and paired with its other rows (module docstring)."""
    doc = json.loads((folder / "results.json").read_text(encoding="utf-8"))
    kept = json.loads((folder / "episodes.json").read_text(encoding="utf-8"))
    config = CascadeV1Config(**{**doc["config"], "levels": tuple(doc["config"]["levels"])})
    out: dict[str, Any] = {}
    for lv in doc["levels"]:
        level = lv["level"]
        others = {name: _episodes(e) for name, e in kept[level].items() if name != row}
        seeds = next(iter(others.values())).seeds
        val_means = dict(lv["val_mean_catches"])
        equals_kept = None
        chosen: dict[str, Any] = {}
        est_offset = lv.get("estimator_offset_s", 0.0)
        if row == "estimator_offset_catch" and "estimator_offset_s" not in lv and not kept_row:
            est_offset, est_means = choose_estimator_offset(level, config)
            val_means[row] = est_means[offset_key(est_offset)]
            zero = val_means.get("delay_estimator_catch")
            chosen = {
                "estimator_offset_s": est_offset,
                "estimator_offset_val_mean_catches": est_means,
                "zero_offset_equals_kept_val": None
                if zero is None
                else est_means[offset_key(0.0)] == zero,
            }
        pooled_anchor = (
            lv.get("pooled_anchor_frames", ANCHOR_FRAMES),
            lv.get("pooled_anchor_start", False),
        )
        if row == "pooled_estimator_catch" and "pooled_anchor_frames" not in lv and not kept_row:
            pooled_anchor, pooled_means = choose_pooled_anchor(level, config)
            val_means[row] = pooled_means[pooled_key(pooled_anchor)]
            chosen = {
                "pooled_anchor_frames": pooled_anchor[0],
                "pooled_anchor_start": pooled_anchor[1],
                "pooled_val_mean_catches": pooled_means,
            }
        if kept_row:
            if row not in kept[level]:
                raise ValueError(f"{folder}: no kept episodes of row {row!r} on {level}")
            new = _episodes(kept[level][row])
        else:
            players = _players(
                level, config, lv["late_offset_s"], tuple(lv["constant"]),
                estimator_offset=est_offset, pooled_anchor=pooled_anchor,
            )  # fmt: skip
            ctl, policy, off, gain, extra = players[row]
            kwargs = _kwargs(level, config, ctl, off, gain, extra)
            new = cascade_v1_episodes(policy, kwargs, "test", seeds.size)
            if not np.array_equal(new.seeds, seeds):
                raise ValueError(f"{folder}: the kept test seeds differ from the replayed ones")
            if row in kept[level]:
                equals_kept = _episodes_doc(new) == kept[level][row]
            if row not in REFERENCES and row not in val_means:
                val_means[row] = float(
                    cascade_v1_episodes(policy, kwargs, "val", _pick_episodes(doc)).catches.mean()
                )
        rivals = [name for name in others if name not in REFERENCES]
        top = max(rivals, key=lambda name: float(others[name].catches.mean()))
        # the bench's rule (the first in ROWS order on a tie), the row among the candidates
        order = [r for r in ROWS if r in val_means] + [r for r in val_means if r not in ROWS]
        out[level] = {
            # a kept row's entry as the bench wrote it (with its hand deviation)
            "row": lv["rows"][row] if kept_row else row_summary(new),
            "minus": {name: _paired(new, e) for name, e in others.items()},
            "minus_catch_rate": {
                name: _rate_difference(new, e, (row, name)) for name, e in others.items()
            },
            "best_non_oracle": lv["best_non_oracle"],
            "best_non_oracle_with_row": max(order, key=lambda r: val_means[r]),
            "val_mean_catches": val_means,
            "top_test_mean_non_oracle": top,
            "means": {name: float(e.catches.mean()) for name, e in others.items()},
            "rates": {name: row_summary(e)["catch_rate"] for name, e in others.items()},
            "equals_kept": equals_kept,
            **chosen,
        }
        _print_level(level, row, out[level])
    return out


def pick(folder: Path, rows: list[str], n: int, pooled_anchor: tuple[int, bool]) -> dict[str, Any]:
    """The named rows on ``n`` validation episodes and the pick among them (module
    docstring)."""
    doc = json.loads((folder / "results.json").read_text(encoding="utf-8"))
    config = CascadeV1Config(**{**doc["config"], "levels": tuple(doc["config"]["levels"])})
    k = _pick_episodes(doc)
    if n < k:
        raise ValueError(f"--val-episodes must be >= the bench's {k}; got {n}")
    out: dict[str, Any] = {}
    for lv in doc["levels"]:
        level = lv["level"]
        tracker, est_tracker = lv["tracker"], lv["estimator_tracker"]
        players = _players(
            level, config, lv["late_offset_s"], tuple(lv["constant"]),
            (tracker["gain"], tracker["offset_s"]), lv["estimator_offset_s"],
            (est_tracker["gain"], est_tracker["offset_s"]), pooled_anchor,
        )  # fmt: skip
        unknown = [r for r in rows if r not in players or r in REFERENCES]
        if unknown:
            raise ValueError(f"--rows: not non-oracle rows of the bench: {unknown}")
        eps: dict[str, CascadeEpisodes] = {}
        for row in rows:
            ctl, policy, off, gain, extra = players[row]
            eps[row] = cascade_v1_episodes(
                policy, _kwargs(level, config, ctl, off, gain, extra), "val", n
            )
        first = {r: float(e.catches[:k].mean()) for r, e in eps.items()}
        full = {r: float(e.catches.mean()) for r, e in eps.items()}
        order = [r for r in ROWS if r in eps]  # the bench's rule: the first on a tie
        best_first, best_full = (max(order, key=means.get) for means in (first, full))
        out[level] = {
            "val_episodes": n,
            "bench_val_episodes": k,
            "rows": {r: row_summary(e) for r, e in eps.items()},
            "first_mean_catches": first,
            "first_equal_bench": {
                r: first[r] == lv["val_mean_catches"][r] for r in eps if r in lv["val_mean_catches"]
            },
            "pick_on_bench_episodes": best_first,
            "pick_on_all": best_full,
            "minus_pick_on_all": {
                r: _paired(e, eps[best_full]) for r, e in eps.items() if r != best_full
            },
        }
        print(f"{level}: pick on the bench's {k} validation episodes {best_first}, on {n} "
              f"{best_full}")  # fmt: skip
        for r in sorted(eps, key=lambda r: -full[r]):
            lo, hi = out[level]["rows"][r]["catches_mean_ci"]
            d = out[level]["minus_pick_on_all"].get(r)
            vs = (
                ""
                if d is None
                else f"; - {best_full} {d['value']:+.2f} [{d['ci'][0]:+.2f}, {d['ci'][1]:+.2f}]"
            )
            print(f"  {r:24s} {full[r]:.2f} [{lo:.2f}, {hi:.2f}] on {n} (first {k}: "
                  f"{first[r]:.2f}){vs}")  # fmt: skip
    return out


def _print_level(level: str, row: str, got: dict[str, Any]) -> None:
    m = got["row"]
    (mlo, mhi), (rlo, rhi) = m["catches_mean_ci"], m["catch_rate_ci"]
    print(f"{level}: {row} mean {m['catches_mean']:.2f} [{mlo:.2f}, {mhi:.2f}], median "
          f"{m['catches_median']} {m['catches_median_ci']}, catch rate {m['catch_rate']:.3f} "
          f"[{rlo:.3f}, {rhi:.3f}], censored {m['censored']}, deviation "
          f"{m.get('deviation_m', float('nan')) * 1000:.1f} mm")  # fmt: skip
    for name in sorted(got["minus"], key=lambda n: -got["means"][n]):
        d, r = got["minus"][name], got["minus_catch_rate"][name]
        mean, rate = got["means"][name], got["rates"][name]
        print(f"  {row} - {name:24s} {d['value']:+6.2f} [{d['ci'][0]:+.2f}, {d['ci'][1]:+.2f}]"
              f" catches, {r['value']:+.3f} [{r['ci'][0]:+.3f}, {r['ci'][1]:+.3f}] rate"
              f"  ({name} mean {mean:.2f}, rate {rate:.3f})")  # fmt: skip
    print(
        f"  best non-oracle (validation): {got['best_non_oracle']}; with {row}: "
        f"{got['best_non_oracle_with_row']} (validation means "
        f"{ {k: round(v, 2) for k, v in got['val_mean_catches'].items()} }); highest test "
        f"mean: {got['top_test_mean_non_oracle']}"
        + ("" if got["equals_kept"] is None else f"; equals the kept: {got['equals_kept']}")
    )
    if "estimator_offset_s" in got:
        means = {k: round(v, 2) for k, v in got["estimator_offset_val_mean_catches"].items()}
        print(f"  estimate's offset chosen on validation: {got['estimator_offset_s'] * 1000:+.0f}"
              f" ms (validation means {means}; the 0 ms candidate equals the kept "
              f"delay_estimator_catch's: {got['zero_offset_equals_kept_val']})")  # fmt: skip
    if "pooled_anchor_frames" in got:
        means = {k: round(v, 2) for k, v in got["pooled_val_mean_catches"].items()}
        print(f"  pooled estimate's anchor frames chosen on validation: "
              f"{got['pooled_anchor_frames']}, start anchored: {got['pooled_anchor_start']} "
              f"(validation means {means})")  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bench", type=Path, default=None)
    ap.add_argument("--replay", type=Path, default=None)
    ap.add_argument("--pattern", default="5")
    ap.add_argument("--levels", default="easy,medium,hard")
    ap.add_argument("--row", default="oracle_catch")
    ap.add_argument("--kept", action="store_true", help="pair DIR's own episodes of --row")
    ap.add_argument("--out", default=None)
    ap.add_argument("--pick", type=Path, default=None)
    ap.add_argument("--rows", default="late_meeting,pooled_estimator_catch")
    ap.add_argument("--val-episodes", type=int, default=200)
    ap.add_argument("--pooled-anchor", type=int, default=ANCHOR_FRAMES)
    ap.add_argument("--pooled-start", action="store_true", help="the pooled row's start anchor")
    args = ap.parse_args()
    if sum(a is not None for a in (args.bench, args.replay, args.pick)) != 1:
        ap.error("give one of --bench DIR, --replay DIR and --pick DIR")
    if args.pick is not None:
        try:
            choice = (args.pooled_anchor, args.pooled_start)
            picked = pick(args.pick, args.rows.split(","), args.val_episodes, choice)
        except ValueError as err:
            ap.error(str(err))
        if args.out:
            atomic_write_text(args.out, json.dumps(picked, indent=2) + "\n")
        return
    if args.bench is not None:
        bench(args.bench, args.pattern, tuple(args.levels.split(",")))
        return
    got = replay(args.replay, args.row, args.kept)
    if args.out:
        atomic_write_text(args.out, json.dumps(got, indent=2) + "\n")


if __name__ == "__main__":
    main()
