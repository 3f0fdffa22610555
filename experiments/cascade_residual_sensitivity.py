"""How much a residual's jitter costs the cascade juggler: why PPO's agents lose to it.

Not a timing: a diagnosis. Cascade-v0 (``--level``, the shipped PPO block's
``residual_scale`` 0.15 and ``max_catches`` 10) on VALIDATION seeds
``SPLIT_SEEDS["val"] + i`` (never the test seeds), ``--episodes`` episodes stepped
together in the native vector environment, under residual actions that carry no
information:

* ``zero``: the juggler itself (the reference);
* ``white``: an independent ``N(0, s^2)`` draw per step and action entry (what a policy
  whose output follows the sensor's noise, or PPO's per-step exploration, adds);
* ``white x`` / ``white z``: the same on the hands' horizontal / vertical entries only;
* ``held 16``: a draw held for 16 steps (80 ms; gSDE's ``sde_sample_freq`` 16);
* ``constant``: one draw per episode (a fixed offset of the hands' targets);
* with ``--residual-phases``, each hand's residual acts in those phases only (the env's
  ``residual_phases``): which phases the jitter harms;
* ``fixed A``: with ``--fixed``, the same offset ``A`` (four action entries: right
  ``x, z``, left ``x, z``) in every episode: can a steady offset of the catch, what a
  Juggling-v1 agent learned, help the cascade juggler?

For each: mean catches before the first drop, drops per catch (the agents' validation
criterion) and the paired difference of mean catches from ``zero`` (same seeds) with a
95 % paired bootstrap interval over episodes and its power line (the differences it
detects 80 % of the time at this many episodes:
:func:`baselines.stats.paired_mean_difference`). ``--split train`` plays the TRAINING
seeds instead. The demonstrations the juggler is fitted on are SIMULATED.

    python experiments/cascade_residual_sensitivity.py [--level medium] [--episodes 80]
        [--scales 0.02 0.05 0.1] [--split val] [--fixed=DX,DZ,DX,DZ ...]
        [--residual-phases toss return]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

from baselines.stats import paired_mean_difference
from motion_envs.datasets.juggling import SIMULATED_LABEL, SPLIT_SEEDS
from motion_envs.envs.juggling import CascadeVectorEnv

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))  # _timing, shared
from _timing import machine, print_json, print_machine, print_table

KINDS = ("white", "white x", "white z", "held 16", "constant")
_COLUMNS = {"white x": [0, 2], "white z": [1, 3]}


def first_episodes(
    level: str,
    episodes: int,
    kind: str,
    scale: float,
    split: str = "val",
    phases: list[str] | None = None,
) -> tuple[Any, Any]:
    """Catches and drop flags of each sub-environment's first episode under ``kind``
    (``"fixed A"``: the offset ``A``, comma-separated action entries, in every step)."""
    env = CascadeVectorEnv(
        episodes,
        level=level,
        max_catches=10,
        residual_scale=0.15,
        residual_phases=phases,
        threads=1,
    )
    env.reset(seed=SPLIT_SEEDS[split])
    rng = np.random.default_rng(0)
    catches = np.zeros(episodes)
    dropped = np.zeros(episodes, dtype=bool)
    done = np.zeros(episodes, dtype=bool)
    a = np.zeros((episodes, 4))
    bias = scale * rng.standard_normal((episodes, 4))
    step = 0
    while not done.all():
        if kind == "constant":
            a = bias
        elif kind.startswith("fixed "):
            a = np.tile(np.array(kind[6:].split(","), dtype=float), (episodes, 1))
        elif kind == "held 16":
            if step % 16 == 0:
                a = scale * rng.standard_normal((episodes, 4))
        elif kind != "zero":
            a = np.zeros((episodes, 4))
            cols = _COLUMNS.get(kind, [0, 1, 2, 3])
            a[:, cols] = scale * rng.standard_normal((episodes, len(cols)))
        _, _, terminated, truncated, info = env.step(a.astype(np.float32))
        live = ~done
        catches[live] = info["catches"][live]
        dropped[live] |= terminated[live]
        done |= terminated | truncated
        step += 1
    env.close()
    return catches, dropped


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--level", default="medium")
    parser.add_argument("--episodes", type=int, default=80)
    parser.add_argument("--scales", type=float, nargs="+", default=[0.02, 0.05, 0.1])
    parser.add_argument("--split", choices=("val", "train"), default="val")
    parser.add_argument(
        "--fixed", action="append", default=[], metavar="DX,DZ,DX,DZ",
        help="a fixed offset (repeat for more; --fixed=-0.05,0,0,0 for a leading minus)",
    )  # fmt: skip
    parser.add_argument(
        "--residual-phases", nargs="+", default=None, metavar="PHASE",
        help="the hand phases in which the residual acts (the env's residual_phases)",
    )  # fmt: skip
    args = parser.parse_args(argv)
    for text in args.fixed:
        try:
            ok = len([float(v) for v in text.split(",")]) == 4
        except ValueError:
            ok = False
        if not ok:
            parser.error(f"--fixed: {text!r} is not four comma-separated numbers")
    if args.episodes < 2:
        parser.error("--episodes must be >= 2")
    if any(s <= 0 for s in args.scales):
        parser.error("--scales must be > 0")
    c0 = time.process_time()
    jobs = [("zero", 0.0)] + [(k, s) for s in args.scales for k in KINDS]
    jobs += [(f"fixed {text}", 0.0) for text in args.fixed]
    results: dict[tuple[str, float], tuple[Any, Any]] = {}
    for kind, scale in tqdm(jobs, desc="residuals", file=sys.stderr):
        results[kind, scale] = first_episodes(
            args.level, args.episodes, kind, scale, args.split, args.residual_phases
        )
    base = results["zero", 0.0][0]
    rows: list[list[Any]] = []
    out: dict[str, Any] = {
        "machine": machine(),
        "level": args.level,
        "episodes": args.episodes,
        "split": args.split,
        "residual_phases": args.residual_phases,
        "data": SIMULATED_LABEL,
        "rows": [],
    }
    for (kind, scale), (catches, dropped) in results.items():
        diff = catches - base
        paired = paired_mean_difference(catches, base, kind, "zero")
        per_catch = float(dropped.sum()) / max(float(catches.sum()), 1.0)
        lo, hi = paired.ci95
        row = {
            "residual": kind,
            "std_action": scale,
            "std_m": round(0.15 * scale, 5),
            "mean_catches": round(float(catches.mean()), 3),
            "drops_per_catch": round(per_catch, 3),
            "diff_vs_zero": round(float(diff.mean()), 3),
            "diff_ci95": [round(lo, 3), round(hi, 3)],
            "diff_detectable": [round(v, 3) for v in paired.detectable or ()],
            "diff_power": paired.power_text(),
        }
        out["rows"].append(row)
        rows.append(
            [
                kind,
                f"{scale:g}",
                f"{1000 * 0.15 * scale:.1f}",
                f"{row['mean_catches']:.2f}",
                f"{per_catch:.3f}",
                f"{float(diff.mean()):+.2f} [{lo:+.2f}, {hi:+.2f}]",
                paired.power_cell(),
            ]
        )
    out["cpu_seconds"] = round(time.process_time() - c0, 1)
    print_machine(out["machine"])
    seeds = "validation" if args.split == "val" else "training"
    where = ", residual in " + " + ".join(args.residual_phases) if args.residual_phases else ""
    print(f"Cascade-v0 {args.level}, {args.episodes} {seeds} seeds{where} ({SIMULATED_LABEL})")
    header = ["residual", "std (action)", "std (mm)", "catches", "drops/catch", "vs zero [95 %]",
              "80 % power for"]  # fmt: skip
    print_table(header, rows)
    print_json(out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
