"""The LEARNED delay estimate as a competitor row: ``learned_estimator_catch``.

``learned_estimator_catch`` is ``juggler_delay_estimator_catch`` (the zero action) told
the learned :class:`~baselines.learned.delay_estimator.LearnedDelayRule` (``delay_rule=``):
a supervised regressor from the episode's anchored flights so far to the episode's delay
(features, model and its choice by grouped K-fold CV over TRAINING episodes in
:mod:`baselines.learned.delay_estimator`). Per cell (``--cell``):

* ``cascade3_medium`` / ``cascade3_hard``: Cascade-v1 three balls, paired with the rows
  of a bench folder kept by ``experiments/cascade_v1_replay_row.py --bench`` (``--bench-dir``:
  its ``results.json`` and ``episodes.json``, every row's test seeds and catches; the
  other rows' rollouts are bit-identical at this commit);
* ``v2_medium`` / ``v2_hard``: Juggling-v2 (the bench's keywords, ``max_catches`` 3),
  whose bench keeps no episodes: the rows paired against (``delay_estimator_catch``,
  ``estimator_offset_catch``, ``oracle_catch`` and the best non-oracle row, each with
  the parameters the bench chose on VALIDATION, read from ``--bench-dir``'s
  ``results.json``) are played here on the same test seeds.

For every training seed ``k`` of ``--seeds``: record ``--train-episodes`` TRAINING
episodes (block ``k``: episodes ``k N .. (k + 1) N - 1`` of the training split, so the
seeds differ in their data, their folds and the MLP's initialisation), fit, save the model
file and load it back (the rule played is the loaded one); the CPU time of recording and
fitting is the seed's training budget. Every seed is trained before any test seed is
played. Then:

* the estimate's error on ``--val-episodes`` VALIDATION episodes (the flights of
  ``delay_estimator_catch``'s own episodes, recorded as in training): the learned and the
  default rule's error (estimate minus true delay; mean, sd and RMSE in ms) at the 1st,
  2nd and 3rd flight and over every call;
* the row on the TEST seeds: mean catches (Cascade-v1: before the first drop) and catch
  rate with 95 % bootstrap intervals, the hand deviation, and the paired differences
  (mean catches and catch rate, 95 % bootstrap over the seeds) from every paired row,
  ``oracle_catch`` minus the row too. The median seed is the one with the median catch-rate
  difference from the best non-oracle row.

``--anchor-start`` (Cascade-v1 cells): the balls in flight at ``t = 0`` are anchored on
the juggler's throws before it (the env's ``anchor_start``) for the row, its training and
validation flights (so the start flights are among the flights the rule is trained on, as
the env gives them at play time) and the pooled row it is paired with. The anchor frames
(of both rows) are ``pooled_estimator_catch``'s with the start anchored: the frames of
:data:`~baselines.juggling_bench.v2.POOLED_ANCHOR_FRAMES` (the bench's declared candidates)
with the most mean catches before the first drop of the pooled row with the start anchored
on ``--choice-episodes`` VALIDATION episodes (default the bench's ``val_episodes``; ties:
the fewest frames), chosen before anything is trained or any test seed is played. That
row, ``pooled_estimator_catch_start``, is then played on the test seeds and paired like
the kept rows (``oracle_catch`` minus it too: the room left), and the median seed is the
one with the median catch-rate difference from it. The validation error of the pooled
rule on the same flights is reported beside the learned and the default rule's.

Two further modes, nothing trained: ``--true-delay`` (Cascade-v1) plays
``delay_estimator_catch`` told the episode's TRUE delay through its rule (the drag not
told; a reference) on the kept test seeds and pairs it; ``--pair-pooled FRAMES`` plays
``pooled_estimator_catch`` on ``FRAMES`` anchor frames (its bench's validation choice) on
the test seeds (with ``--anchor-start``: the start anchored too) and pairs it with each
seed's row replayed from ``--out``'s model files and env keywords (``replay_equals_run``:
the replay gives the summary the run wrote).

The demonstrations are SIMULATED.

    python experiments/learned_delay_estimator.py --cell cascade3_medium \
        --bench-dir /work/notes/benchdirs/cascade3_medium --out DIR
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path
from typing import Any

import numpy as np

from baselines.juggling_bench.cascade_v1 import _paired, pooled_extra, pooled_key
from baselines.learned.delay_estimator import (
    CONTROLLER,
    FlightSamples,
    LearnedDelayRule,
    collect_flights,
    train_delay_rule,
)
from motion_envs._io import atomic_write_text

CELLS = ("cascade3_medium", "cascade3_hard", "v2_medium", "v2_hard")
ROW = "learned_estimator_catch"
#: The pooled row with the start anchored, played by ``--anchor-start`` on the test seeds.
POOLED_START = "pooled_estimator_catch_start"
CASCADE_ID, V2_ID = "MotionEnvs/Cascade-v1", "MotionEnvs/Juggling-v2"


def _cell(cell: str) -> tuple[str, str]:
    if cell not in CELLS:
        raise ValueError(f"cell must be one of {list(CELLS)}; got {cell!r}")
    env, level = cell.split("_")
    return env, level


def _bench(folder: Path, level: str) -> tuple[dict[str, Any], dict[str, Any]]:
    doc = json.loads((folder / "results.json").read_text(encoding="utf-8"))
    lv = next((x for x in doc["levels"] if x["level"] == level), None)
    if lv is None:
        raise ValueError(f"{folder}: no level {level!r} in results.json")
    return doc, lv


def env_kwargs(cell: str, doc: dict[str, Any]) -> tuple[str, dict[str, Any]]:
    """The env id and keywords (no controller) of ``cell``'s row, as its bench plays it."""
    env, level = _cell(cell)
    if env == "cascade3":
        from baselines.juggling_bench.cascade_v1 import CascadeV1Config, _kwargs

        config = CascadeV1Config(**{**doc["config"], "levels": tuple(doc["config"]["levels"])})
        kw = _kwargs(level, config, CONTROLLER)
        if config.pattern != "3":
            raise ValueError(f"the bench folder is of pattern {config.pattern!r}, not '3'")
        return CASCADE_ID, {k: v for k, v in kw.items() if k != "controller"}
    from baselines.juggling_bench import v2

    v2_config = v2.V2Config(**{**doc["config"], "levels": tuple(doc["config"]["levels"])})
    kw = v2._kwargs(level, v2_config, CONTROLLER)
    return V2_ID, {k: v for k, v in kw.items() if k != "controller"}


