"""Table 1 on vr-kitchen against a second, independent computation.

The oracle below uses only scipy's ``Rotation``/``Slerp`` (no motion_envs geometry), a
per-trajectory Python loop, ``math.comb`` Bernstein polynomials with one
``np.linalg.lstsq`` per curve, and pandas group-bys for the criteria. Both must agree to
1e-9 on every criterion.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from scipy.spatial.transform import Rotation, Slerp

from motion_envs.datasets import load_vr_kitchen
from motion_envs.datasets.vr_kitchen import MODES
from motion_envs.models.criteria import table1

GRID = np.linspace(0.0, 1.0, 50)


def oracle_residual(q_wxyz: np.ndarray, t: np.ndarray, alpha_grid: np.ndarray | None = None):
    rot = Rotation.from_quat(q_wxyz[:, [1, 2, 3, 0]])
    tau = (t - t[0]) / (t[-1] - t[0])
    steps = (rot[:-1].inv() * rot[1:]).magnitude()
    alpha = np.concatenate([[0.0], np.cumsum(steps) / steps.sum()])
    ends = Slerp([0.0, 1.0], rot[[0, len(rot) - 1]])
    if alpha_grid is None:
        resid = (ends(np.clip(alpha, 0, 1)).inv() * rot).as_rotvec()
        out = np.stack([np.interp(GRID, tau, resid[:, c]) for c in range(3)], axis=1)
    else:
        observed = Slerp(tau, rot)(GRID)
        out = (ends(np.clip(alpha_grid, 0, 1)).inv() * observed).as_rotvec()
    return out, np.interp(GRID, tau, alpha)


def bernstein(d: int) -> np.ndarray:
    return np.array(
        [[math.comb(d, i) * s**i * (1 - s) ** (d - i) for i in range(1, d)] for s in GRID]
    )


def median_max(R: np.ndarray, pred: np.ndarray) -> float:
    return float(np.median(np.linalg.norm(R - pred, axis=2).max(axis=1)))


def oracle_path_frame(q_start: np.ndarray, q_end: np.ndarray, up: np.ndarray):
    """The path frame's axes (columns) and scale from scipy's rotations (no motion_envs)."""
    start = Rotation.from_quat(q_start[[1, 2, 3, 0]])
    rel = (start.inv() * Rotation.from_quat(q_end[[1, 2, 3, 0]])).as_rotvec()
    theta = np.linalg.norm(rel)
    a = rel / theta
    u_b = start.inv().apply(up)
    u = u_b - (u_b @ a) * a
    u /= np.linalg.norm(u)
    return np.stack([a, u, np.cross(a, u)], axis=1), max(theta, 1e-3)


def oracle_floors(R: np.ndarray, df: pd.DataFrame, ds) -> dict[str, float]:
    """Each reach against the mean of the other replicates of its (subject, task), in the
    body frame and in the path frame (mean of ``F^T r / s``, mapped back with the reach's
    own ``s F``), and the same scaled by ``sqrt((n - 1) / n)``."""
    frames = [oracle_path_frame(q[0], q[-1], np.asarray(ds.up)) for q in ds.quaternions]
    P = np.stack([r @ F / s for r, (F, s) in zip(R, frames, strict=True)])
    loo: dict[str, list[float]] = {"": [], "_path": []}
    floor: dict[str, list[float]] = {"": [], "_path": []}
    for _, idx in df.groupby(df["subject"] + "|" + df["task"]).indices.items():
        n = len(idx)
        for l in idx if n >= 2 else []:
            rest = [k for k in idx if k != l]
            F, s = frames[l]
            errors = {
                "": np.linalg.norm(R[l] - R[rest].mean(axis=0), axis=1).max(),
                "_path": np.linalg.norm(R[l] - s * P[rest].mean(axis=0) @ F.T, axis=1).max(),
            }
            for key, e in errors.items():
                loo[key].append(e)
                floor[key].append(e * math.sqrt((n - 1) / n))
    out = {}
    for key in loo:
        out[f"within_subject{key}_loo"] = float(np.median(loo[key]))
        out[f"predictive_floor{key}"] = float(np.median(floor[key]))
    return out


def oracle_table1(ds) -> dict[str, float]:
    R, alphas = zip(
        *(oracle_residual(q, t) for q, t in zip(ds.quaternions, ds.times, strict=True)),
        strict=True,
    )
    R = np.stack(R)
    abar = np.mean(alphas, axis=0)
    R_avg = np.stack(
        [oracle_residual(q, t, abar)[0] for q, t in zip(ds.quaternions, ds.times, strict=True)]
    )
    df = pd.DataFrame({"subject": ds.subjects, "task": ds.tasks})
    out: dict[str, float] = {}

    pair = df["subject"] + "|" + df["task"]
    within = []
    for _, idx in df.groupby(pair).indices.items():
        if len(idx) >= 2:
            mean = R[idx].mean(axis=0)
            within += list(np.linalg.norm(R[idx] - mean, axis=2).max(axis=1))
    out["within_subject"] = float(np.median(within))
    out.update(oracle_floors(R, df, ds))
    per_task = []
    for _, idx in df.groupby("task").indices.items():
        mean = R[idx].mean(axis=0)
        per_task.append(np.median(np.linalg.norm(R[idx] - mean, axis=2).max(axis=1)))
    out["between_subject"] = float(np.median(per_task))
    out["slerp_empirical"] = median_max(R, 0.0)
    out["slerp_average"] = median_max(R_avg, 0.0)
    out["null_average"] = median_max(R, R.mean(axis=0))
    for d in (2, 3, 4):
        B = bernstein(d)
        P = np.stack([np.linalg.lstsq(B, R[l], rcond=None)[0] for l in range(len(R))])
        out[f"approximation_d{d}"] = median_max(R, np.stack([B @ p for p in P]))
        out[f"null_d{d}"] = median_max(R, B @ P.mean(axis=0))
        for kind, col in (("subject_predictor", "subject"), ("task_predictor", "task")):
            pred = np.empty_like(R)
            for _, idx in df.groupby(col).indices.items():
                pred[idx] = B @ P[idx].mean(axis=0)
            out[f"{kind}_d{d}"] = median_max(R, pred)
        null_loso = np.empty_like(R)
        task_loso = np.empty_like(R)
        for s in df["subject"].unique():
            test = (df["subject"] == s).to_numpy()
            null_loso[test] = B @ P[~test].mean(axis=0)
            for l in np.flatnonzero(test):
                same_task = (~test) & (df["task"] == df["task"][l]).to_numpy()
                task_loso[l] = B @ P[same_task].mean(axis=0)
        out[f"null_d{d}_loso"] = median_max(R, null_loso)
        out[f"task_predictor_d{d}_loso"] = median_max(R, task_loso)
        loro = np.empty_like(R)
        for l in range(len(R)):
            others = (df["subject"] == df["subject"][l]).to_numpy().copy()
            others[l] = False
            loro[l] = B @ P[others].mean(axis=0)
        out[f"subject_predictor_d{d}_loro"] = median_max(R, loro)
    return out


@pytest.fixture(scope="module")
def vr_kitchen():
    return load_vr_kitchen()


def test_table1_matches_independent_scipy_computation(vr_kitchen):
    ours = table1(
        vr_kitchen.ragged, vr_kitchen.subjects, vr_kitchen.tasks, up=vr_kitchen.up
    ).criteria
    ref = oracle_table1(vr_kitchen)
    assert set(ref) == set(ours)
    for name, value in ref.items():
        assert ours[name] == pytest.approx(value, abs=1e-9), name


def test_vr_kitchen_design(vr_kitchen):
    """Both response modes by default: 800 trials, 152 dropped (148 laser, 4 stick),
    the mode part of the task (20 tasks) and a 0/1 predictor."""
    assert len(vr_kitchen) + vr_kitchen.n_dropped == 800
    assert vr_kitchen.n_dropped == 152  # start-to-end rotation below 10 degrees
    assert np.unique(vr_kitchen.subjects).size == 8
    assert np.unique(vr_kitchen.tasks).size == 20
    assert not vr_kitchen.simulated
    stick = vr_kitchen.predictors["stick"]
    assert set(stick) == {0.0, 1.0}
    assert np.all(np.char.startswith(vr_kitchen.tasks, "stick/") == (stick == 1.0))
    everything = load_vr_kitchen(min_deg=0)
    assert len(everything) == 800 and everything.n_dropped == 0
    assert everything.replicates.max() == 4
    for mode, dropped in (("laser", 148), ("stick", 4)):
        one = load_vr_kitchen(modes=mode)
        assert one.name == f"vr-kitchen:{mode}" and len(one) + one.n_dropped == 400
        assert one.n_dropped == dropped and np.unique(one.tasks).size == 10
        assert "stick" not in one.predictors
        assert set(one.trajectory_ids) == {
            i.replace(f"-{mode}-", "-") for i in vr_kitchen.trajectory_ids if f"-{mode}-" in i
        }
    people = np.char.partition(vr_kitchen.trajectory_ids, "-")[:, 0]
    assert np.array_equal(people, np.char.add("p", vr_kitchen.subjects))  # ids start with it
    with pytest.raises(ValueError, match="modes must be distinct response modes"):
        load_vr_kitchen(modes=("laser", "pen"))


def test_vr_kitchen_angles_match_trial_table(vr_kitchen):
    """The loader's start-to-end angles equal the data's own start_end_deg column."""
    from importlib import resources

    folder = resources.files("motion_envs.datasets") / "data" / "vr-pointing"
    trials = pd.concat([pd.read_csv(folder / f"kitchen_{m}_trials.csv") for m in MODES])
    trials["id"] = (
        "p"
        + trials.participant.astype(str)
        + "-"
        + trials["mode"]
        + "-s"
        + trials.session.astype(str)
        + "-t"
        + trials.trial.astype(str)
    )
    ref = trials.set_index("id").loc[vr_kitchen.trajectory_ids, "start_end_deg"].to_numpy()
    np.testing.assert_allclose(np.degrees(vr_kitchen.rotation_angles()), ref, atol=0.006)
