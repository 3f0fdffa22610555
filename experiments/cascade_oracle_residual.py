"""Is there a residual policy that beats the cascade juggler on medium, within the action
space? The latency-aware juggler's targets given as the residual.

Not a timing: a diagnosis of the setting, before any agent is trained. Cascade-v0
(``--level``, ``--max-catches``) on TRAINING seeds ``SPLIT_SEEDS["train"] + i`` (or
validation seeds with ``--split val``; never the test seeds). In every control period
an oracle runs the latency-aware juggler beside the env's juggler on the same measured
state (the same controller seed, so the same random phase end points) and gives the
difference of their hand targets as the residual, clipped to ``[-s, s]`` per entry (the
action space of ``residual_scale`` ``s``) and, with ``--phases``, kept only in those
phases of the hand (the env's ``residual_phases``). The oracle is not a policy an agent
sees (it reads the latency-aware juggler's plans); it says what the action space
leaves room for:

* if the clipped oracle does not beat the juggler, no residual agent with that
  ``residual_scale`` can be expected to;
* the oracle's residual per phase (median, 90th percentile, largest) says where the
  latency's cost lies.

For each ``residual_scale`` and phase set: mean and median catches before the first drop
(at most ``--max-catches``), drops, and the paired difference from the juggler alone
(same seeds) with a 95 % paired bootstrap interval over episodes and its power line
(:func:`baselines.stats.paired_mean_difference`). Then trivial policies in the
shipped agents' action space (``residual_scale`` 0.4, the catch phase alone): uniform
random actions and constant vertical actions of 0.4 and 1 up and down: what an agent
must beat besides the juggler. The demonstrations the juggler is
fitted on are SIMULATED.

    python experiments/cascade_oracle_residual.py [--level medium] [--episodes 40]
        [--max-catches 10] [--scales 0.05 0.15 0.3 0.4 0.5] [--split train]
"""

from __future__ import annotations

import argparse
import copy
import math
import sys
import time
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from numpy.typing import NDArray
from tqdm import tqdm

import motion_envs  # noqa: F401  (registers the ids)
from baselines.agents.config import resolve_hyperparams
from baselines.stats import paired_mean_difference
from motion_envs.datasets.juggling import PHASES, SIMULATED_LABEL, SPLIT_SEEDS
from motion_envs.models.juggling import CascadeController, cascade_fit, make_cascade_controller

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))  # _timing, shared
from _timing import machine, print_json, print_machine, print_table

#: The phase sets tried: every phase (the env's default) and the catch alone.
PHASE_SETS: tuple[tuple[str, ...], ...] = (PHASES, ("catch",))
#: The shipped agents' action space (read from ``configs/agents/ppo.yaml``).
SHIPPED = {
    key: resolve_hyperparams("ppo", "MotionEnvs/Cascade-v0")["env_kwargs"][key]
    for key in ("residual_scale", "residual_phases")
}
#: Trivial policies: a name and the action of a period given a generator.
TRIVIAL: dict[str, Any] = {
    "uniform random": lambda rng: rng.uniform(-1.0, 1.0, 4),
    "constant up 1": lambda rng: np.array([0.0, 1.0, 0.0, 1.0]),
    "constant up 0.4": lambda rng: np.array([0.0, 0.4, 0.0, 0.4]),
    "constant down 0.4": lambda rng: np.array([0.0, -0.4, 0.0, -0.4]),
    "constant down 1": lambda rng: np.array([0.0, -1.0, 0.0, -1.0]),
}


class OracleResidual:
    """The env's juggler, with the latency-aware juggler's targets minus its own added
    (clipped to ``clip`` per entry, zero outside ``phases``); records the unclipped
    difference and the hand's phase of every period."""

    #: Its commands run in Python every period: the env's batch must not step the
    #: juggler's plans in its compiled arrays between events.
    compiled_events = False

    def __init__(
        self, juggler: CascadeController, aware: CascadeController, clip: float, phases: Any
    ) -> None:
        self.juggler, self.aware, self.clip, self.phases = juggler, aware, clip, phases
        self.records: list[tuple[str, NDArray[np.float64]]] = []

    def __getattr__(self, name: str) -> Any:
        return getattr(self.juggler, name)

    def reset(self, state: Any, rng: np.random.Generator | None = None) -> None:
        rng = rng if rng is not None else np.random.default_rng(0)
        twin = copy.deepcopy(rng)  # its seed sequence too: the hands spawn from it
        self.juggler.reset(state, rng)
        self.aware.reset(state, twin)

    def command(self, state: Any) -> tuple[NDArray[np.float64], tuple[bool, bool]]:
        targets, armed = self.juggler.command(state)
        aware, _ = self.aware.command(state)
        diff = aware - targets
        residual = np.clip(diff, -self.clip, self.clip)
        for h in range(2):
            phase = self.juggler.phase(h)
            self.records.append((phase, np.abs(diff[h])))
            if phase not in self.phases:
                residual[h] = 0.0
        return targets + residual, armed


