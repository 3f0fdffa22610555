"""Cascade-v1 (a pattern at Juggling-v2's human levels) and its rows
(``motion-bench juggling --version v2 --pattern P``): the refusals, the hidden delay and
per-ball drag, the camera's occlusion near either palm, the oracle's equivalent
ballistic state against an independent integration, the zero action as ``play``, and
the rows' choices made on validation seeds only (a spy that can fail). The env's
Gymnasium contract (checkers, determinism, the zero action against the juggler rebuilt
from its parts, the docstring) is in ``tests/test_env_contract.py``."""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any

import numpy as np
import pytest
from _helpers import assert_picked_on, pick_ranking_catches, recording_ilc
from scipy.integrate import solve_ivp

from baselines import options
from baselines.juggling_bench.cascade import CascadeEpisodes
from baselines.juggling_bench.cascade_v1 import (
    LATE_OFFSETS,
    REFERENCES,
    ROWS,
    CascadeV1Config,
    check_cascade_v1_config,
    choose_late_offset,
    report_cascade_v1,
    run_cascade_v1,
    write_cascade_v1,
)
from motion_envs.datasets.juggling import episode_seeds
from motion_envs.envs.juggling import CascadeV1Env, cascade_v1_obs_dim
from motion_envs.models.juggling import V2_LEVELS, equivalent_ballistic


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"level": "drift"}, "level must be one of"),
        ({"controller": "juggler_drift"}, "controller must be one of"),
        ({"controller": "juggler", "delay_offset": 0.02}, "delay_offset is for"),
        ({"controller": "juggler_mean_delay", "delay_offset": -0.01}, "delay_offset must be in"),
        ({"controller": "juggler_mean_delay", "delay_offset": float("nan")}, "delay_offset"),
        ({"pattern": "7"}, "pattern"),
    ],
)
def test_bad_arguments_are_one_line_errors(kwargs: dict[str, Any], match: str) -> None:
    with pytest.raises(ValueError, match=match) as err:
        CascadeV1Env(**kwargs)
    assert "\n" not in str(err.value)


def test_delay_and_drags_are_drawn_per_episode_and_set_in_the_world() -> None:
    """The delay is the level's, the same for every ball's camera; each ball's drag is its
    own, in the level's range, and is what MuJoCo's fluid model flies (``k m / (rho pi
    r^2)`` in the ball geom's blunt drag coefficient)."""
    env = CascadeV1Env(level="hard", pattern="5")
    lv = V2_LEVELS["hard"]
    seen = set()
    for seed in range(4):
        env.reset(seed=seed)
        assert lv.delay[0] <= env.delay <= lv.delay[1]
        assert all(c.delay == env.delay for c in env.cameras)
        assert env.drags.shape == (5,) and len(set(env.drags.tolist())) == 5
        assert ((lv.drag[0] <= env.drags) & (env.drags <= lv.drag[1])).all()
        spec = env.world.spec
        area = math.pi * spec.ball_radius**2
        for i, drag in enumerate(env.drags.tolist()):
            got = env.model.geom_fluid[int(env.world.ball_geoms[i]), 1]
            assert got == pytest.approx(drag * spec.ball_mass / (spec.air_density * area))
        seen.add(round(env.delay, 9))
    assert len(seen) == 4
    assert cascade_v1_obs_dim(5) == env.observation_space.shape[0] == 122


def test_no_frame_is_captured_near_either_palm_or_of_a_held_ball() -> None:
    """Every received frame's capture time: the ball was in flight and at least the
    occlusion radius from both hands' origins (checked on the true states, with the
    noise's few mm of slack)."""
    env = CascadeV1Env(level="easy", pattern="3", controller="juggler_mean_delay")
    env.reset(seed=3)
    lv = V2_LEVELS["easy"]
    truth: dict[int, tuple[np.ndarray, np.ndarray, tuple[int, ...]]] = {}
    captured = []
    for _ in range(600):
        _, _, terminated, truncated, info = env.step(np.zeros(4, np.float32))
        k = int(env.world.k[0])
        truth[k] = (info["balls"], info["hands"], env.world.state.holder)
        for i, frames in enumerate(env._frames):
            captured += [(i, f) for f in frames]
        if terminated or truncated:
            break
    assert captured
    for i, f in captured:
        balls, hands, holder = truth[round(f.capture / env.task.dt)]
        assert holder[i] < 0
        d = min(math.dist(balls[i], h) for h in hands)
        assert d >= lv.occlusion_radius
        assert math.dist((f.x, f.z), balls[i]) < 6 * lv.position_std


