"""The online delay tracker (``juggler_delay_tracker``): its update worked by hand (a
constant delay error shrinks by ``1 - k s`` per catch), ``k = 0`` is the mean-delay catch
plan exactly, the env hands it each catch's task error and never the hidden delay, its
episodes are deterministic, and the benches choose its gain and offset on validation
seeds only (a spy that can fail)."""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any

import gymnasium as gym
import numpy as np
import pytest

import motion_envs  # noqa: F401  (registers the ids)
from baselines.juggling_bench import v2
from baselines.juggling_bench.cascade_v1 import (
    CascadeV1Config,
    choose_late_offset,
    report_cascade_v1,
    run_cascade_v1,
)
from baselines.juggling_bench.cascade_v1 import choose_constant as cascade_constant
from baselines.juggling_bench.cascade_v1 import choose_tracker as cascade_tracker
from motion_envs.envs.juggling import CascadeV1Env, JugglingV2Env
from motion_envs.models.juggling import V2_LEVELS, DelayTracker, FlightEstimator
from tests.test_cascade_v1 import Spy as CascadeSpy
from tests.test_juggling_v2_bench import Spy as V2Spy

# -- the update, worked by hand ------------------------------------------------------------


@pytest.mark.parametrize(("gain", "slope"), [(0.5, 1.0), (0.25, 0.92), (1.0, 0.85), (0.1, 2.3)])
def test_a_constant_delay_error_shrinks_geometrically(gain: float, slope: float) -> None:
    """Catches whose timing is ``offset + s (D - d)`` (the linear model of the module
    docstring) take the estimate's error from ``D_0 - d`` to ``(1 - k s)^n (D_0 - d)``."""
    tracker = DelayTracker(gain, 0.02, (0.10, 0.25))
    true = 0.21
    assert tracker.estimate == pytest.approx(0.175) and tracker.told == pytest.approx(0.195)
    error0 = tracker.estimate - true
    for n in range(1, 9):
        tracker.update(0.02 + slope * (tracker.estimate - true))
        assert tracker.estimate - true == pytest.approx((1 - gain * slope) ** n * error0, abs=1e-12)
    assert tracker.told == pytest.approx(tracker.estimate + 0.02)


def test_one_hand_worked_step_its_clip_and_a_catch_without_timing() -> None:
    tracker = DelayTracker(0.5, 0.04, (0.10, 0.20))
    # D = 0.15; a catch 64 ms late against the 40 ms steered to: D = 0.15 - 0.5 * 0.024
    assert tracker.update(0.064) == pytest.approx(0.138)
    assert tracker.update(math.nan) == pytest.approx(0.138)  # no timing: unchanged
    assert tracker.update(-1.0) == 0.20  # far early: clipped at the range's high end
    assert tracker.update(1.0) == 0.10  # far late: at the low end
    tracker.reset()
    assert tracker.estimate == pytest.approx(0.15)
    still = DelayTracker(0.0, 0.0, (0.10, 0.20))
    assert still.update(0.3) == pytest.approx(0.15)  # k = 0 never moves


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"gain": -0.1, "offset": 0.0, "delay_range": (0.1, 0.2)}, "gain must be"),
        ({"gain": 2.0, "offset": 0.0, "delay_range": (0.1, 0.2)}, "gain must be"),
        ({"gain": math.nan, "offset": 0.0, "delay_range": (0.1, 0.2)}, "gain must be"),
        ({"gain": 0.5, "offset": 0.3, "delay_range": (0.1, 0.2)}, "offset must be"),
        ({"gain": 0.5, "offset": 0.0, "delay_range": (0.2, 0.1)}, "delay_range must be"),
    ],
)
def test_bad_tracker_arguments_are_refused(kwargs: dict[str, Any], match: str) -> None:
    with pytest.raises(ValueError, match=match):
        DelayTracker(**kwargs)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"controller": "juggler_mean_delay_catch", "tracker_gain": 0.5}, "tracker_gain is for"),
        ({"controller": "juggler_delay_tracker", "tracker_gain": 1.6}, "tracker_gain must be"),
        ({"controller": "juggler_delay_tracker", "tracker_gain": True}, "tracker_gain must be"),
        ({"controller": "juggler_oracle_catch", "delay_offset": 0.02}, "delay_offset is for"),
    ],
)
def test_the_envs_refuse_a_gain_for_another_controller(kwargs: dict[str, Any], match: str) -> None:
    with pytest.raises(ValueError, match=match):
        JugglingV2Env(level="medium", **kwargs)
    with pytest.raises(ValueError, match=match):
        CascadeV1Env(level="medium", **kwargs)


