"""Juggling-v2's ``gaze`` level: each frame's latency grows with the ball's eccentricity
from the fixated apex. Hand-worked eccentricity and arrival step; a zero slope (every
other level, and the camera without the new arguments) leaves every frame and every
rollout as before (digests recorded on the code before the level existed); both
checkers, determinism, the zero action rebuilt from its parts; the oracle places each
frame at its capture time up to the control step."""

from __future__ import annotations

import dataclasses
import hashlib
import math

import numpy as np
import pytest

from motion_envs.envs.juggling import JugglingV2Env
from motion_envs.models.juggling import (
    GAZE_EYE,
    V2_LEVELS,
    CameraFrame,
    CameraSensor,
    FlightEstimator,
    V2Level,
    ballistic_apex,
    eccentricity,
    gaze_eye,
)

GAZE = V2_LEVELS["gaze"]
DT = 0.005


def test_gaze_is_medium_plus_the_slope() -> None:
    assert GAZE.gaze_slope == (0.0005, 0.0015)
    assert dataclasses.replace(GAZE, gaze_slope=(0.0, 0.0)) == V2_LEVELS["medium"]
    assert all(V2_LEVELS[n].gaze_slope == (0.0, 0.0) for n in V2_LEVELS if n != "gaze")
    for bad in ((0.002, 0.001), (-0.001, 0.001), (0.0, 0.02), (math.nan, 0.001)):
        with pytest.raises(ValueError, match="gaze_slope"):
            dataclasses.replace(GAZE, gaze_slope=bad)
    assert isinstance(GAZE, V2Level)


def test_eccentricity_hand_worked() -> None:
    eye = gaze_eye((0.2, 1.0))
    assert eye == (0.2 + GAZE_EYE[0], 1.0 + GAZE_EYE[1], GAZE_EYE[2]) == (0.2, 1.45, 0.40)
    # fixation level with the eye, straight ahead of it: (0.2, 1.45) in the plane, 0.40 m
    # away; the ball 0.30 m straight below it: tan(ecc) = 0.30 / 0.40
    ecc = eccentricity((0.2, 1.15), (0.2, 1.45), eye)
    assert ecc == pytest.approx(math.degrees(math.atan(0.3 / 0.4)), abs=1e-12)
    assert ecc == pytest.approx(36.86989764584402, abs=1e-12)
    assert eccentricity((0.2, 1.45), (0.2, 1.45), eye) == 0.0
    # a general pair against the dot product's arccos
    ball, fix = (0.35, 0.95), (0.05, 1.80)
    a = np.array([ball[0] - 0.2, ball[1] - 1.45, -0.40])
    b = np.array([fix[0] - 0.2, fix[1] - 1.45, -0.40])
    want = math.degrees(math.acos(a @ b / np.linalg.norm(a) / np.linalg.norm(b)))
    assert eccentricity(ball, fix, eye) == pytest.approx(want, abs=1e-9)
    # the apex of a toss at (0.5, 4.905) m/s from (0.1, 1.0): 0.5 s up, 1.22625 m higher
    assert ballistic_apex((0.1, 1.0), (0.5, 4.905), 9.81) == pytest.approx((0.35, 2.22625))
    assert ballistic_apex((0.1, 1.0), (0.5, -1.0), 9.81) == (0.1, 1.0)


def test_a_frames_arrival_on_gaze_is_hand_computed() -> None:
    cam = CameraSensor(DT, 100.0, 0.0, 0.0, 0.0, 0.0)
    eye = (0.2, 1.45, 0.40)
    cam.reset(0.12, np.random.default_rng(0), slope=0.001, eye=eye)
    cam.fixate((0.2, 1.45))
    # captured at step 10, 36.870 deg from the fixation: 0.12 + 0.036870 s = 31.37 steps,
    # so it arrives at step 10 + 32 = 42
    assert [cam.record(k, (0.2, 1.15), (9.0, 9.0), True) for k in range(10)] == [[]] * 10
    assert cam.record(10, (0.2, 1.15), (9.0, 9.0), False) == []  # captured, in flight
    for k in range(11, 42):
        assert cam.record(k, (9.0, 9.0), (9.0, 9.0), True) == []
    (frame,) = cam.record(42, (9.0, 9.0), (9.0, 9.0), True)
    assert frame.capture == 10 * DT and frame.arrival == 42 * DT
    assert frame.gaze == pytest.approx(0.001 * 36.86989764584402, abs=1e-15)
    # before any release (nothing fixated) a frame carries no gaze latency
    cam.reset(0.12, np.random.default_rng(0), slope=0.001, eye=eye)
    frames = [f for k in range(60) for f in cam.record(k, (0.2, 1.15), (9.0, 9.0), False)]
    assert frames[0].arrival == 24 * DT and all(f.gaze == 0.0 for f in frames)


