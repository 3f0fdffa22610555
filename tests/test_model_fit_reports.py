"""Issue 23 (second pass): one's own fitted models judged, summarised and plotted.

The oracles are independent of the code under test: positions are predicted from the
plan and the sine series directly, rotation angles by scipy's ``Rotation``, the
per-subject criterion by plain numpy loops, and the figures are checked artist by artist.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from motion_envs.geometry import expmap, slerp
from motion_envs.geometry import quaternion as quat
from motion_envs.geometry import sine_series as ss
from motion_envs.models import (
    FitErrors,
    OrientationModel,
    SineSeriesRegression,
    fit_summary,
    orientation_fit_errors,
    plot_fit,
    position_fit_errors,
)

RATE = 120.0


def _reaches(seed: int = 5):
    """SIMULATED reaches of 3 subjects to 2 targets, 2 replicates, varied lengths."""
    rng = np.random.default_rng(seed)
    ys, subjects, tasks = [], [], []
    for subject in ("s1", "s2", "s3"):
        for task, target in (("near", [0.2, 0.1, 0.0]), ("far", [0.35, 0.0, 0.1])):
            for _ in range(2):
                n = int(rng.integers(90, 130))
                tau = np.linspace(0.0, 1.0, n)
                s5 = 10 * tau**3 - 15 * tau**4 + 6 * tau**5
                start = rng.normal(0, 0.02, 3)
                end = start + np.asarray(target) + rng.normal(0, 0.02, 3)
                bump = 0.01 * rng.normal() * np.sin(np.pi * tau)[:, None]
                ys.append(start + (end - start) * s5[:, None] + bump + rng.normal(0, 5e-4, (n, 3)))
                subjects.append(subject)
                tasks.append(task)
    q = np.array([np.r_[y[0], y[-1]] for y in ys])
    return ys, q, np.array(subjects), np.array(tasks)


def _turns(seed: int = 6):
    """SIMULATED orientation recordings with sign flips."""
    rng = np.random.default_rng(seed)
    qs, subjects = [], []
    for i in range(9):
        n = int(rng.integers(60, 90))
        tau = np.linspace(0.0, 1.0, n)
        q = slerp(expmap([0.0, 0.0, 0.1]), expmap([0.8, 0.1 * (i % 3), 0.0]), tau)
        q = q * np.where(rng.random(n) < 0.2, -1.0, 1.0)[:, None]  # sign flips
        wobble = expmap((0.05 + 0.02 * (i % 3)) * np.sin(np.pi * tau)[:, None] * [0, 1, 0])
        qs.append(quat.multiply(q, wobble))
        subjects.append(f"s{i % 3}")
    return qs, np.array(subjects)


@pytest.fixture(scope="module")
def position_case():
    ys, q, subjects, tasks = _reaches()
    model = SineSeriesRegression(n_sines=3).fit(q, ys, rate=RATE)
    return model, ys, q, subjects, tasks


def test_position_fit_errors_against_the_plan_and_the_sine_series(position_case):
    model, ys, q, _, _ = position_case
    errors = position_fit_errors(model, ys, q, rate=RATE)
    assert errors.kind == "position" and errors.n_trajectories == len(ys)
    for i, y in enumerate(ys):
        p = model.plan(q[i], (len(y) - 1) / RATE, y[0], y[-1])
        oracle = ss.evaluate(p, np.linspace(0.0, 1.0, len(y)))
        np.testing.assert_allclose(errors.fit[i], oracle, atol=1e-12)
        e = np.sqrt(((oracle - y) ** 2).sum(axis=1))
        np.testing.assert_allclose(errors.errors[i], e, atol=1e-12)
        assert errors.max_errors[i] == pytest.approx(e.max(), abs=1e-12)
        assert errors.max_error_times[i] == pytest.approx(np.argmax(e) / RATE)
    assert errors.criterion == pytest.approx(float(np.median([e.max() for e in errors.errors])))
    m = errors.median_trajectory
    assert np.sum(errors.max_errors < errors.max_errors[m]) == (len(ys) - 1) // 2
    frame = errors.to_frame({"subject": position_case[3]})
    assert list(frame.columns) == [
        "trajectory", "subject", "n_samples", "duration", "max_error", "t_max_error",
    ]  # fmt: skip
    assert frame["n_samples"].tolist() == [len(y) for y in ys]


def test_fit_summary_per_subject_and_task_against_a_hand_computed_groupby(position_case):
    model, ys, q, subjects, tasks = position_case
    errors = position_fit_errors(model, ys, q, rate=RATE)
    maxima = [
        float(np.max(np.linalg.norm(f - y, axis=1))) for f, y in zip(errors.fit, ys, strict=True)
    ]
    by_subject = fit_summary(errors, subjects)
    assert list(by_subject.columns[:3]) == ["subject", "n_trajectories", "criterion"]
    for row in by_subject.itertuples():
        mine = [m for m, s in zip(maxima, subjects, strict=True) if s == row.subject]
        assert row.n_trajectories == len(mine) == 4
        assert row.criterion == pytest.approx(float(np.median(mine)), abs=1e-12)
        assert row.worst_max_error == pytest.approx(max(mine), abs=1e-12)
    both = fit_summary(errors, subjects, tasks)
    assert len(both) == 6 and list(both.columns[:4]) == [
        "subject",
        "task",
        "n_trajectories",
        "criterion",
    ]
    for row in both.itertuples():
        mine = [
            m for m, s, t in zip(maxima, subjects, tasks, strict=True)
            if s == row.subject and t == row.task
        ]  # fmt: skip
        assert row.n_trajectories == 2
        assert row.criterion == pytest.approx(float(np.median(mine)), abs=1e-12)
    with pytest.raises(ValueError, match="subject"):
        fit_summary(errors, subjects[:-1])


def test_orientation_fit_errors_are_scipy_rotation_angles():
    qs, subjects = _turns()
    model = OrientationModel(degree=3, by="subject").fit(subjects, qs, rate=RATE)
    errors = orientation_fit_errors(model, qs, rate=RATE, subjects=subjects)
    assert errors.kind == "orientation" and errors.unit == "rad"
    for i, q in enumerate(qs):
        fit = model.predict(q[0], q[-1], np.arange(len(q)) / RATE, subjects=[subjects[i]])
        r_fit = Rotation.from_quat(fit[:, [1, 2, 3, 0]])
        r_data = Rotation.from_quat(q[:, [1, 2, 3, 0]])
        np.testing.assert_allclose(errors.errors[i], (r_fit.inv() * r_data).magnitude(), atol=1e-9)
        assert np.all(np.sum(errors.fit[i] * q, axis=1) >= 0)  # signs follow the data
    summary = fit_summary(errors, subjects)
    assert summary["n_trajectories"].tolist() == [3, 3, 3]
    # the wobble differs by subject: the subject model beats the null model
    null = OrientationModel(degree=3).fit(None, qs, rate=RATE)
    assert errors.criterion < 0.5 * orientation_fit_errors(null, qs, rate=RATE).criterion


def _by_gid(fig, gid):
    found = [a for ax in fig.axes for a in ax.get_children() if a.get_gid() == gid]
    assert found, gid
    return found


def test_plot_position_fit_shows_data_fit_and_the_marked_criterion(position_case, tmp_path):
    from matplotlib.figure import Figure

    from motion_envs._io import save_figure

    model, ys, q, _, _ = position_case
    errors = position_fit_errors(model, ys, q, rate=RATE)
    fig = plot_fit(errors)
    assert isinstance(fig, Figure)
    assert len(fig.axes) == 4  # x, y, z, error
    m = errors.median_trajectory
    for i, y in enumerate(ys):
        for d in range(3):
            (data,) = _by_gid(fig, f"data-{i}-{d}")
            (fit,) = _by_gid(fig, f"fit-{i}-{d}")
            np.testing.assert_array_equal(data.get_xdata(), np.arange(len(y)) / RATE)
            np.testing.assert_array_equal(data.get_ydata(), y[:, d])
            np.testing.assert_array_equal(fit.get_ydata(), errors.fit[i][:, d])
            assert (data.get_linewidth() > 1.5) == (i == m)  # the median one highlighted
        (err,) = _by_gid(fig, f"error-{i}")
        np.testing.assert_array_equal(err.get_ydata(), errors.errors[i])
    (dots,) = _by_gid(fig, "max-errors")
    np.testing.assert_allclose(dots.get_offsets(), np.c_[errors.max_error_times, errors.max_errors])
    (star,) = _by_gid(fig, "median-max")
    np.testing.assert_allclose(
        star.get_offsets(), [[errors.max_error_times[m], errors.max_errors[m]]]
    )
    (line,) = _by_gid(fig, "criterion")
    assert np.all(np.asarray(line.get_ydata()) == errors.criterion)
    assert all(
        np.all(v.get_xdata() == errors.max_error_times[m]) for v in _by_gid(fig, "criterion-time")
    )
    assert f"{errors.criterion:.3g} m" in " ".join(
        t.get_text() for t in fig.axes[-1].get_legend().get_texts()
    )
    path = save_figure(fig, tmp_path / "fit.png")
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_plot_orientation_fit_has_four_quaternion_panels():
    qs, subjects = _turns()
    model = OrientationModel(degree=3, by="subject").fit(subjects, qs, rate=RATE)
    errors = orientation_fit_errors(model, qs, rate=RATE, subjects=subjects)
    fig = plot_fit(errors)
    assert [ax.get_ylabel() for ax in fig.axes] == ["w", "x", "y", "z", "error (rad)"]
    (line,) = _by_gid(fig, "criterion")
    assert np.all(np.asarray(line.get_ydata()) == errors.criterion)
    (data,) = _by_gid(fig, "data-0-0")
    np.testing.assert_array_equal(data.get_ydata(), errors.data[0][:, 0])
    assert isinstance(errors, FitErrors)