# -- in the envs -----------------------------------------------------------------------------


def _v2_episodes(seeds: range, **kwargs: Any) -> list[dict[str, Any]]:
    env = JugglingV2Env(level="drift", max_catches=4, **kwargs)
    return [env.nominal_episode(s) for s in seeds]


def _same(a: list[dict[str, Any]], b: list[dict[str, Any]]) -> bool:
    keys = ("catches", "tosses", "dropped", "hand", "task_errors")
    return all(np.array_equal(x[k], y[k]) for x, y in zip(a, b, strict=True) for k in keys)


def test_gain_zero_is_the_mean_delay_catch_plan_exactly() -> None:
    seeds = range(3)
    base = _v2_episodes(seeds, controller="juggler_mean_delay_catch")
    assert _same(base, _v2_episodes(seeds, controller="juggler_delay_tracker"))
    moved = _v2_episodes(seeds, controller="juggler_delay_tracker", tracker_gain=1.0)
    assert not _same(base, moved)  # the comparison can tell a moving tracker apart
    for pattern in ("3", "5"):
        env = CascadeV1Env(level="medium", pattern=pattern, max_catches=8,
                           controller="juggler_mean_delay_catch")  # fmt: skip
        trk = CascadeV1Env(level="medium", pattern=pattern, max_catches=8,
                           controller="juggler_delay_tracker")  # fmt: skip
        assert [env.play(s) for s in range(3)] == [trk.play(s) for s in range(3)]


def test_the_tracker_is_deterministic() -> None:
    kw = {"controller": "juggler_delay_tracker", "tracker_gain": 0.5, "delay_offset": 0.02}
    assert _same(_v2_episodes(range(2), **kw), _v2_episodes(range(2), **kw))
    env = CascadeV1Env(level="hard", controller="juggler_delay_tracker", tracker_gain=0.5,
                       max_catches=8)  # fmt: skip
    assert [env.play(s) for s in range(2)] == [env.play(s) for s in range(2)]


def test_juggling_v2_hands_the_controller_each_catchs_task_error() -> None:
    """An independent replay: a :class:`DelayTracker` fed the ``info["task_error"]`` of
    each catch (its timing made relative to the meeting, ``lead`` after the reach's end)
    ends where the controller's tracker is, catch by catch."""
    env = gym.make("MotionEnvs/Juggling-v2", level="drift", controller="juggler_delay_tracker",
                   tracker_gain=0.5, delay_offset=0.02, max_catches=5)  # fmt: skip
    ctl = env.unwrapped.controller
    replay = DelayTracker(0.5, 0.02, V2_LEVELS["drift"].delay)
    catches = 0
    for seed in range(3):
        env.reset(seed=seed)
        replay.reset()
        done = False
        while not done:
            _, _, term, trunc, info = env.step(np.zeros(2, dtype=np.float32))
            done = term or trunc
            if "task_error" in info:
                catches += 1
                replay.update(float(info["task_error"][1]) - ctl.plan.lead)
            assert ctl.tracker.estimate == pytest.approx(replay.estimate, abs=1e-15)
            assert ctl.estimator.fixed_delay == pytest.approx(replay.told, abs=1e-15)
    assert catches >= 5


