"""The models as a modeller calls them on their own arrays (issue 23).

Every test is a friction a human-motion modeller met, written as the modeller's call, on
SIMULATED reaches: 3 people to 4 targets, 120 Hz, 0.5 mm Gaussian noise.
"""

from __future__ import annotations

import numpy as np
import pytest

from motion_envs.geometry import sine_series as ss
from motion_envs.models.sine_regression import SineSeriesRegression

RATE = 120.0
NOISE = 0.5e-3
TARGETS = np.array([[0.3, 0.0, 0.0], [0.0, 0.3, 0.0], [-0.2, 0.2, 0.1], [0.2, -0.2, -0.1]])


def _min_jerk(s):
    return 10 * s**3 - 15 * s**4 + 6 * s**5


def simulated_reaches(seed=0, n_reps=3, noise=NOISE):
    """SIMULATED reaches: positions (n_i, 3) in metres, times (n_i,) in s, conditions."""
    rng = np.random.default_rng(seed)
    ys, ts, qs, subjects = [], [], [], []
    for subject in range(3):
        bow = 0.02 * (subject + 1)
        for target in TARGETS:
            for _ in range(n_reps):
                start = rng.normal(scale=0.01, size=3)
                end = target + rng.normal(scale=0.005, size=3)
                duration = 0.8 + 0.1 * subject + rng.uniform(0, 0.1)
                t = np.arange(int(duration * RATE) + 1) / RATE
                s = t / t[-1]
                side = np.cross(end - start, [0.0, 0.0, 1.0])
                side = side / max(np.linalg.norm(side), 1e-9)
                y = start + np.outer(_min_jerk(s), end - start)
                y = y + bow * np.outer(np.sin(np.pi * s) ** 2, side)
                ys.append(y + rng.normal(scale=noise, size=y.shape))
                ts.append(t)
                qs.append(np.r_[start, end])
                subjects.append(f"s{subject}")
    return ys, ts, np.array(qs), np.array(subjects)


@pytest.fixture(scope="module")
def reaches():
    return simulated_reaches()


@pytest.fixture(scope="module")
def sine_model(reaches):
    ys, ts, q, _ = reaches
    return SineSeriesRegression(n_sines=6).fit(q, ys, times=ts)


# -- 1. eq. 9: safe by default ---------------------------------------------------------
def test_plan_final_velocity_holds_start_and_end_by_default(sine_model):
    y0, y1 = np.zeros(3), np.array([0.3, 0.0, 0.0])
    q, duration = np.r_[y0, y1], 1.0
    p = sine_model.plan(q, duration, start=y0, end=y1, final_velocity=[0, 0, -0.1])
    np.testing.assert_allclose(ss.evaluate(p, 0.0), y0, atol=1e-12)
    np.testing.assert_allclose(ss.evaluate(p, 1.0), y1, atol=1e-12)
    np.testing.assert_allclose(ss.velocity(p, [1.0], duration)[0], [0, 0, -0.1], atol=1e-12)
    _t, y = sine_model.generate(q, duration, start=y0, end=y1, final_velocity=[0, 0, -0.1])
    np.testing.assert_allclose(y[-1], y1, atol=1e-12)


def test_plan_hyperplane_reports_and_limits_the_end_shift(sine_model):
    y0, y1 = np.zeros(3), np.array([0.3, 0.0, 0.0])
    q = np.r_[y0, y1]
    kw = dict(start=y0, end=y1, final_velocity=[0, 0, -0.1], mode="hyperplane")
    with pytest.raises(ValueError, match="fix_end=False"):
        sine_model.plan(q, 1.0, **kw)
    with pytest.raises(ValueError, match=r"moves the end point by .*max_end_shift"):
        sine_model.plan(q, 1.0, fix_end=False, **kw)
    p, shift = sine_model.plan(q, 1.0, fix_end=False, max_end_shift=None,
                               return_end_shift=True, **kw)  # fmt: skip
    np.testing.assert_allclose(ss.evaluate(p, 1.0), y1 + shift, atol=1e-12)
    assert np.linalg.norm(shift) > 1e-3
    np.testing.assert_allclose(ss.velocity(p, [1.0], 1.0)[0], [0, 0, -0.1], atol=1e-9)


