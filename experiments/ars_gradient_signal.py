"""Is there a gradient for ARS to follow? The split-half reliability of its
finite-difference estimates on the juggling blocks (issue 34).

ARS (``baselines/agents/ars.py``) steps its linear policy ``W`` along directions
``delta`` weighted by the return difference ``d = R(W + s delta) - R(W - s delta)`` of one
paired episode (both candidates on the same reset seed). Here ``W = 0`` (the policy at the
start of training, i.e. the base controller) and, for each of ``--directions`` random
directions, ``d`` is measured twice, on two different TRAINING seeds ``a`` and ``b``. If
the direction changes the expected return, ``d_a`` and ``d_b`` share that change and are
correlated across directions; if ``d`` is only the episode's own noise (a catch won or lost
by chance), the correlation is 0. The split-half correlation ``r = corr(d_a, d_b)`` is the
fraction of ``d``'s variance that is the direction's effect (the signal), so ``r`` near 0
says an ARS update, which sums a few such ``d``, is a random walk.

The candidates are played as sb3-contrib's ``LinearPolicy`` plays them on ``VecNormalize``d
observations: ``a = clip(W z, -1, 1)``, ``z = clip((o - mu) / sigma, -10, 10)``, with
``mu, sigma`` the observation's mean and std over ``--norm-episodes`` zero-action episodes
on training seeds (a fixed normaliser, where ARS's keeps updating; no bias). ``s`` is
ARS's ``delta_std`` (0.025 in ``configs/agents/ars.yaml``) and a four times larger one.
Every seed is a training seed (below ``SPLIT_SEEDS["val"]``). The demonstrations
(the likeness reward term) are SIMULATED.

    python experiments/ars_gradient_signal.py [--block cascade|cascade_late|drift]
        [--directions 40] [--stds 0.025 0.1] [--out results.json]
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from scipy import stats
from tqdm import tqdm

import motion_envs  # noqa: F401  (registers the ids)
from motion_envs._io import atomic_write_text

#: The env id and keywords of each block: ``configs/agents/ars.yaml``'s Cascade-v1 and
#: Juggling-v2 blocks, and the Cascade-v1 block on the best non-oracle row (late_meeting:
#: the mean-delay juggler told +80 ms, chosen on validation by ``motion-bench juggling
#: --version v2 --pattern 3``).
BLOCKS: dict[str, tuple[str, dict[str, Any]]] = {
    "cascade": (
        "MotionEnvs/Cascade-v1",
        {
            "level": "medium",
            "pattern": "3",
            "controller": "juggler_mean_delay_catch",
            "max_catches": 10,
            "residual_scale": 0.1,
            "residual_phases": ["catch"],
            "observe_task_error": True,
        },
    ),
    "cascade_late": (
        "MotionEnvs/Cascade-v1",
        {
            "level": "medium",
            "pattern": "3",
            "controller": "juggler_mean_delay",
            "delay_offset": 0.08,
            "max_catches": 10,
            "residual_scale": 0.1,
            "residual_phases": ["catch"],
            "observe_task_error": True,
        },
    ),
    "drift": (
        "MotionEnvs/Juggling-v2",
        {
            "level": "drift",
            "controller": "juggler_mean_delay_catch",
            "max_catches": 3,
            "residual_scale": 0.1,
            "residual_phases": ["catch"],
            "observe_task_error": True,
        },
    ),
}


def play(
    env: gym.Env[Any, Any], seed: int, weights: np.ndarray, norm: tuple[np.ndarray, np.ndarray]
) -> tuple[float, int]:
    """Return and catches of one episode of ``a = clip(W z, -1, 1)``."""
    mu, sigma = norm
    obs, info = env.reset(seed=seed)
    total, done = 0.0, False
    while not done:
        z = np.clip((np.asarray(obs, dtype=np.float64) - mu) / sigma, -10.0, 10.0)
        action = np.clip(weights @ z, -1.0, 1.0).astype(np.float32)
        obs, reward, terminated, truncated, info = env.step(action)
        total += float(reward)
        done = terminated or truncated
    return total, int(info["catches"])


def normaliser(env: gym.Env[Any, Any], seeds: range) -> tuple[np.ndarray, np.ndarray]:
    """The observation's mean and std (floored at 1e-8, as VecNormalize's epsilon) over
    the zero action's episodes on ``seeds``."""
    rows: list[np.ndarray] = []
    for s in seeds:
        obs, _ = env.reset(seed=s)
        rows.append(np.asarray(obs, dtype=np.float64))
        done = False
        while not done:
            obs, _, terminated, truncated, _ = env.step(
                np.zeros(env.action_space.shape, np.float32)
            )
            rows.append(np.asarray(obs, dtype=np.float64))
            done = terminated or truncated
    data = np.stack(rows)
    return data.mean(axis=0), np.sqrt(data.var(axis=0) + 1e-8)


