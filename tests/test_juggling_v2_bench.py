"""``motion-bench juggling --version v2``: the rows' choices read no test seed (a spy
that can fail), the two-line row's arithmetic, and a small real run with its files."""

from __future__ import annotations

from dataclasses import replace
from typing import Any, ClassVar

import numpy as np
import pytest
from _helpers import assert_picked_on, pick_ranking_catches, recording_ilc

from baselines import options
from baselines.agents.juggling_score import JugglingEpisodes
from baselines.juggling_bench.v2 import (
    CONSTANT_GRID,
    LATE_OFFSETS,
    REFERENCES,
    ROWS,
    UPPER_REFERENCE,
    V2Config,
    VelocityTimesDelay,
    choose_constant,
    choose_offset,
    report_v2,
    run_v2,
    write_v2,
)
from motion_envs.datasets.juggling import episode_seeds
from motion_envs.envs.juggling import JugglingV2Env
from motion_envs.models.juggling import V2_LEVELS


class Spy:
    """A ``play`` that records the splits it is asked for and fails when a test seed is
    played while a choice is being made (synthetic episodes: the order is the point)."""

    #: Synthetic rankings that differ between the splits: on validation the delay
    #: estimator catches every toss, on test the mean-delay juggler does (and the delay
    #: estimator none), so a best row chosen on test seeds is told apart.
    FAVOURED: ClassVar[dict[str, str]] = {
        "val": "juggler_delay_estimator",
        "test": "juggler_mean_delay",
    }

    def __init__(self) -> None:
        self.choosing = False
        self.calls: list[tuple[str, bool]] = []
        self.levels: list[tuple[str, str]] = []

    def play(
        self, policy: Any, env_id: str, kwargs: dict[str, Any], split: str, n: int
    ) -> JugglingEpisodes:
        self.calls.append((split, self.choosing))
        self.levels.append((kwargs["level"], split))
        if split == "test" and self.choosing:
            raise AssertionError("a test seed was played before the choice was made")
        seeds = episode_seeds(split, n)
        catches = np.minimum(np.arange(n, dtype=np.int64) % 3 + len(self.calls) % 2, 2)
        controller = kwargs.get("controller")
        if controller == self.FAVOURED[split]:
            catches = np.full(n, 3, dtype=np.int64)
        elif controller in self.FAVOURED.values():
            catches = np.zeros(n, dtype=np.int64)
        return JugglingEpisodes(
            seeds=seeds,
            tosses=np.full(n, 3, dtype=np.int64),
            catches=catches,
            dropped=catches < 3,
            segment_phase=np.array(["catch"] * n),
            segment_episode=np.arange(n, dtype=np.int64),
            segment_deviation=np.linspace(0.01, 0.02, n),
        )

    def chooser(self, inner: Any) -> Any:
        def choose(level: str, config: V2Config, play: Any) -> Any:
            self.choosing = True
            try:
                return inner(level, config, play)
            finally:
                self.choosing = False

        return choose


def test_choices_read_only_validation_seeds() -> None:
    spy = Spy()
    config = V2Config(levels=("medium", "hard"), episodes=5, val_episodes=4, ilc=False)
    doc = run_v2(config, spy.play, spy.chooser(choose_constant), spy.chooser(choose_offset))
    during = [split for split, choosing in spy.calls if choosing]
    assert during == ["val"] * (2 * (len(CONSTANT_GRID) + len(LATE_OFFSETS)))
    assert [lv["level"] for lv in doc["levels"]] == ["medium", "hard"]
    for level in ("medium", "hard"):  # per level, every validation play before any test play
        splits = [split for lv, split in spy.levels if lv == level]
        assert "test" in splits and "val" not in splits[splits.index("test") :]


def test_the_best_non_oracle_row_is_chosen_on_validation_seeds() -> None:
    spy = Spy()
    config = V2Config(levels=("medium", "hard"), episodes=5, val_episodes=4, ilc=False)
    doc = run_v2(config, spy.play, spy.chooser(choose_constant))
    for lv in doc["levels"]:
        rates = {n: m["catch_rate"] for n, m in lv["rows"].items() if n not in REFERENCES}
        # on test the mean-delay juggler is best: a choice on test would pick it
        assert max(rates, key=lambda r: rates[r]) == "juggler_mean_delay"
        assert lv["best_non_oracle"] == "delay_estimator"
        assert lv["val_catch_rates"]["delay_estimator"] == 1.0
        assert lv["val_catch_rates"]["juggler_mean_delay"] == 0.0
        assert "oracle" not in lv["val_catch_rates"]
        assert set(lv["val_catch_rates"]) == set(ROWS) - {*REFERENCES, "task_error_ilc"}


