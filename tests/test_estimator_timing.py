"""The timing entry (``timing_scale``) on ``juggler_delay_estimator_catch``, Juggling-v2 and
Cascade-v1: the estimator's offset for a flight is ``delay_offset + timing_scale * u`` of
the step of its release, kept until the ball's next release; ``u = 0`` is the row; and
the catch-timing script's ``--base estimator`` (its ``w = 0`` is the row).

Independent checks: the zero entry against the env without the entry (the row as the
bench plays it), episode for episode; the offset attribute and the frames' placement
after a release against the sums worked by hand (0.02 + 0.1 x 0.4 = 0.06 s); a constant
entry against the row told ``delay_offset = 0.06`` (Juggling-v2: the ball is held until
the first release, so every flight is told the same offset); the latch against the run
whose entry never changed, identical up to the next release."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from _helpers import check_timing_entry, load_experiment, rollout_digest

import motion_envs  # noqa: F401  (registers the ids)
from baselines.agents import catch_timing as ct
from motion_envs.envs.juggling import CascadeV1Env, JugglingV2Env
from motion_envs.models.juggling import (
    CameraFrame,
    CascadeBallView,
    FlightEstimator,
    PooledReleaseEstimator,
)

NAME = "juggler_delay_estimator_catch"
V2, C1 = "MotionEnvs/Juggling-v2", "MotionEnvs/Cascade-v1"
OFFSET, SCALE = 0.02, 0.1
#: float32's 0.4 times 0.1: the adjustment a constant entry u = 0.4 makes (about 40 ms)
U = 0.4
ADJ = SCALE * float(np.float32(U))


def _v2_episodes(seeds: range, **kw: Any) -> list[dict[str, Any]]:
    env = JugglingV2Env(level="medium", controller=NAME, max_catches=3, **kw)
    return [env.nominal_episode(s) for s in seeds]  # the zero action, the entry's too


def _same(a: list[dict[str, Any]], b: list[dict[str, Any]]) -> bool:
    keys = ("catches", "tosses", "dropped", "hand", "task_errors")
    return all(np.array_equal(x[k], y[k]) for x, y in zip(a, b, strict=True) for k in keys)


@pytest.mark.parametrize("offset", [0.0, OFFSET, -0.01])
def test_juggling_v2_zero_entry_is_the_row(offset: float) -> None:
    seeds = range(3)
    row = _v2_episodes(seeds, delay_offset=offset)
    assert _same(row, _v2_episodes(seeds, delay_offset=offset, timing_scale=SCALE))
    assert sum(e["catches"] for e in row) >= 3  # flights were fitted


def test_cascade_v1_zero_entry_is_the_row() -> None:
    def digests(**kw: Any) -> list[str]:
        env = CascadeV1Env(level="medium", controller=NAME, max_catches=6, **kw)
        return [rollout_digest(env, s) for s in (0, 1)]

    assert digests(delay_offset=OFFSET) == digests(delay_offset=OFFSET, timing_scale=SCALE)


def _v2_run(u_before: float, u_after: float, releases: int, **kw: Any) -> dict[str, Any]:
    """Juggling-v2 medium, seed 1001, with the timing entry ``u_before`` up to and in the
    step of the first release, then ``u_after``, until the ``releases``-th release: the
    estimator's offset after every step, the hand path and the release steps."""
    env = JugglingV2Env(level="medium", controller=NAME, delay_offset=OFFSET,
                        timing_scale=SCALE, max_catches=5, **kw)  # fmt: skip
    env.reset(seed=1001)
    out: dict[str, Any] = {"offsets": [env.controller.estimator.offset], "hand": [],
                           "released": [], "env": env}  # fmt: skip
    u = u_before
    for k in range(3000):
        _, _, term, trunc, info = env.step(np.array([0.0, 0.0, u], np.float32))
        out["offsets"].append(env.controller.estimator.offset)
        out["hand"].append(info["hand"])
        if env.world.state.released:
            out["released"].append(k)
            u = u_after
        if term or trunc or len(out["released"]) == releases:
            break
    out["hand"] = np.array(out["hand"])
    return out