def test_equivalent_ballistic_meets_the_drag_flight_at_the_crossing() -> None:
    """The oracle's equivalent ballistic velocity flies from ``p`` to the point where
    scipy's integration of the drag flight comes down through the catch height."""
    g, k, h = 9.81, 0.1, 1.0
    p0, v0 = np.array([0.2, 1.1]), np.array([-0.5, 3.0])

    def rhs(_t: float, y: np.ndarray) -> list[float]:
        s = math.hypot(y[2], y[3])
        return [y[2], y[3], -k * s * y[2], -g - k * s * y[3]]

    def down(_t: float, y: np.ndarray) -> float:
        return y[1] - h

    down.terminal, down.direction = True, -1  # type: ignore[attr-defined]
    sol = solve_ivp(rhs, (0, 3), [*p0, *v0], events=down, rtol=1e-10, atol=1e-12)
    t_e = float(sol.t_events[0][0])
    x_e = float(sol.y_events[0][0][0])
    v = equivalent_ballistic(p0, (t_e, x_e, h), 0.0, g)
    assert v is not None
    reached = p0 + v * t_e - np.array([0.0, 0.5 * g * t_e * t_e])
    np.testing.assert_allclose(reached, [x_e, h], atol=1e-12)
    assert equivalent_ballistic(p0, (0.004, x_e, h), 0.0, g) is None
    assert equivalent_ballistic(p0, None, 0.0, g) is None


def test_the_oracle_view_crossing_matches_scipy() -> None:
    """The view's own crossing search (10 ms RK4 steps, linear within a step) against
    scipy's event: within 1 mm and 1 ms."""
    env = CascadeV1Env(level="hard", pattern="3", controller="juggler_oracle")
    view = env.view
    est = view.estimators[0]
    est.reset(0.12, 0.2)
    p, v = np.array([0.1, 1.2]), np.array([0.3, 2.5])
    crossing = view._crossing(0, 0.0, p, v)
    assert crossing is not None
    g, k, h = 9.81, 0.12, view.height

    def rhs(_t: float, y: np.ndarray) -> list[float]:
        s = math.hypot(y[2], y[3])
        return [y[2], y[3], -k * s * y[2], -g - k * s * y[3]]

    def down(_t: float, y: np.ndarray) -> float:
        return y[1] - h

    down.terminal, down.direction = True, -1  # type: ignore[attr-defined]
    sol = solve_ivp(rhs, (0, 3), [*p, *v], events=down, rtol=1e-10, atol=1e-12)
    assert crossing[0] == pytest.approx(float(sol.t_events[0][0]), abs=1e-3)
    assert crossing[1] == pytest.approx(float(sol.y_events[0][0][0]), abs=1e-3)


def test_play_is_the_zero_action_episode() -> None:
    env = CascadeV1Env(level="medium", pattern="5", controller="juggler_mean_delay",
                       max_catches=6)  # fmt: skip
    played = env.play(11)
    env.reset(seed=11)
    terminated = truncated = False
    while not (terminated or truncated):
        _, _, terminated, truncated, info = env.step(np.zeros(4, np.float32))
    assert (info["catches"], info["tosses"], terminated, info["time"]) == played


def test_the_delay_offset_moves_only_the_mean_delay_estimators() -> None:
    env = CascadeV1Env(controller="juggler_mean_delay", delay_offset=0.04)
    mean = V2_LEVELS["medium"].mean_delay
    assert all(e.fixed_delay == mean + 0.04 for e in env.view.estimators)
    assert all(e.mode == "arrival" for e in CascadeV1Env(controller="juggler").view.estimators)


# -- the rows' choices: a spy ---------------------------------------------------------------