def test_generate_fix_end_false_free_mode_shift_is_checked(sine_model):
    y0, y1 = np.zeros(3), np.array([0.3, 0.0, 0.0])
    with pytest.raises(ValueError, match="max_end_shift"):
        sine_model.generate(np.r_[y0, y1], 1.0, start=y0, end=y1,
                            final_velocity=[0, 0, -5.0], fix_end=False)  # fmt: skip


# -- 2. segmentation criteria: keyword-only, never-firing refused -----------------------
def test_criteria_are_keyword_only_and_refuse_never_firing():
    from motion_envs.models import segmentation as sg

    with pytest.raises(TypeError):
        sg.SpeedAbove(0.05)  # type: ignore[misc]
    assert sg.SpeedAbove(threshold=0.05).threshold == 0.05
    for bad in (
        lambda: sg.SpeedBelow(threshold=0.0),
        lambda: sg.SpeedBelow(threshold=float("nan")),
        lambda: sg.SpeedAbove(threshold=-1.0),
        lambda: sg.SpeedAbove(threshold=float("inf")),
        lambda: sg.AccelerationBelow(axis=2, threshold=float("-inf")),
        lambda: sg.PositionReached(target=(0.3, 0.0, 0.0), tolerance=-1e-3),
        lambda: sg.EventOccurred(name=""),
        lambda: sg.SpeedAbove(threshold=0.05, min_elapsed=-0.1),
    ):
        with pytest.raises(ValueError, match=r"never|must"):
            bad()


# -- 3. one shape rule for scalar and array tau ------------------------------------------
def test_scalar_and_array_tau_share_one_shape_rule(sine_model):
    y0, y1 = np.zeros(3), np.array([0.3, 0.0, 0.0])
    duration = 0.9
    p = sine_model.plan(np.r_[y0, y1], duration, start=y0, end=y1)
    for f in (
        lambda tau: ss.evaluate(p, tau),
        lambda tau: ss.velocity(p, tau, duration),
        lambda tau: ss.acceleration(p, tau, duration),
    ):
        assert f(0.5).shape == (3,)
        assert f([0.5]).shape == (1, 3)
        assert f(np.linspace(0, 1, 7)).shape == (7, 3)
        np.testing.assert_array_equal(f(0.5), f([0.5])[0])
    # batched coefficients with one duration each
    pb = np.stack([p, 2 * p])
    assert ss.velocity(pb, 0.5, [duration, 2 * duration]).shape == (2, 3)
    assert ss.acceleration(pb, [0.2, 0.5], [duration, 2 * duration]).shape == (2, 2, 3)
    np.testing.assert_allclose(ss.velocity(pb, 0.5, [duration, 2 * duration])[1],
                               ss.velocity(p, 0.5, duration), rtol=1e-12)  # fmt: skip
    # oracle: central differences of the position in seconds
    h = 1e-4
    t = 0.4 * duration
    pos = [ss.evaluate(p, (t + k * h) / duration) for k in (-1, 0, 1)]
    np.testing.assert_allclose(ss.velocity(p, t / duration, duration),
                               (pos[2] - pos[0]) / (2 * h), atol=1e-6)  # fmt: skip
    np.testing.assert_allclose(ss.acceleration(p, t / duration, duration),
                               (pos[2] - 2 * pos[1] + pos[0]) / h**2, atol=1e-3)  # fmt: skip
    # eq. 10 takes the executed velocity straight from velocity(P, tau1, T)
    tau1 = 0.5
    v1 = ss.velocity(p, tau1, duration)
    p2 = sine_model.correct(p, tau1, ss.evaluate(p, tau1), [0.25, 0.05, 0.0], duration,
                            velocity=v1)  # fmt: skip
    np.testing.assert_allclose(ss.velocity(p2, tau1, duration), v1, atol=1e-12)
    np.testing.assert_allclose(ss.evaluate(p2, 1.0), [0.25, 0.05, 0.0], atol=1e-12)


# -- 4. smooth before differentiating ---------------------------------------------------
def simulated_session(seed=1, noise=NOISE):
    """SIMULATED: 4 reaches out and back with 0.6 s of rest between them, at 120 Hz."""
    rng = np.random.default_rng(seed)
    rest = np.zeros((int(0.6 * RATE), 3))
    pieces = [rest]
    here = np.zeros(3)
    for target in TARGETS:
        s = np.linspace(0, 1, int(0.9 * RATE) + 1)[1:]
        pieces.append(here + np.outer(_min_jerk(s), target - here))
        here = target
        pieces.append(np.tile(here, (len(rest), 1)))
    y = np.concatenate(pieces)
    return np.arange(len(y)) / RATE, y + rng.normal(scale=noise, size=y.shape)


