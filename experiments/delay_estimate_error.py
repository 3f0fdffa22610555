"""How far the release-anchored delay estimate is from the episode's true delay, per
rule and anchor frames, as the episode's flights are anchored: the controller
``juggler_delay_estimator_catch`` (zero action) on Cascade-v1 pattern 3 and Juggling-v2,
on VALIDATION seeds only (``SPLIT_SEEDS["val"] + i``; no test seed is played).

Each candidate is a delay rule and an ``anchor_frames`` (the envs' ``delay_rule`` and
``anchor_frames``): ``mean`` (:func:`~motion_envs.models.juggling.mean_flight_delay`, the
default: each flight's least-residual delay on the 5 ms grid, averaged; given as the rule
it plays the default's episodes exactly) and ``pooled``
(:func:`~motion_envs.models.juggling.pooled_flight_delay`: one least-squares delay for
all of the episode's flights, refined below the grid), each at every ``anchor_frames``
of :data:`ANCHOR_GRID`. Each candidate plays its own episodes (its estimates steer its
catches, so its flights). The rule is wrapped by a recorder that keeps the estimate the
controller was given after ``k`` anchored flights (the rule is asked once per new
flight), and the error is that estimate minus the env's true delay (its attribute
``delay``). Reported per candidate: the error's mean, sd and RMSE after the 1st, 2nd,
3rd anchored flight, after the episode's last (``final``) and over every estimate the
episode used (``all``), with the number of estimates behind each; and the validation
mean catches (Cascade-v1: before the first drop, at most ``--max-catches``; Juggling-v2:
catches of at most 3 tosses, the bench's). A diagnosis: no row is chosen from it (the
bench row ``pooled_estimator_catch`` chooses its anchor frames on validation itself).

    python experiments/delay_estimate_error.py [--episodes 40] [--max-catches 30]

Prints a table and one JSON object.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))  # _timing
from _timing import machine, print_json

from motion_envs.datasets.juggling import episode_seeds
from motion_envs.envs.juggling import CascadeV1Env, JugglingV2Env
from motion_envs.models.juggling import (
    AnchoredFlight,
    DelayRule,
    mean_flight_delay,
    pooled_flight_delay,
)

#: The anchor frames tried, declared before any run (8 the default).
ANCHOR_GRID = (8, 12, 16, 20)
#: The rules compared.
RULES: dict[str, DelayRule] = {"mean": mean_flight_delay, "pooled": pooled_flight_delay}
#: The settings: name -> (env, level).
SETTINGS = {
    "cascade3-medium": ("cascade", "medium"),
    "cascade3-hard": ("cascade", "hard"),
    "v2-medium": ("v2", "medium"),
    "v2-hard": ("v2", "hard"),
}
CONTROLLER = "juggler_delay_estimator_catch"


class Recorder:
    """A :class:`~motion_envs.models.juggling.DelayRule` that answers as ``rule`` and
    keeps each answer by the number of flights it was given (cleared per episode)."""

    def __init__(self, rule: DelayRule) -> None:
        self.rule = rule
        self.seen: dict[int, float] = {}

    def __call__(self, flights: Sequence[AnchoredFlight], gravity: float) -> float | None:
        got = self.rule(flights, gravity)
        if got is not None:
            self.seen.setdefault(len(flights), got)
        return got


def play(setting: str, rule: str, anchor: int, n: int, max_catches: int) -> dict[str, Any]:
    """One candidate's ``n`` validation episodes: per episode the true delay, the
    estimates by flight count and the catches."""
    kind, level = SETTINGS[setting]
    rec = Recorder(RULES[rule])
    kw: dict[str, Any] = {"level": level, "controller": CONTROLLER, "delay_rule": rec,
                          "anchor_frames": anchor}  # fmt: skip
    episodes = []
    if kind == "cascade":
        env: Any = CascadeV1Env(pattern="3", max_catches=max_catches, **kw)
    else:
        env = JugglingV2Env(max_catches=3, **kw)
    for seed in episode_seeds("val", n).tolist():
        rec.seen = {}
        catches = env.play(seed)[0] if kind == "cascade" else env.nominal_episode(seed)["catches"]
        episodes.append({"delay": float(env.delay), "estimates": dict(sorted(rec.seen.items())),
                         "catches": int(catches)})  # fmt: skip
    return {"episodes": episodes}


def _stats(errors: list[float]) -> dict[str, float]:
    e = np.asarray(errors, dtype=np.float64) * 1000.0
    if e.size == 0:
        return {"n": 0, "mean_ms": float("nan"), "sd_ms": float("nan"), "rmse_ms": float("nan")}
    sd = float(e.std(ddof=1)) if e.size > 1 else float("nan")
    return {"n": int(e.size), "mean_ms": float(e.mean()), "sd_ms": sd,
            "rmse_ms": float(np.sqrt((e * e).mean()))}  # fmt: skip


def summarise(episodes: list[dict[str, Any]]) -> dict[str, Any]:
    """The error's statistics after the 1st, 2nd, 3rd anchored flight, the last, all."""
    by: dict[str, list[float]] = {"1": [], "2": [], "3": [], "final": [], "all": []}
    for ep in episodes:
        est = ep["estimates"]
        for k, d in est.items():
            err = d - ep["delay"]
            by["all"].append(err)
            if str(k) in by:
                by[str(k)].append(err)
        if est:
            by["final"].append(est[max(est)] - ep["delay"])
    out = {key: _stats(v) for key, v in by.items()}
    out["mean_catches"] = float(np.mean([ep["catches"] for ep in episodes]))
    return out


def run(episodes: int, max_catches: int) -> dict[str, Any]:
    doc: dict[str, Any] = {"split": "val", "episodes": episodes, "max_catches": max_catches,
                           "controller": CONTROLLER, "anchor_grid": list(ANCHOR_GRID),
                           "settings": {}}  # fmt: skip
    for setting in SETTINGS:
        t0 = time.process_time()
        got: dict[str, Any] = {}
        for rule in RULES:
            for anchor in ANCHOR_GRID:
                played = play(setting, rule, anchor, episodes, max_catches)
                got[f"{rule}-{anchor}"] = {**summarise(played["episodes"]), **played}
        doc["settings"][setting] = {"candidates": got, "cpu_s": time.process_time() - t0}
    return doc


def _cell(s: dict[str, float]) -> str:
    return f"{s['mean_ms']:+5.1f} {s['sd_ms']:4.1f} {s['rmse_ms']:4.1f} ({s['n']:3d})"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--episodes", type=int, default=40)
    ap.add_argument("--max-catches", type=int, default=30)
    args = ap.parse_args(argv)
    doc = run(args.episodes, args.max_catches)
    head = "error ms: mean sd rmse (n)"
    print(f"{'setting':16s} {'candidate':10s} " + "  ".join(
        f"{k:>22s}" for k in ("1st flight", "2nd", "3rd", "final", "all")
    ) + f"  val mean catches   [{head}]")  # fmt: skip
    for setting, sv in doc["settings"].items():
        for name, c in sv["candidates"].items():
            cells = "  ".join(f"{_cell(c[k]):>22s}" for k in ("1", "2", "3", "final", "all"))
            print(f"{setting:16s} {name:10s} {cells}  {c['mean_catches']:6.2f}")
        print(f"{setting:16s} CPU {sv['cpu_s']:.1f} s")
    doc["machine"] = machine()
    print_json(doc)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