def test_juggling_v2_a_constant_entry_tells_the_offset_from_the_release_hand_worked() -> None:
    """Before the first release the estimator holds ``delay_offset`` (0.02 s); from the
    step of a release under ``u = 0.4`` it holds 0.02 + 0.1 x 0.4 = 0.06 s, and places
    the flight's frames at ``arrival - (estimate + 0.06)``."""
    run = _v2_run(U, U, 1)
    first = run["released"][0]
    assert set(run["offsets"][: first + 1]) == {OFFSET}  # index 0: the reset
    assert run["offsets"][first + 1] == pytest.approx(0.06, abs=1e-8)
    assert run["offsets"][first + 1] == OFFSET + ADJ
    env = run["env"]
    est = env.controller.estimator
    for _ in range(200):  # into the flight: frames and the release-anchored estimate
        env.step(np.array([0.0, 0.0, U], np.float32))
        if est.delay_estimate is not None and len(est.frames) >= 3:
            break
    frames = est.frames[-3:]
    by_hand = [f.arrival - (est.delay_estimate + 0.06) for f in frames]
    np.testing.assert_allclose(est._times(frames), by_hand, rtol=0, atol=1e-8)


def test_juggling_v2_a_constant_entry_is_the_row_told_the_sum_and_changes_the_episodes() -> None:
    """Independent oracle: a constant ``u`` tells every flight ``0.02 + 0.1 u`` (the
    ball is held until the first release), so its episodes are the row's told
    ``delay_offset = 0.06`` (to rounding: 0.1 x float32(0.4) is not 0.04), and not the
    row's told 0.02."""
    seeds = range(3)
    told = _v2_episodes(seeds, delay_offset=0.06)
    env = JugglingV2Env(level="medium", controller=NAME, max_catches=3,
                        delay_offset=OFFSET, timing_scale=SCALE)  # fmt: skip
    timed = []
    for seed in seeds:
        env.reset(seed=seed)
        hands, done = [], False
        while not done:
            _, _, term, trunc, info = env.step(np.array([0.0, 0.0, U], np.float32))
            hands.append(info["hand"])
            done = term or trunc
        timed.append({"hand": np.array(hands), "catches": info["catches"]})
    for t, r in zip(timed, told, strict=True):
        assert t["catches"] == r["catches"]
        np.testing.assert_allclose(t["hand"], r["hand"][1:], rtol=0, atol=1e-6)
    assert not _same(_v2_episodes(seeds, delay_offset=OFFSET), told)


def test_juggling_v2_the_offset_is_latched_at_the_release() -> None:
    """``u`` changed to -0.5 in the step after the first release leaves the flight's
    offset (0.06 s) and hand path as under a constant ``u = 0.4`` up to the next
    release, whose flight is told 0.02 - 0.05 = -0.03 s."""
    switched = _v2_run(U, -0.5, 2)
    constant = _v2_run(U, U, 2)
    first, second = switched["released"]
    assert constant["released"] == [first, second]
    assert set(switched["offsets"][first + 1 : second + 1]) == {OFFSET + ADJ}
    np.testing.assert_array_equal(switched["hand"][: second + 1], constant["hand"][: second + 1])
    assert switched["offsets"][second + 1] == pytest.approx(-0.03, abs=1e-8)
    assert (
        switched["env"].controller.estimator.offset
        < 0
        < constant["env"].controller.estimator.offset
    )


def _cascade_run(switch: int) -> dict[str, Any]:
    """Cascade-v1 three balls medium, seed 1005, the entry ``u = 0.4`` up to ``switch``
    steps after the first release, then -0.5 (``switch < 0``: never), until the first
    released ball is released again: each ball's estimator ``(offset, prior)`` after
    every step, the steps at which each ball was released, the first released ball, and
    at the first step in its flight with a pooled estimate its newest 3 frames' placed
    times and their ``arrival - (pooled estimate + offset)``."""
    env = CascadeV1Env(level="medium", controller=NAME, delay_offset=OFFSET,
                       timing_scale=SCALE, max_catches=6)  # fmt: skip
    env.reset(seed=1005)
    out: dict[str, Any] = {"told": [], "releases": {}, "first": -1, "placed": None}
    since = -1
    for k in range(1500):
        u = -0.5 if 0 <= switch <= since else U
        *_, term, trunc, _ = env.step(np.array([0, 0, 0, 0, u], np.float32))
        out["told"].append([(e.offset, e.fixed_delay) for e in env.view.estimators])
        for b in (int(b) for b in env.world.state.released if b >= 0):
            out["releases"].setdefault(b, []).append(k)
            out["first"] = b if out["first"] < 0 else out["first"]
        since += out["first"] >= 0
        first = out["first"]
        if first >= 0 and out["placed"] is None and env.view.pool:
            est = env.view.estimators[first]
            if len(est.frames) >= 3:
                frames = est.frames[-3:]
                d = float(np.mean(env.view.pool)) + est.offset
                out["placed"] = (est._times(frames), [f.arrival - d for f in frames], est.offset)
        if term or trunc or len(out["releases"].get(first, ())) == 2:
            break
    return out