class Spy:
    """A ``play`` recording the splits asked for, failing when a test seed is played
    while a choice is made; synthetic episodes whose ranking differs between splits: on
    validation ``fixed_point`` and the +40 ms offset are best, on test the mean-delay
    juggler and +80 ms, so a choice made on test seeds is told apart."""

    def __init__(self) -> None:
        self.choosing = False
        self.calls: list[tuple[str, str, bool]] = []

    def catches(self, policy: Any, kwargs: dict[str, Any], split: str) -> int:
        """Every episode's catches for a row (the ranking above)."""
        ctl, off = kwargs["controller"], kwargs.get("delay_offset", 0.0)
        good = {"val": ("fixed_point", 0.04), "test": ("juggler_mean_delay", 0.08)}[split]
        c = 1
        if ctl == good[0] and split == "val":
            c = 9
        if ctl == "juggler_mean_delay":
            c = 12 if off == good[1] else (5 if split == "test" and off == 0.0 else 2)
        return c

    def play(self, policy: Any, kwargs: dict[str, Any], split: str, n: int) -> CascadeEpisodes:
        self.calls.append((kwargs["level"], split, self.choosing))
        if split == "test" and self.choosing:
            raise AssertionError("a test seed was played before the choice was made")
        catches = np.full(n, self.catches(policy, kwargs, split), dtype=np.int64)
        return CascadeEpisodes(
            seeds=episode_seeds(split, n),
            catches=catches,
            tosses=catches + 1,
            dropped=np.ones(n, dtype=bool),
            time=np.full(n, 1.0),
        )

    def chooser(self, inner: Any) -> Any:
        def choose(level: str, config: CascadeV1Config, play: Any) -> Any:
            self.choosing = True
            try:
                return inner(level, config, play)
            finally:
                self.choosing = False

        return choose


def test_every_choice_is_made_on_validation_seeds() -> None:
    spy = Spy()
    config = CascadeV1Config(levels=("easy", "hard"), episodes=5, val_episodes=4, ilc=False)
    doc = run_cascade_v1(config, spy.play, spy.chooser(choose_late_offset))
    assert [split for _, split, choosing in spy.calls if choosing] == ["val"] * (
        2 * len(LATE_OFFSETS)
    )
    for level in ("easy", "hard"):  # per level every validation play before any test play
        splits = [s for lv, s, _ in spy.calls if lv == level]
        assert "test" in splits and "val" not in splits[splits.index("test") :]
    for lv in doc["levels"]:
        assert lv["late_offset_s"] == 0.04  # test would pick 0.08
        assert lv["best_non_oracle"] == "late_meeting"  # 12 on validation
        assert lv["rows"]["late_meeting"]["catches_mean"] == 2.0  # its test value at +40 ms
        assert set(lv["val_mean_catches"]) == set(ROWS) - set(REFERENCES) - {"task_error_ilc"}
        assert lv["val_mean_catches"]["fixed_point"] == 9.0
        assert not lv["upper_is_upper"]  # oracle_catch (1) is below late meeting (2)
        assert lv["room"]["value"] == -1.0  # oracle_catch 1 - late meeting 2 on test
        assert lv["upper_minus_rows"]["late_meeting"]["ci"][1] < 0


def test_the_best_row_is_not_read_from_test_seeds() -> None:
    """With the late-meeting grid tied on validation, the best row is fixed_point (9 on
    validation, 1 on test) although juggler_mean_delay is best on test."""
    spy = Spy()

    def play(policy: Any, kwargs: dict[str, Any], split: str, n: int) -> CascadeEpisodes:
        eps = spy.play(policy, kwargs, split, n)
        if kwargs["controller"] == "juggler_mean_delay" and split == "val":
            return replace(eps, catches=np.zeros(n, dtype=np.int64))
        return eps

    config = CascadeV1Config(levels=("medium",), episodes=5, val_episodes=4, ilc=False)
    lv = run_cascade_v1(config, play, spy.chooser(choose_late_offset))["levels"][0]
    assert lv["best_non_oracle"] == "fixed_point"
    test_means = {k: m["catches_mean"] for k, m in lv["rows"].items() if k != "oracle"}
    assert max(test_means, key=lambda r: test_means[r]) != "fixed_point"


