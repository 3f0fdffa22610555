"""Agents on Cascade-v1 (a pattern at Juggling-v2's human levels) against the reference
rows, by catches before the first drop (issue 34, item 5).

For each level and seed: a run folder ``RUNS/{level}-seed{seed}`` reused when complete,
trained otherwise by ``motion-bench train`` (:func:`baselines.agents.train.run`;
``--algo``, default ``ppo``: ``configs/agents/ppo.yaml``'s Cascade-v1 block, the residual
in the catch phase on ``juggler_mean_delay_catch`` with a frame stack of 8, trained with
at most 10 catches per episode, its checkpoint chosen on the VALIDATION seeds by drops
per catch). The kept policy (:func:`baselines.agents.rundir.load_run`, with its frame
stack) is played on the TEST seeds (``SPLIT_SEEDS["test"] + i``) by
:func:`baselines.agents.cascade_score.cascade_agent_episodes` with its own env keywords
but the ROWS' ``max_catches`` (the bench's 30, ``--max-catches``), so its catches before
the first drop are censored where the rows' are.

The rows are ``motion-bench juggling --version v2 --pattern P``'s
(:func:`baselines.juggling_bench.cascade_v1.run_cascade_v1`: its grids' choices made on
``--val-episodes`` and the best non-oracle row on ``--pick-episodes`` VALIDATION episodes
by mean catches before the first drop, before any test seed is played,
``task_error_ilc`` trained on TRAINING episodes; ``oracle_catch``, given the true delay
and drag, the upper reference); their test episodes are kept as the bench plays them
(``run_cascade_v1(..., keep=)``: the same seeds, no replay) and paired with the agent's.

Per run: the agent's mean and median catches before the first drop and catch rate with
95 % bootstrap intervals; ``agent - best non-oracle row`` and ``oracle_catch - agent``
in mean catches and in catch rate (paired bootstrap over episodes,
:func:`baselines.stats.paired_mean_difference` and
:func:`baselines.agents.cascade_score.catch_rate_comparison`, each with its power line).
Per level: the run at the median over the seeds of each difference and the validation
pick (the lowest validation drops per catch), and the issue's targets in words: catch
rate ``agent - best row >= +0.05`` with the interval above 0; mean catches, the interval
of ``agent - best row`` above 0 (the issue gives its margin in catch rate only); the
oracle above the agent (the room left reported); and the likeness target: the agent's
hand deviation from the HELD-OUT SIMULATED cascade demonstrations
(:func:`baselines.agents.cascade_score.cascade_agent_episodes` with ``deviation=True``:
each hand in its own frame, per phase segment, the median over segments with a 95 %
interval resampling test episodes; the bench rows' criterion,
:func:`baselines.juggling_bench.cascade_v1.deviation_note`) at most the ``juggler`` row's
plus :data:`~baselines.agents.against_rows.DEVIATION_SLACK_MM` (5 mm), per run and for
the median of the seeds' deviations.

    python experiments/cascade_v1_agents.py [--levels medium hard] [--seeds 0 1 2]
        [--algo ppo] [--timesteps N] [--test-episodes 100] [--runs DIR] [--reuse-only]
        [--out results.json]

Writes ``results.json`` (the rows, every run with its per-episode catches and seeds, the
verdicts), ``cascade_v1_agents.png`` (mean catches before the first drop against catch
rate: the rows' points with their intervals, each seed's agent a star) and
``cascade_v1_agents_deviation.png`` (the bench's plot, mean catches and catch rate
against the hand deviation, with each seed's agent a star) beside it. The
demonstrations (the likeness reward, the deviation's) are SIMULATED.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))  # _timing, shared
from _timing import machine, print_json

from baselines.agents import against_rows as shared
from baselines.juggling_bench.cascade_v1 import (
    CASCADE_V1_ENV_ID,
    UPPER_REFERENCE,
    CascadeV1Config,
    deviation_note,
    plot_cascade_v1,
    report_cascade_v1,
    row_summary,
    run_cascade_v1,
)

ENV = CASCADE_V1_ENV_ID
#: The two quantities compared: key in a run, words.
QUANTITIES = {"mean_catches": "mean catches before the first drop", "catch_rate": "catch rate"}


def level_rows(
    level: str, config: CascadeV1Config, every_row: bool = False
) -> tuple[dict[str, Any], dict[str, Any]]:
    """The bench's document for ``level`` (:func:`run_cascade_v1`) and the test episodes
    of its best non-oracle row and of ``oracle_catch``, as the bench played them
    (``every_row``: of every row it kept)."""
    config = replace(config, levels=(level,))
    kept: dict[str, dict[str, Any]] = {}
    doc = run_cascade_v1(config, keep=kept)
    lv = doc["levels"][0]
    names = (lv["best_non_oracle"], UPPER_REFERENCE, *(kept[level] if every_row else ()))
    played = {name: kept[level][name] for name in dict.fromkeys(names)}
    for name, eps in played.items():
        if not math.isclose(row_summary(eps)["catches_mean"], lv["rows"][name]["catches_mean"]):
            raise RuntimeError(f"{level} {name}: the kept episodes differ from the bench's row")
    return doc, played


def scoring_kwargs(loaded: Any, config: CascadeV1Config) -> dict[str, Any]:
    """The run's env keywords with the rows' ``max_catches`` (the agent trained with its
    own); a run of another pattern is a one-line ``ValueError``."""
    kwargs = dict(loaded.env_kwargs)
    pattern = str(kwargs.get("pattern", "3"))
    if pattern != config.pattern:
        raise ValueError(
            f"run folder {loaded.run_dir}: pattern {pattern!r}, the rows' is {config.pattern!r}"
        )
    kwargs["max_catches"] = config.max_catches
    return kwargs


def _episodes(eps: Any) -> dict[str, list[Any]]:
    return {
        "seed": eps.seeds.tolist(),
        "catches": eps.catches.tolist(),
        "tosses": eps.tosses.tolist(),
        "dropped": eps.dropped.tolist(),
    }


def score_run(
    run_dir: Path,
    played: dict[str, Any],
    best: str,
    config: CascadeV1Config,
    args: argparse.Namespace,
    job: tuple[str, int],
    juggler_mm: float = math.nan,
) -> dict[str, Any]:
    """The kept policy of ``run_dir`` on the test seeds against the rows' episodes;
    ``juggler_mm``: the ``juggler`` row's hand deviation (mm) on the same test seeds,
    the likeness target's reference (NaN: not measured)."""
    from baselines.agents.cascade_score import cascade_agent_episodes, catch_rate_comparison
    from baselines.agents.rundir import load_run
    from baselines.stats import paired_mean_difference

    loaded = load_run(run_dir)
    shared.check_run(loaded, ENV, args.algo, *job)
    kwargs = scoring_kwargs(loaded, config)
    eps = cascade_agent_episodes(
        loaded.policy(), ENV, kwargs, "test", config.episodes, deviation=True
    )
    if eps.max_catches != config.max_catches:
        raise RuntimeError(f"the agent was scored with max_catches {eps.max_catches}")
    upper = played[UPPER_REFERENCE]
    for row in played.values():
        shared.check_same_seeds(eps.seeds, row.seeds)
    diffs = {
        "minus_best_mean_catches": paired_mean_difference(eps.catches, played[best].catches,
                                                          "agent", best),
        "minus_best_catch_rate": catch_rate_comparison(eps, played[best], names=("agent", best)),
        "oracle_minus_mean_catches": paired_mean_difference(upper.catches, eps.catches,
                                                            UPPER_REFERENCE, "agent"),
        "oracle_minus_catch_rate": catch_rate_comparison(upper, eps,
                                                         names=(UPPER_REFERENCE, "agent")),
    }  # fmt: skip
    out: dict[str, Any] = {
        **shared.run_fields(loaded, "drops_per_catch"),
        "trained_max_catches": loaded.env_kwargs.get("max_catches"),
        "scored_env_kwargs": kwargs,
        "agent": row_summary(eps),
    }
    for key, d in diffs.items():
        out[key] = d.difference
        out[f"{key}_ci"] = list(d.ci95)
    out["differences"] = {key: d.to_dict() for key, d in diffs.items()}
    agent = out["agent"]
    out["deviation_mm"] = 1000 * agent.get("deviation_m", math.nan)
    out["deviation_ci_mm"] = [1000 * v for v in agent.get("deviation_ci", [math.nan] * 2)]
    out["juggler_deviation_mm"] = juggler_mm
    out["targets"] = targets(out)
    out["episodes"] = _episodes(eps)
    return out


