"""Sine-series regression: eq. 6 fit, generation, eq. 9 and eq. 10 constraints, validation."""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from motion_envs.geometry import sine_series as ss
from motion_envs.models import sine_regression as sr
from motion_envs.models.serialization import ModelFileError

N_SINES = 4
DIMS = 2


def _synthetic(n=30, noise=0.0, seed=0, n_samples=60, n_sines=N_SINES):
    """Trajectories whose sine coefficients are an exact affine function of Q=[start, end]."""
    rng = np.random.default_rng(seed)
    start = rng.normal(size=(n, DIMS))
    end = start + rng.normal(loc=2.0, size=(n, DIMS))
    q = np.column_stack([start, end])
    w = rng.normal(size=(n_sines * DIMS, 2 * DIMS + 1))
    b = (np.column_stack([q, np.ones(n)]) @ w.T).reshape(n, n_sines, DIMS)
    b = b + noise * rng.normal(size=b.shape)
    p = np.concatenate([start[:, None], (end - start)[:, None], b], axis=1)
    tau = np.linspace(0, 1, n_samples)
    y = ss.evaluate(p, tau)
    return [yi for yi in y], q, p, w


@pytest.fixture(scope="module")
def fitted():
    ys, q, p, w = _synthetic()
    model = sr.SineSeriesRegression(n_sines=N_SINES).fit(q, ys, times="normalised")
    return model, q, p, w


def test_fit_recovers_affine_map(fitted):
    model, _, p, w = fitted
    np.testing.assert_allclose(model.coefficients_, p, atol=1e-10)
    # rows 0/1 of P are the start and end - start: F restricted to them is known
    f = model.F_.reshape(N_SINES + 2, DIMS, 2 * DIMS + 1)
    np.testing.assert_allclose(f[0, :, :DIMS], np.eye(DIMS), atol=1e-9)
    np.testing.assert_allclose(f[1, :, DIMS : 2 * DIMS], np.eye(DIMS), atol=1e-9)
    np.testing.assert_allclose(f[1, :, :DIMS], -np.eye(DIMS), atol=1e-9)
    np.testing.assert_allclose(f[2:].reshape(-1, 2 * DIMS + 1), w, atol=1e-9)


def test_fit_matches_lstsq_oracle_with_noise():
    ys, q, _, _ = _synthetic(n=25, noise=0.1, seed=3)
    model = sr.SineSeriesRegression(n_sines=N_SINES).fit(q, ys, times="normalised")
    design = np.column_stack([q, np.ones(len(q))])
    oracle = np.linalg.lstsq(design, model.coefficients_.reshape(len(q), -1), rcond=None)[0].T
    np.testing.assert_allclose(model.F_, oracle, atol=1e-10)


def test_rank_deficient_design_warns():
    ys, q, _, _ = _synthetic(n=10)
    q = np.column_stack([q, np.full(len(q), 3.0)])
    with pytest.warns(sr.RankDeficientDesignWarning, match=r"constant"):
        sr.SineSeriesRegression(n_sines=N_SINES).fit(q, ys, times="normalised")


def test_generation_hits_requested_ends(fitted):
    model, _, _, _ = fitted
    start, end = np.array([0.3, -1.0]), np.array([2.5, 1.5])
    t, y = model.generate(
        np.concatenate([start, end]), duration=2.0, n_points=11, start=start, end=end
    )
    np.testing.assert_allclose(t, np.linspace(0, 2.0, 11))
    np.testing.assert_allclose(y[0], start, atol=1e-12)
    np.testing.assert_allclose(y[-1], end, atol=1e-12)
    # on the hyperplane, the generated sine coefficients are the affine map of Q
    p = model.predict_coefficients(np.concatenate([start, end]))
    np.testing.assert_allclose(p[2:].reshape(-1), model.F_[2 * DIMS :] @ np.r_[start, end, 1])


def test_non_uniform_times_fit(fitted):
    model, q, p, _ = fitted
    rng = np.random.default_rng(5)
    times = [np.concatenate([[0.0], np.sort(rng.uniform(0, 3, 40)), [3.0]]) for _ in range(len(q))]
    ys = [ss.evaluate(p[i], times[i] / 3.0) for i in range(len(q))]
    m2 = sr.SineSeriesRegression(n_sines=N_SINES).fit(q, ys, times=times)
    np.testing.assert_allclose(m2.F_, model.F_, atol=1e-8)
    np.testing.assert_allclose(m2.durations_, 3.0)


def _end_velocity(p, duration):
    return ss.velocity(p, [1.0], duration)[0]