def _picked_cascade(
    pick_episodes: int, monkeypatch: pytest.MonkeyPatch
) -> tuple[dict[str, Any], list[tuple[str, int, bool, str]]]:
    """Cascade-v1's bench (medium, 5 test and 4 validation episodes, every chooser spied)
    picking on ``pick_episodes`` validation episodes, over a play where on validation
    ``mean_delay_catch`` catches 9 balls in each of the first 4 episodes and none after,
    late meeting (+40 ms only) 5 in every episode, a stand-in task-error ILC 1, every
    other row none (on test: none at all); the document and the plays ``(split, n,
    choosing, controller)``, the ILC's with controller ``"ilc"``."""
    from baselines.juggling_bench import cascade_v1, cascade_v1_ilc

    spy, calls = Spy(), []

    def episodes(split: str, n: int, catches: Any) -> CascadeEpisodes:
        return CascadeEpisodes(seeds=episode_seeds(split, n), catches=catches,
                               tosses=catches + 1, dropped=np.ones(n, dtype=bool),
                               time=np.full(n, 1.0))  # fmt: skip

    def play(policy: Any, kwargs: dict[str, Any], split: str, n: int) -> CascadeEpisodes:
        spy.play(policy, kwargs, split, n)  # fails on test while choosing
        calls.append((split, n, spy.choosing, kwargs["controller"]))
        return episodes(split, n, pick_ranking_catches(kwargs, split, n, 9, 5))

    ilc = recording_ilc(calls, spy, lambda split, n: episodes(split, n, np.ones(n, np.int64)))
    monkeypatch.setattr(cascade_v1_ilc, "CascadeTaskErrorILC", ilc)
    config = CascadeV1Config(levels=("medium",), episodes=5, val_episodes=4,
                             pick_episodes=pick_episodes)  # fmt: skip
    choosers = {
        f"{n}chooser": spy.chooser(getattr(cascade_v1, f"choose_{c}"))
        for n, c in (("offset_", "late_offset"), ("constant_", "constant"),
                     ("tracker_", "tracker"), ("estimator_offset_", "estimator_offset"),
                     ("estimator_tracker_", "estimator_tracker"), ("pooled_", "pooled_anchor"))
    }  # fmt: skip
    return run_cascade_v1(config, play, **choosers), calls


