"""MotionEnvs/Juggling-v1: checkers, determinism, pickling, the zero-action invariant, the
physics (actuated hand within its limits, capture rule, drops, no tunnelling), the sensor,
the level table, ``residual_phases``, first frames and the juggler's toss."""

from __future__ import annotations

import inspect
import math
import pickle
import re
import warnings

import gymnasium as gym
import numpy as np
import pytest

import motion_envs
from motion_envs.datasets.juggling import PHASES, JugglingTask, rules
from motion_envs.envs.juggling import (
    CAPTURE_SPEED,
    HAND_ACCEL_LIMIT,
    HAND_SPEED_LIMIT,
    V1_OBS_DIM,
    JugglingV1Env,
    JugglingV1World,
)
from motion_envs.models.juggling import (
    LEVELS,
    BallSensor,
    HumanLikeness,
    make_controller,
    perturb_release,
    predict_forward,
    v1_fit,
    v1_juggler,
    v1_likeness,
)

ENV_ID = "MotionEnvs/Juggling-v1"
TASK = JugglingTask(gravity=9.81)


def rollout(env, seed, actions):
    obs, _ = env.reset(seed=seed)
    out, rewards, infos = [obs], [], []
    for a in actions:
        obs, reward, terminated, truncated, info = env.step(a)
        out.append(obs)
        rewards.append(reward)
        infos.append(info)
        if terminated or truncated:
            break
    return np.array(out), np.array(rewards), infos


def test_registered_spaces_and_speed_limit():
    env = gym.make(ENV_ID, level="easy")
    assert env.observation_space.shape == (V1_OBS_DIM,) == (31,)
    assert env.action_space.shape == (2,)
    assert env.unwrapped.hand_speed_limit == HAND_SPEED_LIMIT == 6.0
    assert env.unwrapped.model.opt.gravity[2] == -9.81
    assert env.unwrapped.model.opt.disableflags & 1 == 0  # contacts on
    assert "MotionEnvs/Juggling-v1" in motion_envs.envs.ENV_IDS


def test_gymnasium_and_sb3_check_env_with_warnings_as_errors():
    from gymnasium.utils.env_checker import check_env

    sb3_checker = pytest.importorskip("stable_baselines3.common.env_checker")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        # gym.make of Juggling-v1 notes that -v2 exists; this test makes v1 on purpose
        warnings.filterwarnings("ignore", message=".*is out of date.*", category=DeprecationWarning)
        for level in LEVELS:
            check_env(gym.make(ENV_ID, level=level).unwrapped, skip_render_check=True)
        sb3_checker.check_env(JugglingV1Env(level="hard"), warn=True)
        sb3_checker.check_env(JugglingV1Env(controller="fixed_point", gravity=1.0), warn=True)
        phases = {"residual_phases": ["catch"], "residual_scale": 0.2}
        check_env(gym.make(ENV_ID, **phases).unwrapped, skip_render_check=True)
        sb3_checker.check_env(JugglingV1Env(**phases), warn=True)


def test_seeded_rollouts_are_deterministic_and_pickle():
    actions = np.random.default_rng(3).uniform(-1, 1, (600, 2)).astype(np.float32)
    a = JugglingV1Env(level="medium")
    b = JugglingV1Env(level="medium")
    oa, ra, _ = rollout(a, 7, actions)
    ob, rb, _ = rollout(b, 7, actions)
    np.testing.assert_array_equal(oa, ob)
    np.testing.assert_array_equal(ra, rb)
    oc, _, _ = rollout(a, 8, actions)
    assert not np.array_equal(oa[: len(oc)], oc[: len(oa)])
    # a pickled copy mid-episode continues exactly as the original
    _, _, infos = rollout(a, 11, actions[:400])
    middle = len(infos) // 2
    assert middle >= 40
    a.reset(seed=11)
    for x in actions[:middle]:
        a.step(x)
    clone = pickle.loads(pickle.dumps(a))
    for x in actions[middle:400]:
        s1 = a.step(x)
        s2 = clone.step(x)
        np.testing.assert_array_equal(s1[0], s2[0])
        assert s1[1:4] == s2[1:4]
        if s1[2] or s1[3]:
            break


