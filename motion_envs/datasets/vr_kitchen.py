"""The ``vr-kitchen`` dataset: real hand-held controller orientations in VR pointing.

Source: Schuetz, Baltaretu & Fiehler (2024), *Journal of Vision* 24(7):10,
doi:10.1167/jov.24.7.10; public repository ``ischtz/jov2023-vr-objects`` (commit
fe12e11), MIT licence, copyright (c) 2023 Immo Schuetz. The files ship in
``motion_envs/datasets/data/vr-pointing/`` with their ``LICENSE`` and ``README.md``.

8 participants pointed a VR controller at remembered objects in a kitchen scene: 10
targets x 5 repetitions = 400 trials at about 90 Hz, response window only. Mapping onto
Faraway & Choe's design: participant = subject, target = task, repetition = replicate.

The logged quaternions are in Unity's left-handed, y-up frame. They are converted to a
right-handed frame with ``(w, x, y, z) -> (w, -x, -y, z)`` (the data README's rule), so
every geodesic angle is unchanged. Trajectories that rotate less than ``min_deg``
(default 10 degrees) from start to end are dropped (the slerp and the speed profile are
ill-posed there); the count is in ``n_dropped``. Predictor: ``duration_s``. Vertical
axis (``up``): ``+y`` (Unity is y-up and the conversion keeps y).
"""

from __future__ import annotations

import itertools
from importlib import resources
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from importlib.resources.abc import Traversable

from motion_envs.datasets.orientation import OrientationDataset
from motion_envs.datasets.sample_table import read_csv_exact, replicate_numbers
from motion_envs.geometry import quaternion as quat

__all__ = ["CITATION", "DEFAULT_MIN_DEG", "load_vr_kitchen"]

DEFAULT_MIN_DEG = 10.0

CITATION = (
    "Schuetz, I., Baltaretu, B. R., & Fiehler, K. (2024). Where was this thing again? "
    "Evaluating methods to indicate remembered object positions in virtual reality. "
    "Journal of Vision, 24(7):10. doi:10.1167/jov.24.7.10"
)


def _data_dir() -> Traversable:
    return resources.files("motion_envs.datasets") / "data" / "vr-pointing"


def load_vr_kitchen(min_deg: float = DEFAULT_MIN_DEG) -> OrientationDataset:
    """Load the real VR pointing trajectories as an :class:`OrientationDataset`.

    Parameters
    ----------
    min_deg:
        Drop trajectories whose start-to-end rotation is below this many degrees
        (``0`` keeps all 400).
    """
    folder = _data_dir()
    with resources.as_file(folder / "kitchen_laser_samples.csv.gz") as path:
        samples = read_csv_exact(path)
    with resources.as_file(folder / "kitchen_laser_trials.csv") as path:
        trials = read_csv_exact(path)
    keys = ["participant", "session", "trial"]
    samples = samples.sort_values([*keys, "t_s"], kind="stable")
    trials = trials.sort_values(keys, kind="stable").reset_index(drop=True)
    q = samples[["qw", "qx", "qy", "qz"]].to_numpy(dtype=np.float64)
    q = q * np.array([1.0, -1.0, -1.0, 1.0])  # left-handed Unity -> right-handed
    q = quat.normalize(q, name="vr-kitchen quaternions")
    t = samples["t_s"].to_numpy(dtype=np.float64)
    group = samples.groupby(keys, sort=True).size()
    if len(group) != len(trials):
        raise ValueError("vr-kitchen data files disagree on the number of trials")
    offsets = np.concatenate([[0], np.cumsum(group.to_numpy())])
    quats = tuple(quat.make_continuous(q[a:b]) for a, b in itertools.pairwise(offsets))
    times = tuple(t[a:b] - t[a] for a, b in itertools.pairwise(offsets))
    subjects = trials["participant"].astype(str).to_numpy()
    tasks = trials["target"].astype(str).to_numpy()
    ids = (
        "p"
        + trials["participant"].astype(str)
        + "-s"
        + trials["session"].astype(str)
        + "-t"
        + trials["trial"].astype(str)
    ).to_numpy()
    dataset = OrientationDataset(
        name="vr-kitchen",
        quaternions=quats,
        times=times,
        trajectory_ids=ids.astype(str),
        subjects=subjects.astype(str),
        tasks=tasks.astype(str),
        replicates=replicate_numbers(subjects, tasks),
        predictors={"duration_s": np.array([tt[-1] for tt in times])},
        up=(0.0, 1.0, 0.0),
    )
    return dataset.drop_small_rotations(min_deg)