@settings(max_examples=25, deadline=None)
@given(
    v=st.lists(st.floats(-5, 5), min_size=DIMS, max_size=DIMS),
    duration=st.floats(0.2, 3.0),
    mode=st.sampled_from(["hyperplane", "free"]),
)
def test_final_velocity_constraint_holds(fitted, v, duration, mode):
    model, _, _, _ = fitted
    start, end = np.array([0.1, 0.2]), np.array([2.0, 2.4])
    p0 = model.predict_coefficients(np.r_[start, end], start, end)
    p = model.plan(
        np.r_[start, end], duration, start, end, final_velocity=v, mode=mode,
        fix_end=False, max_end_shift=None,
    )  # fmt: skip
    np.testing.assert_allclose(_end_velocity(p, duration), v, atol=1e-9)
    np.testing.assert_allclose(ss.evaluate(p, [0.0])[0], start, atol=1e-12)
    dp = (p - p0).reshape(-1)
    if mode == "hyperplane":
        # dP lies in the span of F_Q: dP = F_Q dQ
        dq = np.linalg.lstsq(model.F_Q_, dp, rcond=None)[0]
        np.testing.assert_allclose(model.F_Q_ @ dq, dp, atol=1e-9)
    else:
        # closed form per coordinate: dP_d = g (v_d - vfree_d) / |g|^2
        g = ss.basis_derivative(1.0, N_SINES) / duration
        vfree = g @ p0
        expected = np.outer(g, (np.asarray(v) - vfree) / (g @ g))
        np.testing.assert_allclose(p - p0, expected, atol=1e-9)


def test_final_velocity_single_axis_and_fixed_end(fitted):
    model, _, _, _ = fitted
    start, end = np.array([0.0, 0.0]), np.array([1.0, 3.0])
    p0 = model.predict_coefficients(np.r_[start, end], start, end)
    p = sr.constrain_final_velocity(
        p0, [0.0, 0.0], 1.5, model.F_Q_, "hyperplane", axes=[1], fix_end=False
    )
    assert abs(_end_velocity(p, 1.5)[1]) < 1e-9
    p = sr.constrain_final_velocity(p0, [0.7, -0.2], 1.5, mode="free", fix_end=True)
    np.testing.assert_allclose(_end_velocity(p, 1.5), [0.7, -0.2], atol=1e-9)
    np.testing.assert_allclose(ss.evaluate(p, [0.0, 1.0]), [start, end], atol=1e-12)
    with pytest.raises(ValueError, match="cannot meet"):
        sr.constrain_final_velocity(p0, [0.7, -0.2], 1.5, model.F_Q_, "hyperplane", fix_end=True)


def test_online_correction_closed_form_line():
    # N = 0: Y = c0 + c1 tau through (tau1, a) and (1, b) is unique.
    p = np.array([[0.0, 1.0], [1.0, 1.0]])
    tau1, a, b = 0.25, np.array([0.5, 0.0]), np.array([2.0, -1.0])
    p2 = sr.correct_online(p, tau1, a, b, duration=1.0)
    c1 = (b - a) / (1 - tau1)
    np.testing.assert_allclose(p2, [b - c1, c1], atol=1e-14)


@settings(max_examples=25, deadline=None)
@given(
    tau1=st.floats(0.05, 0.9),
    dy=st.lists(st.floats(-1, 1), min_size=DIMS, max_size=DIMS),
    dtarget=st.lists(st.floats(-1, 1), min_size=DIMS, max_size=DIMS),
    with_velocity=st.booleans(),
)
def test_online_correction_constraints(fitted, tau1, dy, dtarget, with_velocity):
    model, _, _, _ = fitted
    start, end, duration = np.array([0.0, 0.5]), np.array([2.0, 2.0]), 1.3
    p = model.plan(np.r_[start, end], duration, start, end)
    y1 = ss.evaluate(p, [tau1])[0] + dy
    target = end + dtarget
    v1 = ss.velocity(p, [tau1], duration)[0] + 0.5 if with_velocity else None
    modes = ["free"] if with_velocity else ["free", "hyperplane"]
    for mode in modes:
        p2 = model.correct(p, tau1, y1, target, duration, velocity=v1, mode=mode)
        np.testing.assert_allclose(ss.evaluate(p2, [tau1])[0], y1, atol=1e-9)
        np.testing.assert_allclose(ss.evaluate(p2, [1.0])[0], target, atol=1e-9)
        if v1 is not None:
            np.testing.assert_allclose(ss.velocity(p2, [tau1], duration)[0], v1, atol=1e-9)
        tau = np.linspace(0, 1, 41)
        y = sr.evaluate_corrected(p, p2, tau1, tau)
        past = tau < tau1
        np.testing.assert_array_equal(y[past], ss.evaluate(p, tau[past]))
        if mode == "free":
            # minimum norm: dP is in the row space of the condition matrix
            rows = [ss.basis(tau1, N_SINES), ss.basis(1.0, N_SINES)]
            if v1 is not None:
                rows.append(ss.basis_derivative(tau1, N_SINES) / duration)
            a = np.stack(rows)
            proj = np.linalg.pinv(a) @ a
            np.testing.assert_allclose(proj @ (p2 - p), p2 - p, atol=1e-9)


def test_online_correction_hyperplane_with_velocity_is_refused(fitted):
    model, _, _, _ = fitted
    p = model.plan(np.array([0, 0, 1, 1.0]), 1.0, [0, 0], [1, 1])
    with pytest.raises(ValueError, match="cannot meet"):
        model.correct(p, 0.3, [0.5, 0.5], [1, 1], 1.0, velocity=[3.0, 0.0], mode="hyperplane")