@pytest.mark.parametrize("controller", ["juggler", "juggler_latency_aware", "fixed_point"])
def test_zero_action_is_the_controller_exactly(controller):
    """An independent loop of the public parts (world, sensor, controller) with the env's
    seeding gives the same hand path, events and catches as the zero-action episode."""
    env = JugglingV1Env(level="medium", controller=controller, max_catches=3)
    _, _, infos = rollout(env, 5, np.zeros((5000, 2), np.float32))
    lv = LEVELS["medium"]
    juggler = v1_juggler(9.81)
    ctrl = make_controller(controller, juggler, 0.1)
    world = JugglingV1World(TASK, lv.release_speed_std, math.radians(lv.release_angle_std))
    sensor = BallSensor(20, lv.position_std, lv.velocity_std)
    w_ss, s_ss, c_ss = np.random.SeedSequence(5).spawn(3)
    true = world.reset(juggler.home_, rng=np.random.default_rng(w_ss))
    m = sensor.reset(true.ball_pos, true.ball_vel, np.random.default_rng(s_ss))

    def seen(t, m):
        return type(t)(
            t.time, t.hand_pos, t.hand_vel, m.position, m.velocity, t.held, t.released,
            t.caught, t.dropped,
        )  # fmt: skip

    state = seen(true, m)
    ctrl.reset(state, np.random.default_rng(c_ss))
    for info in infos:
        target, armed = ctrl.command(state)
        true = world.step(target, armed)
        m = sensor.measure(true.ball_pos, true.ball_vel, true.held)
        state = seen(true, m)
        np.testing.assert_array_equal(info["hand"], true.hand_pos)
        np.testing.assert_array_equal(info["ball"], true.ball_pos)
        assert info["caught"] == true.caught
    assert infos[-1]["catches"] + int(infos[-1]["reward_drop"] < 0) >= 1


def test_reward_terms_and_info():
    env = JugglingV1Env(level="easy", max_catches=2)
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    saw_catch = False
    while True:
        a = rng.uniform(-0.2, 0.2, 2)
        _, r, term, trunc, info = env.step(a)
        parts = ("reward_catch", "reward_drop", "reward_likeness", "reward_action")
        assert r == pytest.approx(sum(info[k] for k in parts), abs=1e-12)
        assert info["reward_action"] == pytest.approx(-0.01 * float(a @ a))
        assert info["reward_likeness"] == pytest.approx(-0.01 * info["likeness"])
        assert info["hand"].shape == info["ball"].shape == (2,)
        saw_catch |= info["reward_catch"] == 10.0
        if term or trunc:
            break
    assert saw_catch
    assert (trunc and info["catches"] == 2) or (term and info["reward_drop"] == -10.0)


def test_human_likeness_against_a_brute_force_oracle():
    fit = v1_fit(9.81)
    demos, train = fit.demos, fit.train
    like = HumanLikeness(demos, train)
    rng = np.random.default_rng(0)
    pts = {}
    for s in demos.segments():
        if (s.recording, s.cycle) in train:
            v = np.diff(s.positions, axis=0) / np.diff(s.times)[:, None]
            rows = np.hstack([s.positions[1:], 0.1 * v])
            pts[s.phase] = np.vstack([pts[s.phase], rows]) if s.phase in pts else rows
    for phase, rows in pts.items():
        for _ in range(5):
            p, v = rng.normal([0.0, 1.0], 0.3), rng.normal(0, 2, 2)
            q = np.concatenate([p, 0.1 * v])
            expected = np.sqrt(((rows - q) ** 2).sum(axis=1)).min()
            assert like.distance(phase, p, v) == pytest.approx(expected, rel=1e-12)
    assert v1_likeness(9.81, "test") is not v1_likeness(9.81, "train")
    with pytest.raises(ValueError, match="split"):
        v1_likeness(9.81, "val")


def test_human_likeness_is_the_tree_query_bit_for_bit():
    # the sorted-sample search returns the k-d tree's number exactly, near the samples
    # (small slabs) and far from them (a slab of most samples), in any query order
    like = v1_likeness(9.81, "train")
    rng = np.random.default_rng(1)
    for phase, tree in like.trees.items():
        for i in range(300):
            base = tree.data[rng.integers(tree.n)]
            p = base[:2] + rng.normal(0, (1e-3, 1e-2, 0.1, 1.0)[i % 4], 2)
            v = base[2:] / 0.1 + rng.normal(0, (1e-2, 0.1, 1.0, 10.0)[i % 4], 2)
            q = (float(p[0]), float(p[1]), 0.1 * float(v[0]), 0.1 * float(v[1]))
            assert like.distance(phase, p, v) == float(tree.query(q)[0])


