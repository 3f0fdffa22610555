"""The models as scikit-learn (>= 1.6, installed 1.9) sees them, written as a modeller's
calls: tags, check_is_fitted, fit(X, y) in scikit-learn's order, score() against the
criterion computed independently, cross_val_score, GridSearchCV and a Pipeline; the
warning of Lippi's regression outside its training conditions; scikit-learn's own
estimator checks, with the ones that cannot apply listed with their reason."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

pytest.importorskip("sklearn")

from sklearn.exceptions import NotFittedError as SklearnNotFittedError
from sklearn.model_selection import GridSearchCV, KFold, cross_val_score
from sklearn.pipeline import Pipeline
from sklearn.preprocessing import StandardScaler
from sklearn.utils import get_tags
from sklearn.utils.estimator_checks import parametrize_with_checks
from sklearn.utils.validation import check_is_fitted

from motion_envs.geometry import expmap, minimum_jerk, slerp
from motion_envs.geometry import quaternion as quat
from motion_envs.models import (
    ExtrapolationWarning,
    LinearBezierModel,
    MinimumJerk,
    NullBezierModel,
    OrientationModel,
    PoseModel,
    SineSeriesRegression,
    SpeedProfileModel,
    orientation_fit_errors,
    position_fit_errors,
)

RATE = 120.0


def reaches(n: int = 24, seed: int = 1) -> tuple[np.ndarray, list[np.ndarray]]:
    """``(Q, Ys)``: starts and ends ``(n, 6)`` and noisy minimum-jerk reaches of 1-1.3 s."""
    rng = np.random.default_rng(seed)
    starts = rng.normal(0, 0.02, (n, 3))
    ends = starts + np.array([0.3, 0.1, 0]) + rng.normal(0, 0.02, (n, 3))
    ys = []
    for s, e in zip(starts, ends, strict=True):
        k = int(rng.integers(120, 157))
        bow = 0.01 * np.sin(np.pi * np.linspace(0, 1, k))[:, None] * [0, 0, 1]
        ys.append(minimum_jerk.minimum_jerk(s, e, np.linspace(0, 1, k)) + bow)
        ys[-1] = ys[-1] + rng.normal(0, 5e-4, ys[-1].shape)
    return np.hstack([starts, ends]), ys


def turns(n: int = 12) -> tuple[np.ndarray, list[np.ndarray]]:
    """``(subjects, qs)``: hand turns with a wobble that depends on the subject."""
    out, subjects = [], []
    for i in range(n):
        tau = np.linspace(0, 1, 100 + 5 * i)
        q = slerp(expmap([0, 0, 0.1]), expmap([0.6 + 0.05 * (i % 4), 0.1, 0.0]), tau)
        amp = 0.04 if i % 2 else 0.1
        out.append(quat.multiply(q, expmap(amp * np.sin(np.pi * tau)[:, None] * [1, 0, 0])))
        subjects.append("a" if i % 2 else "b")
    return np.array(subjects), out


def test_tags_and_check_is_fitted_before_and_after_fit():
    """scikit-learn 1.9 asks every estimator for __sklearn_tags__ (AttributeError before)."""
    Q, ys = reaches()
    subjects, qs = turns()
    poses = [np.hstack([y[:100], q[:100]]) for y, q in zip(ys, qs, strict=False)]
    alpha = np.random.default_rng(0).random((24, 5))
    cases = [
        (SineSeriesRegression(4), lambda m: m.fit(Q, ys, rate=RATE)),
        (MinimumJerk(), lambda m: m.fit(Q, ys, rate=RATE)),
        (OrientationModel(by="subject"), lambda m: m.fit(subjects, qs, rate=RATE)),
        (PoseModel(n_sines=3), lambda m: m.fit(None, poses, rate=RATE)),
        (SpeedProfileModel(lam=1.0), lambda m: m.fit(Q[:, :2], np.sort(alpha, axis=1))),
        (NullBezierModel(2), lambda m: m.fit(np.zeros((4, 10, 3)))),
    ]  # fmt: skip
    for model, fit in cases:
        tags = get_tags(model)
        assert tags.requires_fit and tags.target_tags.required
        with pytest.raises(SklearnNotFittedError):
            check_is_fitted(model)
        check_is_fitted(fit(model))


def test_score_is_the_negative_criterion():
    Q, ys = reaches()
    model = SineSeriesRegression(n_sines=5).fit(Q, ys, rate=RATE)
    oracle = position_fit_errors(model, ys, Q, rate=RATE).criterion
    assert model.score(Q, ys, rate=RATE) == pytest.approx(-oracle, rel=1e-12)
    assert model.score(Q, ys) == pytest.approx(-oracle, rel=1e-9)  # any uniform rate
    # minimum jerk: each reach from its row of X over its own duration, by hand
    mj = MinimumJerk().fit(Q, ys, rate=RATE)
    by_hand = []
    for q, y in zip(Q, ys, strict=True):
        path = minimum_jerk.minimum_jerk(q[:3], q[3:], np.linspace(0, 1, len(y)))
        by_hand.append(np.linalg.norm(path - y, axis=1).max())
    assert mj.score(Q, ys, rate=RATE) == pytest.approx(-np.median(by_hand), rel=1e-12)
    subjects, qs = turns()
    om = OrientationModel(degree=3, by="subject").fit(subjects, qs, rate=RATE)
    crit = orientation_fit_errors(om, qs, rate=RATE, subjects=subjects).criterion
    assert om.score(subjects, qs, rate=RATE) == pytest.approx(-crit, rel=1e-9)
    # the pose: positions, then (w, x, y, z); lever 0 scores the position alone
    poses = [np.hstack([y[:100], q[:100]]) for y, q in zip(ys, qs, strict=False)]
    pm = PoseModel(n_sines=3, by="subject").fit(subjects, poses, rate=RATE)
    ends = np.array([np.r_[p[0, :3], p[-1, :3]] for p in poses])
    pos = position_fit_errors(pm.position_model_, [p[:, :3] for p in poses], ends, rate=RATE)
    assert pm.score(subjects, poses, rate=RATE, lever=0.0) == pytest.approx(-pos.criterion)
    assert pm.score(subjects, poses, rate=RATE) < pm.score(subjects, poses, rate=RATE, lever=0)
    # the speed profile: the largest error of each alpha curve, median, negated
    rng = np.random.default_rng(4)
    X = rng.normal(size=(30, 2))
    alpha = np.sort(rng.random((30, 8)), axis=1)
    alpha[:, 0], alpha[:, -1] = 0.0, 1.0
    sp = SpeedProfileModel(lam=0.5).fit(X, alpha)
    expected = -np.median(np.abs(sp.predict(X) - alpha).max(axis=1))
    assert sp.score(X, alpha) == pytest.approx(expected, rel=1e-12)


def test_fit_takes_scikit_learns_order_and_says_so():
    Q, ys = reaches(n=8)
    with pytest.raises(ValueError, match=r"scikit-learn's order: X the conditions \(n, q\)"):
        SineSeriesRegression(3).fit(ys, Q, rate=RATE)  # the order before: movements first
    with pytest.raises(ValueError, match=r"MinimumJerk.*X the starts and ends"):
        MinimumJerk().fit(ys, Q, rate=RATE)
    with pytest.raises(ValueError, match=r"X must be the finite starts and ends"):
        MinimumJerk().fit(Q[:, :3], ys, rate=RATE)
    with pytest.raises(ValueError, match=r"X has 7 rows and y 8 movements"):
        SineSeriesRegression(3).fit(Q[:7], ys, rate=RATE)


def test_cross_val_score_grid_search_and_pipeline():
    Q, ys = reaches()
    folds = KFold(4)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ExtrapolationWarning)  # held-out reaches, expected
        scores = cross_val_score(SineSeriesRegression(5), Q, ys, cv=folds, params={"rate": RATE})
        by_hand = []
        for train, test in folds.split(Q):
            m = SineSeriesRegression(5).fit(Q[train], [ys[i] for i in train], rate=RATE)
            by_hand.append(m.score(Q[test], [ys[i] for i in test], rate=RATE))
        np.testing.assert_allclose(scores, by_hand, rtol=1e-12)
        search = GridSearchCV(SineSeriesRegression(), {"n_sines": [1, 3, 6]}, cv=folds)
        search.fit(Q, ys, rate=RATE)
        means = []
        for n in (1, 3, 6):
            kw = {"cv": folds, "params": {"rate": RATE}}
            means.append(cross_val_score(SineSeriesRegression(n), Q, ys, **kw).mean())
        assert search.best_params_ == {"n_sines": (1, 3, 6)[int(np.argmax(means))]}
        assert search.best_score_ == pytest.approx(max(means), rel=1e-12)
        pipe = Pipeline([("scale", StandardScaler()), ("model", SineSeriesRegression(5))])
        pipe.fit(Q, ys, model__rate=RATE)
        Qs = StandardScaler().fit_transform(Q)
        alone = SineSeriesRegression(5).fit(Qs, ys, rate=RATE)
        assert pipe.score(Q, ys) == pytest.approx(alone.score(Qs, ys), rel=1e-12)
        subjects, qs = turns()
        orientation = cross_val_score(
            OrientationModel(by="subject"), subjects, qs, cv=KFold(3), params={"rate": RATE}
        )
        assert orientation.shape == (3,) and np.all(orientation < 0)
        mj = cross_val_score(MinimumJerk(), Q, ys, cv=folds, params={"rate": RATE})
        assert np.all(mj < 0) and np.all(mj < scores)  # the sines fit the bow, MJ cannot


def test_lippi_warns_outside_its_training_conditions():
    """The modeller's case: reaches ending near x = 0.3 m, a prediction for one to 0.44 m."""
    Q, ys = reaches()
    model = SineSeriesRegression(n_sines=5).fit(Q, ys, rate=RATE)
    with warnings.catch_warnings():
        warnings.simplefilter("error", ExtrapolationWarning)
        model.predict(Q.mean(axis=0), 1.0)  # inside the range: silent
        shift = np.array([0, 0, 0, 0.14, 0, 0])
        model.plan(Q.mean(axis=0) + shift, 1.0)  # the controllers' call: silent
    far = Q.mean(axis=0) + shift
    sd = Q[:, 3].std(ddof=1)
    z = abs(far[3] - Q[:, 3].mean()) / sd  # the oracle, by hand
    assert z > 5
    with pytest.warns(ExtrapolationWarning) as record:
        model.predict(far, 1.0)
    message = str(record[0].message)
    assert f"condition 3 (column 3 of the conditions) = {far[3]:.4g}" in message
    assert f"{z:.1f} SD from their mean" in message
    assert f"[{Q[:, 3].min():.4g}, {Q[:, 3].max():.4g}]" in message
    assert record[0].filename == __file__  # points at the modeller's line
    with pytest.warns(ExtrapolationWarning, match=r"1 of 24 movement\(s\) outside"):
        model.score(np.vstack([Q[:-1], far]), ys, rate=RATE)


