"""Why Cascade-v1's controllers drop the five-ball cascade: every catch, bounce and drop of
their zero-action episodes on TRAINING seeds (issue 34).

For each controller and level, ``--episodes`` TRAINING episodes (seeds
``SPLIT_SEEDS["train"] + i``; never a validation or test seed) of ``MotionEnvs/Cascade-v1``
with ``pattern=--pattern`` are played period by period with the zero action, at most
``--max-catches`` catches. Recorded:

* per catch: the meeting speed (``info["catch_speed"]``: the palm and the ball at the
  step their contact began), the timing (the catch time minus the hand's planned catch
  time) and the palm's vertical velocity at the period's start;
* per BOUNCE (a flying ball whose vertical velocity turns from falling to rising in a
  period without being released: the palm threw it back): the speed at which the nearest
  palm met it (relative speed at the period's start), whether that palm held a ball
  (a busy hand), and the palm's vertical velocity;
* per DROP, its class: ``bounced`` (the dropped ball bounced off a palm since its last
  release: ``bounced_fast`` if the relative speed was at or above the level's
  ``capture_speed``, ``bounced_busy`` if the palm held another ball,
  ``bounced_slow`` otherwise: an edge or a contact the capture rule refused for
  another reason) or ``missed`` (it never touched a palm; its ``miss_error`` offset
  and timing at its closest approach to a hand in its catch phase, or ``unseen`` when
  it fell past none).

Prints one line per controller and level and, as its last line, one JSON object
(``--out FILE`` also writes it). The demonstrations are SIMULATED.

    python experiments/cascade_v1_five_drops.py [--pattern 5] [--levels easy,medium,hard]
        [--controllers juggler_oracle_catch,juggler_mean_delay,juggler_delay_estimator]
        [--episodes 40] [--max-catches 30] [--out FILE]
"""

from __future__ import annotations

import argparse
import json
import math
import time
from typing import Any

import numpy as np
from tqdm import tqdm

from motion_envs._io import atomic_write_text
from motion_envs.datasets.juggling import CASCADE_HANDS, SIMULATED_LABEL, episode_seeds
from motion_envs.envs.juggling import CascadeV1Env
from motion_envs.models.juggling import CASCADE_V1_LEVELS, V2_LEVELS

DEFAULT_CONTROLLERS = "juggler_oracle_catch,juggler_mean_delay,juggler_delay_estimator"


def episode(env: CascadeV1Env, seed: int) -> dict[str, Any]:
    """One zero-action episode with its catches, bounces and drop (module docstring)."""
    env.reset(seed=seed)
    zero = np.zeros((CASCADE_HANDS, 2))
    nh = 2 * CASCADE_HANDS
    cap = V2_LEVELS[env.level].capture_speed
    catches: list[dict[str, float]] = []
    bounces: list[dict[str, Any]] = []
    bounced: dict[int, list[dict[str, Any]]] = {}
    while True:
        q, v = env.data.qpos.copy(), env.data.qvel.copy()
        holder_before = list(env.world.holder[0])
        true = env._advance(zero)
        for h, b in enumerate(true.caught):
            if b >= 0:
                catches.append(
                    {
                        "speed": float(env._errors[1][h]),
                        "timing": float(env._errors[0][h, 1]),
                        "hand_vz": float(v[2 * h + 1]),
                    }
                )
        for b in true.released:
            if b >= 0:
                bounced.pop(b, None)
        for b in range(env.balls):
            c = nh + 2 * b
            if holder_before[b] >= 0 or true.holder[b] >= 0 or b in true.released:
                continue
            if v[c + 1] < 0 <= true.ball_vel[b, 1]:
                d = [math.hypot(q[c] - q[2 * h], q[c + 1] - q[2 * h + 1]) for h in range(2)]
                h = int(np.argmin(d))
                rel = math.hypot(v[c] - v[2 * h], v[c + 1] - v[2 * h + 1])
                event = {
                    "speed": rel,
                    "hand_vz": float(v[2 * h + 1]),
                    "busy": h in holder_before,
                    "fast": rel >= cap,
                }
                bounces.append(event)
                bounced.setdefault(b, []).append(event)
        terminated, truncated = env._episode_end(true.any_dropped, true.time)
        if terminated or truncated:
            break
    drop: dict[str, Any] | None = None
    if terminated:
        b = next(i for i, d in enumerate(true.dropped) if d)
        if b in bounced:
            first = bounced[b][0]
            kind = "bounced_busy" if first["busy"] else (
                "bounced_fast" if first["fast"] else "bounced_slow")  # fmt: skip
            drop = {"class": kind, "speed": first["speed"]}
        else:
            miss = env._misses.miss(true)
            if miss:
                off, timing = (float(x) for x in miss["miss_error"])
                drop = {"class": "missed", "offset": off, "timing": timing,
                        "speed": float(miss["miss_speed"])}  # fmt: skip
            else:
                drop = {"class": "unseen"}
    return {"catches": env._catches, "catch": catches, "bounces": bounces, "drop": drop}