def estimate_errors(rule: Any, samples: FlightSamples) -> dict[str, Any]:
    """The rule's error (estimate minus true delay, ms) over ``samples``: mean, sd and
    RMSE at the 1st, 2nd, 3rd flight and over every sample."""
    n = samples.n_flights()
    err = np.full(n.size, np.nan)
    for i, fl in enumerate(samples.flights):
        got = rule(list(fl), samples.gravity)
        if got is not None:
            err[i] = 1000.0 * (got - samples.delay[i])
    out: dict[str, Any] = {}
    for key, mask in (("1", n == 1), ("2", n == 2), ("3", n == 3), ("all", n >= 1)):
        e = err[mask & np.isfinite(err)]
        out[key] = {
            "n": int(e.size),
            "mean_ms": float(e.mean()) if e.size else None,
            "sd_ms": float(e.std()) if e.size else None,
            "rmse_ms": float(np.sqrt((e**2).mean())) if e.size else None,
        }
    return out


def _paired_rate(a: Any, b: Any) -> dict[str, Any]:
    from baselines.agents.juggling_score import catch_rate_comparison

    c = catch_rate_comparison(a, b)
    return {"value": c.difference, "ci": list(c.ci95)}


def _row_entry(eps: Any, cascade: bool) -> dict[str, Any]:
    from baselines.stats import group_bootstrap

    if cascade:
        from baselines.juggling_bench.cascade_v1 import row_summary

        return row_summary(eps)
    from baselines.juggling_bench.levels import summary

    c = eps.catches.astype(np.float64)
    _, lo, hi = group_bootstrap(lambda rows: float(c[rows].mean()), np.arange(c.size))
    return {**summary(eps), "catches_mean": float(c.mean()), "catches_mean_ci": [lo, hi]}