def test_cascade_v1_hands_the_view_each_catchs_timing() -> None:
    env = CascadeV1Env(level="medium", controller="juggler_delay_tracker", tracker_gain=0.5,
                       max_catches=10)  # fmt: skip
    replay = DelayTracker(0.5, 0.0, V2_LEVELS["medium"].delay)
    env.reset(seed=4)
    done, catches = False, 0
    while not done:
        _, _, term, trunc, info = env.step(np.zeros(4))
        done = term or trunc
        if "task_error" in info:
            for timing in info["task_error"][:, 1]:
                catches += int(np.isfinite(timing))
                replay.update(float(timing))
        assert env.view.tracker is not None
        assert env.view.tracker.estimate == pytest.approx(replay.estimate, abs=1e-15)
    assert catches >= 3


def test_on_real_episodes_the_estimate_moves_toward_the_hidden_delay() -> None:
    """Medium (one delay per episode, 100-200 ms): after up to 6 catches with ``k = 0.5``
    the estimate is nearer the episode's delay than the prior was (mean over episodes)."""
    env = JugglingV2Env(level="medium", controller="juggler_delay_tracker", tracker_gain=0.5,
                        max_catches=6)  # fmt: skip
    before, after = [], []
    for seed in range(10):
        episode = env.nominal_episode(seed)
        if episode["catches"] >= 3:
            before.append(abs(env.controller.tracker.prior - env.delay))
            after.append(abs(env.controller.tracker.estimate - env.delay))
    assert len(after) >= 5
    assert np.mean(after) < 0.6 * np.mean(before)


class _Poisoned(JugglingV2Env):
    """Juggling-v2 whose hidden delay and drag are NaN wherever the controller could be
    told them: the estimators' ``reset``/``retell`` get NaN, and after ``reset`` (the
    camera already holds the true delay) the env's own ``delay`` is NaN (level
    ``medium``: no drift reads it again)."""

    def reset(self, **kw: Any) -> Any:
        out = super().reset(**kw)
        self.delay = math.nan
        return out


class _Cheat(_Poisoned):
    """A tracker that sets its estimate to the hidden delay at every catch."""

    def _step_batch(self, action: Any) -> Any:
        out = super()._step_batch(action)
        if self._caught is not None:
            self.controller.tracker.estimate = self.delay  # type: ignore[attr-defined]
            self.controller.felt(np.array([0.0, math.nan]))
        return out


def test_the_tracker_never_reads_the_hidden_delay(monkeypatch: pytest.MonkeyPatch) -> None:
    """With every way the world's hidden delay and drag reach the controller poisoned
    (:class:`_Poisoned`), the tracker's episodes are unchanged; a tracker that reads the
    delay (:class:`_Cheat`) is told apart."""
    kw = {"controller": "juggler_delay_tracker", "tracker_gain": 0.5, "delay_offset": 0.02}
    seeds = range(4)
    honest = [JugglingV2Env(level="medium", max_catches=4, **kw).nominal_episode(s) for s in seeds]
    reset, retell = FlightEstimator.reset, FlightEstimator.retell
    monkeypatch.setattr(FlightEstimator, "reset", lambda self, drag=0.0, delay=0.0: reset(
        self, math.nan, math.nan))  # fmt: skip
    monkeypatch.setattr(FlightEstimator, "retell",
                        lambda self, drag, delay: retell(self, math.nan, math.nan))  # fmt: skip
    poisoned = _Poisoned(level="medium", max_catches=4, **kw)
    assert _same(honest, [poisoned.nominal_episode(s) for s in seeds])
    cheat = _Cheat(level="medium", max_catches=4, **kw)
    try:  # the cheat's NaN delay either changes the episodes or breaks the fit
        assert not _same(honest, [cheat.nominal_episode(s) for s in seeds])
    except np.linalg.LinAlgError:
        pass