def test_segmentation_smooths_noise_before_differentiating():
    from motion_envs.geometry import kinematics
    from motion_envs.models import segmentation as sg

    t, y = simulated_session()
    phases = [
        ("rest", sg.SpeedAbove(threshold=0.05)),
        ("reach", sg.SpeedBelow(threshold=0.05, min_elapsed=0.2)),
    ]
    reaches = [s for s in sg.segment(t, y, phases) if s.name == "reach"]
    assert len(reaches) == 4
    for s, start in zip(reaches, np.arange(4) * 1.5 + 0.6, strict=True):
        assert abs(t[s.start] - start) < 0.1  # the reach begins within 0.1 s of the truth
    raw = [s for s in sg.segment(t, y, phases, window=None) if s.name == "reach"]
    assert len(raw) != 4  # the friction: raw differences fire on 0.5 mm noise
    # the same smoothing is the public helper's, window settable
    v = kinematics.smoothed_velocity(y, rate=RATE, window=0.2)
    assert v.shape == y.shape
    assert np.max(kinematics.speed(y[:60], rate=RATE)[8:-8]) < 0.03  # at rest: noise only


# -- 5. the time base is required, sample indices are not seconds -----------------------
def test_fit_requires_times_or_rate(reaches):
    ys, ts, q, _ = reaches
    with pytest.raises(ValueError, match=r"times=.*rate="):
        SineSeriesRegression(n_sines=6).fit(q, ys)
    with pytest.raises(ValueError, match="sample indices are not seconds"):
        SineSeriesRegression(n_sines=6).fit(q, ys, times=[np.arange(len(y)) for y in ys])
    by_rate = SineSeriesRegression(n_sines=6).fit(q, ys, rate=RATE)
    by_times = SineSeriesRegression(n_sines=6).fit(q, ys, times=ts)
    np.testing.assert_allclose(by_rate.durations_, [t[-1] for t in ts], rtol=1e-12)
    np.testing.assert_allclose(by_rate.F_, by_times.F_, atol=1e-12)
    assert 0.8 <= by_rate.durations_.min() and by_rate.durations_.max() < 1.15  # seconds
    unit = SineSeriesRegression(n_sines=6).fit(q, ys, times="normalised")
    np.testing.assert_array_equal(unit.durations_, 1.0)


# -- 6. scikit-learn estimator conventions ------------------------------------------------
def _all_models():
    from motion_envs.models.bezier_models import (
        GroupBezierModel,
        LinearBezierModel,
        NullBezierModel,
        SubjectBezierModel,
        TaskBezierModel,
    )
    from motion_envs.models.orientation_model import OrientationModel
    from motion_envs.models.timing_model import SpeedProfileModel

    return [
        OrientationModel(degree=3, by="subject"),
        SineSeriesRegression(n_sines=5),
        NullBezierModel(degree=3),
        GroupBezierModel(degree=2, by="subject", unseen="global"),
        SubjectBezierModel(degree=2),
        TaskBezierModel(degree=3, frame="path", up=(0, 1, 0)),
        LinearBezierModel(degree=2),
        SpeedProfileModel(lam=0.1),
    ]


def _predict_unfitted(model):
    if type(model).__name__ == "OrientationModel":
        model.predict([1.0, 0, 0, 0], [0.0, 1, 0, 0], [0.0, 0.5])
    elif isinstance(model, SineSeriesRegression):
        model.predict([0.0] * 6, 1.0)
    elif type(model).__name__ == "SpeedProfileModel":
        model.predict(np.zeros((2, 2)))
    else:
        model.predict(n=2, subjects=["a", "b"], tasks=["a", "b"], predictors=np.zeros((2, 1)))