def targets(run: dict[str, Any]) -> dict[str, bool | None]:
    """The issue's targets for one run (``likeness``: None when not measured)."""
    return {
        "catch_rate": shared.margin_met(
            run["minus_best_catch_rate"], run["minus_best_catch_rate_ci"]
        ),
        "mean_catches": run["minus_best_mean_catches_ci"][0] > 0,
        "oracle_above": run["oracle_minus_mean_catches"] > 0,
        "likeness": shared.likeness_met(run["deviation_mm"], run["juggler_deviation_mm"]),
    }


def _pick(run: dict[str, Any]) -> dict[str, Any]:
    keys = ("minus_best_mean_catches", "minus_best_catch_rate", "oracle_minus_mean_catches")
    return {
        "seed": run["seed"],
        **{k: run[k] for k in keys},
        **{f"{k}_ci": run[f"{k}_ci"] for k in keys},
        "deviation_mm": run["deviation_mm"],
        "deviation_ci_mm": run["deviation_ci_mm"],
        "targets": run["targets"],
    }


def summarise_level(doc: dict[str, Any], runs: list[dict[str, Any]]) -> dict[str, Any]:
    """The level's entry: the rows, every run, the run at the median of each difference
    over the seeds and the validation pick."""
    lv = doc["levels"][0]
    median = {q: _pick(shared.median_run(runs, f"minus_best_{q}")) for q in QUANTITIES}
    juggler = lv["rows"]["juggler"]
    juggler_mm = 1000 * juggler.get("deviation_m", math.nan)
    deviation_mm = float(np.median([r["deviation_mm"] for r in runs]))
    return {
        "level": lv["level"],
        "pattern": doc["pattern"],
        "bench": lv,
        "best_non_oracle": lv["best_non_oracle"],
        "runs": runs,
        "median": median,
        "median_over_seeds": {
            key: float(np.median([r[key] for r in runs]))
            for key in (
                "minus_best_mean_catches",
                "minus_best_catch_rate",
                "oracle_minus_mean_catches",
                "oracle_minus_catch_rate",
            )
        },
        "validation_pick": _pick(shared.validation_pick(runs, "val_drops_per_catch")),
        "deviation": {
            "juggler_mm": juggler_mm,
            "juggler_ci_mm": [1000 * v for v in juggler.get("deviation_ci", [math.nan] * 2)],
            "median_over_seeds_mm": deviation_mm,
            "target_mm": juggler_mm + shared.DEVIATION_SLACK_MM,
            "median_met": shared.likeness_met(deviation_mm, juggler_mm),
            "what": deviation_note(doc["pattern"]["name"]),
        },
    }


