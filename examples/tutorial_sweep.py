"""
Tutorial: run a sweep on one machine and on a cluster
=====================================================

A sweep trains every configuration of a search space for every seed, chooses each
run's checkpoint on the validation split, scores it on the test split and prints one
row per configuration (median and spread over seeds, the best on *validation* marked).
``motion-bench sweep`` runs the trials on Ray Tune, so the same sweep file runs on a
laptop or on a cluster. Needs the ``sweep`` extra (Ray Tune; ``optuna`` for
``search: optuna``). This tutorial runs a two-trial sweep on one CPU (about a minute)
and shows the three commands that run it on several machines.
"""

# %%
# 1. The sweep file
# -----------------
# Plain YAML, checked before Ray starts (schema, bounds, and ``motion-bench train``'s
# checks for every configuration it can produce). ``space`` lists the values to combine
# (``search: grid``); ``hyperparams`` override ``configs/agents/ALGO.yaml`` key by key and
# ``env_kwargs`` the environment's arguments. This one is 1 configuration x 2 seeds of
# 2,000 steps; the shipped sweeps (``configs/sweeps/``) use 100,000 steps and 5 seeds.
import subprocess
import sys
import tempfile
from pathlib import Path

import pandas as pd

work = Path(sys.argv[1] if len(sys.argv) > 1 else tempfile.mkdtemp())
sweep_file = work / "tiny_sweep.yaml"
sweep_file.write_text(
    "description: two trials of 2,000 steps\n"
    "search: grid\n"
    "seeds: [0, 1]\n"
    "timesteps: 2000\n"
    "n_envs: 2\n"
    "space:\n"
    "  algo: [ppo]\n"
    "  env_id: [MotionEnvs/OrientationReach-v1]\n"
    "  hyperparams: {eval_freq: [1000], n_steps: [100], batch_size: [100], n_epochs: [2]}\n"
)

# %%
# 2. On one machine
# -----------------
# ``motion-bench sweep`` starts a local Ray (``--num-cpus`` limits the cores it uses; by
# default all of them), runs the trials and writes ``table.md``/``table.csv`` (one row per
# configuration), ``trials.csv`` (one row per trial) and ``sweep.png`` into ``--out``.
# ``--resume`` continues an interrupted sweep in the same folder.
out = work / "sweep"
cmd = [sys.executable, "-m", "baselines.cli", "sweep", "--config", str(sweep_file)]
printed = subprocess.run(
    [*cmd, "--num-cpus", "1", "--out", str(out)], check=True, capture_output=True, text=True
).stdout
print(printed)
print(sorted(p.name for p in out.iterdir() if not p.name.startswith(".")))
trials = pd.read_csv(out / "trials.csv")
print(trials.iloc[:, :6].to_string(index=False))

# %%
# 3. On a cluster
# ---------------
# Start Ray on every machine, then run the same command with ``--address auto`` on any
# of them. ``--out`` must be on storage every machine mounts (NFS or similar): each
# trial writes its run folder there and the table is built from them::
#
#     ray start --head --port=6379                  # on the first machine
#     ray start --address=HEAD_IP:6379              # on every other machine
#     motion-bench sweep --config configs/sweeps/orientation_ppo.yaml \
#         --address auto --out /shared/sweeps/orientation_ppo
#
# In a batch script (SLURM or similar) the same lines run inside the allocation: the head
# on the first node, the workers on the others, then the sweep. Each trial takes one CPU,
# so Ray runs as many trials at once as the cluster has cores. The sweep file, the trials
# and the table are the same as on one machine.