@pytest.mark.parametrize("model", _all_models(), ids=lambda m: type(m).__name__)
def test_every_model_follows_sklearn_conventions(model):
    from motion_envs.models.estimator import NotFittedError

    params = model.get_params()
    assert params and all(getattr(model, k) is v for k, v in params.items())
    assert repr(model).startswith(type(model).__name__ + "(")
    assert model.set_params(**params) is model
    with pytest.raises(ValueError, match="invalid parameter"):
        model.set_params(not_a_parameter=1)
    assert hasattr(model, "predict") and hasattr(model, "fit")
    assert not [k for k in vars(model) if k.endswith("_") and not k.startswith("_")]
    with pytest.raises(NotFittedError, match="not fitted") as info:
        _predict_unfitted(model)
    assert isinstance(info.value, ValueError) and isinstance(info.value, AttributeError)


@pytest.mark.parametrize("model", _all_models(), ids=lambda m: type(m).__name__)
def test_sklearn_clone_and_not_fitted_error(model):
    sklearn_base = pytest.importorskip("sklearn.base")
    from sklearn.exceptions import NotFittedError as SkNotFitted

    twin = sklearn_base.clone(model)
    assert type(twin) is type(model) and twin is not model
    assert repr(twin) == repr(model)
    with pytest.raises(SkNotFitted):
        _predict_unfitted(model)


def test_sine_model_fit_returns_self_and_predicts_at_times(reaches, sine_model):
    ys, ts, q, _ = reaches
    model = SineSeriesRegression(n_sines=6)
    assert model.fit(q, ys, times=ts) is model
    i = 5
    y_hat = sine_model.predict(q[i], ts[i][-1], ts[i], start=ys[i][0], end=ys[i][-1])
    assert y_hat.shape == ys[i].shape
    # within 2 cm: the subjects bow by 2, 4, 6 cm and Q (start, end) does not say whose reach
    assert np.sqrt(np.mean(np.sum((y_hat - ys[i]) ** 2, axis=1))) < 0.02
    batch = sine_model.predict(q[:3], [t[-1] for t in ts[:3]], np.linspace(0, 0.8, 5))
    assert batch.shape == (3, 5, 3)


# -- 7. one orientation model object; selecting ragged trajectories ----------------------
def simulated_turns(seed=2, n_reps=3):
    """SIMULATED wrist turns (w, x, y, z) at 120 Hz with sign flips, 3 subjects x 4 goals."""
    from motion_envs.geometry import quaternion as quat

    rng = np.random.default_rng(seed)
    qs, ts, subjects = [], [], []
    goals = quat.expmap(np.array([[0.6, 0, 0], [0, 0.8, 0], [0, 0, -0.7], [0.4, 0.4, 0]]))
    for subject in range(3):
        tilt = np.array([0.0, 0.0, 0.05 * (subject + 1)])
        for goal in goals:
            for _ in range(n_reps):
                start = quat.expmap(rng.normal(scale=0.05, size=3))
                duration = 0.7 + 0.1 * subject + rng.uniform(0, 0.1)
                t = np.arange(int(duration * RATE) + 1) / RATE
                s = t / t[-1]
                base = quat.slerp(start, goal, _min_jerk(s))
                q = quat.multiply(base, quat.expmap(np.outer(np.sin(np.pi * s), tilt)))
                flips = rng.random(len(q)) < 0.2
                q[flips] *= -1.0
                qs.append(q)
                ts.append(t)
                subjects.append(f"s{subject}")
    return qs, ts, np.array(subjects)


def test_orientation_model_predicts_quaternions_at_given_times():
    from motion_envs.geometry import quaternion as quat
    from motion_envs.models.orientation_model import OrientationModel

    qs, ts, subjects = simulated_turns()
    model = OrientationModel(degree=3, by="subject")
    assert model.fit(subjects, qs, rate=RATE) is model
    i = 7
    q_hat = model.predict(qs[i][0], qs[i][-1], ts[i], subjects=[subjects[i]])
    assert q_hat.shape == (len(ts[i]), 4)
    np.testing.assert_allclose(quat.angle(q_hat[[0, -1]], qs[i][[0, -1]]), 0.0, atol=1e-9)
    assert np.max(quat.angle(q_hat, qs[i])) < np.deg2rad(3.0)  # 0.15 rad tilt, 4 rad turns
    # the same as the three-module pipeline it wraps, on the paper's grid
    from motion_envs.datasets.ragged import RaggedTrajectories
    from motion_envs.models.bezier_models import SubjectBezierModel
    from motion_envs.models.orientation_prediction import predict_orientations
    from motion_envs.models.slerp_residual import slerp_residuals
    from motion_envs.models.speed_profile import average_speed_profile

    traj = RaggedTrajectories.from_sequences(qs, ts)
    alpha = average_speed_profile(traj)
    bez = SubjectBezierModel(3).fit(slerp_residuals(traj, average_alpha=alpha), subjects=subjects)
    points = bez.predict_control_points(subjects=[subjects[i]])[0]
    oracle = predict_orientations(traj.starts[i], traj.ends[i], points, alpha=alpha)
    on_grid = model.predict(traj.starts[i], traj.ends[i], subjects=[subjects[i]])
    np.testing.assert_allclose(on_grid, oracle, atol=1e-12)
    # any times, batches of movements, one duration each
    starts = np.stack([q[0] for q in qs[:2]])
    ends = np.stack([q[-1] for q in qs[:2]])
    q2 = model.predict(starts, ends, [0.0, 0.2, 0.4], duration=[0.8, 0.9], subjects=subjects[:2])
    assert q2.shape == (2, 3, 4)
    with pytest.raises(ValueError, match="times"):
        model.predict(starts, ends, [0.0, 2.0], duration=[0.8, 0.9], subjects=subjects[:2])