def _fmt(run: dict[str, Any], key: str, digits: int = 3) -> str:
    return shared.format_difference(run[key], run[f"{key}_ci"], digits)


def words(lv: dict[str, Any], n_seeds: int) -> str:
    """The level's verdict on the issue's targets in words: the median of the seeds for
    each quantity, then the validation pick."""
    best = lv["best_non_oracle"]

    def verdict(p: dict[str, Any], q: str) -> str:
        if q == "catch_rate":
            rule = f"target >= +{shared.MARGIN:.2f} with the interval above 0"
            digits = 3
        else:
            rule = "target: interval above 0; the issue's margin is in catch rate"
            digits = 2
        diff = _fmt(p, f"minus_best_{q}", digits)
        return f"{QUANTITIES[q]} agent - {best} {diff} ({rule}: {_met(p['targets'][q])})"

    med = lv["median"]
    room = med["mean_catches"]
    above = "oracle_catch is above the agent" if room["targets"]["oracle_above"] else (
        "the agent reaches oracle_catch")  # fmt: skip
    pick = lv["validation_pick"]
    return (
        f"median of {n_seeds} seeds: {verdict(med['catch_rate'], 'catch_rate')} [seed "
        f"{med['catch_rate']['seed']}]; {verdict(room, 'mean_catches')} [seed "
        f"{room['seed']}]; {above} (room in mean catches "
        f"{_fmt(room, 'oracle_minus_mean_catches', 2)}"
        f"); {likeness(lv)}. Validation pick (seed {pick['seed']}): "
        f"{verdict(pick, 'catch_rate')}; {verdict(pick, 'mean_catches')}; hand deviation "
        f"{_deviation(pick)} ({_met(pick['targets']['likeness'])})"
    )


def _met(ok: bool | None) -> str:
    return "not measured" if ok is None else ("met" if ok else "NOT met")


def _deviation(run: dict[str, Any]) -> str:
    lo, hi = run["deviation_ci_mm"]
    return f"{run['deviation_mm']:.1f} mm [{lo:.1f}, {hi:.1f}]"