#: Why scikit-learn's data checks cannot apply to these models: they fit X with a target
#: of one number per sample (and sparse, complex, object or NaN X); here y is one whole
#: movement per row of X (a ragged (n_i, D) array), and the model's input checks name
#: that. Listed per check so that a check that starts to pass is seen (XPASS).
ONE_MOVEMENT_PER_SAMPLE = (
    "scikit-learn's check fits a target of one number per sample; this model's y is one "
    "movement per sample (an (n_i, D) recording), so the check's data are not a fit"
)
DATA_CHECKS = (
    "check_complex_data", "check_dict_unchanged", "check_dont_overwrite_parameters",
    "check_dtype_object", "check_estimator_sparse_array", "check_estimator_sparse_matrix",
    "check_estimator_sparse_tag", "check_estimators_dtypes",
    "check_estimators_empty_data_messages", "check_estimators_fit_returns_self",
    "check_estimators_nan_inf", "check_estimators_overwrite_params",
    "check_estimators_pickle", "check_f_contiguous_array_estimator",
    "check_fit2d_1feature", "check_fit2d_1sample", "check_fit2d_predict1d",
    "check_fit_check_is_fitted", "check_fit_idempotent", "check_fit_score_takes_y",
    "check_methods_sample_order_invariance", "check_methods_subset_invariance",
    "check_n_features_in", "check_n_features_in_after_fitting", "check_pipeline_consistency",
    "check_positive_only_tag_during_fit", "check_readonly_memmap_input",
)  # fmt: skip
VALIDATES_IN_INIT = (
    "the project validates constructor arguments in __init__ (a bad value fails at once "
    "with a message naming the argument); scikit-learn defers that to fit"
)
BEZIER_Y = (
    "the Bézier models fit residual curves (L, n_points, 3) given first, with the labels "
    "as keywords: building blocks of the criteria and nominals, not the (X, y) order"
)