def test_hand_respects_its_speed_and_acceleration_limits():
    world = JugglingV1World(TASK)
    world.reset((0.2, 1.0))
    speeds, accs = [], []
    prev = world.data.qvel[0:2].copy()
    targets = [(1.2, 1.0)] * 100 + [(-0.8, 1.6)] * 100 + [(0.2, 0.7)] * 100
    for t in targets:  # targets 1 m away: approached, not teleported to
        st = world.step(t, False)
        speeds.append(np.linalg.norm(st.hand_vel))
        accs.append(np.linalg.norm(st.hand_vel - prev) / TASK.dt)
        prev = st.hand_vel
    assert max(speeds) <= HAND_SPEED_LIMIT * (1 + 1e-9)
    assert max(speeds) > 0.9 * HAND_SPEED_LIMIT
    assert max(accs) <= HAND_ACCEL_LIMIT * (1 + 1e-6)
    first = world.step((5.0, 1.0), False)
    assert abs(first.hand_pos[0] - 0.2) < 1.5  # never a jump to the target


def _flying_ball(world, hand, ball, ball_vel, hand_vel=(0.0, 0.0)):
    """A world whose ball flies at ``ball`` with ``ball_vel``, the hand at ``hand``."""
    world.reset(hand, hand_vel=hand_vel)
    world.launch(ball, ball_vel)


def test_capture_rule_and_no_tunnelling_at_the_fastest_closing_speed():
    # a slow falling ball landing on a resting palm is captured
    world = JugglingV1World(TASK)
    _flying_ball(world, (0.2, 1.0), (0.2, 1.1), (0.0, -1.0))
    caught = [world.step((0.2, 1.0), False).caught for _ in range(40)]
    assert any(caught) and world.held
    # a rising ball touching the palm from below is not captured and does not pass through
    _flying_ball(world, (0.2, 1.0), (0.2, 0.9), (0.0, 0.8))
    for _ in range(20):
        st = world.step((0.2, 1.0), False)
        assert not st.caught
        assert st.ball_pos[1] < st.hand_pos[1] - 0.035  # stays below the palm
    # the fastest closing speed: the ball falling from 2 m (6.3 m/s) onto a hand rising at
    # its speed limit: it bounces off (relative speed > CAPTURE_SPEED), never through
    v_fall = math.sqrt(2 * 9.81 * 2.0)
    assert v_fall + HAND_SPEED_LIMIT > CAPTURE_SPEED
    _flying_ball(world, (0.2, 0.8), (0.2, 1.3), (0.0, -v_fall), (0.0, HAND_SPEED_LIMIT))
    z = 0.8
    above = []
    for _ in range(60):
        z += HAND_SPEED_LIMIT * TASK.dt
        st = world.step((0.2, z), False)
        above.append(st.ball_pos[1] - st.hand_pos[1])
        assert not st.caught
    assert min(above) > -0.035 - 0.008  # the ball centre never got below the palm's middle
    assert above[-1] > -1e-3  # it ends on (or above) the palm, never under it


def test_floor_is_a_contact_and_a_drop():
    world = JugglingV1World(TASK)
    _flying_ball(world, (0.9, 1.0), (0.2, 0.8), (0.0, -3.0))
    dropped = False
    for _ in range(100):
        st = world.step((0.9, 1.0), False)
        dropped |= st.dropped
        assert st.ball_pos[1] > TASK.floor_z  # the floor holds the ball up
    assert dropped


