"""The MuJoCo juggling scene: compiles, stays quiet, flies the closed-form parabola, holds,
releases, catches and drops as the contract says."""

from __future__ import annotations

import pickle
from dataclasses import replace

import mujoco
import numpy as np
import pytest

from motion_envs.datasets.juggling import JugglingNoise, JugglingState, JugglingTask
from motion_envs.envs.juggling import JugglingScene, load_juggling_model

TASK = JugglingTask()


def _no_warnings(scene: JugglingScene) -> None:
    fired = {i: int(w.number) for i, w in enumerate(scene.data.warning) if w.number}
    assert not fired, f"MuJoCo warnings fired: {fired}"


def _toss_path(scene: JugglingScene, start=(0.0, 1.0), vel=(-0.4, 1.6), n_up=30):
    """Accelerate uniformly to ``vel + (0, 0.2)`` over ``n_up`` steps, then one step at
    ``vel`` (deceleration 0.2 / dt = 40 m/s^2, past the threshold: the toss, at ``vel``)."""
    dt = scene.task.dt
    top = np.asarray(vel, float) + np.array([0.0, 0.2])
    p = np.array(start, float)
    targets = []
    for k in range(1, n_up + 1):
        p = p + top * (k / n_up) * dt
        targets.append(p.copy())
    targets.append(p + np.asarray(vel, float) * dt)
    return targets


def test_compiles_with_the_task_constants():
    task = replace(TASK, gravity=9.81, dt=0.002, ball_radius=0.04, catch_radius=0.08, floor_z=0.2)
    model = load_juggling_model(task)
    assert model.opt.timestep == 0.002
    np.testing.assert_array_equal(model.opt.gravity, [0.0, 0.0, -9.81])
    assert model.opt.integrator == mujoco.mjtIntegrator.mjINT_RK4
    assert model.nq == 2 and model.nv == 2 and model.nmocap == 1 and model.nu == 0
    ball = model.geom("ball")
    assert ball.size[0] == 0.04 and model.geom("hand").size[0] == 0.08
    assert model.geom("floor").pos[2] == 0.2
    assert model.body("ball").mass[0] == pytest.approx(0.13)


@pytest.mark.parametrize("gravity", [TASK.gravity, 9.81])
def test_two_seconds_of_random_hand_motion_fire_no_warning(gravity):
    scene = JugglingScene(replace(TASK, gravity=gravity))
    rng = np.random.default_rng(0)
    scene.reset([0.0, 1.0], noise=JugglingNoise(release=0.1), rng=rng)
    n = round(2.0 / TASK.dt)
    targets = np.array([0.0, 1.0]) + np.cumsum(rng.normal(0, 0.01, (n, 2)), axis=0)
    events = {"released": 0, "caught": 0}
    for k, target in enumerate(targets):
        s = scene.step(target, bool(k % 3 == 0))
        events["released"] += s.released
        events["caught"] += s.caught
        assert np.all(np.isfinite(s.ball_pos)) and np.all(np.isfinite(s.ball_vel))
    assert scene.data.time == pytest.approx(2.0)
    assert events["released"] > 0  # random motion did toss (and the scene kept quiet)
    _no_warnings(scene)


@pytest.mark.parametrize("gravity", [TASK.gravity, 9.81])
def test_free_flight_is_the_closed_form_parabola(gravity):
    task = replace(TASK, gravity=gravity, floor_z=-100.0)
    scene = JugglingScene(task)
    scene.reset([0.0, 1.0], rng=np.random.default_rng(1))
    for target in _toss_path(scene):
        s = scene.step(target, True)
    assert s.released and not s.held
    p0, v0, t0 = s.ball_pos.copy(), s.ball_vel.copy(), s.time
    np.testing.assert_allclose(v0, [-0.4, 1.6], atol=1e-12)
    hand = s.hand_pos
    worst = 0.0
    for _ in range(round(3.0 / task.dt)):  # the hand stays still, far below: no catch
        s = scene.step(hand, False)
        t = s.time - t0
        expected = p0 + v0 * t + np.array([0.0, -0.5 * gravity * t * t])
        worst = max(worst, float(np.abs(s.ball_pos - expected).max()))
        np.testing.assert_allclose(s.ball_vel, v0 + np.array([0.0, -gravity * t]), atol=1e-9)
    assert worst <= 1e-6, worst
    _no_warnings(scene)