def episodes(
    level: str,
    n: int,
    max_catches: int,
    split: str,
    clip: float | None,
    phases: Any,
    trivial: str | None = None,
) -> tuple[NDArray[np.float64], NDArray[np.bool_], list[tuple[str, NDArray[np.float64]]]]:
    """Catches and drop flags of ``n`` episodes (``clip`` None: the juggler alone, or
    the ``trivial`` policy in the shipped action space), and the oracle's per-period
    records."""
    catches = np.zeros(n)
    dropped = np.zeros(n, dtype=bool)
    records: list[tuple[str, NDArray[np.float64]]] = []
    rng = np.random.default_rng(0)
    shipped = SHIPPED if trivial is not None else {}
    for i in range(n):
        env: Any = gym.make(
            "MotionEnvs/Cascade-v0", level=level, max_catches=max_catches, **shipped
        )
        base = env.unwrapped
        if clip is not None:
            aware = make_cascade_controller(
                "juggler_latency_aware",
                cascade_fit(base.gravity),
                base.delay_steps * base.task.dt,
                base.dwell_ratio,
            )
            base.controller = OracleResidual(base.controller, aware, clip, phases)
        env.reset(seed=SPLIT_SEEDS[split] + i)
        done = False
        info: dict[str, Any] = {}
        while not done:
            a = np.zeros(4) if trivial is None else TRIVIAL[trivial](rng)
            _, _, term, trunc, info = env.step(a.astype(np.float32))
            done = term or trunc
            dropped[i] |= term
        catches[i] = info["catches"]
        if clip is not None:
            records += base.controller.records
        env.close()
    return catches, dropped, records


def _scale(clip: Any) -> float | None:
    """The row's ``residual_scale`` (None: the juggler alone or the unclipped oracle)."""
    if isinstance(clip, str):
        return float(SHIPPED["residual_scale"])
    return None if clip is None or math.isinf(clip) else float(clip)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--level", default="medium")
    parser.add_argument("--episodes", type=int, default=40)
    parser.add_argument("--max-catches", type=int, default=10)
    parser.add_argument("--scales", type=float, nargs="+", default=[0.05, 0.15, 0.3, 0.4, 0.5])
    parser.add_argument("--split", choices=("train", "val"), default="train")
    args = parser.parse_args(argv)
    if args.episodes < 2:
        parser.error("--episodes must be >= 2")
    if any(s <= 0 for s in args.scales):
        parser.error("--scales must be > 0")
    c0 = time.process_time()
    jobs: list[tuple[float | None, tuple[str, ...]]] = [(None, PHASES)]
    jobs += [(s, p) for p in PHASE_SETS for s in args.scales] + [(math.inf, PHASES)]
    results: dict[tuple[Any, tuple[str, ...]], Any] = {}
    for clip, phases in tqdm(jobs, desc="oracle", file=sys.stderr):
        results[clip, phases] = episodes(
            args.level, args.episodes, args.max_catches, args.split, clip, phases
        )
    for name in tqdm(TRIVIAL, desc="trivial", file=sys.stderr):
        results[name, ("catch",)] = episodes(
            args.level, args.episodes, args.max_catches, args.split, None, ("catch",), name
        )
    base = results[None, PHASES][0]
    out: dict[str, Any] = {
        "machine": machine(),
        "level": args.level,
        "episodes": args.episodes,
        "max_catches": args.max_catches,
        "split": args.split,
        "data": SIMULATED_LABEL,
        "rows": [],
    }
    rows: list[list[str]] = []
    for (clip, phases), (catches, dropped, _) in results.items():
        diff = catches - base
        paired = paired_mean_difference(catches, base, "residual", "juggler alone")
        lo, hi = paired.ci95
        if isinstance(clip, str):
            name = f"{clip}, s = {SHIPPED['residual_scale']:g}"
        else:
            name = "juggler alone" if clip is None else f"oracle, s = {clip:g}"
        where = "all" if phases == PHASES else ",".join(phases)
        out["rows"].append(
            {
                "residual": name,
                "residual_scale": _scale(clip),
                "phases": list(phases),
                "mean_catches": round(float(catches.mean()), 3),
                "median_catches": float(np.median(catches)),
                "drops": int(dropped.sum()),
                "diff_vs_juggler": round(float(diff.mean()), 3),
                "diff_ci95": [round(lo, 3), round(hi, 3)],
                "diff_detectable": [round(v, 3) for v in paired.detectable or ()],
                "diff_power": paired.power_text(),
            }
        )
        rows.append(
            [
                name,
                where,
                f"{catches.mean():.2f}",
                f"{np.median(catches):g}",
                str(int(dropped.sum())),
                "" if clip is None else f"{diff.mean():+.2f} [{lo:+.2f}, {hi:+.2f}]",
                "" if clip is None else paired.power_cell(),
            ]
        )
    records = results[math.inf, PHASES][2]
    spread: list[list[str]] = []
    out["unclipped_by_phase_m"] = {}
    for phase in PHASES:
        d = np.array([r for p, r in records if p == phase])
        if d.size == 0:
            continue
        q = np.percentile(d, [50, 90, 100], axis=0)
        out["unclipped_by_phase_m"][phase] = {
            "periods": len(d),
            "p50": q[0].round(4).tolist(),
            "p90": q[1].round(4).tolist(),
            "max": q[2].round(4).tolist(),
        }
        spread.append(
            [phase, str(len(d))]
            + [f"{1000 * q[k, 0]:.0f} / {1000 * q[k, 1]:.0f}" for k in range(3)]
        )
    out["cpu_seconds"] = round(time.process_time() - c0, 1)
    print_machine(out["machine"])
    seeds = "training" if args.split == "train" else "validation"
    print(
        f"Cascade-v0 {args.level}, {args.episodes} {seeds} seeds, at most {args.max_catches}"
        f" catches ({SIMULATED_LABEL})"
    )
    header = ["residual", "phases", "mean", "median", "drops", "vs juggler [95 %]",
              "80 % power for"]  # fmt: skip
    print_table(header, rows)
    print("\nthe unclipped oracle residual per hand phase, x / z (mm):")
    print_table(["phase", "periods", "median", "90th pct", "largest"], spread)
    print_json(out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
