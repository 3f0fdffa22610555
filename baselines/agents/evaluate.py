"""The papers' criterion of a policy on a split, and ``motion-bench agent``.

:func:`episode_max_errors` plays one episode per trajectory of a split (trajectories
``0 .. episodes-1``, all by default) on the native vector environment, all at once, with
a deterministic policy, and returns ``info["max_error"]`` of each: the per-trajectory
maximum over time of the error. The criterion is their median (Faraway & Choe's
"median over trajectories of the max over time"). The validation callback of
``motion-bench train`` and ``motion-bench agent`` both call it, so their numbers agree.

``motion-bench agent DIR [--split test] [--episodes N] [--out DIR]`` scores the saved
agent, the zero action (the analytic nominal) and, for the reaching environments, the
learned ridge regressor fitted on the environment's training data
(:mod:`baselines.agents.learned_criterion`) on the same episodes with the same
criterion, and writes ``results.json`` (``criterion``, ``nominal_criterion``,
``learned_criterion``, ``ratio = criterion / nominal_criterion``, ``learned_ratio =
criterion / learned_criterion``, the per-episode values), ``results.csv`` (one row per
episode) and ``agent_vs_nominal.png``. Without scikit-learn (or for an environment
without a regressor) the learned values are null and ``learned_skipped`` says why.

``Juggling-v0`` has no trajectories to replay: its splits are seed ranges and its
criterion the drop rate per toss (:mod:`baselines.agents.juggling_score`;
:func:`split_criterion` and :func:`run` ask the env family's scorer,
:mod:`baselines.agents.scorers`). ``motion-bench agent`` then reports the catch
rates of the agent and of the zero action (the analytic juggler) on the same seeds and
the hand's deviation from the demonstrations (held-out ones on ``--split test``):
``catch_rate``, ``nominal_catch_rate``, ``deviation``, ``nominal_deviation``,
``deviation_ratio``, per phase, and per episode in results.csv. ``Cascade-v0`` plays the
same seed ranges (:mod:`baselines.agents.cascade_score`): catches before the first drop
(``catches_median`` with its interval, ``nominal_catches_median``, the paired
``catches_median_difference``), catch rates and their difference; its criterion is the
drops per catch.
"""

from __future__ import annotations

import argparse
import warnings
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from baselines import options
from baselines.agents import checks
from baselines.agents.reaching_score import EpisodeErrors, Policy, episode_max_errors
from motion_envs._io import atomic_write_text, save_figure

__all__ = [
    "AgentConfig",
    "EpisodeErrors",
    "episode_max_errors",
    "register",
    "run",
    "split_criterion",
]


def split_criterion(
    policy: Policy | None,
    env_id: str,
    env_kwargs: Mapping[str, Any],
    split: str,
    episodes: int | None = None,
    frame_stack: int = 1,
) -> float:
    """The criterion checkpoints are chosen by (lower is better), the env family's
    (:func:`baselines.agents.scorers.scorer_for`): for the reaching environments the
    papers' criterion (:func:`episode_max_errors`), for Juggling-v0 the drop rate per toss
    on the split's seeds (:func:`~baselines.agents.juggling_score.juggling_episodes`).
    ``policy`` takes stacks of ``frame_stack`` observations (:mod:`baselines.agents.memory`)."""
    from baselines.agents.memory import stacked_policy
    from baselines.agents.scorers import scorer_for

    if policy is not None:
        policy = stacked_policy(policy, frame_stack)
    got = scorer_for(env_id).episodes(policy, env_id, env_kwargs, split, episodes)
    return float(got.criterion)


# -- motion-bench agent ------------------------------------------------------------------
@dataclass(frozen=True)
class AgentConfig:
    """What ``motion-bench agent`` evaluates."""

    run_dir: str
    split: str = "test"
    episodes: int | None = None
    which: str = "best"


def run(config: AgentConfig) -> dict[str, Any]:
    """Score the saved agent and the zero-action nominal on the same episodes."""
    from baselines.agents.rundir import load_run

    if config.split not in ("train", "val", "test"):
        raise ValueError(f"split must be 'train', 'val' or 'test'; got {config.split!r}")
    loaded = load_run(config.run_dir, config.which)
    from baselines.agents.scorers import scorer_for

    scores = scorer_for(loaded.env_id).agent_results(loaded, config.split, config.episodes)
    from baselines.verdicts import kept_initial_policy

    initial = kept_initial_policy(loaded.manifest, config.which)
    return {**_run_entries(loaded, config), **scores, "kept_initial_policy": initial}


