"""The ``vr-kitchen`` dataset: real hand-held controller orientations in VR pointing.

Source: Schuetz, Baltaretu & Fiehler (2024), *Journal of Vision* 24(7):10,
doi:10.1167/jov.24.7.10; public repository ``ischtz/jov2023-vr-objects`` (commit
fe12e11), MIT licence, copyright (c) 2023 Immo Schuetz. The files ship in
``motion_envs/datasets/data/vr-pointing/`` with their ``LICENSE`` and ``README.md``.

8 participants pointed a VR controller at remembered objects in a kitchen scene: 10
targets x 5 repetitions = 400 trials per response mode at about 90 Hz, response window
only, in two response modes (:data:`MODES`): ``laser`` (a virtual laser from the
controller) and ``stick`` (the study's "fixed" condition, a short pointing stick: longer
reaches that rotate more, median start-to-end 66 degrees against about 20). Mapping onto
Faraway & Choe's design: participant = subject, target = task, repetition = replicate.

Both modes by default (800 trials): the response mode is then part of the task
(``"laser/picture"``, ``"stick/picture"``: Table 1's task rows, the learned rows'
one-hot and the environments' task observation see 20 tasks) and a factor among the
predictors (``stick``: 1.0 for the stick, 0.0 for the laser); trajectory ids name the
mode after the person (``p13-stick-s4-t1``; a single mode: ``p13-s1-t1``), so that an id
still starts with its person. ``modes=("laser",)`` (``data="vr-kitchen:laser"``) or
``("stick",)`` loads one: tasks are then the target alone, as the laser-only data set
was.

The logged quaternions are in Unity's left-handed, y-up frame. They are converted to a
right-handed frame with ``(w, x, y, z) -> (w, -x, -y, z)`` (the data README's rule), so
every geodesic angle is unchanged. Trajectories that rotate less than ``min_deg``
(default 10 degrees) from start to end are dropped (the slerp and the speed profile are
ill-posed there); the count is in ``n_dropped``. Predictor: ``duration_s``. Vertical
axis (``up``): ``+y`` (Unity is y-up and the conversion keeps y).
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from importlib import resources
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

if TYPE_CHECKING:
    from importlib.resources.abc import Traversable

from motion_envs.datasets.orientation import OrientationDataset
from motion_envs.datasets.sample_table import read_csv_exact, replicate_numbers
from motion_envs.geometry import quaternion as quat

__all__ = ["CITATION", "DEFAULT_MIN_DEG", "MODES", "load_vr_kitchen"]

DEFAULT_MIN_DEG = 10.0
#: The response modes of the study, in load order.
MODES: tuple[str, ...] = ("laser", "stick")

CITATION = (
    "Schuetz, I., Baltaretu, B. R., & Fiehler, K. (2024). Where was this thing again? "
    "Evaluating methods to indicate remembered object positions in virtual reality. "
    "Journal of Vision, 24(7):10. doi:10.1167/jov.24.7.10"
)


def _data_dir() -> Traversable:
    return resources.files("motion_envs.datasets") / "data" / "vr-pointing"


def _check_modes(modes: str | Sequence[str] | None) -> tuple[str, ...]:
    chosen = MODES if modes is None else (modes,) if isinstance(modes, str) else tuple(modes)
    bad = [m for m in chosen if m not in MODES]
    if not chosen or bad or len(set(chosen)) != len(chosen):
        raise ValueError(
            f"modes must be distinct response modes among {list(MODES)}; got {modes!r}"
        )
    return tuple(m for m in MODES if m in chosen)


def _load_mode(mode: str) -> tuple[Any, Any, Any]:
    """Sorted samples and trials of one mode, and the per-trial sample counts."""
    folder = _data_dir()
    with resources.as_file(folder / f"kitchen_{mode}_samples.csv.gz") as path:
        samples = read_csv_exact(path)
    with resources.as_file(folder / f"kitchen_{mode}_trials.csv") as path:
        trials = read_csv_exact(path)
    keys = ["participant", "session", "trial"]
    samples = samples.sort_values([*keys, "t_s"], kind="stable")
    trials = trials.sort_values(keys, kind="stable").reset_index(drop=True)
    group = samples.groupby(keys, sort=True).size()
    if len(group) != len(trials):
        raise ValueError(f"vr-kitchen {mode} data files disagree on the number of trials")
    return samples, trials, group.to_numpy()


def load_vr_kitchen(
    min_deg: float = DEFAULT_MIN_DEG, modes: str | Sequence[str] | None = None
) -> OrientationDataset:
    """Load the real VR pointing trajectories as an :class:`OrientationDataset`.

    Parameters
    ----------
    min_deg:
        Drop trajectories whose start-to-end rotation is below this many degrees
        (``0`` keeps all).
    modes:
        The response modes to load (:data:`MODES`; None: both, the mode then part of
        the task and a predictor; see the module docstring).
    """
    chosen = _check_modes(modes)
    both = len(chosen) > 1
    quats: list[NDArray[np.float64]] = []
    times: list[NDArray[np.float64]] = []
    subjects: list[str] = []
    tasks: list[str] = []
    ids: list[str] = []
    stick: list[float] = []
    for mode in chosen:
        samples, trials, counts = _load_mode(mode)
        q = samples[["qw", "qx", "qy", "qz"]].to_numpy(dtype=np.float64)
        q = q * np.array([1.0, -1.0, -1.0, 1.0])  # left-handed Unity -> right-handed
        q = quat.normalize(q, name=f"vr-kitchen {mode} quaternions")
        t = samples["t_s"].to_numpy(dtype=np.float64)
        offsets = np.concatenate([[0], np.cumsum(counts)])
        quats += [quat.make_continuous(q[a:b]) for a, b in itertools.pairwise(offsets)]
        times += [t[a:b] - t[a] for a, b in itertools.pairwise(offsets)]
        subjects += trials["participant"].astype(str).tolist()
        prefix = f"{mode}/" if both else ""
        tasks += (prefix + trials["target"].astype(str)).tolist()
        trial_ids = (
            "p"
            + trials["participant"].astype(str)
            + ("-" + mode if both else "")
            + "-s"
            + trials["session"].astype(str)
            + "-t"
            + trials["trial"].astype(str)
        )
        ids += trial_ids.tolist()
        stick += [float(mode == "stick")] * len(trials)
    subject_arr = np.asarray(subjects, dtype=str)
    task_arr = np.asarray(tasks, dtype=str)
    predictors = {"duration_s": np.array([tt[-1] for tt in times])}
    if both:
        predictors["stick"] = np.asarray(stick)
    dataset = OrientationDataset(
        name="vr-kitchen" if both else f"vr-kitchen:{chosen[0]}",
        quaternions=tuple(quats),
        times=tuple(times),
        trajectory_ids=np.asarray(ids, dtype=str),
        subjects=subject_arr,
        tasks=task_arr,
        replicates=replicate_numbers(subject_arr, task_arr),
        predictors=predictors,
        up=(0.0, 1.0, 0.0),
    )
    return dataset.drop_small_rotations(min_deg)
