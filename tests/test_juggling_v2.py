"""Juggling-v2: the world's air drag and capture at impact, the camera, the flight
estimators and the environment (Gymnasium's and SB3's checks, determinism, the zero
action is the analytic juggler, the task-error vector)."""

from __future__ import annotations

import math
from collections.abc import Callable

import gymnasium as gym
import mujoco
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import motion_envs  # noqa: F401
from motion_envs.datasets.juggling import JugglingTask
from motion_envs.envs.juggling import HandsWorld, JugglingV2Env, WorldSpec, world_mjcf
from motion_envs.models.juggling import (
    CameraFrame,
    CameraSensor,
    FlightEstimator,
    drag_flight,
)

TASK = JugglingTask(gravity=9.81)


def _air_world(backend: str = "auto", capture_speed: float = 5.0) -> HandsWorld:
    spec = WorldSpec.of(
        TASK, capture_speed=capture_speed, air_density=1.2, impact_capture=True,
        contact_damping=0.2,
    )  # fmt: skip
    return HandsWorld(spec, backend=backend)


def _drag_ode(k: float, g: float = 9.81) -> Callable[[float, np.ndarray], list[float]]:
    def f(_t: float, y: np.ndarray) -> list[float]:
        sp = math.hypot(y[2], y[3])
        return [y[2], y[3], -k * sp * y[2], -g - k * sp * y[3]]

    return f


def test_default_spec_has_no_air_and_the_contact_rule() -> None:
    xml = world_mjcf(WorldSpec())
    assert " density=" not in xml and "fluidshape" not in xml and 'solref="0.004 0.2"' not in xml
    assert WorldSpec().constants()[-1] == 0.0  # impact_capture off


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("air_density", -1.0),
        ("air_density", math.nan),
        ("impact_capture", 1),
        ("contact_damping", 0),
    ],
)
def test_spec_rejects_bad_fields(field: str, value: object) -> None:
    with pytest.raises(ValueError, match=f"WorldSpec.{field}"):
        WorldSpec(**{field: value})  # type: ignore[arg-type]


def test_mujoco_drag_is_half_rho_cd_a_v_squared() -> None:
    """MuJoCo's fluid force on the ball equals the textbook drag for the k set."""
    world = _air_world()
    k = 0.1
    world.set_drag(0, k)
    d = world.data
    world.launch_ball(0, (0.0, 2.0), (3.0, -4.0))
    mujoco.mj_forward(world.model, d)
    v = np.array([3.0, -4.0])
    r, m, rho = TASK.ball_radius, TASK.ball_mass, 1.2
    cd = 2 * k * m / (rho * math.pi * r * r)
    textbook = -0.5 * rho * cd * math.pi * r * r * np.linalg.norm(v) * v
    np.testing.assert_allclose(d.qfrc_passive[2:4], textbook, rtol=1e-12)
    assert d.qfrc_passive[0] == 0.0  # the hand feels no air (x; z holds gravcomp)
    spec0 = WorldSpec.of(TASK)
    dry = HandsWorld(spec0)
    dry.launch_ball(0, (0.0, 2.0), (3.0, -4.0))
    mujoco.mj_forward(dry.model, dry.data)
    assert d.qfrc_passive[1] == dry.data.qfrc_passive[1]


def test_ball_flight_in_air_matches_the_drag_ode() -> None:
    """A ball flying 0.3 s in the world (hand far away) against scipy's solution of
    dv/dt = -g - k |v| v; and drag_flight against the same."""
    world = _air_world()
    world.set_drag(0, 0.14)
    world.reset_state(
        np.array([[3.0, 1.0]]), np.zeros((1, 2)), (-1,), (-1,),
        np.array([[0.0, 1.0]]), np.array([[1.5, 4.0]]),
    )  # fmt: skip
    for _ in range(60):
        world.period(((3.0, 1.0),), (False,))
    sol = solve_ivp(_drag_ode(0.14), (0, 0.3), [0, 1.0, 1.5, 4.0], rtol=1e-11, atol=1e-12)
    got = world.data.qpos[2:4]
    np.testing.assert_allclose(got, sol.y[:2, -1], atol=2e-3)  # Euler, 1 ms steps
    ballistic_z = 1.0 + 4.0 * 0.3 - 0.5 * 9.81 * 0.09
    assert abs(got[1] - ballistic_z) > 0.01  # the drag is felt
    x, z, vx, vz = drag_flight((0.0, 1.0), (1.5, 4.0), 0.3, 9.81, 0.14)
    np.testing.assert_allclose([x, z, vx, vz], sol.y[:, -1], atol=1e-6)