def _run_entries(loaded: Any, config: AgentConfig) -> dict[str, Any]:
    """The first entries of results.json: which run, environment, split and checkpoint."""
    return {
        "run_dir": str(config.run_dir),
        "algo": loaded.config["algo"],
        "env_id": loaded.env_id,
        "env_kwargs": loaded.env_kwargs,
        "seed": loaded.config["seed"],
        "split": config.split,
        "checkpoint": config.which,
    }


def write_results(results: Mapping[str, Any], out: Path) -> None:
    """results.json, results.csv and agent_vs_nominal.png in ``out``."""
    import pandas as pd

    from baselines.agents.rundir import write_json

    out.mkdir(parents=True, exist_ok=True)
    write_json(out / "results.json", dict(results))
    table = pd.DataFrame(results["episodes"])
    atomic_write_text(out / "results.csv", table.to_csv(index=False, float_format="%.17g"))
    if "agent_deviation" in results["episodes"]:
        plot_juggling_agent_vs_nominal(results, out / "agent_vs_nominal.png")
    elif "catches_median" in results:
        plot_cascade_agent_vs_nominal(results, out / "agent_vs_nominal.png")
    else:
        plot_agent_vs_nominal(results, out / "agent_vs_nominal.png")


def _agent_against_nominal(ax: Any, nominal: NDArray[Any], agent: NDArray[Any], what: str,
                           algo: str) -> None:  # fmt: skip
    """One point per episode, the agent's value against the nominal's, and the diagonal."""
    hi = float(max(np.max(agent, initial=1e-9), np.max(nominal, initial=1e-9))) * 1.05
    ax.scatter(nominal, agent, s=14, alpha=0.8)
    ax.plot([0, hi], [0, hi], "k--", lw=1, label="agent = nominal")
    ax.set_xlim(0, hi)
    ax.set_ylim(0, hi)
    ax.set_xlabel(f"nominal (zero action): {what}")
    ax.set_ylabel(f"agent ({algo}): {what}")
    ax.legend(loc="upper left")


def plot_agent_vs_nominal(results: Mapping[str, Any], path: Path) -> None:
    """Per-episode max error, agent against nominal (one point per episode) and sorted
    (with the learned regressor's, when there is one)."""
    from baselines.plots import new_figure

    ep = results["episodes"]
    a = np.asarray(ep["agent_max_error"])
    n = np.asarray(ep["nominal_max_error"])
    fig = new_figure(10, 4.2)
    ax1, ax2 = fig.subplots(1, 2)
    _agent_against_nominal(ax1, n, a, "max error", results["algo"])
    ax1.set_title(f"{results['env_id']}, {results['split']} split, per episode")
    order = np.argsort(n)
    ax2.plot(n[order], "o-", ms=3, label=f"nominal (median {results['nominal_criterion']:.4g})")
    ax2.plot(a[order], "o-", ms=3, label=f"agent (median {results['criterion']:.4g})")
    if "learned_max_error" in ep:
        lrn = np.asarray(ep["learned_max_error"])
        ax2.plot(
            lrn[order], "o-", ms=3,
            label=f"learned regressor (median {results['learned_criterion']:.4g})",
        )  # fmt: skip
    ax2.set_xlabel("episode (sorted by the nominal's error)")
    ax2.set_ylabel("max error over the episode")
    ax2.legend()
    save_figure(fig, path, dpi=120)


