"""A learned catch-timing policy (the felt task error in, the told delay out) against the
reference rows, on Juggling-v2 and Cascade-v1 (issue 34: an agent whose action can
re-time the catch).

For each block and learner seed: :func:`baselines.agents.catch_timing.train_timing_cem`
trains the linear timing policy by CEM on TRAINING episodes on top of its base: the delay
tracker the rows' bench chose on VALIDATION seeds (its gain and offset; ``--base
tracker``, the default) or, with ``--base estimator``, the delay estimator with the catch
plan told the offset the bench chose on VALIDATION seeds for ``estimator_offset_catch``
(the level document's ``estimator_offset_s``, taken whether or not that row is the best
non-oracle one: a validation choice either way); it keeps the generation best on
VALIDATION episodes, and only then plays the TEST seeds, the same seeds the
rows' bench played (``motion-bench juggling --version v2 [--pattern 3]``, replayed by
``experiments/juggling_v2_agents.py`` / ``cascade_v1_agents.py``'s ``level_rows``: every
grid choice and the best non-oracle row made on validation, ``oracle_catch`` the upper
reference). Blocks: ``v2-LEVEL`` (Juggling-v2, catch rate; ``drift`` by default) and
``cascade3-LEVEL`` / ``cascade5-LEVEL`` (Cascade-v1 three or five balls, trained with at
most 10 catches per episode, scored with the rows' 30: mean catches before the first
drop and catch rate). With ``--memory`` the policy also keeps the sum and the mean of the
timing errors it felt in the episode (:class:`baselines.agents.catch_timing.FeltErrors`).

Per seed: the agent's score, ``agent - best non-oracle row``, ``agent - its base`` (the
tracker or the estimator, ``w = 0``) and ``oracle_catch - agent`` (paired bootstrap over
test episodes, with power lines), its hand deviation from the held-out SIMULATED
demonstrations against the juggler's + 5 mm; per block the median seed (by ``agent -
best row``) and the validation pick (the best validation score), and the issue's targets
in words. With
``--every-row`` the agent is also paired with EVERY non-oracle row, the issue's last
target (each simple hand-written row below the agent), not only with the row validation
chose; ``--keep-base`` lets the base (``w = 0``) compete in the validation choice of
the kept generation, and ``--keep-margin M`` makes a generation replace it only when
its paired validation gain exceeds M standard errors (the winner's curse; the gain and
its standard error are written per seed); ``--rescore JSON ...`` scores the kept
policies of earlier runs without training.

    python experiments/catch_timing_agents.py [--blocks v2-drift cascade3-medium]
        [--seeds 0 1 2] [--generations 10] [--population 10] [--batch 16]
        [--memory] [--base {tracker,estimator}] [--test-episodes 100] [--every-row]
        [--keep-base [--keep-margin 1.0]]
        [--rescore JSON ...] [--out DIR]

Writes ``DIR/catch_timing_agents.json`` (with the base it played on) and
``DIR/catch_timing_agents.png`` (each seed's validation score per generation, the base's
as a line).
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import math
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))  # _timing
from _timing import machine, print_json

from baselines.agents.against_rows import (
    DEVIATION_SLACK_MM,
    MARGIN,
    likeness_met,
    margin_met,
    rows_not_beaten,
)
from baselines.agents.catch_timing import CEMSettings, TimingPolicy, n_features, train_timing_cem

HERE = Path(__file__).resolve().parent
TIMING_SCALE = 0.1
#: The controllers the policy can act on (``--base``), the first the default.
BASES = ("tracker", "estimator")


def _script(name: str) -> Any:
    """A sibling experiment script as a module (its ``level_rows``)."""
    spec = importlib.util.spec_from_file_location(name, HERE / f"{name}.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def base_kwargs(base: str, lv: dict[str, Any]) -> dict[str, Any]:
    """The env keywords of the policy's ``base`` (one of :data:`BASES`) from the rows'
    level document ``lv``: the delay tracker with the gain and offset validation chose for
    ``delay_tracker``, or the delay estimator with the catch plan told the offset
    validation chose for ``estimator_offset_catch`` (``estimator_offset_s``)."""
    if base == "tracker":
        trk = lv.get("tracker", {"gain": 0.0, "offset_s": 0.0})
        return {"controller": "juggler_delay_tracker", "tracker_gain": trk["gain"],
                "delay_offset": trk["offset_s"]}  # fmt: skip
    if base == "estimator":
        return {
            "controller": "juggler_delay_estimator_catch",
            "delay_offset": float(lv["estimator_offset_s"]),
        }
    raise ValueError(f"--base must be one of {list(BASES)}; got {base!r}")


def block_rows(
    block: str,
    test_episodes: int,
    val_rows: int = 30,
    every_row: bool = False,
    base: str = "tracker",
) -> dict[str, Any]:
    """The rows of ``block``: its env, the agent's training and scoring keywords (its
    ``base``'s, :func:`base_kwargs`), the played test episodes of the best non-oracle row
    (``every_row``: of every row), ``oracle_catch`` and the juggler's deviation
    (``val_rows``: the cascade bench's validation episodes, its default 30)."""
    kind, level = block.split("-", 1)
    if kind == "v2":
        from baselines.juggling_bench.v2 import RESIDUAL_SCALE, UPPER_REFERENCE, V2Config

        lv, played = _script("juggling_v2_agents").level_rows(level, test_episodes, every_row)
        kw = {
            "level": level,
            **base_kwargs(base, lv),
            "max_catches": V2Config().max_catches,
            "residual_scale": RESIDUAL_SCALE,
            "observe_task_error": True,
            "timing_scale": TIMING_SCALE,
        }
        juggler_mm = 1000 * played["juggler"].deviation
        return {"env": "MotionEnvs/Juggling-v2", "train_kwargs": kw, "test_kwargs": kw,
                "lv": lv, "played": played, "upper": UPPER_REFERENCE, "cascade": False,
                "juggler_mm": juggler_mm}  # fmt: skip
    if kind in ("cascade3", "cascade5"):
        pattern = kind[-1]
        from baselines.juggling_bench.cascade_v1 import UPPER_REFERENCE, CascadeV1Config

        config = CascadeV1Config(
            pattern=pattern, episodes=test_episodes, val_episodes=val_rows,
            pick_episodes=max(val_rows, CascadeV1Config.pick_episodes),
        )  # fmt: skip
        doc, played = _script("cascade_v1_agents").level_rows(level, config, every_row)
        lv = doc["levels"][0]
        kw = {
            "level": level,
            "pattern": pattern,
            **base_kwargs(base, lv),
            "max_catches": 10,
            "observe_task_error": True,
            "timing_scale": TIMING_SCALE,
        }
        juggler_mm = 1000 * lv["rows"]["juggler"].get("deviation_m", math.nan)
        return {"env": "MotionEnvs/Cascade-v1", "train_kwargs": kw,
                "test_kwargs": {**kw, "max_catches": config.max_catches}, "lv": lv,
                "played": played, "upper": UPPER_REFERENCE, "cascade": True,
                "juggler_mm": juggler_mm}  # fmt: skip
    raise ValueError(f"--blocks: unknown block {block!r} (v2-, cascade3- or cascade5-LEVEL)")


def _diff(d: Any) -> dict[str, Any]:
    return {"value": d.difference, "ci": list(d.ci95), "detail": d.to_dict()}


def score_test(rows: dict[str, Any], weights: Any, n: int, memory: bool = False) -> dict[str, Any]:
    """The policy ``weights`` (and its base, ``w = 0``) on the TEST seeds against the
    rows' played episodes (``memory``: the policy keeps the felt errors)."""
    from baselines.agents.juggling_score import catch_rate_comparison, juggling_episodes

    env, kw = rows["env"], rows["test_kwargs"]
    hands = 2 if rows["cascade"] else 1
    dim = 5 if rows["cascade"] else 3
    best, upper = rows["lv"]["best_non_oracle"], rows["upper"]
    out: dict[str, Any] = {}
    for who, w in (("agent", np.asarray(weights)), ("base", np.zeros(n_features(hands, memory)))):
        policy = TimingPolicy(w, hands, dim, memory)
        if rows["cascade"]:
            from baselines.agents.cascade_score import cascade_agent_episodes

            eps = cascade_agent_episodes(policy, env, kw, "test", n, deviation=True)
            dev = (
                eps.deviations.summary().get("deviation_m", math.nan)
                if eps.deviations
                else math.nan
            )
        else:
            eps = juggling_episodes(policy, env, kw, "test", n)
            dev = eps.deviation
        out[who] = eps
        out[f"{who}_deviation_mm"] = 1000 * dev
    agent, played = out.pop("agent"), rows["played"]
    base = out.pop("base")
    res: dict[str, Any] = {
        "catch_rate": float(agent.catches.sum() / max(int(agent.tosses.sum()), 1)),
        "mean_catches": float(agent.catches.mean()),
        "deviation_mm": out["agent_deviation_mm"],
        "base_deviation_mm": out["base_deviation_mm"],
    }
    pairs = {
        "minus_best_catch_rate": (agent, played[best], ("agent", best)),
        "minus_base_catch_rate": (agent, base, ("agent", "base")),
        "oracle_minus_catch_rate": (played[upper], agent, (upper, "agent")),
    }
    for key, (a, b, names) in pairs.items():
        res[key] = _diff(catch_rate_comparison(a, b, 0, names))
    others = [r for r in played if not r.startswith("oracle")]  # the upper references out
    each = {r: _diff(catch_rate_comparison(agent, played[r], 0, ("agent", r))) for r in others}
    res["minus_each_row_catch_rate"] = each
    res["every_row"] = rows_not_beaten({r: (d["value"], d["ci"]) for r, d in each.items()})
    if rows["cascade"]:
        from baselines.stats import paired_mean_difference

        res["minus_best_mean_catches"] = _diff(
            paired_mean_difference(agent.catches, played[best].catches, "agent", best)
        )
        res["minus_base_mean_catches"] = _diff(
            paired_mean_difference(agent.catches, base.catches, "agent", "base")
        )
        res["oracle_minus_mean_catches"] = _diff(
            paired_mean_difference(played[upper].catches, agent.catches, upper, "agent")
        )
    d = res["minus_best_catch_rate"]
    res["targets"] = {
        "margin": bool(margin_met(d["value"], d["ci"])),
        "likeness": likeness_met(res["deviation_mm"], rows["juggler_mm"]),
        "oracle_above": res["oracle_minus_catch_rate"]["value"] > 0,
    }
    return res


def kept_score(run: dict[str, Any], base_val_score: float) -> float:
    """The validation score of the run's kept policy (the base's when it kept the base)."""
    return base_val_score if run["kept"] == -1 else float(run["val_scores"][run["kept"]])


def load_earlier(paths: list[Path], base: str = "tracker") -> dict[str, Any]:
    """Earlier runs' ``catch_timing_agents.json`` files (``--rescore``), their blocks'
    runs pooled by block (one seed per file, as the runs were made); a missing or
    unreadable file, or one trained on another ``base`` than this run's (a file without
    one was trained on the tracker, the only base then), is a one-line ``ValueError``
    naming it."""
    pooled: dict[str, dict[str, Any]] = {}
    for path in paths:
        try:
            doc = json.loads(path.read_text())
        except (OSError, ValueError) as err:
            raise ValueError(f"--rescore {path}: not a readable results file ({err})") from None
        if not isinstance(doc, dict) or not isinstance(doc.get("blocks"), list):
            raise ValueError(f"--rescore {path}: no 'blocks' list; not a catch_timing_agents.json")
        for blk in doc["blocks"]:
            if blk.get("base", "tracker") != base:
                raise ValueError(
                    f"--rescore {path}: {blk['block']} was trained on the base "
                    f"{blk.get('base', 'tracker')!r}, not --base {base!r}"
                )
            into = pooled.setdefault(blk["block"], {**blk, "runs": []})
            into["runs"] += blk["runs"]
    return {"blocks": list(pooled.values())}


def _names(paths: list[Path]) -> str:
    return " ".join(map(str, paths))


def earlier_block(doc: dict[str, Any], path: Any, block: str) -> dict[str, Any]:
    """The block ``block`` of an earlier run; one-line ``ValueError`` if it has none."""
    for blk in doc["blocks"]:
        if blk.get("block") == block:
            return dict(blk)
    raise ValueError(f"--rescore {path}: no block {block!r}")


def earlier_run(
    doc: dict[str, Any], path: Any, block: str, seed: int, memory: bool
) -> dict[str, Any]:
    """The kept policy of ``block``'s ``seed`` in an earlier run (its weights, kept
    generation, validation and training scores and training CPU), checked to have the
    number of weights a policy with (or without) ``memory`` takes."""
    for run in earlier_block(doc, path, block)["runs"]:
        if run.get("seed") == seed:
            hands = 2 if block.startswith("cascade") else 1
            if len(run["weights"]) != n_features(hands, memory):
                raise ValueError(
                    f"--rescore {path}: {block} seed {seed} has {len(run['weights'])} weights; "
                    f"a policy {'with' if memory else 'without'} --memory takes "
                    f"{n_features(hands, memory)}"
                )
            keys = ("kept", "weights", "val_scores", "train_scores", "train_cpu_s")
            return {k: run[k] for k in keys}
    raise ValueError(f"--rescore {path}: {block} has no seed {seed}")


def words(
    block: str, best: str, run: dict[str, Any], juggler_mm: float, tag: str, base: str = "tracker"
) -> str:
    d, b, o = (run[k] for k in ("minus_best_catch_rate", "minus_base_catch_rate",
                                "oracle_minus_catch_rate"))  # fmt: skip
    t = run["targets"]

    def f(x: dict[str, Any]) -> str:
        return f"{x['value']:+.3f} [{x['ci'][0]:+.3f}, {x['ci'][1]:+.3f}]"

    kept = " (validation kept the base itself, w = 0)" if run["kept"] == -1 else ""
    text = (
        f"{block}, {tag} (seed {run['seed']}){kept}: agent - {best} {f(d)} catch rate (target >= "
        f"+{MARGIN:.2f} with the interval above 0: {'met' if t['margin'] else 'NOT met'}); "
        f"agent - its base (the {base}) {f(b)}; oracle_catch - agent {f(o)}; deviation "
        f"{run['deviation_mm']:.1f} mm against the juggler's {juggler_mm:.1f} + "
        f"{DEVIATION_SLACK_MM:.0f} mm ({'met' if t['likeness'] else 'NOT met'})"
    )
    if len(run["minus_each_row_catch_rate"]) > 1:  # --every-row: each row in turn
        text += f"; {run['every_row']['sentence']}"
    return text


def plot(blocks: list[dict[str, Any]], path: Path) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from motion_envs._io import save_figure

    fig, axes = plt.subplots(1, len(blocks), figsize=(5 * len(blocks), 3.6), squeeze=False)
    for ax, blk in zip(axes[0], blocks, strict=True):
        for run in blk["runs"]:
            g = np.arange(1, len(run["val_scores"]) + 1)
            ax.plot(g, run["val_scores"], marker="o", ms=3, label=f"seed {run['seed']}")
            if run["kept"] >= 0:
                ax.plot(run["kept"] + 1, run["val_scores"][run["kept"]], "k*", ms=10)
            else:  # --keep-base: the base itself kept, drawn at generation 0
                ax.plot(0, blk["base_val_score"], "k*", ms=10)
        base = blk.get("base", "tracker")
        ax.axhline(blk["base_val_score"], color="grey", ls="--", label=f"base (w = 0, the {base})")
        ax.set_xlabel("CEM generation")
        ax.set_ylabel("mean catches" if blk["cascade"] else "catch rate")
        ax.set_title(f"{blk['block']}: validation score (* kept)")
        ax.legend(fontsize=7)
    fig.tight_layout()
    save_figure(fig, path, dpi=130)
    plt.close(fig)
    return path


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--blocks", nargs="+", default=["v2-drift", "cascade3-medium"])
    ap.add_argument("--seeds", nargs="+", type=int, default=[0, 1, 2])
    ap.add_argument("--generations", type=int, default=10)
    ap.add_argument("--population", type=int, default=10)
    ap.add_argument("--batch", type=int, default=16)
    ap.add_argument("--val-episodes", type=int, default=50)
    ap.add_argument("--test-episodes", type=int, default=100)
    ap.add_argument(
        "--memory",
        action="store_true",
        help="the policy also keeps the sum and mean of the felt timing errors",
    )
    ap.add_argument(
        "--base",
        choices=BASES,
        default=BASES[0],
        help="the controller the policy re-times: the delay tracker (validated gain and "
        "offset) or the delay estimator with the catch plan (estimator_offset_catch's "
        "validated offset)",
    )
    ap.add_argument(
        "--keep-base",
        action="store_true",
        help="the base (w = 0) competes in the validation choice of the kept generation",
    )
    ap.add_argument(
        "--keep-margin",
        type=float,
        default=0.0,
        metavar="M",
        help="with --keep-base: a generation replaces the base only when its paired "
        "validation gain exceeds M standard errors (default 0: any gain)",
    )
    ap.add_argument(
        "--every-row",
        action="store_true",
        help="also pair the agent with every non-oracle row (Juggling-v2 replays them all)",
    )
    ap.add_argument(
        "--rescore",
        type=Path,
        nargs="+",
        default=None,
        metavar="JSON",
        help="no training: score the kept policies of earlier runs' catch_timing_agents.json",
    )
    ap.add_argument("--out", type=Path, default=Path("catch_timing_agents"))
    args = ap.parse_args(argv)
    try:
        earlier = None if args.rescore is None else load_earlier(args.rescore, args.base)
    except ValueError as err:
        ap.error(str(err))
    from tqdm import tqdm

    from motion_envs._io import atomic_write_text

    try:
        settings = CEMSettings(generations=args.generations, population=args.population,
                               batch=args.batch, val_episodes=args.val_episodes,
                               memory=args.memory, keep_base=args.keep_base,
                               keep_margin=args.keep_margin)  # fmt: skip
    except ValueError as err:
        ap.error(str(err))
    args.out.mkdir(parents=True, exist_ok=True)
    doc: dict[str, Any] = {"machine": machine(), "settings": vars(settings),
                           "timing_scale": TIMING_SCALE, "base": args.base,
                           "blocks": []}  # fmt: skip
    for block in args.blocks:
        t0 = time.process_time()
        rows = block_rows(block, args.test_episodes, every_row=args.every_row, base=args.base)
        rows_cpu = time.process_time() - t0
        best = rows["lv"]["best_non_oracle"]
        blk: dict[str, Any] = {"block": block, "base": args.base, "cascade": rows["cascade"],
                               "best_non_oracle": best,
                               "base_kwargs": rows["train_kwargs"], "rows_cpu_s": rows_cpu,
                               "juggler_deviation_mm": rows["juggler_mm"], "runs": []}  # fmt: skip
        for seed in args.seeds:
            if earlier is not None:
                trained = earlier_run(earlier, _names(args.rescore), block, seed, args.memory)
            else:
                t0 = time.process_time()
                bar = tqdm(total=settings.generations, desc=f"{block} seed {seed}", leave=False)

                def tick(g: int, train: float, val: float, bar: Any = bar) -> None:
                    bar.set_postfix(train=f"{train:.3f}", val=f"{val:.3f}")
                    bar.update(1)

                tr = train_timing_cem(rows["env"], rows["train_kwargs"], settings, seed, tick)
                bar.close()
                trained = {"kept": tr.kept, "weights": tr.weights.tolist(),
                           "val_scores": tr.val_scores, "train_scores": tr.train_scores,
                           "train_cpu_s": time.process_time() - t0}  # fmt: skip
                if settings.keep_base:  # the base's validation score, played by the learner
                    trained["base_score"] = tr.base_score
                    trained["val_gain_over_base"] = {"value": tr.gain[0], "se": tr.gain[1]}
            t0 = time.process_time()
            run = score_test(rows, trained["weights"], args.test_episodes, args.memory)
            run.update(seed=seed, **trained, test_cpu_s=time.process_time() - t0)
            blk["runs"].append(run)
            print(words(block, best, run, rows["juggler_mm"], "this seed", args.base), flush=True)
        from baselines.agents.catch_timing import block_score, play_scores
        from motion_envs.datasets.juggling import SPLIT_SEEDS

        val_seeds = SPLIT_SEEDS["val"] + np.arange(settings.val_episodes, dtype=np.int64)
        hands, dim = (2, 5) if rows["cascade"] else (1, 3)
        zero = TimingPolicy(np.zeros(n_features(hands, args.memory)), hands, dim, args.memory)
        played_base = [r["base_score"] for r in blk["runs"] if "base_score" in r]
        blk["base_val_score"] = (
            earlier_block(earlier, _names(args.rescore), block)["base_val_score"]
            if earlier is not None
            else played_base[0]
            if played_base  # --keep-base: the same zero policy on the same seeds
            else block_score(
                *play_scores(rows["env"], rows["train_kwargs"], zero, val_seeds), rows["cascade"]
            )
        )
        runs = sorted(blk["runs"], key=lambda r: r["minus_best_catch_rate"]["value"])
        median = runs[len(runs) // 2]
        pick = max(blk["runs"], key=lambda r: kept_score(r, blk["base_val_score"]))
        blk["median_seed"], blk["validation_pick"] = median["seed"], pick["seed"]
        jmm = rows["juggler_mm"]
        blk["words"] = [
            words(block, best, median, jmm, "median seed", args.base),
            words(block, best, pick, jmm, "validation pick", args.base),
        ]
        for line in blk["words"]:
            print(line, flush=True)
        doc["blocks"].append(blk)
        atomic_write_text(
            args.out / "catch_timing_agents.json", json.dumps(doc, indent=1, default=float)
        )
    plot(doc["blocks"], args.out / "catch_timing_agents.png")
    print_json({"blocks": [{k: b[k] for k in ("block", "median_seed", "validation_pick", "words")}
                           for b in doc["blocks"]]})  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