def test_sensor_delay_noise_and_release_noise():
    sensor = BallSensor(3, 0.0, 0.0)
    sensor.reset(np.zeros(2), np.zeros(2), None)
    truth = [(np.array([k, 2.0 * k]), np.array([1.0, -k])) for k in range(10)]
    out = [sensor.measure(p, v, held=False) for p, v in truth]
    for k in range(3, 10):
        np.testing.assert_array_equal(out[k].position, truth[k - 3][0])
        np.testing.assert_array_equal(out[k].velocity, truth[k - 3][1])
    noisy = BallSensor(0, 0.01, 0.1)
    noisy.reset(np.zeros(2), np.zeros(2), np.random.default_rng(0))
    e = np.array([noisy.measure(np.zeros(2), np.zeros(2), False).position for _ in range(4000)])
    assert e.std(axis=0) == pytest.approx([0.01, 0.01], rel=0.05)
    held = noisy.measure(np.ones(2), np.ones(2), True)
    np.testing.assert_array_equal(held.position, np.ones(2))
    # release noise: speed and angle (an oracle by polar coordinates), also for a vertical toss
    rng = np.random.default_rng(1)
    v0 = np.array([0.0, 2.0])
    vs = np.array([perturb_release(v0, 0.1, math.radians(5), rng) for _ in range(4000)])
    speed = np.hypot(vs[:, 0], vs[:, 1])
    angle = np.degrees(np.arctan2(vs[:, 1], vs[:, 0])) - 90.0
    assert speed.std() / 2.0 == pytest.approx(0.1, rel=0.05)
    assert angle.std() == pytest.approx(5.0, rel=0.05)
    assert np.abs(vs[:, 0]).mean() > 0.1  # a vertical toss gets a sideways error
    p, v = predict_forward(np.array([0.0, 1.0]), np.array([1.0, 2.0]), 0.5, 9.81)
    np.testing.assert_allclose(p, [0.5, 1.0 + 1.0 - 0.5 * 9.81 * 0.25])
    np.testing.assert_allclose(v, [1.0, 2.0 - 9.81 * 0.5])


def test_level_table_and_overrides():
    doc = inspect.getdoc(JugglingV1Env)
    rows = {}
    for line in doc.splitlines():
        m = re.match(r"\|\s*`(easy|medium|hard)`\s*\|(.*)\|\s*$", line)
        if m:
            rows[m.group(1)] = [float(x) for x in m.group(2).split("|")]
    assert set(rows) == set(LEVELS)
    for name, level in LEVELS.items():
        assert rows[name] == [
            level.latency,
            level.position_std,
            level.velocity_std,
            level.release_speed_std,
            level.release_angle_std,
        ]
        env = JugglingV1Env(level=name)
        assert env.latency == level.latency and env.delay_steps == round(level.latency / 0.005)
    env = JugglingV1Env(level="hard", latency=0.0, release_angle_std=0.0)
    assert env.latency == 0.0 and env.release_angle_std == 0.0
    assert env.release_speed_std == LEVELS["hard"].release_speed_std
    # the documented defaults equal the signature's: tests/test_env_contract.py, every id


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"level": "expert"}, "level"),
        ({"latency": -0.1}, "latency"),
        ({"release_speed_std": float("nan")}, "release_speed_std"),
        ({"gravity": 0.0}, "gravity"),
        ({"controller": "oracle"}, "controller"),
        ({"max_catches": 0}, "max_catches"),
        ({"residual_scale": 0.0}, "residual_scale"),
        ({"reward_weights": {"deviation": 1.0}}, "reward_weights"),
        ({"render_mode": "human"}, "render_mode"),
        ({"residual_phases": "catch"}, "residual_phases"),
        ({"residual_phases": ["catch", "catch"]}, "residual_phases"),
        ({"residual_phases": []}, "residual_phases"),
        ({"residual_phases": ["throw"]}, "residual_phases"),
        ({"residual_phases": [1]}, "residual_phases"),
        ({"residual_phases": 3}, "residual_phases"),
        ({"residual_phases": {"catch": 1}}, "residual_phases"),
    ],
)
def test_bad_arguments_raise_value_error(kwargs, match):
    with pytest.raises(ValueError, match=match):
        JugglingV1Env(**kwargs)


def _phase_gated_episode(phases, gate, seed=0):
    """Every step's return of a medium episode (3 catches under the zero action) whose
    action is 0.8 in both entries while ``gate(obs)`` holds (else 0),
    ``residual_phases=phases``."""
    env = gym.make(
        ENV_ID, level="medium", residual_phases=phases, residual_scale=0.3, max_catches=3
    )
    obs, _ = env.reset(seed=seed)
    steps, done = [], False
    while not done:
        a = np.full(2, 0.8 if gate(obs) else 0.0, np.float32)
        obs, reward, term, trunc, info = env.step(a)
        steps.append((obs, reward, term, trunc, info))
        done = term or trunc
    return steps


def _in(*phases):
    """Whether the observation's phase one-hot (``5..8``: toss, go_down, catch, return)
    shows one of ``phases``."""
    return lambda obs: any(obs[5 + PHASES.index(p)] == 1.0 for p in phases)


def _hands(steps):
    return np.array([info["hand"] for *_, info in steps])