def plot_juggling_agent_vs_nominal(results: Mapping[str, Any], path: Path) -> None:
    """Juggling: per-episode deviation from the demonstrations, agent against nominal, and
    the median deviation per phase with the catch rates in the legend."""
    from baselines.plots import new_figure

    ep = results["episodes"]
    a = np.asarray(ep["agent_deviation"], dtype=float) * 1000.0
    n = np.asarray(ep["nominal_deviation"], dtype=float) * 1000.0
    fig = new_figure(10, 4.2)
    ax1, ax2 = fig.subplots(1, 2)
    ok = np.isfinite(a) & np.isfinite(n)  # an episode without a complete phase has none
    _agent_against_nominal(ax1, n[ok], a[ok], "deviation (mm)", results["algo"])
    ax1.set_title(
        f"{results['env_id']} [SIMULATED demonstrations], {results['split']}, per episode",
        fontsize=9,
    )
    phases = list(results["phase_deviation"])
    # per phase: the median of that phase's segments; "all": the median over every segment,
    # the deviation the console and the verdict report (phases weighed by their counts)
    labels = [*(p.replace("_", " ") for p in phases), "all\n(console)"]
    agent_mm = [1000.0 * results["phase_deviation"][p] for p in phases]
    nominal_mm = [1000.0 * results["nominal_phase_deviation"][p] for p in phases]
    agent_mm.append(1000.0 * results["deviation"])
    nominal_mm.append(1000.0 * results["nominal_deviation"])
    counts = results.get("phase_segments")
    if counts is not None:
        ncounts = results["nominal_phase_segments"]
        labels = [
            *(f"{lab}\nn={ncounts[p]}/{counts[p]}" for lab, p in zip(labels, phases, strict=False)),
            f"{labels[-1]}\nn={sum(ncounts.values())}/{sum(counts.values())}",
        ]
    x = np.arange(len(labels))
    ax2.bar(
        x - 0.2, nominal_mm, 0.4, label=f"nominal (catch rate {results['nominal_catch_rate']:.3f})"
    )
    ax2.bar(x + 0.2, agent_mm, 0.4, label=f"agent (catch rate {results['catch_rate']:.3f})")
    ax2.axvline(len(phases) - 0.5, color="0.6", lw=0.8, ls=":")
    ax2.set_xticks(x, labels, fontsize=8)
    ax2.set_ylabel(f"median deviation from {results['deviation_reference']} (mm)", fontsize=9)
    ax2.set_title(
        "hand vs nearest demonstration: median per phase and over all\n"
        "segments (n = segments, nominal/agent; the phases' shares differ)",
        fontsize=8,
    )
    ax2.legend(loc="upper center", bbox_to_anchor=(0.5, -0.22), ncol=2, fontsize=8)
    save_figure(fig, path, dpi=120)


def plot_cascade_agent_vs_nominal(results: Mapping[str, Any], path: Path) -> None:
    """Cascade: per-episode catches before the first drop, agent against nominal (one
    point per episode), and both sorted by the nominal's, with the medians."""
    from baselines.plots import new_figure

    ep = results["episodes"]
    a = np.asarray(ep["agent_catches"], dtype=float)
    n = np.asarray(ep["nominal_catches"], dtype=float)
    fig = new_figure(10, 4.2)
    ax1, ax2 = fig.subplots(1, 2)
    _agent_against_nominal(ax1, n, a, "catches before the first drop", results["algo"])
    ax1.set_title(
        f"{results['env_id']} [SIMULATED demonstrations], {results['split']}, per episode",
        fontsize=9,
    )
    order = np.lexsort((a, n))
    ax2.plot(n[order], "o-", ms=3, label=f"nominal (median {results['nominal_catches_median']:g})")
    ax2.plot(a[order], "o-", ms=3, label=f"agent (median {results['catches_median']:g})")
    ax2.axhline(results["max_catches"], color="k", lw=0.8, ls=":", label="max_catches")
    ax2.set_xlabel("episode (sorted by the nominal's catches)")
    ax2.set_ylabel("catches before the first drop")
    ax2.legend(loc="upper left", fontsize=8)
    save_figure(fig, path, dpi=120)


def eval_folder_name(args: argparse.Namespace) -> str:
    """The default output folder of ``motion-bench agent``: ``eval-SPLIT`` for the best
    checkpoint, ``eval-SPLIT-final`` for the final one (never overwriting the other)."""
    suffix = "" if args.checkpoint == "best" else f"-{args.checkpoint}"
    return f"eval-{args.split}{suffix}"