PREDICT_NEEDS_MORE = (
    "predict needs more than X: the movement's duration (SineSeriesRegression: "
    "predict(conditions, duration)) or its start and end (MinimumJerk, OrientationModel, "
    "PoseModel: predict(start, end, ...)); the check calls predict(X) alone (before fit "
    "each raises NotFittedError: tests/test_modeller_api.py, tests/test_pose_model.py)"
)


def expected_failures(estimator):
    """The checks each model is expected to fail, with the reason (exactly those: a check
    that passes would show as XPASS)."""
    name = type(estimator).__name__
    bezier = name.endswith("BezierModel")
    out = {check: BEZIER_Y if bezier else ONE_MOVEMENT_PER_SAMPLE for check in DATA_CHECKS}
    if bezier:
        out["check_requires_y_none"] = BEZIER_Y
    if name != "SineSeriesRegression":  # n_sines is checked where it is used
        out["check_do_not_raise_errors_in_init_or_set_params"] = VALIDATES_IN_INIT
    if name in ("SineSeriesRegression", "MinimumJerk", "OrientationModel", "PoseModel"):
        out["check_estimators_unfitted"] = PREDICT_NEEDS_MORE
    return out


@parametrize_with_checks(
    [
        SineSeriesRegression(),
        MinimumJerk(),
        OrientationModel(),
        PoseModel(),
        SpeedProfileModel(),
        NullBezierModel(),
        LinearBezierModel(),
    ],
    expected_failed_checks=expected_failures,
)
@pytest.mark.filterwarnings("ignore:Estimator .* does not inherit from:UserWarning")
@pytest.mark.filterwarnings("ignore:ValueError occurred during set_params:UserWarning")
def test_scikit_learn_estimator_checks(estimator, check):
    """The API checks pass (clone, get/set_params, repr, tags, nothing set in __init__,
    NotFittedError before fit, ...); the data checks are expected to fail (above)."""
    check(estimator)
