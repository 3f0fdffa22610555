"""Five-ball demonstrations against the hand's limits, and what the juggler fitted on them
does (a diagnosis on TRAINING seeds; no test seeds are used).

For each variant of the SIMULATED five-ball population (``registered``: the population
``pattern="5"`` is fitted on; ``follow-top``: the same draws with the hand meeting the
ball moving (``CascadeStyle.catch_follow``), going on to its toss's top after the release
(``toss_to_top``) and a narrower pattern, see ``VARIANTS``) it prints:

* the demonstrations' peak hand speed and acceleration (noise-free, two persons, the
  fit's seed) against Cascade-v0's 6 m/s and 120 m/s^2, and the 99th percentile of the
  acceleration per phase;
* the demonstrations' nominal release speed and flight against the fitted juggler's
  (``cascade_fit(g, 5).pattern``: its toss's release speed and flight);
* the juggler's catches before the first drop on ``easy`` over ``--episodes`` TRAINING
  seeds (``episode_seeds("train", n)``; at most ``--max-catches``), pattern ``5``.

Then one JSON object with the figures. ``python experiments/five_ball_demos.py
--episodes 20``: about 40 s wall on a loaded machine.
"""

from __future__ import annotations

import argparse
import json
import math
from collections.abc import Callable
from dataclasses import replace
from typing import Any

import numpy as np

import motion_envs.datasets.juggling._cascade_demos as demos_module
from baselines.juggling_bench.cascade import cascade_episode
from motion_envs.datasets.juggling import (
    CASCADE_STYLES,
    CascadeStyle,
    JugglingTask,
    episode_seeds,
    generate_cascade_demonstrations,
    style_timing,
)
from motion_envs.models.juggling import cascade_fit
from motion_envs.models.juggling._fit import FIT_SEED

GRAVITY = 9.81
#: Each variant's changes to the registered population's draws (None: unchanged).
VARIANTS: dict[str, dict[str, Any] | None] = {
    "registered": None,
    "follow-top": {
        "home": (0.12, 1.1),
        "toss": (-0.03, 0.4974),
        "toss_time": 0.178,
        "brake": -64.44,
        "catch_drop": -0.0574,
        "catch_follow": 0.1754,
        "catch_share": 0.444,
        "wait": (-0.0222, 0.0422),
        "dwell_ratio": 0.6797,
        "toss_vx": -0.6,
        "toss_to_top": True,
    },
}


def _population(changes: dict[str, Any]) -> Callable[[np.random.Generator], CascadeStyle]:
    base = CASCADE_STYLES[5]

    def person(rng: np.random.Generator) -> CascadeStyle:
        return replace(base(rng), **changes)

    return person


def measure(name: str, episodes: int, max_catches: int) -> dict[str, Any]:
    """One variant's figures (module docstring)."""
    changes = VARIANTS[name]
    original = CASCADE_STYLES[5]
    if changes is not None:
        demos_module.CASCADE_STYLES[5] = _population(changes)
    cascade_fit.cache_clear()
    try:
        task = JugglingTask(gravity=GRAVITY)
        demos = generate_cascade_demonstrations(
            n_persons=2, seed=FIT_SEED, task=task, balls=5, sensor_noise=0.0
        )
        dt = task.dt
        speed, accel = 0.0, 0.0
        per_phase: dict[str, list[np.ndarray[Any, Any]]] = {}
        for rec in demos.recordings:
            v = np.diff(rec.hand, axis=0) / dt
            a = np.linalg.norm(np.diff(v, axis=0) / dt, axis=1)
            speed = max(speed, float(np.linalg.norm(v, axis=1).max()))
            accel = max(accel, float(a.max()))
            assert rec.phase is not None  # simulated recordings carry their phases
            phase = rec.phase[1:-1]
            for p in ("toss", "go_down", "catch", "return"):
                per_phase.setdefault(p, []).append(a[phase == p])
        p99 = {p: float(np.percentile(np.concatenate(x), 99)) for p, x in per_phase.items()}
        seq = np.random.SeedSequence(FIT_SEED).spawn(1)[0]
        style = demos_module.CASCADE_STYLES[5](np.random.default_rng(seq))
        toss, timing = style_timing(style, task, 5)
        pattern = cascade_fit(GRAVITY, 5).pattern
        seeds = episode_seeds("train", episodes)
        catches = [
            cascade_episode("easy", "juggler", int(s), max_catches, GRAVITY, "5")[0] for s in seeds
        ]
    finally:
        demos_module.CASCADE_STYLES[5] = original
        cascade_fit.cache_clear()
    return {
        "variant": name,
        "peak_speed": speed,
        "peak_acceleration": accel,
        "acceleration_p99_by_phase": p99,
        "demo_release_speed": float(toss.velocity[1]),
        "demo_flight": timing.flight,
        "fitted_release_speed": float(pattern.release_velocity[1]),
        "fitted_flight": pattern.flight,
        "train_catches": catches,
        "train_catches_median": float(np.median(catches)),
    }


def main(argv: list[str] | None = None) -> None:
    """Print the table and the JSON (module docstring)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=10, help="TRAINING seeds per variant")
    parser.add_argument("--max-catches", type=int, default=100)
    args = parser.parse_args(argv)
    if args.episodes < 1 or args.max_catches < 1:
        parser.error("--episodes and --max-catches must be >= 1")
    rows = [measure(name, args.episodes, args.max_catches) for name in VARIANTS]
    print("variant     | peak m/s | peak m/s^2 | release demo/fit m/s | flight demo/fit s | "
          "easy catches (train median)")  # fmt: skip
    for r in rows:
        print(
            f"{r['variant']:<11} | {r['peak_speed']:8.2f} | {r['peak_acceleration']:10.0f} | "
            f"{r['demo_release_speed']:.2f} / {r['fitted_release_speed']:.2f}         | "
            f"{r['demo_flight']:.3f} / {r['fitted_flight']:.3f}     | "
            f"{r['train_catches_median']:g} {r['train_catches']}"
        )
    print(json.dumps({"gravity": GRAVITY, "split": "train", "rows": rows}, default=float))
    assert all(math.isfinite(r["fitted_flight"]) for r in rows)


if __name__ == "__main__":
    main()