def paired_rows(cell: str, folder: Path, n_test: int | None) -> tuple[dict[str, Any], str, Any]:
    """``(rows, best non-oracle, test seeds)``: the rows the learned row is paired with,
    on the bench's test seeds (kept for Cascade-v1; played here for Juggling-v2)."""
    env, level = _cell(cell)
    doc, lv = _bench(folder, level)
    if env == "cascade3":
        from baselines.juggling_bench.cascade import CascadeEpisodes

        kept = json.loads((folder / "episodes.json").read_text(encoding="utf-8"))[level]
        rows: dict[str, Any] = {}
        for name, e in kept.items():
            ep = list(zip(e["catches"], e["tosses"], e["dropped"], e["time"], strict=True))
            rows[name] = CascadeEpisodes.from_rows(np.asarray(e["seeds"]), ep)
        seeds = next(iter(rows.values())).seeds
        return rows, lv["best_non_oracle"], seeds
    from baselines.agents.juggling_score import juggling_episodes
    from baselines.juggling_bench import v2

    config = v2.V2Config(**{**doc["config"], "levels": tuple(doc["config"]["levels"])})
    players = v2.row_players(
        level, tuple(lv["constant"]), lv["late_offset_s"],
        (lv["tracker"]["gain"], lv["tracker"]["offset_s"]), lv["estimator_offset_s"],
        (lv["estimator_tracker"]["gain"], lv["estimator_tracker"]["offset_s"]),
    )  # fmt: skip
    best = lv["best_non_oracle"]
    n = n_test or config.episodes
    rows = {}
    for name in dict.fromkeys(
        ["delay_estimator_catch", "estimator_offset_catch", "oracle_catch", best]
    ):
        ctl, policy, extra = players[name]
        rows[name] = juggling_episodes(policy, V2_ID, v2._kwargs(level, config, ctl, extra),
                                       "test", n)  # fmt: skip
    return rows, best, rows[best].seeds


def play_row(cell: str, env_id: str, kwargs: dict[str, Any], rule: Any, n: int) -> Any:
    """``learned_estimator_catch`` on the first ``n`` TEST seeds."""
    full = {**kwargs, "controller": CONTROLLER, "delay_rule": rule}
    if env_id == CASCADE_ID:
        from baselines.juggling_bench.cascade_v1 import cascade_v1_episodes

        return cascade_v1_episodes(None, full, "test", n)
    from baselines.agents.juggling_score import juggling_episodes

    return juggling_episodes(None, env_id, full, "test", n)


class _TrueDelay:
    """A delay rule that tells the env's TRUE delay (a reference, never a competitor)."""

    env: Any = None

    def __call__(self, flights: Any, gravity: float) -> float | None:
        return float(self.env.delay) if flights else None


def true_delay_reference(cell: str, folder: Path) -> dict[str, Any]:
    """Cascade-v1 only: ``delay_estimator_catch`` told the episode's TRUE delay by its
    rule (the drag not told; ``oracle_catch`` is told both) on the bench's test seeds,
    paired with ``delay_estimator_catch`` and ``oracle_catch``: how much of the room the
    exact delay alone takes."""
    from baselines.juggling_bench.cascade import CascadeEpisodes
    from motion_envs.datasets.juggling import episode_seeds
    from motion_envs.envs.juggling import CascadeV1Env

    env, level = _cell(cell)
    if env != "cascade3":
        raise ValueError(f"the true-delay reference is for the Cascade-v1 cells; got {cell!r}")
    doc, _ = _bench(folder, level)
    _, kwargs = env_kwargs(cell, doc)
    rows, best, seeds = paired_rows(cell, folder, None)
    rule = _TrueDelay()
    world = CascadeV1Env(**kwargs, controller=CONTROLLER, delay_rule=rule)
    rule.env = world
    if not np.array_equal(seeds, episode_seeds("test", seeds.size)):
        raise ValueError(f"{folder}: the kept test seeds are not the test split's first ones")
    told = CascadeEpisodes.from_rows(seeds, [world.play(int(s)) for s in seeds.tolist()])
    out = {"cell": cell, "row": _row_entry(told, True), "best_non_oracle": best}
    for name in dict.fromkeys(["delay_estimator_catch", "oracle_catch", best]):
        out[f"minus_{name}"] = {
            "catches": _paired(told, rows[name]),
            "catch_rate": _paired_rate(told, rows[name]),
        }
    print(json.dumps(out, indent=1))
    return out