def test_ragged_trajectories_select_by_mask_and_index():
    from motion_envs.datasets.ragged import RaggedTrajectories

    qs, ts, subjects = simulated_turns(n_reps=1)
    traj = RaggedTrajectories.from_sequences(qs, ts)
    mask = subjects == "s1"
    picked = traj[mask]
    expected = RaggedTrajectories.from_sequences(
        [q for q, m in zip(qs, mask, strict=True) if m],
        [t for t, m in zip(ts, mask, strict=True) if m],
    )
    assert len(picked) == mask.sum()
    for name in ("quaternions", "tau", "offsets", "durations"):
        np.testing.assert_array_equal(getattr(picked, name), getattr(expected, name))
    for key in ([3, 0, -1], np.array([2]), 5, slice(1, None, 4)):
        sub = traj[key]
        idx = np.arange(len(traj))[key] if not isinstance(key, list) else np.array(key) % len(traj)
        idx = np.atleast_1d(idx)
        np.testing.assert_array_equal(sub.durations, traj.durations[idx])
        np.testing.assert_array_equal(sub.starts, traj.starts[idx])
        np.testing.assert_array_equal(sub.ends, traj.ends[idx])
    with pytest.raises(IndexError):
        traj[np.ones(3, dtype=bool)]


# -- 8. one unit tolerance, explicit normalize=, shapes kept ------------------------------
def test_quaternion_tolerance_normalize_and_shapes():
    from motion_envs.geometry import quaternion as quat

    q = np.array([0.99999, 0.0, 0.0, 0.0])
    with pytest.raises(ValueError, match="normalize=True"):
        quat.as_unit(q)
    np.testing.assert_array_equal(quat.as_unit(q, normalize=True), [1.0, 0, 0, 0])
    assert quat.UNIT_TOLERANCE == 1e-6
    single = quat.expmap([0.1, 0.2, 0.3])
    np.testing.assert_array_equal(quat.make_continuous(single), single)
    rng = np.random.default_rng(0)
    batch = quat.normalize(rng.normal(size=(5, 7, 4)))
    rot = quat.to_rotation(batch)
    assert rot.shape == (5, 7)
    back = quat.from_rotation(rot)
    assert back.shape == (5, 7, 4)
    np.testing.assert_allclose(np.abs(np.sum(back * batch, axis=-1)), 1.0, atol=1e-12)
    assert quat.from_rotation(quat.to_rotation(single)).shape == (4,)


# -- 9. resampling, smoothness, minimum jerk, pandas ------------------------------------
def test_resample_to_a_rate_and_time_normalise(reaches):
    from motion_envs.geometry import resampling

    ys, ts, _, _ = reaches
    t100, _ = resampling.resample(ys[0], ts[0], rate=100.0)
    np.testing.assert_allclose(np.diff(t100), 0.01, atol=1e-12)
    assert t100[-1] <= ts[0][-1] + 1e-12 and ts[0][-1] - t100[-1] < 0.01
    # a cubic polynomial is reproduced exactly by the cubic spline (not-a-knot)
    t = np.sort(np.random.default_rng(3).uniform(0, 2, 40))
    poly = np.column_stack([t**3 - t, 2 * t**2])
    tn, yn = resampling.resample(poly, t, rate=50.0)
    np.testing.assert_allclose(yn, np.column_stack([tn**3 - tn, 2 * tn**2]), atol=1e-10)
    tau, y_tau = resampling.time_normalise(poly, t, n_points=11)
    np.testing.assert_array_equal(tau, np.linspace(0, 1, 11))
    t_of_tau = t[0] + tau * (t[-1] - t[0])
    np.testing.assert_allclose(y_tau[:, 1], 2 * t_of_tau**2, atol=1e-10)
    with pytest.raises(ValueError, match="sample indices"):
        resampling.resample(poly, np.arange(40), rate=50.0)