def test_cascade_v1_each_flight_keeps_the_offset_of_its_release_hand_worked() -> None:
    """The balls in the air at the reset are told ``u = 0`` (offset 0.02 s, prior 0.15 +
    0.02 = 0.17 s); a ball released under ``u = 0.4`` is told 0.06 s and the prior 0.21
    s and keeps them when ``u`` turns to -0.5 in its flight, until its next release; a
    ball released after the turn is told 0.02 - 0.05 = -0.03 s and the prior 0.12 s; the
    frames are placed by the pooled estimate plus the flight's offset."""
    env = CascadeV1Env(level="medium", controller=NAME, delay_offset=OFFSET, timing_scale=SCALE)
    env.reset(seed=1005)
    for e in env.view.estimators:
        assert (e.offset, e.fixed_delay) == pytest.approx((OFFSET, 0.17), abs=1e-12)
    run = _cascade_run(switch=1)
    first, releases, told = run["first"], run["releases"], run["told"]
    assert len(releases) == 3 and len(releases[first]) == 2
    k0, k1 = releases[first]
    for k in range(k0, k1):  # the turn 2 steps after the release: kept to the next
        assert told[k][first] == pytest.approx((0.06, 0.21), abs=1e-8)
    assert told[k1][first] == pytest.approx((-0.03, 0.12), abs=1e-8)
    for b in (b for b in releases if b != first):
        assert told[releases[b][0]][b] == pytest.approx((-0.03, 0.12), abs=1e-8)
        assert told[releases[b][0] - 1][b] == pytest.approx((OFFSET, 0.17), abs=1e-8)
    times, by_hand, offset = run["placed"]
    assert offset == pytest.approx(0.06, abs=1e-8)
    np.testing.assert_allclose(times, by_hand, rtol=0, atol=1e-12)


def test_cascade_v1_the_offset_is_latched_and_a_constant_entry_changes_the_episodes() -> None:
    """Up to the turn the two runs are the same; the first ball's flight is told the
    same whether ``u`` turns in it or not; a constant entry changes the episodes."""
    turned, constant = _cascade_run(switch=1), _cascade_run(switch=-1)
    first = turned["first"]
    assert first == constant["first"]
    k0, k1 = turned["releases"][first]
    assert constant["releases"][first][0] == k0
    assert [t[first] for t in turned["told"][k0:k1]] == [t[first] for t in constant["told"][k0:k1]]
    for a, b in zip(turned["placed"], constant["placed"], strict=True):
        np.testing.assert_array_equal(a, b)
    env = CascadeV1Env(level="medium", controller=NAME, delay_offset=OFFSET,
                       timing_scale=SCALE, max_catches=6)  # fmt: skip

    def digest(u: float) -> int:
        env.reset(seed=0)
        h, done = [], False
        while not done:
            obs, _, term, trunc, _ = env.step(np.array([0, 0, 0, 0, u], np.float32))
            h.append(obs.tobytes())
            done = term or trunc
        return hash(tuple(h))

    assert digest(U) != digest(0.0)


def test_the_told_placement_is_at_least_zero_hand_worked() -> None:
    """An offset below minus the estimate places the frames at their arrival (a frame is
    captured no later than it arrives), as the tracker's told delay is at least 0: the
    estimate 0.135 s (noiseless frames arriving 135 ms late) and the offset -0.2 s."""
    est = FlightEstimator("release", 9.81, offset=-0.2)
    est.released(1.0, 0.0, 0.0)
    frames = []
    for j in range(1, 11):
        c = 1.0 + 0.01 * j
        s = c - 1.0
        frames.append(CameraFrame(c, c + 0.135, -0.8 * s, 3.5 * s - 0.5 * 9.81 * s * s))
    est.add(frames)
    assert est.delay_estimate == pytest.approx(0.135)
    np.testing.assert_allclose(est._times(frames), [f.arrival for f in frames])
    view = CascadeBallView(3, "release", 9.81, 0.13, 1.0, offset=-0.03)
    view.adjust = -0.15
    view._retime([0])
    assert view.estimators[0].fixed_delay == 0.0
    assert view.estimators[0].offset == pytest.approx(-0.18)
    assert isinstance(view.estimators[0], PooledReleaseEstimator)