def test_held_ball_follows_the_hand_exactly_and_release_needs_arming():
    scene = JugglingScene()
    scene.reset([0.1, 0.9])
    path = _toss_path(scene, start=(0.1, 0.9))
    for target in path:
        s = scene.step(target, False)  # never armed: no release despite the deceleration
        assert s.held and not s.released
        np.testing.assert_array_equal(s.ball_pos, s.hand_pos)
        np.testing.assert_array_equal(s.ball_vel, s.hand_vel)
        np.testing.assert_array_equal(s.hand_pos, target)


def test_release_takes_the_hand_velocity_times_the_seeded_noise():
    scene = JugglingScene()
    scene.reset([0.0, 1.0], noise=JugglingNoise(release=0.1), rng=np.random.default_rng(7))
    path = _toss_path(scene)
    for target in path[:-1]:
        scene.step(target, True)  # accelerating up: no release
        assert scene.held
    s = scene.step(path[-1], True)
    assert s.released and not s.held
    e = np.random.default_rng(7).standard_normal(2)
    np.testing.assert_allclose(s.ball_vel, np.array([-0.4, 1.6]) * (1 + 0.1 * e), rtol=1e-9)
    np.testing.assert_array_equal(s.ball_pos, s.hand_pos)
    # without noise the ball leaves with the hand's velocity exactly
    scene.reset([0.0, 1.0], rng=np.random.default_rng(7))
    for target in path:
        s = scene.step(target, True)
    assert s.released
    np.testing.assert_array_equal(s.ball_vel, s.hand_vel)
    np.testing.assert_allclose(s.hand_vel, [-0.4, 1.6], atol=1e-9)


def test_catch_only_a_falling_ball_within_the_radius_then_drop_below_the_floor():
    scene = JugglingScene()
    scene.reset([0.0, 1.0], rng=np.random.default_rng(0))
    for target in _toss_path(scene, vel=(0.0, 1.6)):
        s = scene.step(target, True)
    assert s.released
    hand = s.hand_pos.copy()
    # the hand stays under the ball: the rising ball is within the radius, not caught
    s = scene.step(hand, False)
    assert not s.caught and np.linalg.norm(s.ball_pos - hand) <= TASK.catch_radius
    while not s.caught:
        s = scene.step(hand, False)
        assert not s.dropped
    assert s.held and s.ball_vel[1] == 0.0
    np.testing.assert_array_equal(s.ball_pos, hand)
    # caught on the first step after the falling ball crosses catch_radius above the hand:
    # 1.6 t - g t^2 / 2 = catch_radius
    g, r = TASK.gravity, TASK.catch_radius
    crossing = (1.6 + np.sqrt(1.6**2 - 2 * g * r)) / g
    assert 0 <= s.time - (31 * TASK.dt + crossing) < TASK.dt + 1e-9
    # toss again and pull the hand away: the ball falls past the floor
    for target in _toss_path(scene, start=hand, vel=(0.0, 1.6)):
        s = scene.step(target, True)
    away = s.hand_pos + np.array([0.5, 0.0])
    while not s.dropped:
        s = scene.step(away, False)
        assert not s.caught
    assert s.ball_pos[1] < TASK.floor_z and not s.held
    assert scene.step(away, False).dropped  # stays dropped below the floor


def _state_row(s: JugglingState) -> np.ndarray:
    return np.concatenate([s.hand_pos, s.hand_vel, s.ball_pos, s.ball_vel, [s.held]])


def _juggling_targets(task: JugglingTask, cycles: int, seed: int):
    """Hand targets of a crude juggler: toss, move under the predicted landing point, wait."""
    rng = np.random.default_rng(seed)
    targets, armed = [], []
    home = np.array([0.0, 1.0])
    for _ in range(cycles):
        vel = np.array([rng.uniform(-0.3, 0.3), rng.uniform(1.2, 1.8)])
        top = vel + np.array([0.0, 0.2])
        p = home.copy()
        for k in range(1, 31):
            p = p + top * (k / 30) * task.dt
            targets.append(p.copy())
            armed.append(True)
        p = p + vel * task.dt  # the toss step
        targets.append(p.copy())
        armed.append(True)
        flight = 2 * vel[1] / task.gravity
        land = p + np.array([vel[0] * flight, 0.0])
        for k in range(1, round(flight / task.dt) + 20):
            targets.append(p + (land - p) * min(1.0, k / 60))
            armed.append(False)
        home = land
    return np.array(targets), armed


