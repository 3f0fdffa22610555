"""Person calibration (motion_envs.models.person_calibration) against a plain-loop oracle,
with a poisoned row: the prediction of a held-out person's reach never reads the scored
trajectory nor the person's trajectories beyond the K drawn."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from baselines.cli import main
from motion_envs.datasets import load_orientation_dataset
from motion_envs.geometry import quaternion as quat
from motion_envs.models.criteria import table1
from motion_envs.models.person_calibration import (
    K0_GRID,
    calibration_draws,
    person_blend_loso,
    person_calibration_rows,
    person_timing_loso,
)
from motion_envs.models.slerp_residual import (
    normalised_grid,
    resample_orientations,
    residuals_against_profiles,
    slerp_residuals,
)
from motion_envs.models.speed_profile import speed_fractions_on_grid

K, DRAWS = 3, 3


@pytest.fixture(scope="module")
def data():
    ds = load_orientation_dataset("vr-kitchen")
    rows = person_calibration_rows(ds.ragged, ds.subjects, ks=(K,), n_draws=DRAWS, seed=0, up=ds.up)
    return ds, rows


def test_draws_are_other_reaches_of_the_same_person():
    subjects = np.repeat(["a", "b", "c"], [6, 2, 4])
    draws = calibration_draws(subjects, 3, 50, seed=1)
    for r in range(50):
        for l, s in enumerate(subjects):
            got = draws[r, l][draws[r, l] >= 0]
            assert l not in got and np.all(subjects[got] == s)
            assert got.size == min(3, np.sum(subjects == s) - 1) == np.unique(got).size
    assert np.array_equal(draws, calibration_draws(subjects, 3, 50, seed=1))
    assert not np.array_equal(draws, calibration_draws(subjects, 3, 50, seed=2))
    # uniform: every other reach of "a" is drawn for trajectory 0 about 3/5 of the time
    counts = np.bincount(draws[:, 0].ravel(), minlength=6)[1:6] / 50
    assert np.all(np.abs(counts - 0.6) < 0.25)


def _bezier2(P, n):
    tau = np.linspace(0.0, 1.0, n)
    return 2 * tau[:, None] * (1 - tau[:, None]) * P[None, :]


def _oracle_blend(R, subjects, draws, k0_grid):
    """Plain loops: per held-out person, k0 by LOPO on the training people, then the blend
    of each reach's calibration mean (degree 2, the one interior control point by least
    squares on the grid) with the training population's mean."""
    n = R.shape[1]
    basis = _bezier2(np.ones(1), n)[:, 0]
    ctrl = np.array([basis @ R[l] / (basis @ basis) for l in range(R.shape[0])])  # (L, 3)
    frame = pd.DataFrame({"subject": subjects})

    def err(l, P_pop, k0):
        out = []
        for r in range(draws.shape[0]):
            cal = [j for j in draws[r, l] if j >= 0]
            w = len(cal) / (len(cal) + k0) if len(cal) + k0 > 0 else 0.0
            P = w * np.mean(ctrl[cal], axis=0) + (1 - w) * P_pop if cal else P_pop
            out.append(np.max(np.linalg.norm(R[l] - _bezier2(P, n), axis=1)))
        return np.mean(out)

    errors = np.empty(R.shape[0])
    for s, rows in frame.groupby("subject").groups.items():
        train_people = sorted(set(subjects) - {s})
        scores = []
        for k0 in k0_grid:
            inner = []
            for t in train_people:
                others = [l for l in range(R.shape[0]) if subjects[l] not in (s, t)]
                pop = ctrl[others].mean(axis=0)
                inner += [err(l, pop, k0) for l in np.flatnonzero(subjects == t)]
            scores.append(np.median(inner))
        k0 = k0_grid[int(np.argmin(scores))]
        pop = ctrl[subjects != s].mean(axis=0)
        for l in rows:
            errors[l] = err(l, pop, k0)
    return errors