def likeness(lv: dict[str, Any]) -> str:
    """The likeness target in words: the median over the seeds of the agents' hand
    deviation against the juggler's plus the slack."""
    d = lv["deviation"]
    if d["median_met"] is None:
        return f"hand deviation: {d['what']}"
    lo, hi = d["juggler_ci_mm"]
    return (
        f"hand deviation from held-out demonstrations, median of the seeds "
        f"{d['median_over_seeds_mm']:.1f} mm against the juggler's {d['juggler_mm']:.1f} mm "
        f"[{lo:.1f}, {hi:.1f}] + {shared.DEVIATION_SLACK_MM:.0f} mm = {d['target_mm']:.1f} mm "
        f"(target agent <= juggler + {shared.DEVIATION_SLACK_MM:.0f} mm: {_met(d['median_met'])})"
    )


def plot(levels: list[dict[str, Any]], algo: str) -> Any:
    """Mean catches before the first drop against catch rate, a panel per level: each row
    a point with its 95 % intervals, each seed's agent a star (the median seed's
    filled)."""
    from baselines.juggling_bench.cascade_v1 import row_styles
    from baselines.plots import new_figure

    n = len(levels)
    fig = new_figure(5.4 * n, 5.6)
    axes = fig.subplots(1, n, squeeze=False)
    markers, colors = row_styles()
    for ax, lv in zip(axes[0], levels, strict=True):
        rows = lv["bench"]["rows"]
        points = [
            (
                name,
                rows[name],
                {"marker": markers.get(name, "o"), "color": colors.get(name, "grey")},
            )
            for name in rows
        ]
        median_seed = lv["median"]["mean_catches"]["seed"]
        for r in lv["runs"]:
            filled = r["seed"] == median_seed
            label = f"{algo.upper()} agent, seed {r['seed']}" + (" (median)" if filled else "")
            style = {"marker": "*", "color": "black", "markersize": 13 if filled else 10,
                     "markerfacecolor": "black" if filled else "white"}  # fmt: skip
            points.append((label, r["agent"], style))
        for name, m, style in points:
            x, (xlo, xhi) = m["catches_mean"], m["catches_mean_ci"]
            y, (ylo, yhi) = m["catch_rate"], m["catch_rate_ci"]
            ax.errorbar(x, y, xerr=[[x - xlo], [xhi - x]], yerr=[[y - ylo], [yhi - y]],
                        capsize=3, linestyle="none", label=name.replace("_", " "),
                        **style)  # fmt: skip
        ax.set_title(f"Cascade-v1 {lv['level']} (best non-oracle row: {lv['best_non_oracle']})",
                     fontsize=10)  # fmt: skip
        ax.set_xlabel("mean catches before the first drop")
        ax.grid(alpha=0.3)
    axes[0][0].set_ylabel("catch rate (catches per toss)")
    handles, labels = axes[0][0].get_legend_handles_labels()
    fig.legend(handles, labels, fontsize=8, loc="outside lower center", ncol=3, frameon=False)
    fig.suptitle("demonstrations SIMULATED; bars: 95 % bootstrap intervals\n"
                 "over the same test episodes", fontsize=9)  # fmt: skip
    return fig


def deviation_plot(levels: list[dict[str, Any]], algo: str) -> Any:
    """The bench's plot (:func:`plot_cascade_v1`: mean catches and catch rate against
    the hand deviation, a point per row) with each seed's agent as a star."""
    panels = []
    for lv in levels:
        rows = dict(lv["bench"]["rows"])
        for r in lv["runs"]:
            rows[f"{algo.upper()} agent, seed {r['seed']}"] = r["agent"]
        panels.append({"level": lv["level"], "rows": rows})
    return plot_cascade_v1({"pattern": levels[0]["pattern"], "levels": panels})


