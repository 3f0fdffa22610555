"""
Tutorial: train an agent and compare it with the nominal
========================================================

An agent of this project acts *on top of* an analytic model: its action is a residual
added to the nominal (the model's prediction), so the zero action is the model. The
evaluation protocol (see *Protocol: intervals and verdicts*) asks one question: on people
the agent never saw, is its error criterion lower than the nominal's, by more than the
spread between people? This tutorial runs the whole protocol with a tiny budget (2,000
steps of PPO, a minute of CPU); the published runs use 100,000 steps and 5 seeds (see
*Agents: train, evaluate, sweep*). Needs the ``rl`` extra.

The three steps are the two commands ``motion-bench train`` and ``motion-bench agent``
and a look at what they wrote.
"""

# %%
# 1. Hyper-parameters
# -------------------
# ``configs/agents/ppo.yaml`` holds the published ones, keyed by environment id. A file of
# your own overrides them key by key; here the rollout and the validation interval are
# made small enough for 2,000 steps (the checkpoint is still chosen on the validation
# person, never on the test people).
import json
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import pandas as pd

from baselines.stats import compare_errors

work = Path(sys.argv[1] if len(sys.argv) > 1 else tempfile.mkdtemp())
config = work / "ppo_tiny.yaml"
config.write_text(
    "default:\n"
    "  n_timesteps: 2000\n  n_envs: 2\n  policy: MlpPolicy\n"
    "  normalize: {obs: true, reward: true}\n  action_head_scale: 0.0\n"
    "  eval_freq: 500\n  n_steps: 100\n  batch_size: 100\n  n_epochs: 2\n"
    "  policy_kwargs: {net_arch: {pi: [32, 32], vf: [32, 32]}, log_std_init: -2.0}\n"
    "MotionEnvs/OrientationReach-v1:\n"
    "  env_kwargs: {nominal: bezier-null, val_fraction: 0.2}\n"
)


def motion_bench(*args: str) -> str:
    """Run ``motion-bench ARGS`` as a user would and return what it printed."""
    cmd = [sys.executable, "-m", "baselines.cli", *args]
    return subprocess.run(cmd, check=True, capture_output=True, text=True).stdout


# %%
# 2. Train
# --------
# The policy starts at the nominal (its action head is zeroed). Every ``eval_freq`` steps
# the deterministic policy is scored on the validation split with the paper's criterion
# (median over episodes of the max error over time, radians); the best is kept as
# ``agent.zip``.
run = work / "ppo-o1"
motion_bench(
    "train", "--algo", "ppo", "--env", "MotionEnvs/OrientationReach-v1", "--seed", "0",
    "--config", str(config), "--out", str(run), "--no-progress", "--no-tensorboard",
)  # fmt: skip
print(sorted(p.name for p in run.iterdir()))

# %%
# 3. Compare with the nominal on the test people
# ----------------------------------------------
# ``motion-bench agent`` scores the kept policy and the zero-action nominal on the same
# test episodes and prints the ratio of their criteria (below 1: the agent is better),
# its 95 % interval with *people* resampled (the trajectories of one person are not
# independent), the win count over people and the verdict.
print(motion_bench("agent", str(run), "--split", "test"))
results = json.loads((run / "eval-test" / "results.json").read_text())
print("ratio", round(results["ratio"], 4), "interval", np.round(results["ratio_ci"], 4))
print(results["verdict"])

# %%
# The same comparison by hand
# ---------------------------
# ``results.csv`` has one row per test episode (the agent's, the nominal's and the learned
# regressor's max error); a trajectory id starts with its person (``p13-s2-t1``).
# ``baselines.stats.compare_errors`` is the function behind the printed line: the same
# bootstrap over people gives the same ratio and interval.
rows = pd.read_csv(run / "eval-test" / "results.csv")
print(rows.head(3).to_string(index=False))
people = rows["trajectory_id"].str.split("-").str[0]
comparison = compare_errors(
    rows["agent_max_error"], rows["nominal_max_error"], people, "agent", "nominal"
)
print(comparison.line())
assert np.allclose(comparison.ci95, results["ratio_ci"])
print("kept the initial policy:", results["kept_initial_policy"])

# %%
# With 2,000 steps the policy barely moves from the nominal: the ratio is within a per
# cent of 1 and the verdict "no difference". Where validation never improves, the kept
# checkpoint is the initial policy, the nominal itself (``kept_initial_policy`` says so):
# a checkpoint is only kept when it beats the model on the validation person. Report at
# least 3 seeds and the interquartile mean over seeds (``baselines.stats.iqm_intervals``);
# a sweep (the sweep tutorial) runs them.