@pytest.mark.parametrize(
    ("speed", "caught"), [(2.0, True), (4.5, True), (5.5, False), (8.0, False)]
)
def test_capture_at_impact_needs_a_slow_meeting(speed: float, caught: bool) -> None:
    """A ball falling onto a still palm at ``speed``: caught below capture_speed (5
    m/s), bounced off above (the contact alone would slow and catch it: the default
    rule of Juggling-v1's world catches the fast ones too)."""
    for impact in (True, False):
        damping = 0.2 if impact else 1.0  # Juggling-v2's springy palm; v1's world
        spec = WorldSpec.of(TASK, impact_capture=impact, contact_damping=damping)
        world = HandsWorld(spec)
        world.reset_state(
            np.array([[0.0, 1.0]]), np.zeros((1, 2)), (-1,), (-1,),
            np.array([[0.0, 1.004]]), np.array([[0.0, -speed]]),
        )  # fmt: skip
        got = False
        for _ in range(10):
            world.period(((0.0, 1.0),), (False,))
            got = got or world.caught[0, 0] == 0
        assert got == (caught or not impact), (speed, impact)


def test_impact_world_is_bit_identical_compiled_and_python() -> None:
    pytest.importorskip("numba")
    worlds = [_air_world("numba"), _air_world("python")]
    for w in worlds:
        w.set_drag(0, 0.05)
        w.reset_state(
            np.array([[0.0, 1.0]]), np.zeros((1, 2)), (-1,), (-1,),
            np.array([[0.01, 1.3]]), np.array([[0.0, 0.0]]),
        )  # fmt: skip
    for j in range(80):
        for w in worlds:
            w.period(((0.0, 1.0 - 0.001 * j),), (False,))
    a, b = (w.data for w in worlds)
    assert np.array_equal(a.qpos, b.qpos) and np.array_equal(a.qvel, b.qvel)
    assert worlds[0].holder[0, 0] == worlds[1].holder[0, 0]


def test_set_drag_needs_air() -> None:
    with pytest.raises(ValueError, match="air_density"):
        HandsWorld(WorldSpec.of(TASK)).set_drag(0, 0.1)


# -- the camera and the estimators ------------------------------------------------------
def test_camera_rate_delay_fifo_occlusion_and_drops() -> None:
    cam = CameraSensor(0.005, 100.0, 0.0, 0.0, 0.1, 0.0)
    cam.reset(0.123, np.random.default_rng(0))
    got: list[tuple[int, CameraFrame]] = []
    for k in range(100):
        ball = (0.0, 1.0 + 0.01 * k)
        hand = (0.0, 1.0) if k < 20 else (5.0, 5.0)  # near the hand for k < 10 (10 cm)
        got += [(k, f) for f in cam.record(k, ball, hand, held=k < 4)]
    captures = [round(f.capture / 0.005) for _, f in got]
    assert captures[0] == 10 and all(c % 2 == 0 for c in captures)  # 100 Hz, occluded < 10
    for k, f in got:  # arrives at the first control step at or after capture + delay
        assert k == math.ceil((f.capture + 0.123) / 0.005 - 1e-9)
        assert f.arrival == k * 0.005
    cam = CameraSensor(0.005, 100.0, 0.02, 0.3, 0.0, 0.0)
    cam.reset(0.1, np.random.default_rng(1))
    frames = [f for k in range(20000) for f in cam.record(k, (1.0, 1.0), (0.0, 0.0), False)]
    assert abs(len(frames) / 10000 - 0.7) < 0.02  # 30 % dropped
    arrivals = [f.arrival for f in frames]
    assert arrivals == sorted(arrivals)  # first in, first out despite the jitter
    lat = np.array([f.arrival - f.capture for f in frames])
    assert 0.1 < lat.mean() < 0.12 and lat.std() > 0.01


