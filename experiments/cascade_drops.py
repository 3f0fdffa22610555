"""Why the analytic cascade juggler drops: each drop of its zero-action Cascade-v0 episodes
on TRAINING seeds, put in one of four classes.

The episodes are Cascade-v0's own zero-action episodes
(:meth:`~motion_envs.envs.juggling.CascadeEnv.play`, as
:func:`baselines.juggling_bench.cascade.cascade_episode`), each period's releases and
catches recorded; seeds ``SPLIT_SEEDS["train"] + i`` (never the
test seeds), at most ``--max-catches`` catches. For the dropped ball's last release, with
``thrower`` the hand that released it and ``catcher`` the other hand:

* ``out_of_turn_catch``: a hand caught a ball it had thrown itself (a toss too close to
  vertical came down where the thrower was) from ``OWN_WINDOW`` s before the dropped
  ball's release on: the pattern's turn-taking broke (a hand holds a ball when the other
  hand's arrives, or throws out of turn);
* ``weak_toss``: the thrower's hand left the ball slower than ``WEAK`` of the nominal
  toss's release speed (first thought a toss started from a hand still moving after a
  late catch; played step by step, these were the thrower's own previous, near-vertical
  ball hitting the rising palm, whose deceleration fires the release early: the toss now
  moves aside from that ball, see ``CascadeHand.toss_shift``);
* ``release_angle``: the release direction (ball velocity after the release scatter) was
  more than ``WIDE_DEG`` degrees off the nominal toss's: the tail of the level's release
  angle noise; the catcher reaches near the ball but it misses or bounces off the palm;
* ``other``: none of these.

Prints one line per episode and, as its last line, one JSON object with the class counts,
the catches before the first drop and the CPU seconds. The demonstrations the juggler is
fitted on are SIMULATED.

    python experiments/cascade_drops.py [--level easy] [--episodes 40] [--max-catches 100]
"""

from __future__ import annotations

import argparse
import json
import math
import time
from typing import Any

import numpy as np

from motion_envs.datasets.juggling import SIMULATED_LABEL, SPLIT_SEEDS
from motion_envs.envs.juggling import CascadeEnv
from motion_envs.models.juggling import LEVELS, cascade_fit

#: A release slower than this share of the nominal toss's release speed is "weak".
WEAK = 0.85
#: A release direction this many degrees off the nominal toss's is "wide".
WIDE_DEG = 8.0
#: s before the dropped ball's release from which a catch of a hand's own ball counts.
OWN_WINDOW = 1.0


def play(level: str, seed: int, max_catches: int) -> dict[str, Any]:
    """One zero-action episode (juggler) with its release and catch events."""
    env = CascadeEnv(level=level, max_catches=max_catches)
    releases: list[tuple[float, int, int, np.ndarray, np.ndarray]] = []
    caught: list[tuple[float, int, int]] = []
    last: list[Any] = []

    def record(true: Any) -> None:
        for h in range(2):
            if true.released[h] >= 0:
                b = true.released[h]
                releases.append((true.time, h, b, true.ball_vel[b].copy(), true.hand_vel[h]))
            if true.caught[h] >= 0:
                caught.append((true.time, h, true.caught[h]))
        last[:] = [true]

    catches, _, _, _ = env.play(seed, record)
    dropped = [i for i, d in enumerate(last[0].dropped) if d]
    return {
        "catches": catches,
        "dropped": dropped[0] if dropped else None,
        "releases": releases,
        "caught": caught,
    }


def classify(ep: dict[str, Any], nominal_velocity: np.ndarray) -> dict[str, Any] | None:
    """The drop's class and the dropped ball's last release (module docstring)."""
    ball = ep["dropped"]
    if ball is None:
        return None
    t_release, thrower, _, v_ball, v_hand = [r for r in ep["releases"] if r[2] == ball][-1]
    nominal = nominal_velocity * (1.0 if thrower == 0 else -1.0, 1.0)
    speed = float(np.linalg.norm(v_hand) / np.linalg.norm(nominal))
    angle = math.degrees(math.atan2(v_ball[0], v_ball[1]) - math.atan2(nominal[0], nominal[1]))
    own = []
    for t, h, b in ep["caught"]:
        before = [r for r in ep["releases"] if r[2] == b and r[0] < t]
        if before and before[-1][1] == h and t >= t_release - OWN_WINDOW:
            own.append(round(t, 3))
    if own:
        kind = "out_of_turn_catch"
    elif speed < WEAK:
        kind = "weak_toss"
    elif abs(angle) > WIDE_DEG:
        kind = "release_angle"
    else:
        kind = "other"
    return {"class": kind, "hand_speed_ratio": speed, "angle_deg": angle, "own_catches": own}


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Play, classify, print."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--level", default="easy", choices=list(LEVELS))
    ap.add_argument("--episodes", type=int, default=40, help="training episodes")
    ap.add_argument("--max-catches", type=int, default=100, help="episode ends after this")
    args = ap.parse_args(argv)
    if args.episodes < 1:
        ap.error(f"--episodes must be >= 1; got {args.episodes}")
    if args.max_catches < 1:
        ap.error(f"--max-catches must be >= 1; got {args.max_catches}")
    t0 = time.process_time()
    nominal_velocity = cascade_fit(9.81).pattern.release_velocity
    counts: dict[str, int] = {}
    catches = []
    for k in range(args.episodes):
        seed = SPLIT_SEEDS["train"] + k
        ep = play(args.level, seed, args.max_catches)
        catches.append(ep["catches"])
        c = classify(ep, nominal_velocity)
        if c is None:
            print(f"seed {seed}: {ep['catches']} catches, no drop")
            continue
        counts[c["class"]] = counts.get(c["class"], 0) + 1
        print(
            f"seed {seed}: {ep['catches']} catches, {c['class']} (hand speed at the release "
            f"{c['hand_speed_ratio']:.2f} of nominal, direction {c['angle_deg']:+.1f} deg, "
            f"own-ball catches at {c['own_catches']} s)"
        )
    doc = {
        "demonstrations": SIMULATED_LABEL,
        "level": args.level,
        "seeds": {"split": "train", "first": SPLIT_SEEDS["train"], "count": args.episodes},
        "max_catches": args.max_catches,
        "catches_median": float(np.median(catches)),
        "reached_max": int(np.sum(np.asarray(catches) >= args.max_catches)),
        "drops_by_class": counts,
        "cpu_s": time.process_time() - t0,
    }
    print(json.dumps(doc))
    return doc


if __name__ == "__main__":
    main()