def summarise(eps: list[dict[str, Any]], cap: float) -> dict[str, Any]:
    """Per controller and level: mean catches, the catches' meeting speeds and timings,
    the bounces, the drops by class (module docstring)."""
    catch = [c for e in eps for c in e["catch"]]
    speed = np.array([c["speed"] for c in catch])
    timing = np.array([c["timing"] for c in catch]) * 1000.0
    hand_vz = np.array([c["hand_vz"] for c in catch])
    bounces = [b for e in eps for b in e["bounces"]]
    drops: dict[str, int] = {}
    for e in eps:
        if e["drop"] is not None:
            drops[e["drop"]["class"]] = drops.get(e["drop"]["class"], 0) + 1
    missed = [e["drop"] for e in eps if e["drop"] and e["drop"]["class"] == "missed"]

    def q(a: np.ndarray) -> list[float]:
        a = a[np.isfinite(a)]
        return [float(x) for x in np.percentile(a, [25, 50, 75])] if a.size else []

    return {
        "episodes": len(eps),
        "mean_catches": float(np.mean([e["catches"] for e in eps])),
        "catches": int(speed.size),
        "catch_speed_quartiles": q(speed),
        "catch_speed_share_above_4_5": float(np.mean(speed > 4.5)) if speed.size else math.nan,
        "catch_timing_ms_quartiles": q(timing),
        "catch_hand_vz_quartiles": q(hand_vz),
        "bounces": len(bounces),
        "bounces_fast": sum(b["fast"] for b in bounces),
        "bounces_busy": sum(b["busy"] for b in bounces),
        "bounce_speed_quartiles": q(np.array([b["speed"] for b in bounces])),
        "bounce_hand_vz_quartiles": q(np.array([b["hand_vz"] for b in bounces])),
        "drops_by_class": drops,
        "missed_timing_ms_quartiles": q(np.array([m["timing"] for m in missed]) * 1000.0),
        "missed_offset_m_quartiles": q(np.array([m["offset"] for m in missed])),
        "capture_speed": cap,
    }


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Play, classify, print."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pattern", default="5")
    ap.add_argument("--levels", default=",".join(CASCADE_V1_LEVELS))
    ap.add_argument("--controllers", default=DEFAULT_CONTROLLERS)
    ap.add_argument("--episodes", type=int, default=40, help="TRAINING episodes per row")
    ap.add_argument("--max-catches", type=int, default=30)
    ap.add_argument("--out", default=None)
    args = ap.parse_args(argv)
    if args.episodes < 1 or args.max_catches < 1:
        ap.error("--episodes and --max-catches must be >= 1")
    t0 = time.process_time()
    seeds = episode_seeds("train", args.episodes).tolist()
    doc: dict[str, Any] = {"demonstrations": SIMULATED_LABEL, "split": "train",
                           "pattern": args.pattern, "episodes": args.episodes,
                           "max_catches": args.max_catches, "results": {}}  # fmt: skip
    for level in args.levels.split(","):
        for controller in args.controllers.split(","):
            env = CascadeV1Env(level=level, pattern=args.pattern, controller=controller,
                               max_catches=args.max_catches)  # fmt: skip
            eps = [episode(env, int(s)) for s in tqdm(seeds, desc=f"{level} {controller}")]
            s = summarise(eps, V2_LEVELS[level].capture_speed)
            doc["results"][f"{level} {controller}"] = s
            print(f"{level:7s} {controller:25s} catches {s['mean_catches']:5.2f}; meeting "
                  f"speed q {s['catch_speed_quartiles']}; timing ms q "
                  f"{s['catch_timing_ms_quartiles']}; bounces {s['bounces']} (fast "
                  f"{s['bounces_fast']}, busy {s['bounces_busy']}, speed q "
                  f"{s['bounce_speed_quartiles']}); drops {s['drops_by_class']}; missed "
                  f"timing ms q {s['missed_timing_ms_quartiles']}, offset m q "
                  f"{s['missed_offset_m_quartiles']}", flush=True)  # fmt: skip
    doc["cpu_s"] = time.process_time() - t0
    if args.out:
        atomic_write_text(args.out, json.dumps(doc, indent=2) + "\n")
    print(json.dumps(doc))
    return doc


if __name__ == "__main__":
    main()