def test_residual_phases_mask_the_residual_outside_them():
    """With ``residual_phases=["catch"]`` an action given only while the observation shows
    toss or return (the next command cannot start the catch) plays the zero action's
    episode: the same observations, ends and infos; the reward differs by the action's
    penalty alone (charged as in Cascade-v0). The same action with all phases changes the
    episode, and so does an action given in the catch."""
    zero = _phase_gated_episode(None, lambda obs: False)
    outside = _in("toss", "return")
    masked = _phase_gated_episode(["catch"], outside)
    assert len(masked) == len(zero)
    penalised = 0
    for (o1, r1, *ends1, i1), (o2, r2, *ends2, i2) in zip(zero, masked, strict=True):
        assert np.array_equal(o1, o2) and ends1 == ends2
        assert set(i1) == set(i2)
        for key in i1.keys() - {"reward_action"}:
            assert np.array_equal(i1[key], i2[key]), key
        assert r2 == r1 + i2["reward_action"]  # r1's own action term is -0.0
        penalised += i2["reward_action"] < 0
    assert penalised > 100
    free = _phase_gated_episode(None, outside)
    n = min(len(free), len(zero))
    assert not np.array_equal(_hands(free)[:n], _hands(zero)[:n])
    caught = _phase_gated_episode(["catch"], _in("catch"))
    n = min(len(caught), len(zero))
    assert not np.array_equal(_hands(caught)[:n], _hands(zero)[:n])


def test_residual_phases_arguments():
    env = JugglingV1Env(residual_phases=("catch", "go_down"))
    assert env.residual_phases == ("catch", "go_down")
    assert env.residual_acts.tolist() == [False, True, True, False]
    default = gym.make(ENV_ID).unwrapped
    assert default.residual_phases is None and default.residual_acts.all()


def test_bad_actions():
    env = JugglingV1Env(level="easy")
    with pytest.raises(RuntimeError):
        env.step(np.zeros(2))
    env.reset(seed=0)
    with pytest.raises(ValueError, match="shape"):
        env.step(np.zeros(3))
    _, _, _, _, info = env.step(np.array([np.nan, np.inf]))
    assert info["action_invalid"]


def test_first_frame_shows_the_scene():
    env = gym.make(ENV_ID, render_mode="rgb_array", width=120, height=96)
    env.reset(seed=0)
    try:
        frame = env.render()
    except Exception as exc:  # no OpenGL context on this machine
        pytest.skip(f"no MuJoCo OpenGL backend here (MUJOCO_GL=osmesa or egl): {exc}")
    assert frame.shape == (96, 120, 3)
    red = (frame[..., 0] > 150) & (frame[..., 1] < 80) & (frame[..., 2] < 80)
    assert red.sum() > 3  # the ball is drawn where it is, before any step
    for _ in range(60):
        env.step(np.zeros(2, np.float32))
    assert not np.array_equal(frame, env.render())
    env.close()


def test_release_arming_scales_with_gravity_and_paper_gravity_runs():
    assert v1_juggler(9.81).release_after == pytest.approx(0.25 / math.sqrt(9.81))
    env = JugglingV1Env(level="easy", gravity=1.0, max_catches=1)
    _, _, infos = rollout(env, 0, np.zeros((20000, 2), np.float32))
    assert v1_juggler(1.0).release_after == 0.25
    assert infos[-1]["catches"] == 1


def test_closed_loop_toss_like_the_training_demonstrations():
    """Release velocity and catch height of the zero-action juggler (no noise, 50 seeds,
    250 tosses) against the TRAINING demonstrations' medians at 9.81 m/s^2, each within 10 %.
    Measured: release speed +2.7 %, vertical release speed +5.9 %, catch height +8.0 % (the
    world detects the release as the demonstrations do: second backward difference of the
    hand's height at the control samples; with the velocity difference over the period it
    fired half a sample earlier and the catch height was +10.3 %)."""
    fit = v1_fit(9.81)
    demos, train = fit.demos, fit.train
    rel, catch = [], []
    for i, r in enumerate(demos.recordings):
        lab = r.phase
        change = np.flatnonzero(lab[1:] != lab[:-1]) + 1
        v = np.diff(r.ball, axis=0) / TASK.dt
        cycle = -1
        for k in change:
            cycle += lab[k] == "go_down"
            if (i, cycle) in train and lab[k] == "go_down":
                rel.append(v[k])
            if (i, cycle) in train and lab[k] == "return":
                catch.append(r.ball[k][1])
    env = JugglingV1Env(level="easy", release_speed_std=0.0, release_angle_std=0.0, max_catches=5)
    jr, jc = [], []
    for seed in range(50):
        env.reset(seed=seed)
        while True:
            _, _, term, trunc, _ = env.step(np.zeros(2))
            st = env.world.state
            if st.released:
                jr.append(st.ball_vel)
            if st.caught:
                jc.append(st.hand_pos[1])
            if term or trunc:
                break
    d_vel, j_vel = np.median(rel, axis=0), np.median(jr, axis=0)
    assert np.linalg.norm(j_vel - d_vel) / np.linalg.norm(d_vel) <= 0.10  # velocity (7.4 %)
    assert abs(np.linalg.norm(j_vel) / np.linalg.norm(d_vel) - 1) <= 0.10  # speed
    assert abs(j_vel[1] / d_vel[1] - 1) <= 0.10  # vertical speed
    assert abs(np.median(jc) / np.median(catch) - 1) <= 0.10  # catch height


