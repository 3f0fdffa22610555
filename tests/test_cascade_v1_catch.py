"""Cascade-v1's catch plan (``juggler_oracle_catch``, ``juggler_mean_delay_catch``): the
view tells each flying ball ``lead`` s ahead, so the juggler's reach ends ``lead`` early
at the meeting point (hand-worked flights; scipy's drag flight for the oracle's
matching); the controllers' leads are the declared ones; the choice of the plans plays
TRAINING seeds only (a spy on the experiment; the siteswap juggler's own catch in
``tests/test_cascade_v1_siteswap_catch.py``)."""

from __future__ import annotations

import itertools
import math
from typing import Any

import numpy as np
import pytest
from _helpers import load_experiment
from scipy.integrate import solve_ivp

from motion_envs.envs.juggling import CascadeV1Env
from motion_envs.models.juggling import (
    CASCADE_CATCH_PLANS,
    CASCADE_V1_CONTROLLERS,
    CameraFrame,
    CascadeBallView,
    CatchPlan,
    SiteswapCatchController,
    catch_plan,
)
from motion_envs.models.juggling._cascade_v1 import CASCADE_LEAD_GRID, SITESWAP_DESCENT_GRID


def test_a_just_thrown_ball_is_told_lead_ahead_hand_worked() -> None:
    """Thrown at t = 0 from (0, 1) m at (1, 4) m/s, g = 10: at now = 0.1 s with a lead of
    0.12 s the juggler is told the ball at 0.22 s: (0.22, 1 + 0.88 - 0.242) m, (1, 1.8)
    m/s. It comes down through z = 1 at 0.8 s at (1, -4) m/s: the told flight is there
    at 0.68 s, where the hand waits; the planned meeting speed (no descent) is the
    ball's, sqrt(17) = 4.123 m/s."""
    view = CascadeBallView(1, "arrival", 10.0, 0.1, 1.0, lead=0.12)
    view.estimators[0].reset()
    view.priors = [(0.0, np.array([0.0, 1.0]), np.array([1.0, 4.0]))]
    p, v = view.ball(0, 0.1)
    np.testing.assert_allclose(p, [0.22, 1.638], atol=1e-12)
    np.testing.assert_allclose(v, [1.0, 1.8], atol=1e-12)
    s = 0.68 - 0.1  # the told flight at the juggler's catch time 0.68 s
    told = p + v * s - np.array([0.0, 5.0 * s * s])
    np.testing.assert_allclose(told, [0.8, 1.0], atol=1e-12)
    assert CatchPlan(0.12, 0.0).meeting_speed(np.array([1.0, -4.0])) == pytest.approx(
        math.sqrt(17.0)
    )
    assert CascadeBallView(1, "arrival", 10.0, 0.1, 1.0).lead == 0.0
    with pytest.raises(ValueError, match="lead"):
        CascadeBallView(1, "arrival", 10.0, 0.1, 1.0, lead=-0.1)


def _thrown(view: CascadeBallView, delay: float) -> None:
    """A ballistic flight (g = 9.81) from (0.1, 1) m at (-0.4, 4) m/s at t = 0, its frames
    every 10 ms arriving ``delay`` s after their capture, up to 0.2 s."""
    for est in view.estimators:
        est.released(0.0, 0.1, 1.0)
        frames = []
        for k in range(1, 21):
            t = 0.01 * k
            frames.append(CameraFrame(t, t + delay, 0.1 - 0.4 * t, 1.0 + 4 * t - 4.905 * t * t))
        est.add(frames)
    view.priors = [(0.0, np.array([0.1, 1.0]), np.array([-0.4, 4.0]))]


def test_with_frames_the_ball_is_the_estimate_lead_ahead() -> None:
    """With 3+ frames (the mean-delay estimator, no drag): the ball told at ``now`` is the
    estimator's state at ``now + lead``; with the true delay that is the true flight."""
    lead, delay = 0.08, 0.15
    planned = CascadeBallView(1, "mean_delay", 9.81, delay, 1.0, lead=lead)
    plain = CascadeBallView(1, "mean_delay", 9.81, delay, 1.0)
    _thrown(planned, delay)
    _thrown(plain, delay)
    now = 0.36
    p, v = planned.ball(0, now)
    q, w = plain.ball(0, now + lead)
    np.testing.assert_array_equal(p, q)
    np.testing.assert_array_equal(v, w)
    t = now + lead
    np.testing.assert_allclose(p, [0.1 - 0.4 * t, 1.0 + 4 * t - 4.905 * t * t], atol=1e-9)