def choose_start_frames(
    cell: str, doc: dict[str, Any], episodes: int
) -> tuple[int, dict[str, float]]:
    """The anchor frames of :data:`~baselines.juggling_bench.v2.POOLED_ANCHOR_FRAMES` with
    the most mean catches before the first drop of ``pooled_estimator_catch`` with the
    start anchored on the first ``episodes`` VALIDATION episodes (ties: the first, the
    fewest frames), and every candidate's validation mean (Cascade-v1 cells)."""
    from baselines.juggling_bench.cascade_v1 import cascade_v1_episodes
    from baselines.juggling_bench.grid_choice import best_on_grid
    from baselines.juggling_bench.v2 import POOLED_ANCHOR_FRAMES

    env, _ = _cell(cell)
    if env != "cascade3":
        raise ValueError(f"anchor_start is for the Cascade-v1 cells; got cell {cell!r}")
    if episodes < 1:
        raise ValueError(f"choice episodes must be >= 1; got {episodes!r}")
    _, kwargs = env_kwargs(cell, doc)
    grid = tuple((frames, True) for frames in POOLED_ANCHOR_FRAMES)

    def mean(choice: tuple[int, bool]) -> float:
        kw = {**kwargs, "controller": CONTROLLER, **pooled_extra(choice)}
        return float(cascade_v1_episodes(None, kw, "val", episodes).catches.mean())

    (frames, _), means = best_on_grid(grid, mean, pooled_key)
    return int(frames), means


def _play_pooled(env_id: str, kwargs: dict[str, Any], frames: int, start: bool, n: int) -> Any:
    """``pooled_estimator_catch`` on ``frames`` anchor frames (``start``: the start
    anchored) on the first ``n`` TEST seeds."""
    kw = {**kwargs, "controller": CONTROLLER, **pooled_extra((frames, start))}
    if env_id == CASCADE_ID:
        from baselines.juggling_bench.cascade_v1 import cascade_v1_episodes

        return cascade_v1_episodes(None, kw, "test", n)
    from baselines.agents.juggling_score import juggling_episodes

    return juggling_episodes(None, env_id, kw, "test", n)


def pair_pooled(
    cell: str, folder: Path, out: Path, frames: int, start: bool = False
) -> dict[str, Any]:
    """``pooled_estimator_catch`` (``delay_estimator_catch`` with the pooled delay rule on
    ``frames`` anchor frames, the bench's validation choice; ``start``: the start anchored
    too) played on the test seeds and paired with each seed's learned row, replayed from
    ``out``'s model files with the env keywords the run wrote (checked equal to the
    summary ``out/results.json`` holds)."""
    env, level = _cell(cell)
    if start and env != "cascade3":
        raise ValueError(f"anchor_start is for the Cascade-v1 cells; got cell {cell!r}")
    doc, _ = _bench(folder, level)
    env_id, kwargs = env_kwargs(cell, doc)
    done = json.loads((out / "results.json").read_text(encoding="utf-8"))
    n = int(done["test_episodes"])
    pooled = _play_pooled(env_id, kwargs, frames, start, n)
    row_kwargs = {**kwargs, **done["env_kwargs"]}
    cascade = env_id == CASCADE_ID
    result: dict[str, Any] = {
        "cell": cell,
        "pooled_anchor_frames": int(frames),
        "pooled_anchor_start": bool(start),
        "pooled_estimator_catch": _row_entry(pooled, cascade),
        "seeds": [],
    }
    for s in done["seeds"]:
        rule = LearnedDelayRule.load(out / f"model_seed{s['seed']}.safetensors")
        played = play_row(cell, env_id, row_kwargs, rule, n)
        again = _row_entry(played, cascade)
        result["seeds"].append(
            {
                "seed": s["seed"],
                "replay_equals_run": again["catch_rate"] == s["row"]["catch_rate"]
                and again["catches"] == s["row"]["catches"],
                "minus_pooled": _paired(played, pooled),
                "minus_pooled_catch_rate": _paired_rate(played, pooled),
            }
        )
    atomic_write_text(out / "pooled_pairing.json", json.dumps(result, indent=2) + "\n")
    print(json.dumps(result, indent=1))
    return result