def _cascade_lines(results: Mapping[str, Any]) -> str:
    """The printed summary of a cascade agent's results (catches before the first drop)."""
    r = results
    clo, chi = r["catches_median_ci"]
    nlo, nhi = r["nominal_catches_median_ci"]
    dlo, dhi = r["catches_median_difference_ci"]
    rlo, rhi = r["catch_rate_difference_ci"]
    median, rate = r["differences"]  # baselines.stats.Difference.to_dict: words and power
    return "\n".join(
        [
            f"{r['env_id']} {r['algo']} ({r['split']}, {r['n_episodes']} episodes, at most "
            f"{r['max_catches']} catches): catches before the first drop, median agent "
            f"{r['catches_median']:g} (95% CI {clo:g} to {chi:g}), nominal "
            f"{r['nominal_catches_median']:g} ({nlo:g} to {nhi:g}); censored agent "
            f"{r['censored']}, nominal {r['nominal_censored']}",
            f"median catches agent - nominal = {r['catches_median_difference']:+g} (95% CI "
            f"{dlo:+g} to {dhi:+g}, paired over the same seeds; higher is better): "
            f"{median['sentence']}; {median['power_line']}",
            f"catch rate agent {r['catch_rate']:.4f}, nominal {r['nominal_catch_rate']:.4f}; "
            f"agent - nominal = {r['catch_rate_difference']:+.3f} (95% CI {rlo:+.3f} to "
            f"{rhi:+.3f}): {rate['sentence']}; {rate['power_line']}; drops per catch agent "
            f"{r['criterion']:.4f}, nominal {r['nominal_criterion']:.4f}",
        ]
    )


def _cli(args: argparse.Namespace) -> int:
    # the user chose the id; Gymnasium's "vN is out of date" notice would repeat per env
    warnings.filterwarnings("ignore", message=".*is out of date", category=DeprecationWarning)
    config = AgentConfig(str(args.run_dir), args.split, args.episodes, args.checkpoint)
    results = run(config)
    out = Path(args.out) if args.out else Path(args.run_dir) / eval_folder_name(args)
    write_results(results, out)
    if "catches_median" in results:
        print(_cascade_lines(results))
    elif "catch_rate" in results:
        print(
            f"{results['env_id']} {results['algo']} ({results['split']}, {results['n_episodes']} "
            f"episodes): catch rate agent {results['catch_rate']:.4f} ({results['tosses']} "
            f"tosses), nominal {results['nominal_catch_rate']:.4f}; deviation from "
            f"{results['deviation_reference']} agent {1000 * results['deviation']:.2f} mm, "
            f"nominal {1000 * results['nominal_deviation']:.2f} mm, ratio "
            f"{results['deviation_ratio']:.4f} (medians over all phase segments; the "
            "figure's per-phase bars are each phase's own median, and the phases' shares of "
            "the segments can differ between agent and nominal)"
        )
        lo, hi = results["catch_rate_difference_ci"]
        print(
            f"catch rate agent - nominal = {results['catch_rate_difference']:+.3f} (95% CI "
            f"{lo:+.3f} to {hi:+.3f} over {results['n_episodes']} episodes; higher is better)"
        )
    else:
        print(
            f"{results['env_id']} {results['algo']} ({results['split']}, "
            f"{results['n_episodes']} episodes): agent {results['criterion']:.6g}, nominal "
            f"{results['nominal_criterion']:.6g}, ratio {results['ratio']:.4f}"
        )
    from baselines.verdicts import format_agent_verdicts

    print(format_agent_verdicts(results))
    if results["learned_criterion"] is not None:
        print(
            f"learned regressor {results['learned_criterion']:.6g}, "
            f"agent / learned {results['learned_ratio']:.4f}"
        )
    else:
        print(f"learned regressor: skipped ({results['learned_skipped']})")
    print(f"wrote {out / 'results.json'}, results.csv, agent_vs_nominal.png")
    return 0


def register(subparsers: Any) -> None:
    """Add ``motion-bench agent``."""
    p = options.add_subcommand(
        subparsers,
        "agent",
        help="evaluate a saved agent against the zero-action nominal (papers' criterion)",
        description=__doc__.split("\n\n")[0].replace("``", ""),
    )
    p.add_argument(
        "run_dir", type=checks.run_folder, metavar="DIR",
        help="run folder written by motion-bench train",
    )  # fmt: skip
    p.add_argument("--split", default="test", choices=("train", "val", "test"))
    p.add_argument(
        "--episodes", type=options.positive_int, default=None,
        help="first N trajectories (default: all)",
    )  # fmt: skip
    p.add_argument("--checkpoint", default="best", choices=("best", "final"),
                   help="best on validation (agent.zip) or the final policy")  # fmt: skip
    p.add_argument(
        "--out", default=None, type=options.output_folder, metavar="DIR",
        help="output folder (default: DIR/eval-SPLIT, DIR/eval-SPLIT-final with --checkpoint "
        "final)",
    )  # fmt: skip
    p.set_defaults(func=_cli)
