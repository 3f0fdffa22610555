"""The learned rows given the calibration summary (baselines.learned.person_rows): the
summary against a plain loop, the closed-form nested ridge against scikit-learn, and a
poisoned row: a held-out person's prediction never reads the scored trajectory's
residual nor the person's trajectories beyond the K drawn."""

from __future__ import annotations

import json

import numpy as np
import pytest

from baselines.cli import main
from baselines.learned.orientation import orientation_features, ridge_nested, sine_targets
from baselines.learned.person_rows import (
    learned_person_rows,
    ridge_nested_closed,
    ridge_predictions,
    summary_predictions,
)
from motion_envs.datasets import load_orientation_dataset
from motion_envs.models.path_frame import to_path_frame
from motion_envs.models.person_calibration import (
    SUMMARY_BOUND,
    calibration_draws,
    calibration_features,
    calibration_summaries,
)
from motion_envs.models.slerp_residual import slerp_residuals

K = 3


@pytest.fixture(scope="module")
def problem():
    ds = load_orientation_dataset("vr-kitchen")
    tr = ds.ragged
    P = to_path_frame(slerp_residuals(tr), tr.starts, tr.ends, ds.up)
    tasks = np.asarray(ds.tasks).astype(str)
    X = orientation_features(tr.starts, tr.ends, tr.durations, tasks, sorted(set(tasks)))
    subjects = np.asarray(ds.subjects).astype(str)
    return ds, X, sine_targets(P), calibration_features(P), subjects, P


def test_features_and_summary_against_a_plain_loop(problem):
    *_, features, subjects, P = problem
    # features: least squares of sin(k pi tau), k = 1..3, one trajectory and axis at a time
    tau = np.linspace(0, 1, P.shape[1])
    B = np.sin(np.pi * tau[:, None] * np.arange(1, 4))
    for l in (0, 17, 200):
        for axis in range(3):
            c = np.linalg.lstsq(B, P[l, :, axis], rcond=None)[0]
            np.testing.assert_allclose(features[l, axis::3], c, rtol=1e-10, atol=1e-13)
    draws = calibration_draws(subjects, K, 2, seed=0)
    S = calibration_summaries(features * 40.0, draws, K)  # scaled: the clip is exercised
    assert S.shape == (2, subjects.size, 10)
    for r in range(2):
        for l in (0, 100, 251):
            drawn = [i for i in draws[r, l] if i >= 0]
            mean = np.clip(np.mean(features[drawn] * 40.0, axis=0), -SUMMARY_BOUND, SUMMARY_BOUND)
            np.testing.assert_allclose(S[r, l, :9], mean, rtol=1e-12)
            assert S[r, l, 9] == len(drawn) / K
    assert np.abs(S[..., :9]).max() == SUMMARY_BOUND
    # no reach drawn: summary 0, share 0
    np.testing.assert_array_equal(calibration_summaries(features, np.full(K, -1), K), 0.0)


def test_closed_form_ridge_equals_scikit_learn(problem):
    _, X, Y, _, subjects, _ = problem
    folds = [(np.flatnonzero(subjects != s), np.flatnonzero(subjects == s)) for s in ("13", "20")]
    alphas = (0.1, 10.0, 1000.0, 1e5)
    got, chosen = ridge_nested_closed(X, Y, subjects, folds, alphas)
    ref, ref_chosen = ridge_nested(X, Y, subjects, folds, alphas)
    assert chosen == ref_chosen
    np.testing.assert_allclose(got, ref, rtol=1e-7, atol=1e-10)
    # one fit, against sklearn's pipeline directly
    from sklearn.linear_model import Ridge
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import StandardScaler

    model = make_pipeline(StandardScaler(), Ridge(alpha=3.0)).fit(X[:150], Y[:150])
    np.testing.assert_allclose(
        ridge_predictions(X[:150], Y[:150], X[150:], [3.0])[0],
        model.predict(X[150:]),
        rtol=1e-7,
        atol=1e-10,
    )


def _mlp_config():
    pytest.importorskip("torch")
    from baselines.learned.batched_mlp import MLPConfig

    return MLPConfig(max_epochs=8, weight_decays=(0.1,), bases=("mean",), inner_splits=2)


@pytest.mark.parametrize("model", ["ridge", "mlp"])
def test_poisoned_rows_never_reach_the_prediction(problem, model):
    """Poison the targets and the calibration features of every trajectory of a held-out
    person except the K drawn for one scored reach (the scored reach's own target
    included): that reach's prediction and its fold's choices are unchanged."""
    _, X, Y, features, subjects, _ = problem
    config = _mlp_config() if model == "mlp" else None
    draws = calibration_draws(subjects, K, 2, seed=0)
    person = "13"
    fold = list(np.unique(subjects)).index(person)
    rows = np.flatnonzero(subjects == person)
    clean, chosen_clean = summary_predictions(X, Y, features, subjects, draws, config, 1)
    for scored in rows[[0, -1]]:
        kept = draws[0, scored][draws[0, scored] >= 0]
        poisoned = np.setdiff1d(rows, kept)
        assert scored in poisoned
        Y_bad, F_bad = Y.copy(), features.copy()
        Y_bad[poisoned] += 5.0
        F_bad[poisoned] -= 2.0
        dirty, chosen_dirty = summary_predictions(X, Y_bad, F_bad, subjects, draws, config, 1)
        np.testing.assert_array_equal(dirty[0, scored], clean[0, scored])
        assert chosen_dirty[fold] == chosen_clean[fold]
        # the poison is real: a reach of the person that drew a poisoned one changes
        others = [o for o in poisoned if o != scored and np.isin(draws[0, o], poisoned).any()]
        assert any(not np.array_equal(dirty[0, o], clean[0, o]) for o in others)


def test_rows_and_names(problem):
    ds = problem[0]
    res = learned_person_rows(ds, (2,), use_torch=False, n_draws=3)
    assert set(res.criteria) == {"ridge_person_k2_loso", "mlp_person_k2_loso"}
    assert np.isfinite(res.criteria["ridge_person_k2_loso"])
    assert np.isnan(res.criteria["mlp_person_k2_loso"]) and "mlp_person_k2_loso" in res.skipped
    assert res.errors["ridge_person_k2_loso"].shape == (len(ds),)
    assert np.median(res.errors["ridge_person_k2_loso"]) == res.criteria["ridge_person_k2_loso"]


def test_cli_learned_calibration_rows_have_intervals(tmp_path, capsys):
    pytest.importorskip("torch")
    args = ["orientation", "--learned", "quick", "--calibration", "5", "--out", str(tmp_path)]
    assert main(args) == 0
    text = capsys.readouterr().out
    doc = json.loads((tmp_path / "results.json").read_text())
    for name in ("ridge_person_k5_loso", "mlp_person_k5_loso"):
        assert np.isfinite(doc["criteria"][name]) and name in text
        for ref in ("person_k5_path_loso", name.split("_person")[0] + "_loso"):
            lo, hi = doc["intervals"][f"{name} / {ref}"]
            assert lo <= hi
            assert any(line.strip().startswith(f"{name} / {ref}") for line in text.splitlines())
    assert doc["calibration"]["learned"]["mlp_train_draws"] == 2
    assert doc["noise_floor"]["rows"]["ridge_person_k5_loso"]["frame"] == "path"