@pytest.mark.parametrize(
    ("gravity", "noise"),
    [(TASK.gravity, JugglingNoise()), (TASK.gravity, JugglingNoise(0.05, 0.002)), (9.81, None)],
)
def test_scene_equals_ballistic_world_for_the_same_hand_targets(gravity, noise):
    """The contract: JugglingScene and the pure-model BallisticWorld agree to 1e-9."""
    from motion_envs.models.juggling import BallisticWorld

    task = replace(TASK, gravity=gravity)
    targets, armed = _juggling_targets(task, 6, 3)
    scene, world = JugglingScene(task), BallisticWorld(task)
    home = np.array([0.0, 1.0])
    rows = [_state_row(scene.reset(home, noise=noise, rng=np.random.default_rng(11)))]
    ref = [_state_row(world.reset(home, noise=noise, rng=np.random.default_rng(11)))]
    for target, arm in zip(targets, armed, strict=True):
        a, b = scene.step(target, arm), world.step(target, arm)
        rows.append(_state_row(a))
        ref.append(_state_row(b))
        assert (a.released, a.caught, a.dropped) == (b.released, b.caught, b.dropped)
        assert a.time == pytest.approx(b.time, abs=1e-12)
    rows, ref = np.array(rows), np.array(ref)
    np.testing.assert_allclose(rows, ref, atol=1e-9, rtol=0)
    assert np.count_nonzero(np.diff(rows[:, -1]) > 0) >= 3  # several catches happened
    assert np.count_nonzero(np.diff(rows[:, -1]) < 0) >= 4  # and tosses


def test_bad_input_and_pickling():
    scene = JugglingScene()
    with pytest.raises(RuntimeError, match="reset"):
        scene.step([0.0, 1.0], False)
    with pytest.raises(ValueError, match="hand_pos"):
        scene.reset([0.0, 1.0, 2.0])
    with pytest.raises(ValueError, match="gravity"):
        JugglingScene(replace(TASK, gravity=float("nan")))
    scene.reset([0.0, 1.0], rng=np.random.default_rng(0))
    with pytest.raises(ValueError, match="finite"):
        scene.step([np.nan, 1.0], False)
    for target in _toss_path(scene):
        scene.step(target, True)
    clone = pickle.loads(pickle.dumps(scene))
    for k in range(50):
        a = scene.step([0.01 * k, 1.0], False)
        b = clone.step([0.01 * k, 1.0], False)
        np.testing.assert_array_equal(_state_row(a), _state_row(b))


def test_a_position_actuated_hand_would_lag_its_target(tmp_path, monkeypatch):
    """The measurement behind the mocap choice (module docstring of juggling_scene)."""
    monkeypatch.chdir(tmp_path)  # the unstable servo's warning goes to MUJOCO_LOG.TXT here

    def run(kp: float, substeps: int) -> tuple[float, bool]:
        m, kv = 0.4, 2 * np.sqrt(kp * 0.4)
        xml = f"""<mujoco><option timestep="{0.005 / substeps}" gravity="0 0 0"/>
        <worldbody><body><joint name="x" type="slide" axis="1 0 0"/>
        <joint name="z" type="slide" axis="0 0 1"/><geom type="sphere" size="0.05" mass="{m}"/>
        </body></worldbody><actuator><position joint="x" kp="{kp}" kv="{kv}"/>
        <position joint="z" kp="{kp}" kv="{kv}"/></actuator></mujoco>"""
        model = mujoco.MjModel.from_xml_string(xml)
        data = mujoco.MjData(model)
        s = np.clip(np.arange(1, 81) * 0.005 / 0.4, 0, 1)
        z = 0.3 * (10 * s**3 - 15 * s**4 + 6 * s**5)  # minimum-jerk toss, peak 1.4 m/s
        err = 0.0
        for zk in z:
            data.ctrl[:] = (0.0, zk)
            mujoco.mj_step(model, data, nstep=substeps)
            err = max(err, abs(float(data.qpos[1]) - zk))
        return err, any(w.number for w in data.warning)

    err, warned = run(1e4, 1)
    assert 0.005 < err < 0.02 and not warned  # ~1 cm behind the plan
    assert run(1e5, 1)[1]  # stiffer servo: unstable at the 5 ms control period