@pytest.mark.slow
def test_motion_bench_train_and_agent_smoke(tmp_path):
    """``motion-bench train --env MotionEnvs/Juggling-v1`` with the shipped PPO config, then
    ``motion-bench agent``: the juggler's catch rate on the same test seeds is reported."""
    import json

    pytest.importorskip("stable_baselines3")
    from baselines.cli import main

    out = tmp_path / "run"
    argv = ["train", "--algo", "ppo", "--env", ENV_ID, "--timesteps", "2048", "--seed", "0"]
    assert main([*argv, "--out", str(out), "--no-progress"]) == 0
    assert main(["agent", str(out), "--episodes", "4"]) == 0
    doc = json.loads((out / "eval-test" / "results.json").read_text())
    assert doc["env_id"] == ENV_ID
    assert 0 <= doc["nominal_catch_rate"] <= 1 and 0 <= doc["catch_rate"] <= 1


def test_release_fires_on_the_second_difference_of_the_hand_height():
    """The world releases on the demonstrations' rule (``rules.hand_acceleration`` of the
    hand's height at the control samples, at rest before time 0), not on a velocity
    change over the period (which fires half a sample earlier)."""
    env = JugglingV1Env(level="easy", max_catches=5)
    env.reset(seed=4)
    world = env.world
    heights = [float(world.state.hand_pos[1])] * 2
    fired = 0
    while True:
        _, _, term, trunc, _ = env.step(np.zeros(2, np.float32))
        heights.append(float(world.state.hand_pos[1]))
        if world.state.released:
            fired += 1
            a_z = rules.hand_acceleration(heights[-1], heights[-2], heights[-3], TASK.dt)
            assert a_z < -TASK.toss_threshold
        if term or trunc:
            break
    assert fired >= 5


def test_synced_controller_is_the_stepped_plan():
    """``synced_controller()`` gives the controller the batch's step count between its
    plan's events: its phase and time in the phase are the step's (info, observation)."""
    env = JugglingV1Env(level="easy", max_catches=3)
    env.reset(seed=2)
    rng = np.random.default_rng(0)
    for _ in range(400):
        obs, _, term, trunc, info = env.step(0.1 * rng.uniform(-1, 1, 2))
        c = env.synced_controller()
        assert c.phase == info["phase"]
        assert np.float32(c.phase_time) == obs[9]
        if term or trunc:
            break
    assert info["time"] > 1.0  # past the first events


def test_observed_plan_is_the_controllers_after_its_grid_widens():
    """The observation's next target and plan end are the (synced) controller's at every
    step, also after a plan longer than any before has widened the batch's grid (at the
    paper's slow gravity the first flights lengthen it): the step reads its plans'
    arrays after the Python commands that replace them."""
    env = JugglingV1Env(level="easy", gravity=1.0, max_catches=5)
    env.reset(seed=0)
    batch, _ = env._batch_row()
    widths = {batch._grid.shape[1]}
    for _ in range(4000):
        obs, _, term, trunc, _ = env.step(np.zeros(2))
        c = env.synced_controller()
        np.testing.assert_array_equal(obs[11:13], c.nominal_next().astype(np.float32))
        np.testing.assert_array_equal(obs[13:15], c.plan_end.astype(np.float32))
        widths.add(batch._grid.shape[1])
        if term or trunc:
            break
    assert len(widths) >= 2  # the grid widened during the episode