def test_slope_zero_frames_are_the_camera_without_gaze() -> None:
    def frames(gaze: bool) -> list[CameraFrame]:
        cam = CameraSensor(DT, 100.0, 0.01, 0.1, 0.1, 0.002)
        if gaze:
            cam.reset(0.15, np.random.default_rng(4), slope=0.0, eye=(0.2, 1.45, 0.4))
            cam.fixate((0.3, 1.9))
        else:
            cam.reset(0.15, np.random.default_rng(4))
        rng = np.random.default_rng(9)
        out: list[CameraFrame] = []
        for k in range(3000):
            ball = (float(rng.uniform(0, 0.5)), float(rng.uniform(0.8, 2.0)))
            out += cam.record(k, ball, (0.2, 1.0), held=k % 300 < 40)
        return out

    plain = frames(False)
    assert len(plain) > 1000 and plain == frames(True)


#: SHA-256 (first 16 hex digits) of zero-action episodes, seed 3, ``max_catches=3``
#: (every observation, reward and the true ball), recorded on the code before the level
#: ``gaze`` existed: the other levels' episodes are bit-identical.
BEFORE = {
    ("medium", "juggler_oracle_catch"): "46e9209cc5b3d3c0",
    ("drift", "juggler_oracle"): "09a3ef7a41f58bc4",
    ("hard", "juggler_delay_estimator_catch"): "fa54178b923ea634",
    ("easy", "juggler_delay_tracker"): "40a59d7e248e9b36",
}


@pytest.mark.parametrize(("level", "controller"), list(BEFORE))
def test_other_levels_rollouts_are_unchanged(level: str, controller: str) -> None:
    env = JugglingV2Env(level=level, controller=controller, max_catches=3)
    h = hashlib.sha256()
    obs, _ = env.reset(seed=3)
    h.update(obs.tobytes())
    done = False
    while not done:
        obs, reward, te, tr, info = env.step(np.zeros(2, np.float32))
        done = te or tr
        h.update(obs.tobytes() + np.float64(reward).tobytes() + info["ball"].tobytes())
    assert h.hexdigest()[:16] == BEFORE[(level, controller)]
    assert env.slope == 0.0 and env.camera.slope == 0.0


def test_gaze_passes_gymnasium_and_sb3_checks() -> None:
    from gymnasium.utils.env_checker import check_env

    check_env(JugglingV2Env(level="gaze"), skip_render_check=True)
    sb3 = pytest.importorskip("stable_baselines3.common.env_checker")
    sb3.check_env(JugglingV2Env(level="gaze"), warn=True)


def _play(env: JugglingV2Env, seed: int) -> tuple[np.ndarray, float]:
    obs, _ = env.reset(seed=seed)
    rng = np.random.default_rng(seed)
    out, done = [obs], False
    while not done:
        obs, _, te, tr, _ = env.step(rng.uniform(-0.1, 0.1, 2).astype(np.float32))
        out.append(obs)
        done = te or tr
    return np.stack(out), env.slope


def test_gaze_is_deterministic_and_draws_the_slope_from_its_own_stream() -> None:
    env = JugglingV2Env(level="gaze", controller="juggler_oracle_catch", max_catches=2)
    a, sa = _play(env, 11)
    b, sb = _play(JugglingV2Env(level="gaze", controller="juggler_oracle_catch",
                                max_catches=2), 11)  # fmt: skip
    assert np.array_equal(a, b) and sa == sb
    slopes = []
    medium = JugglingV2Env(level="medium")
    for seed in range(20):
        env.reset(seed=seed)
        medium.reset(seed=seed)
        assert (env.delay, env.drag) == (medium.delay, medium.drag)  # the same streams
        slope_rng = np.random.default_rng(np.random.SeedSequence(seed).spawn(6)[5])
        assert env.slope == float(slope_rng.uniform(0.0005, 0.0015))
        slopes.append(env.slope)
    assert 0.0005 <= min(slopes) < max(slopes) <= 0.0015