def _frames(delay: float, v0: tuple[float, float], n: int, t_r: float = 1.0) -> list[CameraFrame]:
    out = []
    for i in range(n):
        t = t_r + 0.05 + 0.01 * i
        s = t - t_r
        x, z = 0.1 + v0[0] * s, 1.0 + v0[1] * s - 0.5 * 9.81 * s * s
        out.append(CameraFrame(t, t + delay, x, z))
    return out


@pytest.mark.parametrize("delay", [0.1, 0.165, 0.245])
def test_release_estimator_finds_the_delay_and_the_oracle_the_state(delay: float) -> None:
    est = FlightEstimator("release", 9.81)
    est.released(1.0, 0.1, 1.0)
    est.add(_frames(delay, (-0.8, 3.5), 12))
    assert est.delay_estimate == pytest.approx(delay, abs=0.0026)
    now = 1.0 + 0.05 + 0.11 + delay
    p, _ = est.estimate(now)  # type: ignore[misc]
    s = now - 1.0
    truth = (0.1 - 0.8 * s, 1.0 + 3.5 * s - 0.5 * 9.81 * s * s)
    np.testing.assert_allclose(p, truth, atol=2e-3)
    naive = FlightEstimator("arrival", 9.81)
    naive.released(1.0, 0.1, 1.0)
    naive.add(_frames(delay, (-0.8, 3.5), 12))
    p_naive, _ = naive.estimate(now)  # type: ignore[misc]
    assert np.linalg.norm(p_naive - truth) > 0.05  # what the delay costs the juggler
    oracle = FlightEstimator("oracle", 9.81)
    oracle.reset(0.0, delay)
    oracle.released(1.0, 0.1, 1.0)
    oracle.add(_frames(delay, (-0.8, 3.5), 12))
    np.testing.assert_allclose(oracle.estimate(now)[0], truth, atol=1e-9)  # type: ignore[index]


def test_estimator_without_frames_gives_none() -> None:
    est = FlightEstimator("arrival", 9.81)
    est.released(0.0, 0.0, 1.0)
    est.add(_frames(0.1, (0.0, 3.0), 2, t_r=0.0))
    assert est.estimate(0.5) is None
    with pytest.raises(ValueError, match="mode"):
        FlightEstimator("psychic", 9.81)


# -- the environment ----------------------------------------------------------------------
def test_env_passes_gymnasium_and_sb3_checks() -> None:
    from gymnasium.utils.env_checker import check_env

    check_env(gym.make("MotionEnvs/Juggling-v2").unwrapped, skip_render_check=True)
    sb3 = pytest.importorskip("stable_baselines3.common.env_checker")
    sb3.check_env(JugglingV2Env(), warn=True)


def test_env_is_deterministic_and_zero_action_is_the_juggler() -> None:
    env = JugglingV2Env(level="hard", max_catches=2)
    played = env.nominal_episode(7)
    rows = []
    for _ in range(2):
        obs, info = env.reset(seed=7)
        trace = [obs]
        hands = [info["hand"]]
        done = False
        while not done:
            obs, _, term, trunc, info = env.step(np.zeros(2, dtype=np.float32))
            trace.append(obs)
            hands.append(info["hand"])
            done = term or trunc
        rows.append((np.stack(trace), np.stack(hands), info["catches"], info["tosses"]))
    assert np.array_equal(rows[0][0], rows[1][0])
    assert np.array_equal(rows[0][1], played["hand"])
    assert (rows[0][2], rows[0][3]) == (played["catches"], played["tosses"])