def run(
    cell: str,
    folder: Path,
    out: Path,
    train_episodes: int,
    val_episodes: int,
    seeds: tuple[int, ...],
    n_test: int | None = None,
    progress: bool = True,
    anchor_start: bool = False,
    choice_episodes: int | None = None,
) -> dict[str, Any]:
    """The cell's measurement (module docstring); writes ``out/results.json`` and the
    model files ``out/model_seed{k}.safetensors``. ``anchor_start``: the start anchored,
    the anchor frames chosen on ``choice_episodes`` VALIDATION episodes (None: the
    bench's ``val_episodes``) first (:func:`choose_start_frames`)."""
    from motion_envs.models.juggling import pooled_flight_delay

    env, level = _cell(cell)
    if anchor_start and env != "cascade3":
        raise ValueError(f"anchor_start is for the Cascade-v1 cells; got cell {cell!r}")
    doc, _ = _bench(folder, level)
    env_id, bench_kwargs = env_kwargs(cell, doc)
    kwargs = dict(bench_kwargs)
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.process_time()
    choice: dict[str, Any] | None = None
    frames = 0
    if anchor_start:
        n_choice = (
            int(doc["config"]["val_episodes"]) if choice_episodes is None else choice_episodes
        )
        frames, means = choose_start_frames(cell, doc, n_choice)
        kwargs.update(pooled_extra((frames, True)))
        del kwargs["delay_rule"]  # the learned rule is the row's; the frames and start kept
        choice = {"split": "val", "episodes": n_choice, "anchor_frames": frames,
                  "val_mean_catches": means, "cpu_s": time.process_time() - t0}  # fmt: skip
    val = collect_flights(env_id, kwargs, "val", val_episodes, progress=progress)
    val_default = estimate_errors(lambda fl, g: _default(fl, g), val)
    val_pooled = estimate_errors(pooled_flight_delay, val)
    trained = []  # every seed trained before any test seed is played
    for k in seeds:
        c0 = time.process_time()
        rule, _ = train_delay_rule(env_id, kwargs, train_episodes, seed=k,
                                   first=k * train_episodes, progress=progress)  # fmt: skip
        train_cpu = time.process_time() - c0
        path = rule.save(out / f"model_seed{k}.safetensors")
        trained.append((k, train_cpu, LearnedDelayRule.load(path)))
    rows, best, test_seeds = paired_rows(cell, folder, n_test)
    n = test_seeds.size
    cascade = env_id == CASCADE_ID
    pooled_cpu = 0.0
    if anchor_start:
        c0 = time.process_time()
        rows[POOLED_START] = _play_pooled(env_id, bench_kwargs, frames, True, n)
        pooled_cpu = time.process_time() - c0
    ref = POOLED_START if anchor_start else best
    per_seed = []
    for k, train_cpu, rule in trained:
        c0 = time.process_time()
        played = play_row(cell, env_id, kwargs, rule, n)
        if not np.array_equal(played.seeds, test_seeds):
            raise ValueError(f"{folder}: the kept test seeds differ from the played ones")
        per_seed.append(
            {
                "seed": k,
                "train_first_episode": k * train_episodes,
                "train_cpu_s": train_cpu,
                "test_cpu_s": time.process_time() - c0,
                "chosen": rule.info["chosen"],
                "cv_rmse": rule.info["cv_rmse"],
                "cv_default_rule_rmse_ms": rule.info["cv_default_rule_rmse_ms"],
                "training_rows": rule.info["training_rows"],
                "val_errors": estimate_errors(rule, val),
                "row": _row_entry(played, cascade),
                "minus": {name: _paired(played, e) for name, e in rows.items()},
                "minus_catch_rate": {name: _paired_rate(played, e) for name, e in rows.items()},
                "oracle_catch_minus_row": {
                    "catches": _paired(rows["oracle_catch"], played),
                    "catch_rate": _paired_rate(rows["oracle_catch"], played),
                },
            }
        )
    order = sorted(range(len(per_seed)),
                   key=lambda i: per_seed[i]["minus_catch_rate"][ref]["value"])  # fmt: skip
    result = {
        "cell": cell,
        "env_id": env_id,
        "env_kwargs": kwargs,
        "bench_dir": str(folder),
        "row": ROW,
        "train_episodes_per_seed": train_episodes,
        "val_episodes": val_episodes,
        "test_episodes": int(n),
        "best_non_oracle": best,
        "anchor_start": anchor_start,
        "anchor_frames_choice": choice,
        "median_seed_against": ref,
        "val_errors_default_rule": val_default,
        "val_errors_pooled_rule": val_pooled,
        "rows": {
            name: _kept_entry(doc, level, name, e) if cascade else _row_entry(e, cascade)
            for name, e in rows.items()
        },
        "oracle_catch_minus_pooled_start": None
        if not anchor_start
        else {
            "catches": _paired(rows["oracle_catch"], rows[POOLED_START]),
            "catch_rate": _paired_rate(rows["oracle_catch"], rows[POOLED_START]),
        },
        "seeds": per_seed,
        "median_seed": per_seed[order[len(order) // 2]]["seed"],
        "pooled_start_cpu_s": pooled_cpu,
        "cpu_s": time.process_time() - t0,
        "demonstrations": "SIMULATED",
    }
    atomic_write_text(out / "results.json", json.dumps(result, indent=2) + "\n")
    _print(result)
    return result


def _default(flights: Any, gravity: float) -> float | None:
    from motion_envs.models.juggling import mean_flight_delay

    return mean_flight_delay(flights, gravity)


def _kept_entry(doc: dict[str, Any], level: str, name: str, eps: Any) -> dict[str, Any]:
    """A kept Cascade-v1 row's entry as its bench wrote it (with its hand deviation)."""
    lv = next(x for x in doc["levels"] if x["level"] == level)
    from baselines.juggling_bench.cascade_v1 import row_summary

    return lv["rows"].get(name) or row_summary(eps)


def _ci(d: dict[str, Any], fmt: str) -> str:
    return f"{d['value']:{fmt}} [{d['ci'][0]:{fmt}}, {d['ci'][1]:{fmt}}]"


def _print(r: dict[str, Any]) -> None:
    print(f"{r['cell']}: {r['row']}, {r['train_episodes_per_seed']} training episodes per "
          f"seed, {r['test_episodes']} test episodes; best non-oracle (validation): "
          f"{r['best_non_oracle']}")  # fmt: skip
    if r["anchor_frames_choice"]:
        c = r["anchor_frames_choice"]
        print(f"  start anchored; anchor frames {c['anchor_frames']} (validation, "
              f"{c['episodes']} episodes: {c['val_mean_catches']})")  # fmt: skip
    for rule in ("default", "pooled"):
        d = r[f"val_errors_{rule}_rule"]
        print(f"  {rule} rule, validation error (ms): " + "; ".join(
            f"{k}: {v['mean_ms']:+.1f} sd {v['sd_ms']:.1f} rmse {v['rmse_ms']:.1f} (n {v['n']})"
            for k, v in d.items() if v["n"]))  # fmt: skip
    if r["oracle_catch_minus_pooled_start"]:
        o = r["oracle_catch_minus_pooled_start"]
        print(f"  oracle_catch - {POOLED_START}: {_ci(o['catches'], '+.2f')} catches, "
              f"{_ci(o['catch_rate'], '+.3f')} rate")  # fmt: skip
    for s in r["seeds"]:
        m = s["row"]
        print(f"  seed {s['seed']}: {s['chosen']}, training {s['train_cpu_s']:.0f} s CPU; "
              f"mean catches {m['catches_mean']:.2f} [{m['catches_mean_ci'][0]:.2f}, "
              f"{m['catches_mean_ci'][1]:.2f}], catch rate {m['catch_rate']:.3f} "
              f"[{m['catch_rate_ci'][0]:.3f}, {m['catch_rate_ci'][1]:.3f}], deviation "
              f"{1000 * m['deviation_m']:.1f} mm")  # fmt: skip
        print("    validation error (ms): " + "; ".join(
            f"{k}: {v['mean_ms']:+.1f} sd {v['sd_ms']:.1f} rmse {v['rmse_ms']:.1f}"
            for k, v in s["val_errors"].items() if v["n"]))  # fmt: skip
        for name in s["minus"]:
            print(f"    - {name:24s} {_ci(s['minus'][name], '+.2f')} catches, "
                  f"{_ci(s['minus_catch_rate'][name], '+.3f')} rate")  # fmt: skip
        o = s["oracle_catch_minus_row"]
        print(f"    oracle_catch - row: {_ci(o['catches'], '+.2f')} catches, "
              f"{_ci(o['catch_rate'], '+.3f')} rate")  # fmt: skip
    print(f"  median seed (against {r['median_seed_against']}): {r['median_seed']}; "
          f"CPU {r['cpu_s']:.0f} s")  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cell", required=True, choices=CELLS)
    ap.add_argument("--bench-dir", type=Path, required=True)
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--train-episodes", type=int, default=2000)
    ap.add_argument("--val-episodes", type=int, default=300)
    ap.add_argument("--seeds", default="0,1,2")
    ap.add_argument("--test-episodes", type=int, default=None,
                    help="Juggling-v2 only: test episodes (default: the bench's)")  # fmt: skip
    ap.add_argument("--no-progress", action="store_true")
    ap.add_argument("--true-delay", action="store_true",
                    help="Cascade-v1: only the reference told the TRUE delay")  # fmt: skip
    ap.add_argument("--pair-pooled", type=int, default=None, metavar="FRAMES",
                    help="pair --out's rows with pooled_estimator_catch")  # fmt: skip
    ap.add_argument("--anchor-start", action="store_true",
                    help="Cascade-v1: the start anchored for the row, its data and the "
                         "pooled row; the anchor frames chosen on validation")  # fmt: skip
    ap.add_argument("--choice-episodes", type=int, default=None,
                    help="--anchor-start: validation episodes of the anchor frames' "
                         "choice (default: the bench's val_episodes)")  # fmt: skip
    args = ap.parse_args()
    if args.anchor_start and not args.cell.startswith("cascade3"):
        ap.error("--anchor-start is for the Cascade-v1 cells (cascade3_*)")
    if args.choice_episodes is not None and args.choice_episodes < 1:
        ap.error("--choice-episodes must be >= 1")
    if args.pair_pooled is not None:
        pair_pooled(args.cell, args.bench_dir, args.out, args.pair_pooled, args.anchor_start)
        return
    if args.true_delay:
        got = true_delay_reference(args.cell, args.bench_dir)
        args.out.mkdir(parents=True, exist_ok=True)
        atomic_write_text(args.out / "true_delay.json", json.dumps(got, indent=2) + "\n")
        return
    seeds = tuple(int(s) for s in args.seeds.split(","))
    if args.train_episodes < 2 or args.val_episodes < 1:
        ap.error("--train-episodes must be >= 2 and --val-episodes >= 1")
    run(args.cell, args.bench_dir, args.out, args.train_episodes, args.val_episodes, seeds,
        args.test_episodes, not args.no_progress, args.anchor_start,
        args.choice_episodes)  # fmt: skip


if __name__ == "__main__":
    main()