def test_save_load_round_trip(fitted, tmp_path):
    model, _, _, _ = fitted
    path = model.save(tmp_path / "m.json")
    loaded = sr.SineSeriesRegression.load(path)
    np.testing.assert_array_equal(loaded.F_, model.F_)
    np.testing.assert_array_equal(loaded.coefficients_, model.coefficients_)
    assert loaded.n_sines == model.n_sines and loaded.rank_ == model.rank_
    q = np.array([0.1, 0.2, 1.0, 2.0])
    np.testing.assert_array_equal(loaded.predict_coefficients(q), model.predict_coefficients(q))
    text = path.read_text()
    (tmp_path / "cut.json").write_text(text[: len(text) // 2])
    with pytest.raises(ModelFileError, match="corrupt"):
        sr.SineSeriesRegression.load(tmp_path / "cut.json")
    doc = json.loads(text)
    doc["format_version"] = 99
    (tmp_path / "v.json").write_text(json.dumps(doc))
    with pytest.raises(ModelFileError, match="format_version"):
        sr.SineSeriesRegression.load(tmp_path / "v.json")


def test_select_n_sines_by_cross_validation():
    rng = np.random.default_rng(2)
    ys, q, _, _ = _synthetic(n=20, noise=0.02, seed=4, n_sines=3, n_samples=40)
    ys = [y + 0.05 * rng.normal(size=y.shape) for y in ys]
    best, scores = sr.select_n_sines(
        ys, q, candidates=[0, 1, 2, 3, 6, 12], times="normalised", n_folds=5
    )
    assert best == 3
    assert scores.shape == (6,)
    assert scores[3] < scores[2] and scores[3] < scores[5]


def test_validation_statistics_against_oracles():
    ys, q, _, _ = _synthetic(n=40, noise=0.05, seed=7)
    model = sr.SineSeriesRegression(n_sines=N_SINES).fit(q, ys, times="normalised")
    rep = model.validate()
    n, k = len(q), model.F_.shape[0]
    assert rep.F.shape == (k, 2 * DIMS + 1)
    # start and end rows are exact functions of Q = [start, end]
    assert rep.exact[: 2 * DIMS].all() and not rep.exact[2 * DIMS :].any()
    design = np.column_stack([q, np.ones(n)])
    p = model.coefficients_.reshape(n, -1)
    # F-test and jackknife against a hand computation for one coefficient
    j = 2 * DIMS + 3
    y = p[:, j]
    beta = np.linalg.lstsq(design, y, rcond=None)[0]
    ssr = np.sum((y - design @ beta) ** 2)
    sst = np.sum((y - y.mean()) ** 2)
    dfm, dfr = q.shape[1], n - q.shape[1] - 1
    f_manual = ((sst - ssr) / dfm) / (ssr / dfr)
    np.testing.assert_allclose(rep.f_stat[j], f_manual, rtol=1e-9)
    loo = np.array(
        [np.linalg.lstsq(np.delete(design, i, 0), np.delete(y, i), rcond=None)[0] for i in range(n)]
    )
    jack = (n - 1) / n * np.sum((loo - loo.mean(0)) ** 2, axis=0)
    np.testing.assert_allclose(rep.jackknife_var[j], jack, rtol=1e-8)
    # 95 % CI: beta +- t_{0.975, dfr} * se
    from scipy import stats

    cov = ssr / dfr * np.linalg.inv(design.T @ design)
    half = stats.t.ppf(0.975, dfr) * np.sqrt(np.diag(cov))
    np.testing.assert_allclose(rep.ci_low[j], beta - half, rtol=1e-8)
    assert np.all(rep.lilliefors_p[~rep.exact] > 0)  # computed
    rows = rep.summary()
    assert [r["coordinate"] for r in rows] == [0, 1]
    assert all(r["ftest_frac"] == 1.0 for r in rows)  # strong linear dependence
    assert all(r["jack_rel"] < 0.1 for r in rows)


def test_bad_input():
    ys, q, _, _ = _synthetic(n=6)
    with pytest.raises(ValueError, match="NaN"):
        sr.SineSeriesRegression(2).fit(
            np.where(np.eye(6, 4, dtype=bool), np.nan, q), ys, times="normalised"
        )
    with pytest.raises(ValueError, match="positions\\[1\\] has 3 samples"):
        sr.SineSeriesRegression(2).fit(q[:2], [ys[0], ys[1][:3]], times="normalised")
    with pytest.raises(ValueError, match="X has 4 rows and y 6 movements"):
        sr.SineSeriesRegression(2).fit(q[:4], ys, times="normalised")
    with pytest.raises(ValueError, match="scikit-learn's order: X the conditions"):
        sr.SineSeriesRegression(2).fit(ys, q, times="normalised")  # the order before 1.0
    with pytest.raises(ValueError, match="not fitted"):
        sr.SineSeriesRegression(2).predict_coefficients([0.0])
    with pytest.raises(ValueError, match="tau1"):
        sr.correct_online(np.zeros((4, 2)), 1.0, [0, 0], [0, 0], 1.0)
