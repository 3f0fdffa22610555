"""
Tutorial: fit the models to your own recordings
===============================================

Your movements reach the models in one of two forms: arrays you already hold (one
``(n_samples, 3)`` array per movement) or a motion-capture file (C3D, BVH, Qualisys TSV;
*Your own recordings* describes every import step). This tutorial does both with a
SIMULATED session: a hand marker making reaches between two targets at 100 Hz, written
as a Qualisys TSV (the one format that needs no extra reader), with a short occlusion.
"""

# %%
# 1. A recording (SIMULATED)
# --------------------------
# Ten reaches of 0.8 s alternating between two targets 30 cm apart, each followed by a
# 0.6 s rest; minimum-jerk paths with a little curvature and 0.1 mm of marker noise; the
# marker is lost for 4 frames during the third reach (a TSV writes a lost sample as
# 0, 0, 0).
import sys
import tempfile
from pathlib import Path

import numpy as np

from motion_envs.datasets.mocap import ImportOptions, import_position
from motion_envs.geometry import minimum_jerk
from motion_envs.models import SineSeriesRegression

rng = np.random.default_rng(0)
rate = 100.0
targets = np.array([[0.2, -0.15, 0.9], [0.2, 0.15, 0.9]])
pieces = [np.repeat(targets[:1], 60, axis=0)]
for k in range(10):
    a, b = targets[k % 2], targets[(k + 1) % 2]
    b = b + rng.normal(0, 0.01, 3)
    tau = np.linspace(0, 1, 81)
    path = minimum_jerk.minimum_jerk(pieces[-1][-1], b, tau)
    path[:, 0] += 0.04 * np.sin(np.pi * tau) * rng.uniform(0.5, 1.5)  # an arc outwards
    pieces += [path[1:], np.repeat(path[-1:], 60, axis=0)]
hand_mm = 1000 * np.concatenate(pieces) + rng.normal(0, 0.1, (sum(map(len, pieces)), 3))
hand_mm[340:344] = 0.0  # occluded: Qualisys writes 0, 0, 0

work = Path(sys.argv[1] if len(sys.argv) > 1 else tempfile.mkdtemp())
tsv = work / "session.tsv"
header = [
    f"NO_OF_FRAMES\t{len(hand_mm)}", "NO_OF_MARKERS\t1", f"FREQUENCY\t{rate:g}",
    "DATA_INCLUDED\t3D", "MARKER_NAMES\tHAND", "Frame\tTime\tHAND X\tHAND Y\tHAND Z",
]  # fmt: skip
body = [
    f"{i + 1}\t{i / rate:.4f}\t" + "\t".join(f"{v:.3f}" for v in p) for i, p in enumerate(hand_mm)
]
tsv.write_text("\n".join(header + body) + "\n")

# %%
# 2. Import: gaps filled, movements cut by speed
# ----------------------------------------------
# The same as ``motion-bench import session.tsv --kind position --marker HAND
# --speed-threshold 0.05 --out reaches.csv``: the 4-frame gap is filled (at most
# ``max_gap`` = 10 frames), and a movement runs from the last resting sample before the
# hand's speed exceeds 0.05 m/s to the first resting sample after it.
dataset, report = import_position(tsv, ImportOptions(marker="HAND", speed_threshold=0.05))
print("\n".join(report.lines()))
dataset.to_csv(work / "reaches.csv")  # what --data and data= take
print(len(dataset.positions), "movements of", [len(p) for p in dataset.positions], "samples")

# %%
# 3. Fit the position model
# -------------------------
# Faraway & Choe's model predicts a whole movement from its conditions as a sum of sines
# added to the straight line from start to end (eqs. 6-8). The conditions are yours to
# choose; with eight movements a few are all the data support: here the displacement
# from start to end (three numbers). Fit on all but the last two movements and predict
# those from their conditions alone.
reaches = [np.asarray(p) for p in dataset.positions]
conditions = np.array([p[-1] - p[0] for p in reaches])
model = SineSeriesRegression(n_sines=4).fit(reaches[:-2], conditions[:-2], rate=rate)
for p, q in zip(reaches[-2:], conditions[-2:], strict=True):
    tau = np.linspace(0, 1, len(p))
    duration = (len(p) - 1) / rate
    predicted = model.predict(q, duration=duration, times=tau * duration, start=p[0], end=p[-1])
    straight = p[0] + tau[:, None] * (p[-1] - p[0])
    error = np.linalg.norm(predicted - p, axis=1).max()
    baseline = np.linalg.norm(straight - p, axis=1).max()
    print(f"held-out reach: max error {1000 * error:.1f} mm, straight line {1000 * baseline:.1f}")

# %%
# 4. The recording as an environment's data
# -----------------------------------------
# Every environment's ``data=`` takes the CSV, or the recording itself with the import's
# options as a query (the option names of ``motion-bench import`` without the dashes).
import gymnasium as gym  # noqa: E402

import motion_envs  # noqa: E402, F401  (registers the ids)

env = gym.make("MotionEnvs/PositionReach-v1", data=f"{tsv}?marker=HAND&speed-threshold=0.05")
obs, info = env.reset(seed=0)
done, steps = False, 0
while not done:  # the zero action: the nominal model's path
    obs, reward, terminated, truncated, info = env.step(np.zeros(env.action_space.shape, "float32"))
    done, steps = terminated or truncated, steps + 1
print(f"{steps} steps, the nominal's max error {info['max_error']:.4f} m")
env.close()