def test_step_is_juggling_v1s_batch_bit_identical_compiled_and_python() -> None:
    """Juggling-v2 steps Juggling-v1's batch of one (``V2Batch``): its compiled kernels and
    the plain-Python path give the same episode bit for bit (residual actions, catches,
    the drift's changes, a NaN action), and the reward is Juggling-v1's formula."""
    pytest.importorskip("numba")
    from motion_envs.envs.juggling._v2_env import V2Batch

    runs = []
    for backend in ("numba", "python"):
        env = JugglingV2Env(level="drift", controller="juggler_oracle", max_catches=3)
        env._batch = V2Batch([env], backend)
        rng = np.random.default_rng(0)
        obs, _ = env.reset(seed=2)  # two catches, then a drop
        trace, values, done = [obs], [], False
        while not done:
            action = rng.uniform(-0.2, 0.2, 2)
            if len(values) == 50:
                action[1] = np.nan
            obs, reward, term, trunc, info = env.step(action)
            a = np.nan_to_num(np.clip(action, -1, 1))
            w = env.reward_weights
            formula = (
                w["catch"] * info["caught"]
                - w["drop"] * term
                - w["likeness"] * info["likeness"]
                - w["action"] * float(a @ a)
            )
            assert reward == pytest.approx(formula, abs=1e-12)
            trace.append(obs)
            values.append((reward, info["likeness"], info["time"], env.delay, env.drag))
            done = term or trunc
        runs.append((np.stack(trace), np.array(values), info["catches"]))
    assert runs[0][2] == 2 and term
    np.testing.assert_array_equal(runs[0][0], runs[1][0])
    np.testing.assert_array_equal(runs[0][1], runs[1][1])


def test_delay_and_drag_are_drawn_per_episode_in_the_level_range() -> None:
    env = JugglingV2Env(level="medium")
    delays, drags = [], []
    for s in range(40):
        env.reset(seed=s)
        delays.append(env.delay)
        drags.append(env.drag)
    assert 0.10 <= min(delays) and max(delays) <= 0.20 and np.std(delays) > 0.02
    assert 0.009 <= min(drags) and max(drags) <= 0.07


def test_task_error_at_a_catch() -> None:
    env = JugglingV2Env(level="easy", controller="juggler_oracle", max_catches=2)
    env.reset(seed=3)
    errors = []
    done = False
    while not done:
        _, _, term, trunc, info = env.step(np.zeros(2))
        done = term or trunc
        if info["caught"]:
            errors.append(info["task_error"])
            assert 0 <= info["catch_speed"] < 5.0
        else:
            assert "task_error" not in info
    assert len(errors) == 2
    e = np.array(errors)
    assert (np.abs(e[:, 0]) < 0.045 + 0.035).all() and (np.abs(e[:, 1]) < 0.1).all()


def test_env_rejects_bad_arguments() -> None:
    with pytest.raises(ValueError, match="level"):
        JugglingV2Env(level="expert")
    with pytest.raises(ValueError, match="controller"):
        JugglingV2Env(controller="psychic")


def test_a_drop_reports_its_miss_vector() -> None:
    """The analytic juggler on hard drops; the drop's step carries the closest
    approach's offset and timing (finite), and no catch's task error."""
    env = JugglingV2Env(level="hard")
    seen = 0
    for seed in range(5):
        env.reset(seed=seed)
        done = False
        while not done:
            _, _, term, trunc, info = env.step(np.zeros(2))
            done = term or trunc
        if term and "miss_error" in info:
            seen += 1
            assert np.isfinite(info["miss_error"]).all() and info["miss_speed"] >= 0
            assert abs(info["miss_error"][0]) < 1.0 and "task_error" not in info
    assert seen >= 3


@pytest.mark.slow
def test_memory_agents_can_train_on_it() -> None:
    """What an agent with memory needs works: Gymnasium's frame stack (the stacked
    observation stays in its space) and sb3-contrib's RecurrentPPO (a short learn)."""
    from gymnasium.wrappers import FrameStackObservation

    stacked = FrameStackObservation(gym.make("MotionEnvs/Juggling-v2", max_catches=1), 16)
    obs, _ = stacked.reset(seed=0)
    for _ in range(20):
        obs, *_ = stacked.step(np.zeros(2, dtype=np.float32))
    assert obs.shape == (16, 32) and stacked.observation_space.contains(obs)
    contrib = pytest.importorskip("sb3_contrib")
    model = contrib.RecurrentPPO(
        "MlpLstmPolicy", JugglingV2Env(max_catches=1), n_steps=64, batch_size=64, seed=0,
        policy_kwargs={"lstm_hidden_size": 16, "net_arch": [16]},
    )  # fmt: skip
    model.learn(128)
    action, state = model.predict(obs[-1], deterministic=True)
    assert action.shape == (2,) and state is not None