def test_the_oracle_plan_reaches_the_drag_crossing_lead_early() -> None:
    """The oracle (true delay, drag k): the told ballistic flight reaches the point where
    scipy's drag flight (from the oracle's estimate) comes down through the catch height,
    ``lead`` s BEFORE the ball does; within 1 mm (the view's 10 ms search)."""
    lead, delay, k, h = 0.1, 0.15, 0.1, 1.0
    view = CascadeBallView(1, "oracle", 9.81, 0.0, h, lead=lead)
    view.estimators[0].reset(k, delay)
    _thrown(view, delay)
    now = 0.36
    est = view.estimators[0].estimate(now + lead)
    assert est is not None

    def rhs(_t: float, y: np.ndarray) -> list[float]:
        s = math.hypot(y[2], y[3])
        return [y[2], y[3], -k * s * y[2], -9.81 - k * s * y[3]]

    def down(_t: float, y: np.ndarray) -> float:
        return y[1] - h

    down.terminal, down.direction = True, -1  # type: ignore[attr-defined]
    y0 = [*est[0], *est[1]]
    sol = solve_ivp(rhs, (0, 3), y0, events=down, rtol=1e-10, atol=1e-12)
    t_h = now + lead + float(sol.t_events[0][0])  # the ball's crossing
    x_h = float(sol.y_events[0][0][0])
    p, v = view.ball(0, now)
    s = t_h - lead - now
    told = p + v * s - np.array([0.0, 0.5 * 9.81 * s * s])
    np.testing.assert_allclose(told, [x_h, h], atol=1e-3)


@pytest.mark.parametrize("pattern", ["3", "5"])
def test_the_controllers_carry_their_declared_leads(pattern: str) -> None:
    """The fitted juggler's plans are told through the view (``lead``, no descent); the
    siteswap juggler's are its controller's own (the view's lead 0;
    ``tests/test_cascade_v1_siteswap_catch.py``)."""
    fitted = pattern == "3"
    for name in CASCADE_V1_CONTROLLERS:
        env = CascadeV1Env(level="easy", pattern=pattern, controller=name, max_catches=2)
        plan = catch_plan(name, fitted)
        # the delay tracker (the mean-delay catch plan with its delay corrected), the
        # delay estimator with the catch plan and the estimate with a tracked correction
        # carry the mean-delay plan itself
        borrows = (
            "juggler_delay_tracker", "juggler_delay_estimator_catch",
            "juggler_estimator_tracker_catch",
        )  # fmt: skip
        base = "juggler_mean_delay_catch" if name in borrows else name
        if base in CASCADE_CATCH_PLANS and plan is not None:
            assert plan is CASCADE_CATCH_PLANS[base]["fitted" if fitted else "siteswap"]
            assert env.view.lead == (plan.lead if fitted else 0.0)
            assert plan.lead in CASCADE_LEAD_GRID and (plan.descent == 0.0 or not fitted)
            assert env.view.estimators[0].mode == CASCADE_V1_CONTROLLERS[name][1]
        else:
            assert plan is None and env.view.lead == 0.0
        catches, tosses, _, _ = env.play(1)
        assert 0 <= catches <= 2 and tosses >= 0


def _experiment() -> Any:
    return load_experiment("cascade_v1_catch_plan")


