"""Juggling-v2's ``drift`` level: the delay's reflected random walk and the drag drawn
per catch stay in their stated ranges (property tests), the level is deterministic
under ``reset(seed)``, the zero action is the analytic juggler with the world drifting
as documented (rebuilt here from its parts), and the other levels do not drift."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from motion_envs.envs.juggling import JugglingV2Env
from motion_envs.models.juggling import V2_LEVELS

DRIFT = V2_LEVELS["drift"]


def _reflect_by_steps(x: float, low: float, high: float) -> float:
    """An independent reflection: fold ``x`` back into ``[low, high]`` one wall at a time."""
    while not (low <= x <= high):
        x = 2 * low - x if x < low else 2 * high - x
    return x


def test_only_drift_drifts() -> None:
    assert DRIFT.drifts and DRIFT.delay_walk == 0.02 and DRIFT.drag_per_toss
    assert DRIFT.delay == (0.10, 0.25) and DRIFT.drag == (0.009, 0.03)
    for name in ("easy", "medium", "hard"):
        lv = V2_LEVELS[name]
        assert not lv.drifts
        rng = np.random.default_rng(0)
        state = rng.bit_generator.state
        assert lv.next_delay(0.12, rng) == 0.12 and lv.next_drag(0.05, rng) == 0.05
        assert rng.bit_generator.state == state  # no draw: the old levels' streams unchanged


@settings(max_examples=200, deadline=None)
@given(
    start=st.floats(0.10, 0.25),
    seed=st.integers(0, 2**32 - 1),
    walk=st.floats(0.001, 1.0),
)
def test_delay_walk_stays_in_range_and_is_reflected(start: float, seed: int, walk: float) -> None:
    lv = dataclasses.replace(DRIFT, delay_walk=walk)
    rng = np.random.default_rng(seed)
    mirror = np.random.default_rng(seed)
    d = start
    for _ in range(30):
        step = walk * float(mirror.standard_normal())
        expected = _reflect_by_steps(d + step, 0.10, 0.25)
        d = lv.next_delay(d, rng)
        assert 0.10 - 1e-12 <= d <= 0.25 + 1e-12
        assert d == pytest.approx(expected, abs=1e-12)


@settings(max_examples=50, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_drag_per_catch_stays_in_range(seed: int) -> None:
    rng = np.random.default_rng(seed)
    drags = [DRIFT.next_drag(0.0, rng) for _ in range(50)]
    assert all(0.009 <= k <= 0.03 for k in drags) and len(set(drags)) == 50


def _episode(env: JugglingV2Env, seed: int) -> tuple[list[np.ndarray], list[tuple[float, float]]]:
    """Seeded random actions until the end: observations and the true (delay, drag)."""
    obs, _ = env.reset(seed=seed)
    rng = np.random.default_rng(seed)
    out, truth = [obs], [(env.delay, env.drag)]
    done = False
    while not done:
        obs, _, te, tr, _ = env.step(rng.uniform(-0.05, 0.05, 2).astype(np.float32))
        out.append(obs)
        truth.append((env.delay, env.drag))
        done = te or tr
    return out, truth


def test_drift_deterministic_under_reset_seed_and_in_range() -> None:
    env = JugglingV2Env(level="drift", controller="juggler_oracle", max_catches=6)
    a, ta = _episode(env, 5)
    b, tb = _episode(JugglingV2Env(level="drift", controller="juggler_oracle", max_catches=6), 5)
    assert len(a) == len(b) and all(np.array_equal(x, y) for x, y in zip(a, b, strict=True))
    assert ta == tb
    _, tc = _episode(env, 6)
    assert tc[0] != ta[0]
    for delay, drag in ta + tc:
        assert 0.10 <= delay <= 0.25 and 0.009 <= drag <= 0.03


def _drifting_seed(env: JugglingV2Env, catches: int) -> int:
    """The first seed from 0 whose zero-action episode catches ``catches`` times."""
    return next(s for s in range(100) if env.nominal_episode(s)["catches"] >= catches)


@pytest.mark.parametrize(
    ("controller", "catches"),
    [("juggler", 1), ("juggler_oracle", 2), ("juggler_delay_estimator", 2)],
)
def test_zero_action_is_the_juggler_with_the_documented_drift(
    controller: str, catches: int
) -> None:
    env = JugglingV2Env(level="drift", controller=controller, max_catches=4)
    seed = _drifting_seed(env, catches)
    env.reset(seed=seed)
    hands, truth = [], []
    done = False
    while not done:
        _, _, te, tr, info = env.step(np.zeros(2, np.float32))
        hands.append(info["hand"])
        truth.append((env.delay, env.drag))
        done = te or tr
    assert len(set(truth)) >= 1 + catches  # the delay and drag changed at every catch

    # the parts of a fresh env (their construction is test_env_contract's), driven here:
    # juggler, world, camera, estimator, the drift at each catch as documented
    parts = JugglingV2Env(level="drift", controller=controller, max_catches=4)
    ctrl, world, camera = parts.controller, parts.world, parts.camera
    w, c, k, d, r = (np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(5))
    delay, drag = float(d.uniform(0.10, 0.25)), float(r.uniform(0.009, 0.03))
    true = world.reset(parts.home, rng=w)
    world.set_drag(0, drag)
    camera.reset(delay, c)
    ctrl.estimator.reset(drag, delay)
    state = dataclasses.replace(true, ball_pos=true.hand_pos, ball_vel=true.hand_vel)
    ctrl.reset(state, k)
    expected, expected_truth = [], []
    for _ in hands:
        target, armed = ctrl.command(state)
        true = world.advance(float(target[0]), float(target[1]), armed)
        hand = (float(true.hand_pos[0]), float(true.hand_pos[1]))
        ball = (float(true.ball_pos[0]), float(true.ball_pos[1]))
        frames = camera.record(int(world.k[0]), ball, hand, true.held)
        if true.released:
            ctrl.estimator.released(true.time, *hand)
        ctrl.estimator.add(frames)
        if true.caught:
            delay = _reflect_by_steps(delay + 0.02 * float(d.standard_normal()), 0.10, 0.25)
            drag = float(r.uniform(0.009, 0.03))
            camera.delay = delay
            world.set_drag(0, drag)
            if controller == "juggler_oracle":
                ctrl.estimator.drag, ctrl.estimator.true_delay = drag, delay
                ctrl.estimator._fitted = False
        state = dataclasses.replace(true, ball_pos=true.hand_pos, ball_vel=true.hand_vel)
        expected.append(true.hand_pos.copy())
        expected_truth.append((delay, drag))
    np.testing.assert_allclose(np.array(hands), np.array(expected), atol=1e-12)
    np.testing.assert_allclose(np.array(truth), np.array(expected_truth), atol=1e-12)


def test_old_levels_keep_one_delay_and_drag_per_episode() -> None:
    env = JugglingV2Env(level="medium", controller="juggler_oracle", max_catches=4)
    seed = next(s for s in range(60) if env.nominal_episode(s)["catches"] >= 2)
    env.reset(seed=seed)
    first = (env.delay, env.drag)
    ep = env.nominal_episode(seed)
    assert ep["catches"] >= 2 and (env.delay, env.drag) == first


def test_cli_levels_name_drift_and_reject_unknown() -> None:
    import argparse

    from baselines.juggling_bench.cli import level_names

    assert level_names("drift") == ("drift",)
    assert level_names("medium,drift") == ("medium", "drift")
    with pytest.raises(argparse.ArgumentTypeError, match="drift"):
        level_names("drifty")


def test_bench_reports_oracle_minus_delay_estimator_paired() -> None:
    """With synthetic episodes per controller, the reported difference is the pooled
    catch rates' difference (catches / tosses, computed here) with an interval around it."""
    from baselines.agents.juggling_score import JugglingEpisodes
    from baselines.juggling_bench.v2 import V2Config, report_v2, run_v2
    from motion_envs.datasets.juggling import episode_seeds

    catches = {"juggler_oracle": [3, 2, 3, 1, 3, 2], "juggler_delay_estimator": [1, 2, 0, 1, 3, 0]}

    def play(policy: object, env_id: str, kwargs: dict, split: str, n: int) -> JugglingEpisodes:
        c = np.array(catches.get(kwargs["controller"], [1] * 6)[:n], dtype=np.int64)
        return JugglingEpisodes(
            seeds=episode_seeds(split, n), tosses=np.full(n, 3, dtype=np.int64), catches=c,
            dropped=c < 3, segment_phase=np.array(["catch"] * n),
            segment_episode=np.arange(n, dtype=np.int64),
            segment_deviation=np.linspace(0.01, 0.02, n),
        )  # fmt: skip

    config = V2Config(levels=("drift",), episodes=6, val_episodes=2, pick_episodes=2, ilc=False)
    doc = run_v2(config, play)
    (level,) = doc["levels"]
    got = level["oracle_minus_delay_estimator"]
    expected = (14 - 7) / 18
    assert got["value"] == pytest.approx(expected)
    assert got["ci"][0] <= expected <= got["ci"][1] and got["ci"][0] >= 0
    assert "oracle - delay_estimator (paired): +0.389" in report_v2(doc)