def test_smoothed_derivatives_are_exact_on_polynomials():
    from motion_envs.geometry import kinematics

    t = np.arange(200) / RATE
    y = np.column_stack([t**3, 1 - t**2, t])
    v = kinematics.smoothed_velocity(y, rate=RATE)
    np.testing.assert_allclose(v, np.column_stack([3 * t**2, -2 * t, np.ones_like(t)]), atol=1e-9)
    a = kinematics.smoothed_acceleration(y, times=t)
    np.testing.assert_allclose(a, np.column_stack([6 * t, -2 + 0 * t, 0 * t]), atol=1e-7)
    j = kinematics.smoothed_jerk(y, rate=RATE, window=0.2)
    np.testing.assert_allclose(j[:, 0], 6.0, atol=1e-5)
    assert kinematics.window_samples(0.1, RATE) == 13
    with pytest.raises(ValueError, match="not uniform"):
        kinematics.smoothed_velocity(y, times=t**1.1)


def test_smoothness_measures_against_closed_forms():
    from scipy import integrate

    from motion_envs.geometry import kinematics, smoothness
    from motion_envs.geometry.minimum_jerk import minimum_jerk

    t = np.arange(int(0.8 * RATE) + 1) / RATE
    y = minimum_jerk([0.0, 0, 0], [0.3, 0.1, 0], t / t[-1])
    ldlj = smoothness.log_dimensionless_jerk(y, rate=RATE)
    assert ldlj == pytest.approx(-np.log(720 / 1.875**2), abs=2e-3)  # -5.322
    wobbly = y + 0.002 * np.sin(2 * np.pi * 6 * t)[:, None]
    assert smoothness.log_dimensionless_jerk(wobbly, rate=RATE) < ldlj - 1
    # SPARC of a Gaussian speed profile: |V(f)| / V(0) = exp(-2 pi^2 s^2 f^2)
    s, rate = 0.1, 1000.0
    tt = np.arange(-1.0, 1.0, 1 / rate)
    sparc = smoothness.spectral_arc_length(np.exp(-(tt**2) / (2 * s**2)), rate)
    fc = np.sqrt(np.log(1 / 0.05) / (2 * np.pi**2 * s**2))  # where V falls to 0.05 (< 10 Hz)

    def arc(f):
        dv = -4 * np.pi**2 * s**2 * f * np.exp(-2 * np.pi**2 * s**2 * f**2)
        return np.sqrt((1 / fc) ** 2 + dv**2)

    assert sparc == pytest.approx(-integrate.quad(arc, 0, fc)[0], abs=5e-3)
    two = np.exp(-(tt**2) / (2 * s**2)) + np.exp(-((tt - 0.35) ** 2) / (2 * s**2))
    assert smoothness.spectral_arc_length(two, rate) < sparc  # two submovements: less smooth
    assert smoothness.spectral_arc_length(kinematics.speed(y, rate=RATE), RATE) < 0