def test_the_leads_are_chosen_on_training_seeds_only(monkeypatch: pytest.MonkeyPatch) -> None:
    """A spy on the experiment's seeds: every episode it plays is a TRAINING seed, and the
    candidate lead is the one the view uses (the fitted juggler) or the candidate plan the
    one the controller carries (the siteswap juggler), for each controller with a plan
    (the mean delay's five-ball plan was chosen by the same run)."""
    module = _experiment()
    from motion_envs.datasets.juggling import SPLIT_SEEDS, episode_seeds

    asked: list[str] = []

    def seeds(split: str, n: int) -> np.ndarray:
        asked.append(split)
        return episode_seeds(split, n)

    played: list[tuple[int, Any]] = []

    def play(self: CascadeV1Env, seed: int) -> tuple[int, int, bool, float]:
        if self.pattern.fitted:
            played.append((seed, self.view.lead))
        else:  # the siteswap juggler's own catch, the view untouched
            assert isinstance(self.controller, SiteswapCatchController)
            assert self.view.lead == 0.0
            played.append((seed, self.controller.catch))
        return 1, 2, True, 1.0

    monkeypatch.setattr(module, "episode_seeds", seeds)
    monkeypatch.setattr(CascadeV1Env, "play", play)
    train = SPLIT_SEEDS["train"]
    others = [SPLIT_SEEDS[k] for k in SPLIT_SEEDS if k != "train"]
    for controller, (pattern, plan, told) in itertools.product(
        CASCADE_CATCH_PLANS,
        (("3", CatchPlan(0.06, 0.0), 0.06), ("5", CatchPlan(0.1, 1.5), CatchPlan(0.1, 1.5))),
    ):
        asked.clear()
        played.clear()
        got = module.score(controller, pattern, plan, 3, 2)
        assert asked == ["train"] * 3 and got == {"easy": 1.0, "medium": 1.0, "hard": 1.0}
        assert {s for s, _ in played} == {train, train + 1, train + 2}
        assert {t for _, t in played} == {told}
        assert all(not (o <= s < o + 3) for s, _ in played for o in others)
    grid = module.candidates("5")
    assert len(grid) == len(CASCADE_LEAD_GRID) * len(SITESWAP_DESCENT_GRID)
    assert module.candidates("3") == [CatchPlan(a, 0.0) for a in CASCADE_LEAD_GRID]


@pytest.mark.parametrize("pattern", ["3", "5"])
def test_a_drop_carries_the_miss_of_the_dropped_ball(pattern: str) -> None:
    """At the drop step: ``miss_error`` is the dropped ball's x offset and timing at its
    closest approach to a catching hand, recomputed here from the true states of every
    step (the ball's ``x`` minus the hand's, while it falls and the hand is in its catch
    phase); no other step carries it."""
    env = CascadeV1Env(level="hard", pattern=pattern, controller="juggler", max_catches=30)
    found = 0
    for seed in range(4):
        env.reset(seed=seed)
        best: dict[int, tuple[float, int, float, float]] = {}
        terminated = truncated = False
        while not (terminated or truncated):
            c = env.controller
            phases = [c.phase(h) for h in range(2)]
            planned = [math.nan if phases[h] != "catch" else _planned(env, h) for h in range(2)]
            _, _, terminated, truncated, info = env.step(np.zeros(4, np.float32))
            state = env.world.state
            for b in state.released:
                if b >= 0:
                    best.pop(b, None)
            for i, holder in enumerate(state.holder):
                if holder >= 0 or state.ball_vel[i, 1] >= 0:
                    continue
                for h in range(2):
                    if phases[h] == "catch":
                        d = float(np.hypot(*(state.ball_pos[i] - state.hand_pos[h])))
                        if i not in best or d < best[i][0]:
                            off = float(state.ball_pos[i, 0] - state.hand_pos[h, 0])
                            best[i] = (d, h, off, state.time - planned[h])
            if not terminated:
                assert "miss_error" not in info
        dropped = [i for i, d in enumerate(env.world.state.dropped) if d]
        if terminated and dropped and dropped[0] in best:
            found += 1
            _, h, off, timing = best[dropped[0]]
            assert info["miss_hand"] == h
            np.testing.assert_allclose(info["miss_error"], [off, timing], atol=1e-12)
            assert info["miss_speed"] > 0
    assert found >= 2


def _planned(env: CascadeV1Env, h: int) -> float:
    from motion_envs.models.juggling import planned_catch

    return planned_catch(env.controller, h) + env.view.lead


def test_a_split_run_is_chosen_from_its_parts_in_grid_order() -> None:
    """``choose_from``: the parts' grid rows merged in grid order (lead, then descent);
    the most pooled catches wins, a tie goes to the first in grid order."""
    module = _experiment()
    key = "juggler_oracle_catch 5"

    def part(*rows: tuple[float, float, float]) -> dict[str, Any]:
        grid = [{"lead_s": a, "descent_m_s": d, "pooled": p, "levels": {}} for a, d, p in rows]
        return {"results": {key: {"grid": grid}}}

    parts = [part((0.14, 0.5, 7.0), (0.14, 0.0, 9.0)), part((0.12, 1.0, 9.0), (0.12, 0.0, 3.0))]
    got = module.choose_from(parts, key)
    assert [(r["lead_s"], r["descent_m_s"]) for r in got["grid"]] == [
        (0.12, 0.0), (0.12, 1.0), (0.14, 0.0), (0.14, 0.5)
    ]  # fmt: skip
    assert (got["choice"]["lead_s"], got["choice"]["descent_m_s"]) == (0.12, 1.0)
