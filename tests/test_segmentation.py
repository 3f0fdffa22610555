"""Online segmentation criteria, recording segmentation and the phase state machine."""

from __future__ import annotations

import numpy as np
import pytest

from motion_envs.geometry import sine_series as ss
from motion_envs.models import segmentation as sg


def test_causal_derivatives_closed_form():
    t = np.linspace(0, 1, 11)
    y = np.column_stack([t**2, 3 * t])
    v, a = sg.causal_derivatives(t, y)
    # backward differences of t^2: (t_k^2 - t_{k-1}^2) / dt = t_k + t_{k-1}; acceleration 2
    np.testing.assert_allclose(v[1:, 0], t[1:] + t[:-1], atol=1e-12)
    np.testing.assert_allclose(v[1:, 1], 3.0, atol=1e-12)
    np.testing.assert_allclose(a[2:, 0], 2.0, atol=1e-9)
    np.testing.assert_array_equal(a[:2], 0.0)


def test_segment_back_and_forth_cycles():
    # x goes 0 -> 1 -> 0 -> 1 -> 0 in 4 ramps of 10 steps each
    ramp = np.linspace(0, 1, 11)
    x = np.concatenate([ramp, ramp[::-1][1:], ramp[1:], ramp[::-1][1:]])
    t = np.arange(x.size) * 0.1
    y = np.column_stack([x, np.zeros_like(x)])
    phases = [
        ("out", sg.PositionReached(target=(1.0,), tolerance=1e-9, axes=(0,))),
        ("back", sg.PositionReached(target=(0.0, 0.0), tolerance=1e-9)),
    ]
    segs = sg.segment(t, y, phases)
    assert [(s.name, s.start, s.stop) for s in segs] == [
        ("out", 0, 10),
        ("back", 10, 20),
        ("out", 20, 30),
        ("back", 30, 40),
    ]
    assert len(sg.segment(t, y, phases, cycle=False)) == 2


def test_acceleration_speed_and_event_criteria():
    t = np.linspace(0, 1, 21)
    y = np.column_stack([t, -(t**2)])  # vertical acceleration -2
    toss = [("toss", sg.AccelerationBelow(axis=1, threshold=-1.0))]
    segs = sg.segment(t, y, toss, cycle=False, window=None)
    assert segs == [sg.Segment("toss", 0, 2)]  # the first sample with a causal acceleration
    fast = [("fast", sg.SpeedAbove(threshold=np.hypot(1, 1.5)))]
    segs = sg.segment(t, y, fast, cycle=False, window=None)
    # |v_k| = |(1, -(t_k + t_{k-1}))| exceeds sqrt(1 + 1.5^2) once t_k + t_{k-1} > 1.5
    k = int(np.argmax(t[1:] + t[:-1] > 1.5)) + 1
    assert segs == [sg.Segment("fast", 0, k)]
    crit = sg.AnyOf((sg.EventOccurred(name="catch"), sg.SpeedBelow(threshold=0.5)))
    segs = sg.segment(t, y, [("catch", crit)], events={7: ["catch"]}, cycle=False, window=None)
    assert segs == [sg.Segment("catch", 0, 7)]
    early = sg.EventOccurred(name="catch", min_elapsed=0.5)
    segs = sg.segment(t, y, [("c", early)], events={7: ["catch"]}, cycle=False, window=None)
    assert segs == []


def _line_planner(target, duration):
    def plan(state):
        start = state.position
        return np.stack([start, np.asarray(target) - start, np.zeros_like(start)]), duration

    return plan


def test_state_machine_chains_phases():
    phases = [
        sg.Phase("go", _line_planner([1.0, 0.0], 1.0), sg.PositionReached(target=(1.0, 0.0))),
        sg.Phase("back", _line_planner([0.0, 0.0], 2.0), None),
    ]
    fsm = sg.PhaseStateMachine(phases)
    fsm.reset(0.0, [0.0, 0.0])
    dt = 0.01
    ts = np.arange(0, 5.5, dt)
    ys = np.array([fsm.step(t) for t in ts])
    names = [(round(t, 6), a, b) for t, a, b in fsm.transitions]
    # "go" is within 1e-3 of its target from t = 0.999 (tau >= 0.999), i.e. at t = 1.00;
    # "back" lasts 2 s; then "go" again for 1 s, "back" again.
    assert [n[1:] for n in names] == [("go", "back"), ("back", "go"), ("go", "back")]
    assert names[0][0] == pytest.approx(1.0)
    assert names[1][0] == pytest.approx(3.0)
    assert names[2][0] == pytest.approx(4.0)
    # continuity: no jump bigger than the commanded speed allows
    assert np.max(np.abs(np.diff(ys, axis=0))) <= dt * 1.0 + 1e-9
    np.testing.assert_allclose(ys[ts == 2.0][0], [0.5, 0.0], atol=1e-9)


def test_state_machine_with_velocity_threshold_toss():
    # a toss-like phase: up and back down; ends when the commanded vertical acceleration
    # falls below -5; its planner is a sine series with a single sin(pi tau) bump
    p = np.array([[0.0, 0.0], [0.0, 0.0], [0.0, 0.3]])

    def toss(state):
        return p + np.stack([state.position, 0 * state.position, 0 * state.position]), 1.0

    phases = [
        sg.Phase("toss", toss, sg.AccelerationBelow(axis=1, threshold=-2.0)),
        sg.Phase("rest", _line_planner([0.0, 0.0], 1.0), None, next="toss"),
    ]
    fsm = sg.PhaseStateMachine(phases)
    fsm.reset(0.0, [0.0, 0.0])
    for t in np.arange(0, 0.5, 0.001):
        fsm.step(t)
    # a_y = -0.3 pi^2 sin(pi tau) < -2 first when sin(pi tau) > 2 / (0.3 pi^2)
    tau = np.arcsin(2 / (0.3 * np.pi**2)) / np.pi
    assert fsm.transitions[0][1:] == ("toss", "rest")
    assert fsm.transitions[0][0] == pytest.approx(tau, abs=1e-3)
    np.testing.assert_allclose(fsm.coefficients[0], ss.evaluate(p, [tau])[0], atol=2e-3)


def test_state_machine_bad_input():
    with pytest.raises(ValueError, match="does not exist"):
        sg.PhaseStateMachine([sg.Phase("a", _line_planner([0.0], 1.0), next="b")])
    fsm = sg.PhaseStateMachine([sg.Phase("a", _line_planner([0.0], 1.0))])
    with pytest.raises(ValueError, match="reset"):
        fsm.step(0.0)
    bad = sg.PhaseStateMachine([sg.Phase("a", lambda s: (np.zeros((3, 1)), 0.0))])
    with pytest.raises(ValueError, match="duration"):
        bad.reset(0.0, [0.0])