def test_a_nan_entry_counts_as_zero_and_is_flagged() -> None:
    env = JugglingV2Env(controller=NAME, delay_offset=OFFSET, timing_scale=SCALE)
    env.reset(seed=5)
    _, _, _, _, info = env.step(np.array([0.0, 0.0, np.nan], np.float32))
    assert info["action_invalid"] and env._adjust == 0.0
    cascade = CascadeV1Env(controller=NAME, timing_scale=SCALE)
    cascade.reset(seed=5)
    _, _, _, _, info = cascade.step(np.array([0, 0, 0, 0, np.nan], np.float32))
    assert info["action_invalid"] and cascade.view.adjust == 0.0


@pytest.mark.parametrize("env_id", [V2, C1])
@pytest.mark.parametrize(
    "controller", ["juggler", "juggler_mean_delay_catch", "juggler_delay_estimator"]
)
def test_timing_scale_with_another_controller_is_one_line(env_id: str, controller: str) -> None:
    with pytest.raises(ValueError) as err:
        gym.make(env_id, controller=controller, timing_scale=SCALE)
    assert str(err.value) == (
        "timing_scale is for controller='juggler_delay_tracker' or "
        f"'juggler_delay_estimator_catch'; got {controller!r}"
    )


@pytest.mark.parametrize(("env_id", "extra"), [(V2, {}), (C1, {"pattern": "3", "max_catches": 6})])
def test_checkers_pass_with_the_entry_on_the_estimator(env_id: str, extra: dict[str, Any]) -> None:
    """One more action entry; Gymnasium's and SB3's checkers pass; ``reset(seed)`` is
    deterministic under a random timing action."""
    kw = {"level": "medium", "controller": NAME, "delay_offset": -0.01, **extra}
    check_timing_entry(gym.make(env_id, **kw, timing_scale=SCALE), gym.make(env_id, **kw))


# -- the catch-timing script's --base estimator ---------------------------------------------
def test_base_keywords_of_the_script() -> None:
    cta = load_experiment("catch_timing_agents")
    lv = {"tracker": {"gain": 0.25, "offset_s": 0.02}, "estimator_offset_s": -0.01}
    assert cta.base_kwargs("tracker", lv) == {
        "controller": "juggler_delay_tracker", "tracker_gain": 0.25, "delay_offset": 0.02,
    }  # fmt: skip
    assert cta.base_kwargs("estimator", lv) == {"controller": NAME, "delay_offset": -0.01}
    with pytest.raises(ValueError, match="--base must be one of"):
        cta.base_kwargs("oracle", lv)


@pytest.mark.parametrize("memory", [False, True])
@pytest.mark.parametrize(
    ("env_id", "extra", "seeds"),
    [(V2, {"max_catches": 3}, (21, 22, 23)), (C1, {"pattern": "3", "max_catches": 6}, (21, 22))],
)
def test_zero_weights_on_the_estimator_base_are_the_row(
    env_id: str, extra: dict[str, Any], seeds: tuple[int, ...], memory: bool
) -> None:
    """``TimingPolicy`` with ``w = 0`` on the script's estimator keywords (with the
    timing entry and the task-error entries) catches what the row's plain controller
    (neither entry) catches on the same seeds."""
    cta = load_experiment("catch_timing_agents")
    kw = {"level": "medium", **extra, **cta.base_kwargs("estimator", {"estimator_offset_s": 0.01})}
    cascade = env_id == C1
    hands, dim = (2, 5) if cascade else (1, 3)
    policy = ct.TimingPolicy(np.zeros(ct.n_features(hands, memory)), hands, dim, memory)
    agent = ct.play_scores(
        env_id, {**kw, "timing_scale": cta.TIMING_SCALE, "observe_task_error": True},
        policy, np.array(seeds, dtype=np.int64),
    )  # fmt: skip
    row = gym.make(env_id, **kw).unwrapped
    if cascade:
        plain = [row.play(s)[:2] for s in seeds]
    else:
        plain = [(e["catches"], e["tosses"]) for e in (row.nominal_episode(s) for s in seeds)]
    assert list(zip(agent[0].tolist(), agent[1].tolist(), strict=True)) == plain
    assert sum(c for c, _ in plain) >= len(seeds)


def test_rescore_refuses_runs_of_another_base(tmp_path: Any) -> None:
    import json

    cta = load_experiment("catch_timing_agents")
    path = tmp_path / "old.json"  # a run from before --base: the tracker's
    path.write_text(json.dumps({"blocks": [{"block": "v2-drift", "runs": []}]}))
    assert cta.load_earlier([path])["blocks"][0]["block"] == "v2-drift"
    with pytest.raises(ValueError, match="trained on the base 'tracker', not --base 'estimator'"):
        cta.load_earlier([path], "estimator")
