"""When Cascade-v1's catches come: the oracle against the mean-delay juggler (issue 34).

A diagnostic of why the oracle (the true delay and each ball's drag) is no upper
reference on Cascade-v1 (BENCHMARKS.md, *Cascade-v1: when the catches come*). For each
pattern (3, 5), level (easy, medium) and controller (``juggler_oracle``,
``juggler_mean_delay``), the zero-action episodes of the VALIDATION seeds
(``SPLIT_SEEDS["val"] + i``; no test seed is read), at most 30 catches each; from every
catch's ``info["task_error"]`` and ``info["catch_speed"]``: the mean catches per episode,
the median and quartiles of the catch's timing (the catch time minus the hand's planned
catch time), the median meeting speed and the share above 4.5 m/s, and the share of
catches outside a catch phase (untimed). Demonstrations: SIMULATED. About 70 s of CPU.

    python experiments/cascade_v1_catch_timing.py [--episodes 30]
"""

from __future__ import annotations

import argparse

import numpy as np

from motion_envs.datasets.juggling import episode_seeds
from motion_envs.envs.juggling import CascadeV1Env


def catch_timing(pattern: str, level: str, controller: str, episodes: int) -> str:
    """One row of the printed table."""
    env = CascadeV1Env(level=level, pattern=pattern, controller=controller, max_catches=30)
    timing: list[float] = []
    speed: list[float] = []
    catches = []
    for seed in episode_seeds("val", episodes).tolist():
        env.reset(seed=seed)
        done = False
        while not done:
            _, _, terminated, truncated, info = env.step(np.zeros(4, np.float32))
            done = terminated or truncated
            if info["caught"]:
                ok = np.isfinite(info["catch_speed"])
                timing += info["task_error"][ok, 1].tolist()
                speed += info["catch_speed"][ok].tolist()
        catches.append(info["catches"])
    t, s = np.array(timing) * 1000, np.array(speed)
    q1, med, q3 = np.nanpercentile(t, [25, 50, 75])
    return (
        f"{pattern:3s} {level:7s} {controller:19s} {np.mean(catches):6.2f} "
        f"{med:7.1f} [{q1:6.1f}, {q3:6.1f}] {np.median(s):6.2f} {np.mean(s > 4.5):6.2f} "
        f"{np.isnan(t).mean():6.2f} {t.size:6d}"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=30, help="validation episodes per row")
    args = parser.parse_args()
    print("SIMULATED demonstrations; validation seeds")
    print(
        "pat level   controller          catches timing ms [IQR]        speed  >4.5  untimed     n"
    )
    for pattern in ("3", "5"):
        for level in ("easy", "medium"):
            for controller in ("juggler_oracle", "juggler_mean_delay"):
                print(catch_timing(pattern, level, controller, args.episodes), flush=True)


if __name__ == "__main__":
    main()