@pytest.mark.parametrize("controller", ["juggler", "juggler_oracle_catch"])
def test_zero_action_is_the_juggler_with_the_documented_gaze(controller: str) -> None:
    env = JugglingV2Env(level="gaze", controller=controller, max_catches=3)
    seed = next(s for s in range(100) if env.nominal_episode(s)["catches"] >= 1)
    env.reset(seed=seed)
    hands, done = [], False
    while not done:
        _, _, te, tr, info = env.step(np.zeros(2, np.float32))
        hands.append(info["hand"])
        done = te or tr

    # a fresh env's parts, driven here: the camera fixates each release's apex
    parts = JugglingV2Env(level="gaze", controller=controller, max_catches=3)
    ctrl, world, camera = parts.controller, parts.world, parts.camera
    w, c, k, d, r, g = (np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(6))
    delay, drag = float(d.uniform(0.10, 0.20)), float(r.uniform(0.009, 0.07))
    slope = float(g.uniform(0.0005, 0.0015))
    true = world.reset(parts.home, rng=w)
    world.set_drag(0, drag)
    home = (float(parts.home[0]), float(parts.home[1]))
    camera.reset(delay, c, slope, (home[0], home[1] + 0.45, 0.40))
    ctrl.estimator.reset(drag, delay)
    state = dataclasses.replace(true, ball_pos=true.hand_pos, ball_vel=true.hand_vel)
    ctrl.reset(state, k)
    expected, gazes = [], []
    for _ in hands:
        target, armed = ctrl.command(state)
        true = world.advance(float(target[0]), float(target[1]), armed)
        hand = (float(true.hand_pos[0]), float(true.hand_pos[1]))
        ball = (float(true.ball_pos[0]), float(true.ball_pos[1]))
        if true.released:
            vz = float(true.ball_vel[1])
            up = vz / 9.81
            camera.fixate((ball[0] + float(true.ball_vel[0]) * up, ball[1] + 0.5 * vz * up))
        frames = camera.record(int(world.k[0]), ball, hand, true.held)
        gazes += [f.gaze for f in frames]
        if true.released:
            ctrl.estimator.released(true.time, *hand)
        ctrl.estimator.add(frames)
        state = dataclasses.replace(true, ball_pos=true.hand_pos, ball_vel=true.hand_vel)
        expected.append(true.hand_pos.copy())
    np.testing.assert_allclose(np.array(hands), np.array(expected), atol=1e-12)
    assert max(gazes) > 0.02  # tens of ms near the palm


def test_oracle_places_synthetic_gaze_frames_at_their_capture() -> None:
    oracle = FlightEstimator("oracle", 9.81)
    oracle.reset(0.0, 0.13)
    oracle.released(1.0, 0.1, 1.0)
    frames = []
    for i in range(12):
        t = 1.05 + 0.01 * i
        s = t - 1.0
        gaze = 0.001 * (40 - 3 * i)  # falling as the ball nears the apex
        frames.append(CameraFrame(t, t + 0.13 + gaze, 0.1 - 0.8 * s, 1.0 + 3.5 * s - 4.905 * s * s,
                                  gaze))  # fmt: skip
    oracle.add(frames)
    times = oracle._times(oracle.frames)
    assert times is not None
    np.testing.assert_allclose(times, [f.capture for f in frames], atol=1e-12)
    now = 1.3
    s = now - 1.0
    p, _ = oracle.estimate(now)  # type: ignore[misc]
    np.testing.assert_allclose(p, (0.1 - 0.8 * s, 1.0 + 3.5 * s - 4.905 * s * s), atol=1e-9)


def test_oracle_frame_times_on_gaze_are_the_capture_times_without_jitter() -> None:
    env = JugglingV2Env(level="gaze", controller="juggler_oracle_catch", max_catches=3)
    env.camera.jitter_std = 0.0
    est = env.controller.estimator
    off, frames = [], 0
    for seed in range(3):
        env.reset(seed=seed)
        done = False
        while not done:
            _, _, te, tr, _ = env.step(np.zeros(2, np.float32))
            done = te or tr
            if est.frames:
                times = est._times(est.frames)
                assert times is not None
                captures = np.array([f.capture for f in est.frames])
                # each frame arrives at the first control step at or after capture +
                # latency: the oracle places it within one step after its capture
                assert np.all(times - captures >= -1e-9) and np.all(times - captures < DT)
                gaze = np.array([f.gaze for f in est.frames])
                off.append(np.max(gaze))
                frames += len(est.frames)
    assert frames > 100 and max(off) > 0.02  # the gaze latency was there to remove