def test_blend_matches_the_oracle(data):
    ds, res = data
    subjects = np.asarray(ds.subjects).astype(str)
    R = slerp_residuals(ds.ragged)
    draws = calibration_draws(subjects, K, DRAWS, 0)
    want = _oracle_blend(R, subjects, draws, K0_GRID)
    np.testing.assert_allclose(res.errors[f"person_k{K}_loso"], want, rtol=1e-9, atol=1e-12)
    assert res.criteria[f"person_k{K}_loso"] == pytest.approx(np.median(want), rel=1e-9)


def test_timing_rows_match_the_oracle(data):
    ds, res = data
    subjects = np.asarray(ds.subjects).astype(str)
    tr = ds.ragged
    q = resample_orientations(tr, normalised_grid(50))
    A = speed_fractions_on_grid(tr, 50)
    draws = calibration_draws(subjects, K, DRAWS, 0)
    # slerp with the mean profile of the calibration reaches, one trajectory at a time
    want = np.empty(len(subjects))
    for l in range(len(subjects)):
        errs = []
        for r in range(DRAWS):
            alpha = A[[j for j in draws[r, l] if j >= 0]].mean(axis=0)
            e = quat.slerp(tr.starts[l][None], tr.ends[l][None], alpha, validate=False)
            v = quat.logmap(quat.multiply(quat.conjugate(e), q[l]), validate=False)[1:-1]
            errs.append(np.max(np.linalg.norm(v, axis=1), initial=0.0))
        want[l] = np.mean(errs)
    got = res.errors[f"slerp_person_timing_k{K}_predicted_timing"]
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-12)
    # the blend under predicted timing: residuals against the training people's profile
    for s in np.unique(subjects)[:2]:
        rows = np.flatnonzero(subjects == s)
        Ro = residuals_against_profiles(q, tr.starts, tr.ends, A[subjects != s].mean(axis=0))
        oracle = _oracle_blend(Ro, subjects, draws, K0_GRID)
        np.testing.assert_allclose(
            res.errors[f"person_k{K}_loso_predicted_timing"][rows], oracle[rows], rtol=1e-9
        )


def test_reference_rows_are_the_benchmark_rows(data):
    ds, res = data
    t1 = table1(ds.ragged, ds.subjects, ds.tasks)
    assert np.median(res.errors["null_d2_loso"]) == t1.criteria["null_d2_loso"]
    # the benchmark value of slerp_loso_predicted_timing (baselines.learned.rows) on
    # vr-kitchen's laser and stick reaches (0.2803844868646229 on the laser alone)
    assert np.median(res.errors["slerp_loso_predicted_timing"]) == pytest.approx(
        0.5891395580523892, rel=1e-12
    )
    # and null_d2_path_loso's (NullBezierModel(frame="path") in baselines.learned.rows)
    assert np.median(res.errors["null_d2_path_loso"]) == pytest.approx(
        0.45488807447767715, rel=1e-12
    )
    # k0 -> infinity: the population alone, i.e. null_d2_loso
    subjects = np.asarray(ds.subjects).astype(str)
    R = slerp_residuals(ds.ragged)
    draws = calibration_draws(subjects, K, 2, 0)
    errs, _, chosen = person_blend_loso(lambda train: R, subjects, draws, k0_grid=(1e15,))
    np.testing.assert_allclose(errs, res.errors["null_d2_loso"], rtol=1e-9)
    assert set(chosen.values()) == {1e15}