def _poisoned_cascade(kw: dict[str, Any], cls: type[CascadeV1Env] = CascadeV1Env) -> CascadeV1Env:
    """A Cascade-v1 env whose own ``delay`` and ``drags`` are NaN after every reset (the
    cameras and the world already hold the true ones)."""
    env = cls(level="medium", **kw)
    real_reset = env.reset

    def poisoned_reset(**k: Any) -> Any:
        out = real_reset(**k)
        env.delay = math.nan
        env.drags = np.full(env.balls, math.nan)
        return out

    env.reset = poisoned_reset  # type: ignore[method-assign]
    return env


@pytest.mark.parametrize(
    "kw",
    [
        {"controller": "juggler_delay_tracker", "tracker_gain": 0.5, "max_catches": 8},
        {"controller": "juggler_delay_estimator_catch", "max_catches": 8},
        {"controller": "juggler_delay_estimator_catch", "max_catches": 8, "pattern": "5"},
    ],
)
def test_cascade_v1_tracker_never_reads_the_hidden_delay(
    kw: dict[str, Any], monkeypatch: pytest.MonkeyPatch
) -> None:
    """The delay tracker and the delay estimator with the catch plan: with the hidden
    delay and drags poisoned wherever the controller could be told them (the estimators'
    ``reset`` gets NaN, the env's own attributes are NaN after the reset) the episodes
    are unchanged."""
    honest = [CascadeV1Env(level="medium", **kw).play(s) for s in range(3)]
    reset = FlightEstimator.reset
    monkeypatch.setattr(FlightEstimator, "reset", lambda self, drag=0.0, delay=0.0: reset(
        self, math.nan, math.nan))  # fmt: skip
    assert honest == [_poisoned_cascade(kw).play(s) for s in range(3)]


class _CheatingEstimatorCatch(CascadeV1Env):
    """``juggler_delay_estimator_catch`` whose pool is the env's hidden delay at every
    period: under the poisoning, NaN."""

    def _advance(self, residual: Any) -> Any:
        self.view.pool[:] = [self.delay]
        return super()._advance(residual)


def test_the_poisoning_tells_a_cheating_estimator_apart() -> None:
    kw = {"controller": "juggler_delay_estimator_catch", "max_catches": 8}
    honest = [CascadeV1Env(level="medium", **kw).play(s) for s in range(3)]
    cheat = _poisoned_cascade(kw, _CheatingEstimatorCatch)
    try:  # the cheat's NaN delay either changes the episodes or breaks the fit
        assert honest != [cheat.play(s) for s in range(3)]
    except (np.linalg.LinAlgError, ValueError):
        pass


# -- the benches' choice ---------------------------------------------------------------------


class TrackerSpy(V2Spy):
    """:class:`tests.test_juggling_v2_bench.Spy` whose tracker catches every toss only with
    ``k = 0.5, +20 ms`` on validation and only with ``k = 1, 0 ms`` on test."""

    def play(self, policy: Any, env_id: str, kwargs: dict[str, Any], split: str, n: int) -> Any:
        eps = super().play(policy, env_id, kwargs, split, n)
        if kwargs.get("controller") != "juggler_delay_tracker":
            return eps
        pair = (kwargs["tracker_gain"], kwargs["delay_offset"])
        good = {"val": (0.5, 0.02), "test": (1.0, 0.0)}[split]
        catches = np.full(n, 3 if pair == good else 0, dtype=np.int64)
        return replace(eps, catches=catches, dropped=catches < 3)