def run(
    block: str, directions: int, stds: list[float], norm_episodes: int, seed: int
) -> dict[str, Any]:
    env_id, kwargs = BLOCKS[block]
    env = gym.make(env_id, **kwargs)
    rng = np.random.default_rng(seed)
    start = time.process_time()
    norm = normaliser(env, range(10_000, 10_000 + norm_episodes))
    n_act = int(np.prod(env.action_space.shape))
    n_obs = int(np.prod(env.observation_space.shape))
    out: dict[str, Any] = {"block": block, "env_id": env_id, "env_kwargs": kwargs, "stds": {}}
    zero = np.zeros((n_act, n_obs))
    base = np.array([play(env, 20_000 + k, zero, norm) for k in range(2 * directions)])
    out["base_return_mean"] = float(base[:, 0].mean())
    out["base_return_std"] = float(base[:, 0].std(ddof=1))
    out["base_mean_catches"] = float(base[:, 1].mean())
    for std in stds:
        d = np.zeros((directions, 2))
        catches = np.zeros((directions, 2, 2))
        for k in tqdm(range(directions), desc=f"{block} std {std}"):
            delta = rng.standard_normal((n_act, n_obs))
            for half in range(2):
                s = 20_000 + 2 * k + half  # training seeds, one per (direction, half)
                rp, cp = play(env, s, std * delta, norm)
                rm, cm = play(env, s, -std * delta, norm)
                d[k, half] = rp - rm
                catches[k, half] = cp, cm
        r, p = stats.pearsonr(d[:, 0], d[:, 1]) if d.std() > 0 else (float("nan"), float("nan"))
        boot = []
        for _ in range(2000):
            i = rng.integers(0, directions, directions)
            a, b = d[i, 0], d[i, 1]
            if a.std() > 0 and b.std() > 0:
                boot.append(float(np.corrcoef(a, b)[0, 1]))
        out["stds"][str(std)] = {
            "split_half_r": float(r),
            "r_ci": [float(np.quantile(boot, q)) if boot else float("nan") for q in (0.025, 0.975)],
            "p_value": float(p),
            "fraction_d_nonzero": float(np.mean(np.abs(d) > 1.0)),
            "mean_abs_d": float(np.mean(np.abs(d))),
            "mean_catches_plus_minus": float(catches.mean()),
            "catches": catches.tolist(),
            "d": d.tolist(),
        }
    out["cpu_s"] = time.process_time() - start
    env.close()
    return out


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--block", choices=sorted(BLOCKS), default="cascade")
    p.add_argument("--directions", type=int, default=40)
    p.add_argument("--stds", type=float, nargs="+", default=[0.025, 0.1])
    p.add_argument("--norm-episodes", type=int, default=10)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--out", type=Path, default=None)
    a = p.parse_args()
    res = run(a.block, a.directions, a.stds, a.norm_episodes, a.seed)
    print(
        f"{res['block']}: base return {res['base_return_mean']:.1f} "
        f"(sd {res['base_return_std']:.1f}), mean catches {res['base_mean_catches']:.2f} on the "
        f"same seeds; CPU {res['cpu_s']:.0f} s"
    )
    for std, m in res["stds"].items():
        print(
            f"  delta_std {std}: split-half r {m['split_half_r']:+.3f} "
            f"[{m['r_ci'][0]:+.3f}, {m['r_ci'][1]:+.3f}] (p {m['p_value']:.3f}); "
            f"|d| > 1 in {m['fraction_d_nonzero']:.0%} of pairs, mean |d| {m['mean_abs_d']:.1f}; "
            f"mean catches {m['mean_catches_plus_minus']:.2f}"
        )
    if a.out is not None:
        atomic_write_text(a.out, json.dumps(res, indent=1))


if __name__ == "__main__":
    main()
