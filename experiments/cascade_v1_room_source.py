"""What of the room above the hand-written fixes on Cascade-v1 is the drag, what the delay,
and when the delay is known: ``oracle_catch`` (told the true delay and every ball's drag
from the episode's start) against the same controller told the true delay but NO drag
(its estimators reset with drag 0); the hand-written estimate with the catch plan
(``juggler_delay_estimator_catch``) told the TRUE delay from the start (its prior, which
places the frames before the first anchored flight, set to the true delay, and its rule
returning it), told it only once a flight is anchored (the rule alone: before, the
level's mean), as it is (the default rule), and with the pooled rule on 20 anchor frames
(``pooled_estimator_catch``'s, the frames validation chose on both levels), the last
two also with the balls in flight at the start anchored on their throws before ``t = 0``
(the env's ``anchor_start``: the first anchored flight comes sooner); and the mean-delay
catch plan. All with the zero action on the same VALIDATION seeds
(``SPLIT_SEEDS["val"] + i``; no test seed is played). Mean catches before the first drop
(at most ``--max-catches``), each row minus ``oracle_catch`` paired over the seeds with a
95 % bootstrap interval, and the steps between neighbouring rows (the drag; the oracle's
own estimator against the hand-written one told the same; the delay before the first
anchored flight; the estimate's error; the same with the start anchored; the start
anchor's gain).

    python experiments/cascade_v1_room_source.py [--pattern 3] [--levels medium hard]
        [--episodes 40] [--max-catches 30]

Prints a table and one JSON object. A diagnosis (no row is chosen from it).
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))  # _timing
from _timing import machine, print_json

from baselines.stats import paired_mean_difference
from motion_envs.datasets.juggling import SPLIT_SEEDS
from motion_envs.envs.juggling import CascadeV1Env
from motion_envs.models.juggling import (
    FlightEstimator,
    PooledReleaseEstimator,
    pooled_flight_delay,
)

#: Row -> (controller, what it is told: ``"no_drag"`` the oracle's drag withheld,
#: ``"true"`` the true delay from the start, ``"anchored"`` the true delay once a flight
#: is anchored, ``"pooled"`` the pooled rule on 20 frames, ``""`` nothing; ``"_start"``:
#: the balls in flight at the start anchored on their throws).
ROWS: dict[str, tuple[str, str]] = {
    "oracle_catch": ("juggler_oracle_catch", ""),
    "oracle_catch_no_drag": ("juggler_oracle_catch", "no_drag"),
    "estimate_told_true_delay": ("juggler_delay_estimator_catch", "true"),
    "estimate_told_true_delay_anchored": ("juggler_delay_estimator_catch", "anchored"),
    "estimate_told_true_delay_anchored_start": ("juggler_delay_estimator_catch", "anchored_start"),
    "pooled_estimator_catch_20": ("juggler_delay_estimator_catch", "pooled"),
    "pooled_estimator_catch_20_start": ("juggler_delay_estimator_catch", "pooled_start"),
    "delay_estimator_catch": ("juggler_delay_estimator_catch", ""),
    "mean_delay_catch": ("juggler_mean_delay_catch", ""),
}
#: The steps reported between rows ``(upper, lower, what the step is)``.
STEPS = (
    ("oracle_catch", "oracle_catch_no_drag", "the drag"),
    ("oracle_catch_no_drag", "estimate_told_true_delay", "the oracle's estimator (should be 0)"),
    (
        "estimate_told_true_delay",
        "estimate_told_true_delay_anchored",
        "the delay before the first anchored flight",
    ),
    ("estimate_told_true_delay_anchored", "delay_estimator_catch", "the estimate's error"),
    ("pooled_estimator_catch_20", "delay_estimator_catch", "the pooled rule on 20 frames"),
    (
        "estimate_told_true_delay",
        "estimate_told_true_delay_anchored_start",
        "the delay before the first anchored flight, the start anchored",
    ),
    (
        "estimate_told_true_delay_anchored_start",
        "pooled_estimator_catch_20_start",
        "the pooled estimate's error, the start anchored",
    ),
    ("pooled_estimator_catch_20_start", "pooled_estimator_catch_20", "the start anchor"),
)
POOLED_FRAMES = 20


@contextmanager
def drag_withheld() -> Iterator[None]:
    """Every estimator reset in the block is told drag 0 (the delay as given)."""
    reset = FlightEstimator.reset

    def no_drag(self: FlightEstimator, drag: float = 0.0, delay: float = 0.0) -> None:
        reset(self, 0.0, delay)

    FlightEstimator.reset = no_drag  # type: ignore[method-assign]
    try:
        yield
    finally:
        FlightEstimator.reset = reset  # type: ignore[method-assign]


@contextmanager
def prior_told_true() -> Iterator[None]:
    """Every pooled estimator reset in the block places its frames by the episode's true
    delay (the ``delay`` its owner resets it with) before its first estimate."""
    reset = PooledReleaseEstimator.reset

    def told(self: PooledReleaseEstimator, drag: float = 0.0, delay: float = 0.0) -> None:
        reset(self, drag, delay)
        self.fixed_delay = float(delay)

    PooledReleaseEstimator.reset = told  # type: ignore[method-assign]
    try:
        yield
    finally:
        PooledReleaseEstimator.reset = reset  # type: ignore[method-assign]


def catches(controller: str, told: str, level: str, pattern: str, seeds: list[int],
            max_catches: int) -> np.ndarray:  # fmt: skip
    """Mean catches before the first drop of the zero-action episodes of ``seeds``."""
    kw: dict[str, Any] = {}
    env_box: list[CascadeV1Env] = []
    if told.endswith("_start"):
        kw["anchor_start"] = True
        told = told.removesuffix("_start")
    if told in ("true", "anchored"):
        kw["delay_rule"] = lambda flights, gravity: env_box[0].delay
    elif told == "pooled":
        kw.update(delay_rule=pooled_flight_delay, anchor_frames=POOLED_FRAMES)
    env = CascadeV1Env(level=level, pattern=pattern, controller=controller,
                       max_catches=max_catches, **kw)  # fmt: skip
    env_box.append(env)
    blocks = {"no_drag": drag_withheld, "true": prior_told_true}
    block = blocks[told]() if told in blocks else None
    if block is None:
        return np.array([env.play(s)[0] for s in seeds], dtype=np.int64)
    with block:
        return np.array([env.play(s)[0] for s in seeds], dtype=np.int64)


def run(pattern: str, levels: list[str], episodes: int, max_catches: int) -> dict[str, Any]:
    seeds = [SPLIT_SEEDS["val"] + i for i in range(episodes)]
    out: dict[str, Any] = {"pattern": pattern, "split": "val", "episodes": episodes,
                           "max_catches": max_catches, "levels": {}}  # fmt: skip
    for level in levels:
        t0 = time.process_time()
        got = {name: catches(c, nd, level, pattern, seeds, max_catches)
               for name, (c, nd) in ROWS.items()}  # fmt: skip
        lv: dict[str, Any] = {"mean_catches": {k: float(v.mean()) for k, v in got.items()}}
        for name, v in got.items():
            if name != "oracle_catch":
                d = paired_mean_difference(v, got["oracle_catch"], name, "oracle_catch")
                lv[f"{name}_minus_oracle_catch"] = {"value": d.difference, "ci": list(d.ci95)}
        lv["steps"] = []
        for upper, lower, what in STEPS:
            d = paired_mean_difference(got[upper], got[lower], upper, lower)
            lv["steps"].append({"upper": upper, "lower": lower, "what": what,
                                "value": d.difference, "ci": list(d.ci95)})  # fmt: skip
        lv["cpu_s"] = time.process_time() - t0
        out["levels"][level] = lv
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--pattern", default="3")
    ap.add_argument("--levels", nargs="+", default=["medium", "hard"])
    ap.add_argument("--episodes", type=int, default=40)
    ap.add_argument("--max-catches", type=int, default=30)
    args = ap.parse_args(argv)
    doc = run(args.pattern, args.levels, args.episodes, args.max_catches)
    for level, lv in doc["levels"].items():
        for name, mean in lv["mean_catches"].items():
            d = lv.get(f"{name}_minus_oracle_catch")
            diff = (
                ""
                if d is None
                else (
                    f"  minus oracle_catch {d['value']:+.2f} [{d['ci'][0]:+.2f}, {d['ci'][1]:+.2f}]"
                )
            )
            print(f"{args.pattern} {level:7s} {name:24s} {mean:6.2f}{diff}")
        for st in lv["steps"]:
            print(f"{args.pattern} {level:7s} step {st['upper']} - {st['lower']} ({st['what']}): "
                  f"{st['value']:+.2f} [{st['ci'][0]:+.2f}, {st['ci'][1]:+.2f}]")  # fmt: skip
        print(f"{args.pattern} {level:7s} CPU {lv['cpu_s']:.1f} s")
    doc["machine"] = machine()
    print_json(doc)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