def test_v2_chooses_the_tracker_on_validation_seeds() -> None:
    spy = TrackerSpy()
    config = v2.V2Config(levels=("medium", "drift"), episodes=5, val_episodes=4, ilc=False)
    doc = v2.run_v2(config, spy.play, spy.chooser(v2.choose_constant),
                    spy.chooser(v2.choose_offset), spy.chooser(v2.choose_tracker))  # fmt: skip
    during = [split for split, choosing in spy.calls if choosing]
    grids = len(v2.CONSTANT_GRID) + len(v2.LATE_OFFSETS) + len(v2.TRACKER_GRID)
    assert during == ["val"] * (2 * grids)
    for lv in doc["levels"]:
        assert lv["tracker"] == {"gain": 0.5, "offset_s": 0.02}  # test would pick (1, 0)
        assert lv["tracker_val_catch_rates"]["k=0.5, +20 ms"] == 1.0
        assert lv["val_catch_rates"]["delay_tracker"] == 1.0
        assert lv["rows"]["delay_tracker"]["catch_rate"] == 0.0  # (0.5, 0.02) on test
    with pytest.raises(AssertionError, match="before the choice"):

        def leaky(level: str, config: Any, play: Any) -> Any:
            play(None, v2.ENV_ID_V2, {"level": level, "controller": "juggler"}, "test", 2)
            return (0.0, 0.0), {}

        v2.run_v2(config, spy.play, spy.chooser(v2.choose_constant),
                  spy.chooser(v2.choose_offset), spy.chooser(leaky))  # fmt: skip


class CascadeTrackerSpy(CascadeSpy):
    def catches(self, policy: Any, kwargs: dict[str, Any], split: str) -> int:
        if kwargs["controller"] != "juggler_delay_tracker":
            return super().catches(policy, kwargs, split)
        pair = (kwargs.get("tracker_gain", 0.0), kwargs.get("delay_offset", 0.0))
        return 20 if pair == {"val": (0.25, 0.04), "test": (0.1, 0.0)}[split] else 0


def test_cascade_v1_chooses_the_tracker_on_validation_seeds() -> None:
    spy = CascadeTrackerSpy()
    config = CascadeV1Config(levels=("medium",), episodes=5, val_episodes=4, ilc=False)
    doc = run_cascade_v1(config, spy.play, spy.chooser(choose_late_offset),
                         spy.chooser(cascade_constant),
                         tracker_chooser=spy.chooser(cascade_tracker))  # fmt: skip
    (lv,) = doc["levels"]
    # its rival is the best OTHER row on validation (the late meeting, 12 catches)
    assert lv["delay_tracker_minus"]["rival"] == "late_meeting"
    assert lv["delay_tracker_minus"]["minus_rival"]["value"] == 0.0 - 2.0
    assert "delay_tracker - late_meeting (the best other row, paired): -2.00" in (
        report_cascade_v1(doc)
    )
    during = [split for _, split, choosing in spy.calls if choosing]
    assert during == ["val"] * (len(v2.CONSTANT_GRID) + 7 + len(v2.TRACKER_GRID))
    assert lv["tracker"] == {"gain": 0.25, "offset_s": 0.04}
    assert lv["val_mean_catches"]["delay_tracker"] == 20.0
    assert lv["best_non_oracle"] == "delay_tracker"
    assert lv["rows"]["delay_tracker"]["catches_mean"] == 0.0  # the validation pair on test


def test_the_reports_pair_the_tracker_with_its_rival() -> None:
    spy = TrackerSpy()
    config = v2.V2Config(levels=("medium",), episodes=5, val_episodes=4, ilc=False)
    doc = v2.run_v2(config, spy.play, spy.chooser(v2.choose_constant),
                    spy.chooser(v2.choose_offset), spy.chooser(v2.choose_tracker))  # fmt: skip
    (lv,) = doc["levels"]
    d = lv["delay_tracker_minus"]
    # on validation the tracker and the delay estimator catch every toss; its rival is
    # the best OTHER row (the delay estimator), which on test catches none
    assert d["rival"] == "delay_estimator"
    assert d["minus_rival"]["value"] == 0.0  # both catch nothing on test
    mdc = lv["rows"]["mean_delay_catch"]["catch_rate"]
    assert d["minus_mean_delay_catch"]["value"] == pytest.approx(0.0 - mdc)
    assert "delay_tracker - delay_estimator (the best other row, paired): +0.000" in (
        v2.report_v2(doc)
    )