def test_minimum_jerk_model_fitted_and_predicted_like_the_others(reaches, tmp_path):
    from motion_envs.geometry.minimum_jerk import minimum_jerk
    from motion_envs.models.minimum_jerk import MinimumJerk

    ys, ts, _, _ = reaches
    model = MinimumJerk()
    X = np.stack([np.concatenate([y[0], y[-1]]) for y in ys])  # starts and ends
    assert model.fit(X, ys, times=ts) is model
    assert model.rmse_.shape == (len(ys),) and np.all(model.rmse_ < 0.05)
    y = model.predict(ys[0][0], ys[0][-1], ts[0], duration=ts[0][-1])
    np.testing.assert_allclose(y, minimum_jerk(ys[0][0], ys[0][-1], ts[0] / ts[0][-1]))
    # a batch, like the other models: each movement over its own duration
    batch = model.predict(X[:3, :3], X[:3, 3:], ts[0], duration=[t[-1] for t in ts[:3]])
    for i in range(3):
        u = np.minimum(ts[0] / ts[i][-1], 1.0)
        np.testing.assert_allclose(batch[i], minimum_jerk(ys[i][0], ys[i][-1], u))
    durations = np.array([t[-1] for t in ts])
    distances = np.array([np.linalg.norm(y[-1] - y[0]) for y in ys])
    a, b = np.polyfit(distances, durations, 1)[::-1]
    np.testing.assert_allclose(model.duration_coef_, [a, b], rtol=1e-9)
    assert model.predict([0.0, 0, 0], [0.3, 0, 0]).shape == (100, 3)
    again = MinimumJerk.load(model.save(tmp_path / "mj.json"))
    np.testing.assert_array_equal(again.predict([0.0, 0, 0], [0.3, 0, 0]),
                                  model.predict([0.0, 0, 0], [0.3, 0, 0]))  # fmt: skip
    sklearn_base = pytest.importorskip("sklearn.base")
    assert repr(sklearn_base.clone(MinimumJerk("mean"))) == "MinimumJerk(duration_model='mean')"


def test_to_frame_exports(reaches, sine_model):
    from motion_envs.datasets.ragged import RaggedTrajectories
    from motion_envs.models import segmentation as sg
    from motion_envs.models.frames import segments_frame, trajectories_frame

    ys, ts, _, subjects = reaches
    frame = trajectories_frame(ys, ts, labels={"subject": subjects})
    assert list(frame.columns) == ["trajectory", "sample", "t", "tau", "subject", "x", "y", "z"]
    assert len(frame) == sum(len(y) for y in ys)
    per_subject = frame.groupby("subject")["trajectory"].nunique()
    assert per_subject.to_dict() == {"s0": 12, "s1": 12, "s2": 12}
    np.testing.assert_array_equal(frame.loc[frame.trajectory == 4, ["x", "y", "z"]], ys[4])
    qs, qts, _ = simulated_turns(n_reps=1)
    rag = RaggedTrajectories.from_sequences(qs, qts).to_frame()
    assert rag.groupby("trajectory")["t"].max().to_numpy() == pytest.approx([t[-1] for t in qts])
    report = sine_model.validate().to_frame()
    assert len(report) == sine_model.F_.shape[0] and "F_intercept" in report
    t, y = simulated_session()
    phases = [("rest", sg.SpeedAbove(threshold=0.05)),
              ("reach", sg.SpeedBelow(threshold=0.05, min_elapsed=0.2))]  # fmt: skip
    segs = segments_frame(sg.segment(t, y, phases), t)
    assert (segs.loc[segs.name == "reach", "duration"] > 0.7).all()


# -- 10. every public name from motion_envs.models / motion_envs.geometry ----------------
@pytest.mark.parametrize("package", ["motion_envs.geometry", "motion_envs.models"])
def test_public_names_are_reexported(package):
    import importlib
    import pkgutil

    pkg = importlib.import_module(package)
    assert len(set(pkg.__all__)) == len(pkg.__all__)
    for name in pkg.__all__:
        assert getattr(pkg, name) is not None
    missing = []
    for info in pkgutil.iter_modules(pkg.__path__):
        if info.name.startswith(("_", "juggling")) or info.ispkg:
            continue
        module = importlib.import_module(f"{package}.{info.name}")
        for name in getattr(module, "__all__", ()):
            obj = getattr(module, name)
            flat = name in pkg.__all__ and getattr(pkg, name) is obj
            via_module = info.name in pkg.__all__ and getattr(getattr(pkg, info.name), name) is obj
            if not (flat or via_module):
                missing.append(f"{info.name}.{name}")
    assert not missing, f"not re-exported by {package}: {missing}"