def test_the_best_row_is_picked_on_pick_episodes_validation_episodes(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """On the grids' 4 validation episodes mean_delay_catch (9) is above late meeting
    (5); on 12 it is below (3): the pick on 12 is late meeting, played at its +40 ms
    chosen on the grid, every row scored on 12 validation episodes (the ILC too), all
    before any test seed."""
    doc, calls = _picked_cascade(12, monkeypatch)
    (lv,) = doc["levels"]
    assert lv["late_offset_s"] == 0.04
    assert (lv["best_non_oracle"], lv["delay_tracker_minus"]["rival"]) == ("late_meeting",) * 2
    means = lv["val_mean_catches"]
    assert (means["mean_delay_catch"], means["late_meeting"], means["task_error_ilc"]) == (3, 5, 1)
    assert "the best non-oracle row picked on 12" in report_cascade_v1(doc)
    assert_picked_on(doc, calls, (4, 12), set(ROWS) - set(REFERENCES))


def test_picked_on_the_grids_episodes_the_pick_is_the_old_rule(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """``pick_episodes == val_episodes``: the best of the rows' means on the grids' 4
    episodes (mean_delay_catch, 9 against late meeting's 5), the grids' plays reused (the
    grid rows are not played again) and the learner scored on those 4."""
    doc, calls = _picked_cascade(4, monkeypatch)
    (lv,) = doc["levels"]
    assert (lv["best_non_oracle"], lv["delay_tracker_minus"]["rival"]) == ("mean_delay_catch",) * 2
    assert lv["val_mean_catches"]["mean_delay_catch"] == 9.0
    assert lv["val_mean_catches"]["late_meeting"] == lv["late_offset_val_mean_catches"]["40 ms"]
    assert_picked_on(doc, calls, (4, 4), set(ROWS) - set(REFERENCES))


def test_the_spy_catches_a_choice_made_on_test_seeds() -> None:
    def leaky(level: str, config: CascadeV1Config, play: Any) -> Any:
        eps = play(None, {"level": level, "controller": "juggler"}, "test", 3)
        return 0.0, {"leaked": float(eps.catches.mean())}

    spy = Spy()
    with pytest.raises(AssertionError, match="before the choice"):
        run_cascade_v1(CascadeV1Config(levels=("medium",), episodes=5, val_episodes=4, ilc=False),
                       spy.play, spy.chooser(leaky))  # fmt: skip


def test_bad_configs_name_the_field() -> None:
    for config, field in (
        (CascadeV1Config(levels=("drift",)), "levels"),
        (CascadeV1Config(pattern="7"), "pattern"),
        (CascadeV1Config(episodes=1), "episodes"),
        (CascadeV1Config(max_catches=0), "max_catches"),
        (CascadeV1Config(val_episodes=30, pick_episodes=29), "pick_episodes"),
    ):
        with pytest.raises(options.ConfigError, match=f"^{field}: "):
            check_cascade_v1_config(config)
    with pytest.raises(options.ConfigError, match=r"must be >= val_episodes \(30\); got 29$"):
        check_cascade_v1_config(CascadeV1Config(val_episodes=30, pick_episodes=29))
    check_cascade_v1_config(CascadeV1Config(val_episodes=30, pick_episodes=30))


def test_a_small_real_run_writes_its_table(tmp_path: Any) -> None:
    config = CascadeV1Config(pattern="3", levels=("easy",), episodes=2, val_episodes=2,
                             pick_episodes=2, max_catches=2, ilc_iterations=2,
                             ilc_episodes=2)  # fmt: skip
    doc = run_cascade_v1(config)
    (lv,) = doc["levels"]
    assert set(lv["rows"]) == set(ROWS)
    assert "SIMULATED" in doc["demonstrations"]
    assert "held-out SIMULATED 3-ball" in doc["deviation"]
    for name, m in lv["rows"].items():
        assert m["catches_median_ci"][0] <= m["catches_median"] <= m["catches_median_ci"][1]
        assert 0 <= m["catches_mean"] <= 2
        # every row's hand deviation from the held-out demonstrations, with its interval
        assert m["deviation_segments"] > 0, name
        lo, hi = m["deviation_ci"]
        assert 0 < lo <= m["deviation_m"] <= hi < 0.5, name
        assert len(m["deviation_hand_m"]) == 2
    # random actions (up to 0.1 m every step) shake the hands far from any demonstration
    assert lv["rows"]["random"]["deviation_m"] > 3 * lv["rows"]["juggler"]["deviation_m"]
    text = report_cascade_v1(doc)
    assert "deviation mm [95% CI]" in text and "not measured" not in text
    # the room in catch rate, the agents' target's unit, decides the target's words
    best, rows = lv["best_non_oracle"], lv["rows"]
    rate = lv["room_catch_rate"]["value"]
    assert rate == pytest.approx(rows["oracle_catch"]["catch_rate"] - rows[best]["catch_rate"])
    assert lv["target_room"]["room"] == rate and lv["target_room"]["sentence"] in text
    paths = write_cascade_v1(doc, tmp_path)
    assert [p.name for p in paths] == ["results.json", "cascade_v1_rows.png"]
    assert all(p.stat().st_size > 0 for p in paths)


@pytest.mark.parametrize("pattern", ["3", "5"])
def test_each_catch_carries_its_task_error_per_hand(pattern: str) -> None:
    """At every step with a catch: the catching hand's offset and meeting speed are
    finite, the speed below the level's capture speed (the capture at impact), the offset
    within the palm's reach, the timing (NaN for a catch outside the hand's catch phase,
    most are in it) within half a second of the plan; a hand that did not catch has NaN;
    steps without a catch carry neither key."""
    env = CascadeV1Env(level="easy", pattern=pattern, controller="juggler_mean_delay",
                       max_catches=8)  # fmt: skip
    lv = V2_LEVELS["easy"]
    seen = timings = 0
    for seed in range(3):
        env.reset(seed=seed)
        terminated = truncated = False
        while not (terminated or truncated):
            _, _, terminated, truncated, info = env.step(np.zeros(4, np.float32))
            if not info["caught"]:
                assert "task_error" not in info and "catch_speed" not in info
                continue
            err, speed = info["task_error"], info["catch_speed"]
            assert err.shape == (2, 2) and speed.shape == (2,)
            catching = np.isfinite(speed)
            assert catching.sum() == info["caught"]
            assert np.isnan(err[~catching]).all()
            assert (speed[catching] < lv.capture_speed).all()
            assert (np.abs(err[catching, 0]) < 0.1).all()
            timed = err[catching, 1][np.isfinite(err[catching, 1])]  # NaN: not in its catch phase
            assert (np.abs(timed) < 0.5).all()
            seen += int(catching.sum())
            timings += timed.size
    assert seen >= 5 and timings >= seen // 2