def test_the_late_offset_is_chosen_on_validation_seeds() -> None:
    """On validation the mean-delay juggler catches every toss only with +40 ms, on test
    only with +80 ms: ``late_meeting`` must carry the validation choice (and so catch
    nothing on test), and it enters the best non-oracle row's choice."""
    spy = Spy()
    favoured = {"val": 0.04, "test": 0.08}

    def play(policy: Any, env_id: str, kwargs: dict[str, Any], split: str, n: int) -> Any:
        eps = spy.play(policy, env_id, kwargs, split, n)
        if kwargs.get("controller") != "juggler_mean_delay":
            return eps
        catches = np.full(n, 3 if kwargs.get("delay_offset", 0.0) == favoured[split] else 0)
        return replace(eps, catches=catches, dropped=catches < 3)

    config = V2Config(levels=("medium",), episodes=5, val_episodes=4, ilc=False)
    lv = run_v2(config, play, spy.chooser(choose_constant), spy.chooser(choose_offset))["levels"][0]
    assert lv["late_offset_s"] == 0.04
    assert lv["late_offset_val_catch_rates"] == {
        f"{20 * i} ms": 1.0 if i == 2 else 0.0 for i in range(11)
    }
    assert lv["val_catch_rates"]["late_meeting"] == 1.0
    assert lv["val_catch_rates"]["juggler_mean_delay"] == 0.0
    assert lv["rows"]["late_meeting"]["catch_rate"] == 0.0
    # ties with the delay estimator (1.0 on validation): the first in ROWS
    assert lv["best_non_oracle"] == "late_meeting"


def test_the_catch_rows_choice_is_made_on_validation_and_never_picks_a_reference() -> None:
    """On validation the catch-plan oracle catches every toss and the mean-delay catch
    plan every toss but one (the best competitor); on test the catch plan catches
    nothing and the mean-delay juggler everything: the best row must be the catch plan
    (a choice on test would pick the mean-delay juggler, one counting the references
    the oracle), and the room is measured against the catch-plan oracle."""
    spy = Spy()

    def play(policy: Any, env_id: str, kwargs: dict[str, Any], split: str, n: int) -> Any:
        eps = spy.play(policy, env_id, kwargs, split, n)
        controller = kwargs.get("controller")
        catches = eps.catches
        if controller == "juggler_oracle_catch":
            catches = np.full(n, 3)
        elif controller == "juggler_mean_delay_catch":
            catches = np.full(n, 3) if split == "val" else np.zeros(n, dtype=np.int64)
            catches[0] = 2 if split == "val" else 0
        elif controller == "juggler_delay_estimator":
            catches = np.zeros(n, dtype=np.int64)
        return replace(eps, catches=catches, dropped=catches < 3)

    config = V2Config(levels=("hard",), episodes=5, val_episodes=4, ilc=False)
    (lv,) = run_v2(config, play, spy.chooser(choose_constant), spy.chooser(choose_offset))["levels"]
    assert lv["best_non_oracle"] == "mean_delay_catch"
    # picked on the default pick_episodes validation episodes: one toss of them all missed
    tosses = 3 * config.pick_episodes
    assert lv["val_catch_rates"]["mean_delay_catch"] == pytest.approx((tosses - 1) / tosses)
    assert UPPER_REFERENCE not in lv["val_catch_rates"]
    assert lv["rows"]["mean_delay_catch"]["catch_rate"] == 0.0
    assert lv["room_below_oracle_catch"]["value"] == pytest.approx(1.0)


