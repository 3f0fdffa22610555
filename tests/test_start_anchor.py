"""The balls in flight at Cascade-v1's start anchored on the juggler's own throws before
``t = 0`` (``anchor_start``): the throws fly the balls to their start state, a start
flight tells the true delay (hand-worked), and in the env the pooled estimate comes
earlier than without, as exact."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from _helpers import G, check_env_contract

from motion_envs.models.juggling import (
    CameraFrame,
    PooledReleaseEstimator,
    pattern_controller,
    pattern_spec,
    pooled_flight_delay,
)


@pytest.mark.parametrize("pattern", ["3", "5"])
def test_the_start_throws_fly_each_ball_to_its_start_state(pattern: str) -> None:
    """Closed form: from ``releases[b] = (t_r, x, z)`` at the velocity ``v(0) + (0, g
    s)``, ``s = -t_r``, the ball is at ``(x, z) + v s - (0, g s^2 / 2)`` at ``t = 0``;
    the five-ball start scattered (its velocity drawn), the three-ball one nominal."""
    spec = pattern_spec(pattern)
    controller = pattern_controller(spec, "juggler", G)
    start = controller.start((0.12, np.radians(12.0)), np.random.default_rng(3))
    assert len(start.releases) == spec.balls
    flying = 0
    for b in range(spec.balls):
        if start.holder[b] >= 0:
            assert start.releases[b] is None
            continue
        flying += 1
        t_r, x, z = start.releases[b]  # type: ignore[misc]
        s = -t_r
        assert s > 0
        v = start.ball_vel[b] + np.array([0.0, G * s])
        want = np.array([x, z]) + v * s - np.array([0.0, 0.5 * G * s * s])
        np.testing.assert_allclose(start.ball_pos[b], want, atol=1e-12)
    assert flying == spec.balls - 2


def _frames(t_r: float, p: tuple[float, float], v: tuple[float, float], delay: float, n: int
            ) -> list[CameraFrame]:  # fmt: skip
    """``n`` noiseless frames captured every 10 ms from ``t = 0`` of the ballistic flight
    thrown at ``t_r < 0`` from ``p`` at ``v``, arriving ``delay`` later."""
    out = []
    for j in range(n):
        c = 0.01 * j
        s = c - t_r
        x, z = p[0] + v[0] * s, p[1] + v[1] * s - 0.5 * G * s * s
        out.append(CameraFrame(c, c + delay, x, z))
    return out


def test_a_start_flight_anchored_on_its_throw_tells_the_true_delay() -> None:
    """Hand-worked: a ball thrown at -0.2 s from (0.1, 1.3) m at (-0.6, 3.2) m/s, its
    frames from ``t = 0`` arriving 145 ms late: anchored on its throw, the eighth frame
    tells 145 ms (the grid's); started as a flight no hand released (the default) it
    tells nothing."""
    p, v = (0.1, 1.3), (-0.6, 3.2)
    frames = _frames(-0.2, p, v, 0.145, 8)
    for anchored in (True, False):
        pool: list[float] = []
        est = PooledReleaseEstimator(G, pool, 0.15)
        est.reset()
        if anchored:
            est.released(-0.2, *p)
        else:
            est.flying_at_start(0.0, *(frames[0].x, frames[0].z))
        for f in frames:
            est.add([f])
        assert pool == ([pytest.approx(0.145)] if anchored else [])


def _first_estimate(anchor_start: bool, seed: int) -> tuple[float, float, float]:
    """``(time, estimate, true delay)`` of the env's first pooled estimate (zero action;
    the pooled rule on 20 frames, ``pooled_estimator_catch``'s)."""
    env = gym.make(
        "MotionEnvs/Cascade-v1", level="medium", controller="juggler_delay_estimator_catch",
        delay_rule=pooled_flight_delay, anchor_frames=20, anchor_start=anchor_start,
    ).unwrapped  # fmt: skip
    env.reset(seed=seed)
    for _ in range(400):
        _, _, term, trunc, info = env.step(np.zeros(4, np.float32))
        got = env.view.delay_estimate  # type: ignore[attr-defined]
        if got is not None:
            return float(info["time"]), float(got), float(env.delay)  # type: ignore[attr-defined]
        assert not (term or trunc)
    raise AssertionError("no estimate in 400 steps")


@pytest.mark.parametrize("seed", [0, 1])
def test_the_start_anchor_brings_the_estimate_before_the_first_release_is_seen(
    seed: int,
) -> None:
    """The first estimate without the start anchor waits for the first release's frames
    (after its first catch phase); with it, the start ball's frames tell it earlier and
    within the jitter and noise of the true delay."""
    late, _, _ = _first_estimate(False, seed)
    early, estimate, delay = _first_estimate(True, seed)
    assert early < late - 0.1
    assert abs(estimate - delay) < 0.02


def test_the_start_anchor_keeps_the_env_contract() -> None:
    check_env_contract(
        gym.make("MotionEnvs/Cascade-v1", level="hard", pattern="5",
                 controller="juggler_delay_estimator_catch", anchor_start=True)
    )  # fmt: skip


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"controller": "juggler_mean_delay_catch", "anchor_start": True}, "anchor_start"),
        ({"controller": "juggler_delay_estimator_catch", "anchor_start": "yes"}, "anchor_start"),
    ],
)
def test_the_env_refuses_a_start_anchor_in_one_line(kwargs: dict, match: str) -> None:
    with pytest.raises(ValueError, match=match) as err:
        gym.make("MotionEnvs/Cascade-v1", level="medium", **kwargs)
    assert "\n" not in str(err.value)