def test_importing_the_packages_stays_cheap():
    import subprocess
    import sys

    code = (
        "import sys, motion_envs.models, motion_envs.geometry; "
        "print(sorted(m for m in ('scipy.signal', 'statsmodels', 'sklearn', 'pandas', "
        "'matplotlib') "
        "if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


# -- 11. the quickstart script and the docs' session run ------------------------------
def test_modeller_quickstart_runs_in_30_lines(tmp_path):
    import subprocess
    import sys
    from pathlib import Path

    script = Path(__file__).resolve().parents[1] / "examples" / "modeller_quickstart.py"
    code = script.read_text().split('"""', 2)[2]  # after the gallery's title docstring
    assert len(code.strip().splitlines()) <= 30
    out = subprocess.run(
        [sys.executable, "-W", "error", str(script), str(tmp_path)],
        capture_output=True, text=True, check=False,
    )  # fmt: skip
    assert out.returncode == 0, out.stderr
    assert (tmp_path / "reach_model.json").exists()
    assert "eq. 9 end velocity" in out.stdout and "-1.0" in out.stdout


def test_docs_models_session_runs():
    import re
    from pathlib import Path

    text = (Path(__file__).resolve().parents[1] / "docs" / "models.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    assert blocks
    for block in blocks:
        exec(compile(block, "docs/models.md", "exec"), {})


@pytest.mark.parametrize("by", ["null", "subject", "task", "linear"])
def test_orientation_model_save_load_round_trip(tmp_path, by):
    from motion_envs.models import OrientationModel, load_model

    qs, ts, subjects = simulated_turns(n_reps=1)
    labels = {"subjects": subjects, "tasks": np.arange(len(qs)) % 4,
              "predictors": {"speed": 1 / np.array([t[-1] for t in ts])}}  # fmt: skip
    X = {"null": None, "subject": subjects, "task": labels["tasks"],
         "linear": labels["predictors"]}[by]  # fmt: skip
    model = OrientationModel(degree=3, by=by).fit(X, qs, ts)
    again = load_model(model.save(tmp_path / "orientation.json"))
    ask = {"subjects": subjects[:2], "tasks": [0, 3], "predictors": {"speed": [1.2, 1.4]}}
    starts, ends = np.stack([q[0] for q in qs[:2]]), np.stack([q[-1] for q in qs[:2]])
    np.testing.assert_array_equal(
        again.predict(starts, ends, [0.0, 0.3, 0.6], **ask),
        model.predict(starts, ends, [0.0, 0.3, 0.6], **ask),
    )


# -- issue 23 (second pass): the time base of select_n_sines and trajectory_coefficients ---
def _reaches(n=8, n_samples=61, seed=3):
    rng = np.random.default_rng(seed)
    tau = np.linspace(0.0, 1.0, n_samples)
    s5 = 10 * tau**3 - 15 * tau**4 + 6 * tau**5
    starts = rng.normal(0, 0.02, (n, 3))
    ends = starts + np.array([0.3, 0.1, 0.0]) + rng.normal(0, 0.02, (n, 3))
    ys = [
        s + (e - s) * s5[:, None] + rng.normal(0, 5e-4, (n_samples, 3))
        for s, e in zip(starts, ends, strict=True)
    ]
    return ys, np.hstack([starts, ends])


def test_select_n_sines_and_trajectory_coefficients_require_the_time_base():
    from motion_envs.models import select_n_sines, trajectory_coefficients

    ys, q = _reaches()
    with pytest.raises(ValueError, match=r"times= .*rate="):
        trajectory_coefficients(ys, 3)
    with pytest.raises(ValueError, match=r"times= .*rate="):
        select_n_sines(ys, q, candidates=[1, 2])
    with pytest.raises(ValueError, match="normalised"):
        trajectory_coefficients(ys, 3, "seconds")
    with pytest.raises(ValueError, match="sample"):
        trajectory_coefficients(ys, 3, [np.arange(61)] * 8)  # sample indices, not seconds
    coefs, durations = trajectory_coefficients(ys, 3, rate=60.0)
    assert np.allclose(durations, 1.0)  # 61 samples at 60 Hz: 1 s
    same, unit = trajectory_coefficients(ys, 3, "normalised")
    assert np.allclose(coefs, same) and np.array_equal(unit, np.ones(8))
    halves, d2 = trajectory_coefficients(ys, 3, rate=120.0)
    assert np.allclose(d2, 0.5) and np.allclose(halves, coefs)  # the shape in tau is rate-free
    best, scores = select_n_sines(ys, q, candidates=[1, 2, 3], rate=120.0, n_folds=4)
    best_n, scores_n = select_n_sines(ys, q, candidates=[1, 2, 3], times="normalised", n_folds=4)
    assert best == best_n and np.allclose(scores, scores_n)