def _picked_v2(
    pick_episodes: int, monkeypatch: pytest.MonkeyPatch
) -> tuple[dict[str, Any], list[tuple[str, int, bool, str]]]:
    """Juggling-v2's bench (medium, 5 test and 4 validation episodes, every chooser
    spied) picking on ``pick_episodes`` validation episodes, over a play where on
    validation ``mean_delay_catch`` catches every toss of the first 4 episodes and none
    after, late meeting (+40 ms only) 2 of 3 tosses in every episode, a stand-in
    task-error ILC 1 of 3, every other row none (on test: none at all); the document and
    the plays ``(split, n, choosing, controller)``, the ILC's with controller ``"ilc"``."""
    from baselines.juggling_bench import v2

    spy, calls = Spy(), []

    def play(policy: Any, env_id: str, kwargs: dict[str, Any], split: str, n: int) -> Any:
        eps = spy.play(policy, env_id, kwargs, split, n)  # fails on test while choosing
        calls.append((split, n, spy.choosing, kwargs["controller"]))
        catches = pick_ranking_catches(kwargs, split, n, 3, 2)
        return replace(eps, catches=catches, dropped=catches < 3)

    def ilc_episodes(split: str, n: int) -> JugglingEpisodes:
        eps = spy.play(None, "ilc", {"level": "medium"}, split, n)
        return replace(eps, catches=np.ones(n, dtype=np.int64), dropped=np.ones(n, bool))

    monkeypatch.setattr(v2, "TaskErrorILC", recording_ilc(calls, spy, ilc_episodes))
    config = V2Config(levels=("medium",), episodes=5, val_episodes=4, pick_episodes=pick_episodes)
    names = ("", "offset_", "tracker_", "estimator_offset_", "estimator_tracker_", "pooled_")
    choosers = {
        f"{n}chooser": spy.chooser(getattr(v2, f))
        for n, f in zip(names, ("choose_constant", "choose_offset", "choose_tracker",
                                "choose_estimator_offset", "choose_estimator_tracker",
                                "choose_pooled_anchor"), strict=True)
    }  # fmt: skip
    return run_v2(config, play, **choosers), calls


