"""What a trained Juggling-v1 agent does: its corrections of the analytic juggler.

Plays ``--episodes`` episodes of the run's environment (its env kwargs, e.g. ``level:
medium``) with the agent (best checkpoint) on the seeds of ``--split`` (default the
validation seeds: what the agent does is read where nothing is chosen; the test seeds
give the same picture) and records, at every step, the residual the agent adds to the
juggler's hand target (metres: ``residual_scale * action``), the phase, the time in the
phase and the newest (delayed) ball measurement (the residual is the one the hand got: none
outside the run's ``residual_phases``). Writes ``corrections.png``: the
residual's horizontal and vertical parts over the time in the catch phase (every episode
a thin line, the median in black), and, in the catch phase, the vertical residual against
``v_z * latency``: how far the ball fell during the sensor's delay (what the
latency-aware juggler adds to its prediction). Prints the residual's mean and spread per
phase and, in the catch phase, the least-squares slope of the residual on
``v * latency`` (1 would be the latency-aware juggler's shift of the ball's position)
and their correlation.

    python experiments/juggling_v1_agent_corrections.py RUN_DIR [--episodes 50] [--out DIR]
        [--env-kwargs '{"level": "medium", "max_catches": 3, "residual_scale": 0.15}']
"""

from __future__ import annotations

import argparse
import json
from collections.abc import Callable
from pathlib import Path

import gymnasium as gym
import numpy as np

import motion_envs  # noqa: F401  (registers the environments)
from baselines.agents.rundir import load_run
from baselines.plots import new_figure
from motion_envs._io import atomic_write_text, save_figure
from motion_envs.datasets.juggling import PHASES, SPLIT_SEEDS

ENV_ID = "MotionEnvs/Juggling-v1"
#: Index of the newest ball measurement's velocity ``vx, vz`` in the observation.
BALL_VELOCITY = slice(17, 19)


def checkpoint_policy(run_dir: str) -> Callable[[np.ndarray], np.ndarray]:
    """The deterministic policy of ``RUN_DIR/agent.zip`` (the validation-chosen checkpoint
    SB3's callback saves during training) with ``normalization.npz``: for a run stopped
    before ``motion-bench train`` wrote its ``run.json``."""
    from stable_baselines3 import PPO

    from baselines.agents.rundir import ObsNormalizer

    model = PPO.load(Path(run_dir) / "agent.zip", device="cpu")
    normalizer = ObsNormalizer.load(Path(run_dir) / "normalization.npz")

    def policy(obs: np.ndarray) -> np.ndarray:
        action, _ = model.predict(normalizer(obs), deterministic=True)
        return np.asarray(action, dtype=np.float32)

    return policy


def play(
    run_dir: str, split: str, episodes: int, env_kwargs: dict[str, object] | None = None
) -> dict[str, np.ndarray]:
    """Per step of all episodes: residual (m), phase index, time in phase, ball velocity.
    ``env_kwargs`` given: the run has no ``run.json`` (:func:`checkpoint_policy`)."""
    if env_kwargs is None:
        loaded = load_run(run_dir)
        predict, env = loaded.predict, gym.make(loaded.env_id, **loaded.env_kwargs)
    else:
        predict, env = checkpoint_policy(run_dir), gym.make(ENV_ID, **env_kwargs)
    scale = env.unwrapped.residual_scale
    rows: dict[str, list[object]] = {k: [] for k in ("res", "phase", "t", "v", "ep")}
    for i in range(episodes):
        obs, _ = env.reset(seed=SPLIT_SEEDS[split] + i)
        done = False
        while not done:
            action = np.clip(predict(obs[None])[0], -1.0, 1.0)
            rows["v"].append(obs[BALL_VELOCITY].astype(np.float64))
            rows["ep"].append(i)
            obs, _, terminated, truncated, _ = env.step(action)
            done = terminated or truncated
            # the phase the step's target belonged to (the controller's after its command)
            # and the residual the hand got in it (none outside the env's residual_phases)
            controller = env.unwrapped.synced_controller()
            phase = PHASES.index(controller.phase)
            rows["res"].append(scale * action * env.unwrapped.residual_acts[phase])
            rows["phase"].append(phase)
            rows["t"].append(controller.phase_time)
    out = {k: np.asarray(v) for k, v in rows.items()}
    out["latency"] = np.array(env.unwrapped.delay_steps * env.unwrapped.dt)
    return out


