"""The SIMULATED juggling demonstration generator: seeded, paper-sized, honest."""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
import pytest

import motion_envs
from motion_envs.datasets.juggling import (
    PHASES,
    SIMULATED_LABEL,
    JugglingTask,
    generate_demonstrations,
)
from motion_envs.geometry.minimum_jerk import quintic

ROOT = Path(motion_envs.__file__).parent


@pytest.fixture(scope="module")
def demos():
    return generate_demonstrations(seed=7)


def test_seeded_output_is_stable():
    d = generate_demonstrations(n_cycles=6, seed=123)
    r = d.recordings[0]
    # golden values recorded when the generator was written (PCG64 streams are stable)
    assert len(r.t) == 3955
    assert float(r.hand.sum()) == pytest.approx(4378.470638780922, abs=1e-9)
    assert float(r.ball.sum()) == pytest.approx(5263.797972668633, abs=1e-9)
    bounds = np.flatnonzero(r.phase[1:] != r.phase[:-1])[:8] + 1
    assert bounds.tolist() == [159, 354, 503, 655, 811, 1012, 1151, 1314]
    again = generate_demonstrations(n_cycles=6, seed=123).recordings[0]
    np.testing.assert_array_equal(again.hand, r.hand)
    other = generate_demonstrations(n_cycles=6, seed=124).recordings[0]
    assert other.hand.shape != r.hand.shape or not np.array_equal(other.hand, r.hand)


def _imports(path: Path) -> set[str]:
    tree = ast.parse(path.read_text())
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom) and node.module:
            out.add(node.module)
            out |= {f"{node.module}.{a.name}" for a in node.names}  # submodules
    return out


def _source(module: str) -> Path | None:
    """The file of a motion_envs module or package (None for a name that is neither)."""
    base = ROOT.parent / module.replace(".", "/")
    for path in (base.with_suffix(".py"), base / "__init__.py"):
        if path.exists():
            return path
    return None


def test_generator_does_not_use_the_sine_series_model():
    """The generator and every motion_envs module it imports avoid the model under test."""
    seen, todo = set(), ["motion_envs.datasets.juggling._person"]
    while todo:
        mod = todo.pop()
        if mod in seen:
            continue
        path = _source(mod)
        if path is None:
            continue
        seen.add(mod)
        todo += [m for m in _imports(path) if m.startswith("motion_envs.")]
    forbidden = {"sine_regression", "sine_series", "nominal", "segmentation"}
    assert "motion_envs.datasets.juggling.rules" in seen  # the walk follows packages
    assert not {m for m in seen if m.rsplit(".", 1)[-1] in forbidden}, seen


def test_paper_sizes_and_label(demos):
    assert demos.simulated and SIMULATED_LABEL in demos.label()
    for phase in PHASES:
        segs = demos.segments(phase)
        assert 40 <= len(segs) <= 60
        lengths = np.array([len(s.times) for s in segs])
        # the paper: 150-200 samples per example; the person model stays close to that
        assert np.median(lengths) >= 150 and np.median(lengths) <= 200
        assert lengths.min() >= 130 and lengths.max() <= 230
    assert np.allclose(np.diff(demos.recordings[0].t), demos.task.dt)


def test_toss_fires_on_the_threshold_and_catch_touches(demos):
    task = demos.task
    r = demos.recordings[0]
    lab, dt = r.phase, task.dt
    starts = np.flatnonzero(lab[1:] != lab[:-1]) + 1
    for k in starts:
        if lab[k] == "go_down":  # the release sample: held-ball acceleration below -threshold
            az = (r.ball[k, 1] - 2 * r.ball[k - 1, 1] + r.ball[k - 2, 1]) / dt**2
            assert az < -task.toss_threshold
            toss = np.flatnonzero(lab[:k] != "toss")
            first = (toss[-1] + 1) if toss.size else 0
            zz = r.ball[first - 2 if first >= 2 else 0 : k, 1]
            earlier = np.diff(zz, 2) / dt**2
            assert np.all(earlier >= -task.toss_threshold)  # it did not fire before
        if lab[k] == "return":  # the catch sample: ball within the catch radius
            assert np.linalg.norm(r.hand[k] - r.ball[k]) <= task.catch_radius + 1e-3
            assert np.linalg.norm(r.hand[k - 1] - r.ball[k - 1]) > task.catch_radius - 1e-3
    # the free ball follows the ballistic closed form: second differences are -g dt^2
    fly = (lab == "go_down") | (lab == "catch")
    inner = fly[1:-1] & fly[:-2] & fly[2:]
    d2 = np.diff(r.ball[:, 1], 2)[inner]
    np.testing.assert_allclose(d2, -task.gravity * dt**2, atol=1e-12)


def test_quintic_boundary_states():
    c = quintic(
        np.array([0.0, 1.0]),
        np.array([0.5, 0.0]),
        np.array([0.0, -1.0]),
        np.array([1.0, 2.0]),
        np.zeros(2),
        np.array([0.0, -9.0]),
        0.8,
    )
    t = 0.8
    pos = sum(c[j] * t**j for j in range(6))
    vel = sum(j * c[j] * t ** (j - 1) for j in range(1, 6))
    acc = sum(j * (j - 1) * c[j] * t ** (j - 2) for j in range(2, 6))
    np.testing.assert_allclose(pos, [1.0, 2.0], atol=1e-12)
    np.testing.assert_allclose(vel, [0.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(acc, [0.0, -9.0], atol=1e-9)
    np.testing.assert_allclose(c[1], [0.5, 0.0])


def test_bad_arguments():
    with pytest.raises(ValueError, match="n_cycles"):
        generate_demonstrations(n_cycles=0)
    with pytest.raises(ValueError, match="sensor_noise"):
        generate_demonstrations(sensor_noise=-1.0)
    with pytest.raises(ValueError, match="floor_z"):
        JugglingTask(floor_z=2.0)
