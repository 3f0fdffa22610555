"""The release-anchored estimators' delay rule: the residual per delay against a
least-squares oracle, the default rule as before, a given rule's reach into both envs."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from _helpers import T_R, G, release_frames, rollout_digest

import motion_envs  # noqa: F401  (registers the ids)
from motion_envs.models.juggling import (
    ANCHOR_FRAMES,
    DELAY_GRID,
    FlightEstimator,
    mean_flight_delay,
    release_residuals,
)


def _anchored(delay: float, n: int = ANCHOR_FRAMES) -> tuple[np.ndarray, np.ndarray]:
    """A noiseless flight's first ``n`` frames as an estimator anchors them."""
    from _helpers import P0

    frames = release_frames(delay, n)
    s0 = np.array([f.arrival - T_R for f in frames])
    q = np.array([[f.x - P0[0], f.z - P0[1]] for f in frames])
    return s0, q


def test_the_residuals_are_each_delays_least_squares_fit() -> None:
    # oracle: per delay, numpy's least squares of y = v s (two unknowns) on the frames
    rng = np.random.default_rng(3)
    s0, q = _anchored(0.130)
    q = q + rng.normal(0, 0.004, q.shape)
    got = release_residuals(s0, q, G)
    for i, d in enumerate(DELAY_GRID):
        s = s0 - d
        if (s <= 0).any():
            assert got[i] == np.inf
            continue
        y = q + np.stack([np.zeros_like(s), 0.5 * G * s * s], axis=1)
        _, res, *_ = np.linalg.lstsq(s[:, None], y, rcond=None)
        assert got[i] == pytest.approx(float(res.sum()), rel=1e-9, abs=1e-15)


def test_a_noiseless_flight_has_no_residual_at_its_delay() -> None:
    s0, q = _anchored(0.145)
    got = release_residuals(s0, q, G)
    assert got[int(np.argmin(got))] == pytest.approx(0.0, abs=1e-20)
    assert DELAY_GRID[int(np.argmin(got))] == pytest.approx(0.145)
    assert mean_flight_delay([(s0, q), _anchored(0.125)], G) == pytest.approx(0.135)
    assert mean_flight_delay([], G) is None


def test_a_flight_with_no_possible_delay_tells_none() -> None:
    s0, q = _anchored(0.0)
    s0 = s0 - 1.0  # every frame before its release
    assert np.isinf(release_residuals(s0, q, G)).all()
    assert mean_flight_delay([(s0, q)], G) is None


def _feed(est: FlightEstimator, delay: float, n: int) -> None:
    from _helpers import P0

    est.released(T_R, P0[0], P0[1])
    for f in release_frames(delay, n):
        est.add([f])


def test_the_given_rule_is_asked_once_per_anchored_flight() -> None:
    seen: list[list[int]] = []

    def rule(flights, gravity):  # type: ignore[no-untyped-def]
        assert gravity == G
        seen.append([len(s0) for s0, _ in flights])
        return 0.2

    est = FlightEstimator("release", G, rule=rule, anchor_frames=12)
    _feed(est, 0.135, 11)
    assert est.delay_estimate is None and seen == []  # not anchored yet
    _feed(est, 0.135, 20)  # the short flight anchored at this release, then this one
    assert est.delay_estimate == 0.2 and est.delay_estimate == 0.2
    assert seen == [[11, 12]]
    _feed(est, 0.135, 20)
    assert est.delay_estimate == 0.2 and seen == [[11, 12], [11, 12, 12]]
    # its frames are placed by the rule's delay
    fit = est.fit()
    assert fit is not None and fit[0] == pytest.approx(T_R + 0.20 + 0.135 - 0.2)


def test_without_a_rule_the_estimate_is_the_mean_of_the_flights() -> None:
    plain = FlightEstimator("release", G)
    ruled = FlightEstimator("release", G, rule=mean_flight_delay)
    for d in (0.130, 0.150):
        _feed(plain, d, 10)
        _feed(ruled, d, 10)
    assert plain.delay_estimate == ruled.delay_estimate == pytest.approx(0.140)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"mode": "oracle", "rule": mean_flight_delay}, "mode 'release'"),
        ({"mode": "mean_delay", "anchor_frames": 12}, "mode 'release'"),
        ({"mode": "release", "anchor_frames": 2}, "anchor_frames"),
        ({"mode": "release", "anchor_frames": 8.5}, "anchor_frames"),
    ],
)
def test_the_estimator_refuses_a_rule_where_it_has_none(kwargs: dict, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        FlightEstimator(gravity=G, **kwargs)


_ENVS = [
    ("MotionEnvs/Juggling-v2", {}),
    ("MotionEnvs/Cascade-v1", {"pattern": "3", "max_catches": 4}),
]


@pytest.mark.parametrize(("env_id", "extra"), _ENVS)
def test_the_default_rule_given_plays_the_same_episodes(env_id: str, extra: dict) -> None:
    kw = {"level": "medium", "controller": "juggler_delay_estimator_catch", **extra}
    plain = gym.make(env_id, **kw)
    given = gym.make(env_id, delay_rule=mean_flight_delay, **kw)
    for seed in (0, 7):
        if env_id.endswith("Cascade-v1"):
            assert rollout_digest(plain, seed) == rollout_digest(given, seed)
        else:
            assert _v2_digest(plain, seed) == _v2_digest(given, seed)


def _v2_digest(env: gym.Env, seed: int) -> bytes:
    obs, _ = env.reset(seed=seed)
    out = [obs.tobytes()]
    done = False
    while not done:
        obs, reward, te, tr, _ = env.step(np.zeros(env.action_space.shape, np.float32))
        out.append(obs.tobytes() + np.float64(reward).tobytes())
        done = te or tr
    return b"".join(out)


@pytest.mark.parametrize(("env_id", "extra"), _ENVS)
def test_a_rule_reaches_the_envs_estimate(env_id: str, extra: dict) -> None:
    kw = {"level": "medium", "controller": "juggler_delay_estimator_catch", **extra}
    env = gym.make(env_id, delay_rule=lambda flights, gravity: 0.123, anchor_frames=10, **kw)
    env.reset(seed=1)
    for _ in range(200):
        env.step(np.zeros(env.action_space.shape, np.float32))
    inner = env.unwrapped
    estimate = (
        inner.view.delay_estimate  # type: ignore[attr-defined]
        if env_id.endswith("Cascade-v1")
        else inner.controller.estimator.delay_estimate  # type: ignore[attr-defined]
    )
    assert estimate == 0.123


@pytest.mark.parametrize(("env_id", "extra"), _ENVS)
@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"controller": "juggler_mean_delay_catch", "anchor_frames": 12}, "anchor_frames"),
        ({"controller": "juggler_oracle_catch", "delay_rule": mean_flight_delay}, "delay_rule"),
        ({"controller": "juggler_delay_estimator_catch", "delay_rule": 0.12}, "delay_rule"),
        ({"controller": "juggler_delay_estimator_catch", "anchor_frames": True}, "anchor_frames"),
    ],
)
def test_the_envs_refuse_a_rule_in_one_line(
    env_id: str, extra: dict, kwargs: dict, match: str
) -> None:
    with pytest.raises(ValueError, match=match) as err:
        gym.make(env_id, level="medium", **extra, **kwargs)
    assert "\n" not in str(err.value)
