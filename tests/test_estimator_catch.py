"""Juggling-v2's ``juggler_delay_estimator_catch``: the catch plan on the hand-written delay
estimator's delay (the two hand-written fixes together, a competitor row).

Independent checks: with the estimator's delay pinned to the level's mean, the controller
plays ``juggler_mean_delay_catch``'s episodes exactly (so it IS that plan, told the
estimate); with the world's hidden delay and drag poisoned wherever a controller could
be told them, its episodes are unchanged (it reads only frames and the release)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from motion_envs.envs.juggling import JugglingV2Env
from motion_envs.models.juggling import (
    CATCH_PLANS,
    V2_LEVELS,
    CatchPlanController,
    FlightEstimator,
)

NAME = "juggler_delay_estimator_catch"
KEYS = ("catches", "tosses", "dropped", "hand", "task_errors")


def _episodes(controller: str, level: str, seeds: range, **kw: Any) -> list[dict[str, Any]]:
    env = JugglingV2Env(level=level, controller=controller, max_catches=3, **kw)
    return [env.nominal_episode(s) for s in seeds]


def _same(a: list[dict[str, Any]], b: list[dict[str, Any]]) -> bool:
    return all(np.array_equal(x[k], y[k]) for x, y in zip(a, b, strict=True) for k in KEYS)


def test_it_is_the_catch_plan_on_the_release_anchored_estimator() -> None:
    controller = JugglingV2Env(controller=NAME).controller
    assert isinstance(controller, CatchPlanController)
    assert controller.plan == CATCH_PLANS["juggler_mean_delay_catch"]
    assert controller.estimator.mode == "release"


def test_pinned_to_the_mean_delay_it_plays_the_mean_delay_catch_episodes(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    seeds = range(3)
    base = _episodes("juggler_mean_delay_catch", "medium", seeds)
    own = _episodes(NAME, "medium", seeds)
    assert not _same(base, own)  # the comparison tells the estimator's delay apart
    mean = V2_LEVELS["medium"].mean_delay
    monkeypatch.setattr(FlightEstimator, "delay_estimate", property(lambda self: mean))
    assert _same(base, _episodes(NAME, "medium", seeds))


class _Poisoned(JugglingV2Env):
    """The env's own hidden delay NaN after ``reset`` (the camera already holds it)."""

    def reset(self, **kw: Any) -> Any:
        out = super().reset(**kw)
        self.delay = math.nan
        return out


def test_it_never_reads_the_hidden_delay_or_drag(monkeypatch: pytest.MonkeyPatch) -> None:
    seeds = range(3)
    honest = _episodes(NAME, "medium", seeds)
    reset, retell = FlightEstimator.reset, FlightEstimator.retell
    monkeypatch.setattr(FlightEstimator, "reset", lambda self, drag=0.0, delay=0.0: reset(
        self, math.nan, math.nan))  # fmt: skip
    monkeypatch.setattr(FlightEstimator, "retell",
                        lambda self, drag, delay: retell(self, math.nan, math.nan))  # fmt: skip
    poisoned = _Poisoned(level="medium", controller=NAME, max_catches=3)
    assert _same(honest, [poisoned.nominal_episode(s) for s in seeds])


def test_its_estimate_lands_near_the_hidden_delay_on_real_episodes() -> None:
    """Medium (100-200 ms, one delay per episode): after the episode the estimator's delay
    is within 25 ms of the hidden one, where the level's mean is off by more on average."""
    env = JugglingV2Env(level="medium", controller=NAME, max_catches=3)
    errors, prior = [], []
    for seed in range(8):
        env.nominal_episode(seed)
        est = env.controller.estimator.delay_estimate
        if est is not None:
            errors.append(abs(est - env.delay))
            prior.append(abs(V2_LEVELS["medium"].mean_delay - env.delay))
    assert len(errors) >= 6
    assert max(errors) < 0.025 and np.mean(errors) < np.mean(prior)