@pytest.mark.parametrize("timing", ["observed", "predicted"])
def test_poisoned_rows_never_reach_the_prediction(data, timing):
    """Poison every trajectory of one held-out person except the K drawn for one scored
    reach (the scored reach included): that reach's prediction and the k0 chosen for the
    person are unchanged."""
    ds, _ = data
    subjects = np.asarray(ds.subjects).astype(str)
    tr = ds.ragged
    q = resample_orientations(tr, normalised_grid(50))
    A = speed_fractions_on_grid(tr, 50)
    draws = calibration_draws(subjects, K, 1, 0)
    person = "13"
    rows = np.flatnonzero(subjects == person)

    R = slerp_residuals(tr)

    def blend(q_grid, alpha, R):
        if timing == "observed":
            return person_blend_loso(lambda train: R, subjects, draws)
        return person_blend_loso(
            lambda train: residuals_against_profiles(
                q_grid, tr.starts, tr.ends, alpha[train].mean(axis=0)
            ),
            subjects,
            draws,
        )

    for scored in rows[[0, 7, -1]]:
        kept = draws[0, scored][draws[0, scored] >= 0]
        poisoned = np.setdiff1d(rows, kept)
        assert scored in poisoned
        q_bad = q.copy()
        q_bad[poisoned] = quat.multiply(quat.expmap([0.35, 0.0, 0.0]), q[poisoned])
        A_bad = A.copy()
        A_bad[poisoned] = np.linspace(0, 1, 50) ** 3
        R_bad = R.copy()
        R_bad[poisoned] += 5.0
        _, clean, k_clean = blend(q, A, R)
        _, dirty, k_dirty = blend(q_bad, A_bad, R_bad)
        np.testing.assert_array_equal(dirty[0, scored], clean[0, scored])
        assert k_dirty[person] == k_clean[person]
        # the poison is real: predictions of reaches that drew a poisoned one change
        others = poisoned[poisoned != scored]
        assert any(not np.array_equal(dirty[0, o], clean[0, o]) for o in others)
        # person timing: same property
        _, p_clean = person_timing_loso(q, tr.starts, tr.ends, A, draws)
        _, p_dirty = person_timing_loso(q_bad, tr.starts, tr.ends, A_bad, draws)
        np.testing.assert_array_equal(p_dirty[0, scored], p_clean[0, scored])


def test_cli_calibration_rows_and_intervals(tmp_path, capsys):
    assert (
        main(["orientation", "--learned", "off", "--calibration", "2", "--out", str(tmp_path)]) == 0
    )
    text = capsys.readouterr().out
    doc = json.loads((tmp_path / "results.json").read_text())
    for name in ("person_k2_loso", "person_k2_path_loso", "person_k2_loso_predicted_timing",
                 "slerp_person_timing_k2_predicted_timing"):  # fmt: skip
        assert name in doc["criteria"] and name in text
        assert name in (tmp_path / "results.csv").read_text()
    assert doc["calibration"]["seed"] == 0 and doc["calibration"]["n_draws"] == 20
    printed = [line for line in text.splitlines() if " / " in line and "95% CI" in line]
    assert len(printed) == len(doc["intervals"]) == 4
    assert set(doc["intervals"]) == {
        "person_k2_loso / null_d2_loso",
        "person_k2_path_loso / null_d2_path_loso",
        "person_k2_loso_predicted_timing / null_d2_loso_predicted_timing",
        "slerp_person_timing_k2_predicted_timing / slerp_loso_predicted_timing",
    }
    for name, (lo, hi) in doc["intervals"].items():
        assert any(line.strip().startswith(name) for line in printed)
        assert lo <= hi
    assert "noise floor" in text and "predictive floors" in text
    rows = doc["noise_floor"]["rows"]
    for name, floor in (("person_k2_loso", "predictive_floor"),
                        ("person_k2_path_loso", "predictive_floor_path")):  # fmt: skip
        assert rows[name]["floor_row"] == floor
        assert rows[name]["distance"] == pytest.approx(
            doc["criteria"][name] - doc["criteria"][floor]
        )


@pytest.mark.parametrize("bad", ["0", "1,1", "x", "-3"])
def test_cli_rejects_bad_calibration(bad, capsys):
    assert main(["orientation", "--learned", "off", f"--calibration={bad}"]) == 2
    assert "--calibration" in capsys.readouterr().err