def summarise(d: dict[str, np.ndarray]) -> dict[str, object]:
    """Mean and std of the residual per phase; in the catch phase, slope and correlation
    of the residual on ``v * latency``."""
    out: dict[str, object] = {"latency_s": float(d["latency"])}
    for k, name in enumerate(PHASES):
        r = d["res"][d["phase"] == k]
        if r.size:
            out[name] = {
                "mean_m": r.mean(axis=0).tolist(),
                "std_m": r.std(axis=0).tolist(),
                "steps": int(r.shape[0]),
            }
    catch = d["phase"] == PHASES.index("catch")
    shift = d["v"][catch] * float(d["latency"])
    for axis, name in ((0, "x"), (1, "z")):
        x, y = shift[:, axis], d["res"][catch, axis]
        if x.std() > 0 and y.std() > 0:
            slope = float(np.polyfit(x, y, 1)[0])
            out[f"catch_{name}_slope_on_v_latency"] = slope
            out[f"catch_{name}_correlation"] = float(np.corrcoef(x, y)[0, 1])
    return out


def plot(d: dict[str, np.ndarray], path: Path, title: str) -> Path:
    """``corrections.png`` (see the module docstring)."""
    fig = new_figure(12, 3.6)
    axes = fig.subplots(1, 3)
    catch = d["phase"] == PHASES.index("catch")
    for axis, (ax, name) in enumerate(zip(axes[:2], ("horizontal", "vertical"), strict=True)):
        for ep in np.unique(d["ep"][catch])[:40]:
            m = catch & (d["ep"] == ep)
            ax.plot(d["t"][m], 1000 * d["res"][m, axis], lw=0.4, alpha=0.35, color="tab:blue")
        t = d["t"][catch]
        bins = np.linspace(0, t.max() if t.size else 1, 25)
        idx = np.digitize(t, bins)
        med = [np.median(d["res"][catch][idx == b, axis]) for b in range(1, len(bins))]
        ax.plot(bins[:-1], 1000 * np.asarray(med), color="black", lw=2, label="median")
        ax.axhline(0, color="grey", lw=0.5)
        ax.set_xlabel("time in the catch phase (s)")
        ax.set_ylabel(f"{name} residual (mm)")
        ax.legend(loc="best", fontsize=8)
    ax = axes[2]
    lat = float(d["latency"])
    ax.scatter(1000 * d["v"][catch, 1] * lat, 1000 * d["res"][catch, 1], s=1, alpha=0.2)
    ax.set_xlabel(f"ball v_z x latency ({lat * 1000:.0f} ms), mm")
    ax.set_ylabel("vertical residual (mm)")
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    return save_figure(fig, path, dpi=110)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("run_dir")
    p.add_argument("--split", default="val", choices=sorted(SPLIT_SEEDS))
    p.add_argument("--episodes", type=int, default=50)
    p.add_argument("--out", default=None, help="folder (default: RUN_DIR)")
    p.add_argument(
        "--env-kwargs",
        default=None,
        help="JSON env kwargs: play RUN_DIR/agent.zip of a run without run.json",
    )
    args = p.parse_args()
    kwargs = None if args.env_kwargs is None else json.loads(args.env_kwargs)
    d = play(args.run_dir, args.split, args.episodes, kwargs)
    out = Path(args.out or args.run_dir)
    summary = summarise(d)
    title = (
        f"Juggling-v1 agent {Path(args.run_dir).name}: residual on the analytic juggler, "
        f"{args.episodes} {args.split} episodes (SIMULATED demonstrations)"
    )
    path = plot(d, out / "corrections.png", title)
    atomic_write_text(out / "corrections.json", json.dumps(summary, indent=2) + "\n")
    print(json.dumps(summary, indent=2))
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