def _print_level(lv: dict[str, Any], n_seeds: int) -> None:
    best = lv["best_non_oracle"]
    for r in lv["runs"]:
        a = r["agent"]
        print(
            f"  seed {r['seed']}: {r['timesteps']} steps (best at {r['best_timesteps']}; trained "
            f"with max_catches {r['trained_max_catches']}, scored with "
            f"{r['scored_env_kwargs']['max_catches']}), mean catches {a['catches_mean']:.2f} "
            f"[{a['catches_mean_ci'][0]:.2f}, {a['catches_mean_ci'][1]:.2f}], median "
            f"{a['catches_median']:.1f}, catch rate {a['catch_rate']:.3f} "
            f"[{a['catch_rate_ci'][0]:.3f}, {a['catch_rate_ci'][1]:.3f}]; - {best}: "
            f"{_fmt(r, 'minus_best_mean_catches', 2)}"
            f" catches, "
            f"{_fmt(r, 'minus_best_catch_rate')}"
            f" rate; oracle_catch - agent "
            f"{_fmt(r, 'oracle_minus_mean_catches', 2)}"
            f" catches; hand deviation {_deviation(r)} (juggler "
            f"{r['juggler_deviation_mm']:.1f} mm; {_met(r['targets']['likeness'])})"
        )
        for d in r["differences"].values():
            print(f"    {d['sentence']}; {d['power_line']}")
    print(f"  {lv['level']}: {words(lv, n_seeds)}")


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    bench = CascadeV1Config()
    shared.add_arguments(
        p,
        levels=["medium", "hard"],
        runs="cascade_v1_agent_runs",
        timesteps_help="default: the config's (ppo: 1e6)",
        controller_help="the controller the residual acts on (default: the config's, "
        "juggler_mean_delay_catch)",
    )
    p.add_argument("--pattern", default=bench.pattern, help=f"default: {bench.pattern}")
    p.add_argument(
        "--val-episodes",
        type=int,
        default=bench.val_episodes,
        help=f"the rows' validation episodes (default: the bench's {bench.val_episodes})",
    )
    p.add_argument(
        "--pick-episodes",
        type=int,
        default=None,
        help=f"the validation episodes the best non-oracle row is picked on (default: the "
        f"bench's {bench.pick_episodes}, or --val-episodes if more)",
    )
    p.add_argument(
        "--max-catches",
        type=int,
        default=bench.max_catches,
        help=f"rows AND agent at test (default: the bench's {bench.max_catches})",
    )
    args = p.parse_args(argv)
    config = CascadeV1Config(
        pattern=args.pattern,
        levels=tuple(args.levels),
        episodes=args.test_episodes,
        val_episodes=args.val_episodes,
        pick_episodes=(
            max(args.val_episodes, bench.pick_episodes)
            if args.pick_episodes is None
            else args.pick_episodes
        ),
        max_catches=args.max_catches,
    )
    from baselines.juggling_bench.cascade_v1 import check_cascade_v1_config

    check_cascade_v1_config(config)  # before any training
    root = Path(args.runs)
    t0 = time.process_time()
    runs_dirs = shared.train_all(ENV, args, env_kwargs={"pattern": args.pattern})
    levels = []
    for level in tqdm(args.levels, desc="score"):
        doc, played = level_rows(level, config)
        print(report_cascade_v1(doc))
        best = doc["levels"][0]["best_non_oracle"]
        juggler_mm = 1000 * doc["levels"][0]["rows"]["juggler"].get("deviation_m", math.nan)
        runs = [
            score_run(runs_dirs[level, s], played, best, config, args, (level, s), juggler_mm)
            for s in args.seeds
        ]
        lv = summarise_level(doc, runs)
        lv["row_episodes"] = {name: _episodes(eps) for name, eps in played.items()}
        levels.append(lv)
        _print_level(lv, len(args.seeds))
    out_doc = {
        "benchmark": f"agents on {ENV}, pattern {args.pattern} (SIMULATED demonstrations)",
        "headline": "mean catches before the first drop (the bench's choice and room statistic)",
        "algo": args.algo,
        "test_episodes": args.test_episodes,
        "val_episodes": args.val_episodes,
        "max_catches": args.max_catches,
        "seeds": args.seeds,
        "timesteps": args.timesteps,
        "deviation": deviation_note(args.pattern),
        "levels": levels,
        "machine": machine(),
        "cpu_s_scoring_and_training_in_process": time.process_time() - t0,
    }
    out = Path(args.out) if args.out else root / "results.json"
    print(f"wrote {shared.write_results(out_doc, out)}")
    figure = out.with_name("cascade_v1_agents.png")
    print(f"wrote {shared.save_plot(plot(levels, args.algo), figure)}")
    if any(np.isfinite(r["deviation_mm"]) for lv in levels for r in lv["runs"]):
        figure = out.with_name("cascade_v1_agents_deviation.png")
        print(f"wrote {shared.save_plot(deviation_plot(levels, args.algo), figure)}")
    print_json(out_doc)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