# -- the hand-written gaze-aware estimator (juggler_gaze_estimator_catch) ----------------
def _gaze_flight(
    est: FlightEstimator, t_r: float, p0: tuple[float, float], v0: tuple[float, float],
    d: float, k: float, eye: tuple[float, float, float],
) -> list[CameraFrame]:  # fmt: skip
    """A noise-free flight released at ``t_r``: 10 frames 10 ms apart from 30 ms, each
    arriving ``d + k ecc`` after its capture (``ecc`` from the true apex)."""
    est.released(t_r, *p0, v0)
    apex = ballistic_apex(p0, v0, 9.81)
    frames = []
    for i in range(10):
        s = 0.03 + 0.01 * i
        x, z = p0[0] + v0[0] * s, p0[1] + v0[1] * s - 0.5 * 9.81 * s * s
        gaze = k * eccentricity((x, z), apex, eye)
        frames.append(CameraFrame(t_r + s, t_r + s + d + gaze, x, z, gaze))
    est.add(frames)
    return frames


@pytest.mark.parametrize(("d", "k"), [(0.125, 0.0012), (0.17, 0.0), (0.10, 0.0025)])
def test_gaze_estimator_finds_delay_and_slope_of_a_noise_free_flight(d: float, k: float) -> None:
    eye = (0.2, 1.45, 0.40)
    est = FlightEstimator("gaze_release", 9.81)
    est.eye = eye
    est.reset()
    plain = FlightEstimator("release", 9.81)
    for n, (p0, v0) in enumerate((((0.2, 1.1), (0.3, 4.0)), ((0.25, 1.05), (-0.2, 3.6)))):
        frames = _gaze_flight(est, 1.0 + 2 * n, p0, v0, d, k, eye)
        # on the grid points: found exactly, every frame placed at its capture
        assert est.gaze_estimate == pytest.approx((d, k), abs=1e-12)
        times = est._times(est.frames)
        assert times is not None
        np.testing.assert_allclose(times, [f.capture for f in frames], atol=1e-12)
        plain.released(1.0 + 2 * n, *p0)
        plain.add(frames)
    one = plain._times(plain.frames)
    assert one is not None
    spread = np.ptp(one - np.array([f.capture for f in plain.frames]))
    assert (spread > 0.02) == (k > 0)  # one delay cannot place a gaze flight's frames


def test_gaze_estimator_has_no_estimate_before_its_first_anchor() -> None:
    est = FlightEstimator("gaze_release", 9.81)
    est.released(0.0, 0.2, 1.0, (0.0, 4.0))
    assert est.estimate(0.2) is None and est.gaze_estimate is None
    from motion_envs.models.juggling import SLOPE_GRID

    assert SLOPE_GRID[0] == 0.0 and SLOPE_GRID[-1] == pytest.approx(0.003) and len(SLOPE_GRID) == 31


def test_eccentricities_vectorised_is_the_scalar() -> None:
    from motion_envs.models.juggling import eccentricities

    rng = np.random.default_rng(0)
    eye = (0.2, 1.45, 0.4)
    pos = rng.uniform(0.0, 2.0, (7, 2))
    fix = rng.uniform(0.0, 2.0, (3, 4, 2))
    got = eccentricities(pos, fix, eye)
    assert got.shape == (3, 4, 7)
    want = [[[eccentricity(tuple(p), tuple(f), eye) for p in pos] for f in row] for row in fix]
    np.testing.assert_allclose(got, want, atol=1e-9)


def test_gaze_estimator_controller_in_the_env() -> None:
    env = JugglingV2Env(level="gaze", controller="juggler_gaze_estimator_catch", max_catches=3)
    assert env.controller.estimator.eye == gaze_eye((float(env.home[0]), float(env.home[1])))
    a, _ = _play(env, 4)
    b, _ = _play(env, 4)
    assert np.array_equal(a, b)
    assert env.controller.estimator.gaze_estimate is not None