def test_the_best_row_is_picked_on_pick_episodes_validation_episodes(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """On the grids' 4 validation episodes mean_delay_catch (1) is above late meeting
    (2/3); on 12 it is below (4/12): the pick on 12 is late meeting, played at its +40 ms
    chosen on the grid, every row scored on 12 validation episodes (the ILC too), all
    before any test seed."""
    doc, calls = _picked_v2(12, monkeypatch)
    (lv,) = doc["levels"]
    assert lv["late_offset_s"] == 0.04
    assert lv["best_non_oracle"] == "late_meeting"
    assert lv["delay_tracker_minus"]["rival"] == "late_meeting"
    assert lv["val_catch_rates"]["mean_delay_catch"] == pytest.approx(4 / 12)
    assert lv["val_catch_rates"]["late_meeting"] == pytest.approx(2 / 3)
    assert lv["val_catch_rates"]["task_error_ilc"] == pytest.approx(1 / 3)
    assert lv["late_offset_val_catch_rates"]["40 ms"] == pytest.approx(2 / 3)  # the grid's 4
    assert "the best non-oracle row picked on 12" in report_v2(doc)
    assert_picked_on(doc, calls, (4, 12), set(ROWS) - set(REFERENCES))


def test_picked_on_the_grids_episodes_the_pick_is_the_old_rule(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """``pick_episodes == val_episodes``: the best of the rows' rates on the grids' 4
    episodes (mean_delay_catch, 1 against late meeting's 2/3), the grids' plays reused
    (the grid rows are not played again) and the learner scored on those 4; a pick on
    fewer episodes than the grids' is refused."""
    from baselines.juggling_bench.v2 import check_v2_config

    doc, calls = _picked_v2(4, monkeypatch)
    (lv,) = doc["levels"]
    assert lv["best_non_oracle"] == "mean_delay_catch"
    assert lv["delay_tracker_minus"]["rival"] == "mean_delay_catch"
    assert lv["val_catch_rates"]["mean_delay_catch"] == 1.0
    assert lv["val_catch_rates"]["late_meeting"] == lv["late_offset_val_catch_rates"]["40 ms"]
    assert_picked_on(doc, calls, (4, 4), set(ROWS) - set(REFERENCES))
    with pytest.raises(
        options.ConfigError, match=r"^pick_episodes: must be >= val_episodes \(30\); got 29$"
    ):
        check_v2_config(V2Config(val_episodes=30, pick_episodes=29))
    check_v2_config(V2Config(val_episodes=30, pick_episodes=30))


def test_env_delay_offset_shifts_only_the_mean_delay_juggler() -> None:
    env = JugglingV2Env(level="medium", controller="juggler_mean_delay", delay_offset=0.04)
    assert env.controller.estimator.fixed_delay == V2_LEVELS["medium"].mean_delay + 0.04
    base = JugglingV2Env(level="medium", controller="juggler_mean_delay")
    assert base.controller.estimator.fixed_delay == V2_LEVELS["medium"].mean_delay
    with pytest.raises(ValueError, match="delay_offset must be in"):
        JugglingV2Env(controller="juggler_mean_delay", delay_offset=-0.01)
    with pytest.raises(ValueError, match="delay_offset must be in"):
        JugglingV2Env(controller="juggler_mean_delay", delay_offset=float("nan"))
    with pytest.raises(ValueError, match="delay_offset is for"):
        JugglingV2Env(controller="juggler", delay_offset=0.02)


def test_the_spy_catches_a_choice_made_on_test_seeds() -> None:
    def leaky(level: str, config: V2Config, play: Any) -> Any:
        eps = play(None, "MotionEnvs/Juggling-v2", {"level": level}, "test", 3)
        return (0.0, 0.0), {"leaked": eps.catch_rate}

    spy = Spy()
    with pytest.raises(AssertionError, match="before the choice"):
        run_v2(V2Config(levels=("medium",), episodes=5, val_episodes=4, ilc=False), spy.play,
               spy.chooser(leaky))  # fmt: skip


def test_velocity_times_delay_is_the_two_line_fix() -> None:
    policy = VelocityTimesDelay(delay=0.15, scale=0.2)
    obs = np.zeros((2, 32), dtype=np.float32)
    obs[:, 7] = 1.0  # catch phase
    # newest first: x, z, age since arrival, valid; the ball moves at (1, -3) m/s
    for i, age in enumerate((0.0, 0.01, 0.02, 0.03)):
        obs[:, 16 + 4 * i : 20 + 4 * i] = (0.1 - 1.0 * age, 1.0 + 3.0 * age, age, 1.0)
    obs[1, 7] = 0.0  # another phase: no residual
    got = policy(obs)
    np.testing.assert_allclose(got[0], np.clip([1.0 * 0.15 / 0.2, -3.0 * 0.15 / 0.2], -1, 1),
                               atol=1e-4)  # fmt: skip
    np.testing.assert_array_equal(got[1], [0.0, 0.0])
    obs[0, 20:32] = 0.0  # only one frame: no velocity
    assert np.array_equal(policy(obs)[0], [0.0, 0.0])


def test_a_small_real_run_writes_the_table_and_the_plot(tmp_path: Any) -> None:
    config = V2Config(levels=("easy",), episodes=3, val_episodes=2, pick_episodes=2,
                      max_catches=1, ilc_iterations=2, ilc_episodes=2)  # fmt: skip
    doc = run_v2(config)
    (level,) = doc["levels"]
    assert set(level["rows"]) == {
        "juggler", "oracle", "oracle_catch", "best_constant", "velocity_x_mean_delay",
        "juggler_mean_delay", "late_meeting", "mean_delay_catch", "delay_estimator",
        "delay_estimator_catch", "estimator_offset_catch", "random", "task_error_ilc",
        "delay_tracker", "gaze_estimator_catch", "estimator_tracker_catch",
        "pooled_estimator_catch",
    }  # fmt: skip
    assert set(level["val_catch_rates"]) == set(level["rows"]) - {"oracle", "oracle_catch"}
    assert set(level["oracle_catch_minus_rows"]) == set(level["rows"]) - {"oracle_catch"}
    room = level["room_below_oracle_catch"]
    assert room == level["oracle_catch_minus_rows"][level["best_non_oracle"]]
    assert level["target_room"]["room"] == room["value"]
    assert level["target_room"]["sentence"] in report_v2(doc)
    assert level["best_non_oracle"] == max(
        level["val_catch_rates"], key=lambda r: level["val_catch_rates"][r]
    )
    assert level["ilc"]["budget_train_episodes"] == 4
    for row in level["rows"].values():
        lo, hi = row["catch_rate_ci"]
        assert lo <= row["catch_rate"] <= hi and row["deviation_m"] > 0
    paths = write_v2(doc, tmp_path)
    assert [p.name for p in paths] == ["results.json", "juggling_v2_rows.png"]
    assert all(p.stat().st_size > 0 for p in paths)


def test_ilc_solve_is_least_squares_and_trains_on_training_seeds(monkeypatch: Any) -> None:
    """The Gauss-Newton step is the least squares of r* = c + d v (numpy's lstsq on the
    stacked rows); training resets only TRAINING seeds."""
    from baselines.juggling_bench import ilc as ilc_module

    rng = np.random.default_rng(0)
    learner = ilc_module.TaskErrorILC("medium", 0.2, 0.15)
    v = rng.normal(0, 2, (20, 2))
    truth = np.array([0.03, -0.02, 0.17])
    r = truth[:2] + truth[2] * v + rng.normal(0, 1e-3, (20, 2))
    learner.samples = [(a, b, c, d) for (a, b), (c, d) in zip(v, r, strict=True)]
    learner._solve()
    a = np.zeros((40, 3))
    a[:20, 0], a[20:, 1], a[:20, 2], a[20:, 2] = 1, 1, v[:, 0], v[:, 1]
    expected, *_ = np.linalg.lstsq(a, np.concatenate([r[:, 0], r[:, 1]]), rcond=None)
    np.testing.assert_allclose([*learner.c, learner.d], expected, atol=1e-6)
    np.testing.assert_allclose(expected, truth, atol=2e-3)

    seen: list[int] = []
    make = ilc_module.TaskErrorILC._env

    def spying_env(self: Any) -> Any:
        env = make(self)
        reset = env.reset

        def spy_reset(*, seed: int, **kw: Any) -> Any:
            seen.append(seed)
            return reset(seed=seed, **kw)

        env.reset = spy_reset  # type: ignore[method-assign,assignment]
        return env

    monkeypatch.setattr(ilc_module.TaskErrorILC, "_env", spying_env)
    learner = ilc_module.TaskErrorILC("medium", 0.2, 0.15, ilc_module.ILCConfig(2, 2))
    learner.train()
    assert seen == [0, 1, 2, 3]  # SPLIT_SEEDS["train"] + i


def test_the_random_row_restarts_its_generator_for_the_test_seeds() -> None:
    """The random row's test episodes do not depend on how many validation episodes were
    played before: its generator is a fresh one, seeded as at the start, when the test
    seeds are played (a generator carried over from validation would have moved on)."""
    from baselines.juggling_bench.v2 import _Random

    spy, states = Spy(), []

    def play(policy: Any, env_id: str, kwargs: dict[str, Any], split: str, n: int) -> Any:
        if isinstance(policy, _Random):
            states.append((split, policy.rng.bit_generator.state["state"]))
            policy(np.zeros((n, 4), dtype=np.float32))  # the draws an episode makes
        return spy.play(policy, env_id, kwargs, split, n)

    run_v2(V2Config(levels=("medium",), episodes=5, val_episodes=4, ilc=False), play,
           spy.chooser(choose_constant), spy.chooser(choose_offset))  # fmt: skip
    fresh = np.random.default_rng(0).bit_generator.state["state"]
    assert [s for s, _ in states] == ["val", "test"]
    assert all(state == fresh for _, state in states)


def test_the_target_room_says_whether_the_level_can_decide() -> None:
    from baselines.agents.against_rows import room_for_target

    shut = room_for_target("delay_estimator_catch", "oracle_catch", 0.010, [-0.011, 0.032])
    assert not shut["open"]
    assert "NO room" in shut["sentence"] and "by at least +0.018" in shut["sentence"]
    wide = room_for_target("late_meeting", "oracle_catch", 0.122, [0.079, 0.169])
    assert wide["open"] and "room for the target" in wide["sentence"]
    edge = room_for_target("a", "b", 0.02, [-0.01, 0.05])  # the high end at the margin: open
    assert edge["open"]
