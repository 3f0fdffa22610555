"""MotionEnvs/Juggling-v0: what is special to it (reset state, bad actions, rendering over
an episode, the reward's terms, the zero-action invariant against motion-bench); the
contract every id keeps (checkers, determinism, pickling, spaces) is in
``test_env_contract.py``."""

from __future__ import annotations

import copy

import gymnasium as gym
import numpy as np
import pytest
from _helpers import run_juggler_alone

from motion_envs.datasets.juggling import JugglingNoise, JugglingTask
from motion_envs.envs.juggling import OBS_DIM, JugglingEnv, JugglingScene, cycle_rngs

ENV_ID = "MotionEnvs/Juggling-v0"


@pytest.fixture(scope="module")
def actions() -> np.ndarray:
    return np.random.default_rng(9).uniform(-1, 1, size=(1000, 2)).astype(np.float32)


def test_registered_class_and_spaces():
    env = gym.make(ENV_ID)
    assert isinstance(env.unwrapped, JugglingEnv)
    assert env.action_space == gym.spaces.Box(-1, 1, (2,), np.float32)
    space = env.observation_space
    assert space.shape == (OBS_DIM,) and space.dtype == np.float32
    # bounds from the documented table only: no data, no seed
    other = JugglingEnv(noise={"release": 0.1, "tracking": 0.01}, max_cycles=10)
    assert other.observation_space == env.unwrapped.observation_space
    assert np.all(space.low[8:14] == 0) and np.all(space.high[8:13] == 1)
    assert np.all(np.isfinite(space.low)) and np.all(np.isfinite(space.high))
    assert env.unwrapped.metadata["render_fps"] == 200
    assert JugglingEnv(frame_skip=4).metadata["render_fps"] == 50


def test_reward_is_the_weighted_sum_of_its_terms(actions):
    weights = {"catch": 3.0, "drop": 7.0, "deviation": 2.0, "action": 0.5}
    env = JugglingEnv(noise=0.05, reward_weights=weights, max_cycles=2)
    env.reset(seed=4)
    seen = set()
    for a in np.concatenate([actions * 0.05, np.zeros((3000, 2), np.float32), actions]):
        _, reward, terminated, truncated, info = env.step(a)
        terms = [info[f"reward_{k}"] for k in ("catch", "drop", "deviation", "action")]
        assert reward == pytest.approx(sum(terms), abs=1e-12)
        ac = np.clip(a.astype(np.float64), -1, 1)
        assert info["reward_action"] == pytest.approx(-0.5 * float(ac @ ac), abs=1e-12)
        assert info["deviation"] == pytest.approx(0.05 * np.linalg.norm(ac), abs=1e-12)
        assert info["reward_deviation"] == pytest.approx(-2.0 * info["deviation"], abs=1e-12)
        assert info["reward_catch"] in (0.0, 3.0) and info["reward_drop"] in (0.0, -7.0)
        seen.update(k for k in ("catch", "drop") if info[f"reward_{k}"])
        assert (info["reward_drop"] != 0) == terminated
        if terminated or truncated:
            env.reset()
    assert seen == {"catch", "drop"}


def _mj_state(env: JugglingEnv):
    return (
        env.data.qpos.copy(),
        env.data.qvel.copy(),
        env.data.mocap_pos.copy(),
        env.data.time,
        env.scene.held,
        env.juggler.phase,
        env.juggler.phase_time,
    )


def _steps(env, actions) -> np.ndarray:
    out = []
    for a in actions:
        obs, _, terminated, truncated, _ = env.step(a)
        out.append(obs)
        if terminated or truncated:
            break
    return np.array(out)


def test_reset_with_a_seed_restores_the_whole_state(actions):
    env = JugglingEnv(noise={"release": 0.05, "tracking": 0.001})
    obs0, _ = env.reset(seed=12)
    s0 = _mj_state(env)
    first = _steps(env, actions[:300] * 0.2)
    assert not np.array_equal(env.data.qpos, s0[0])
    obs1, _ = env.reset(seed=12)
    s1 = _mj_state(env)
    np.testing.assert_array_equal(obs0, obs1)
    for x, y in zip(s0, s1, strict=True):
        np.testing.assert_array_equal(x, y)
    again = _steps(env, actions[:300] * 0.2)
    np.testing.assert_array_equal(np.array(first), np.array(again))


def test_step_after_the_end_raises():
    env = JugglingEnv(max_cycles=1)
    env.reset(seed=0)
    done = False
    while not done:
        _, _, terminated, truncated, _ = env.step(np.zeros(2))
        done = terminated or truncated
    with pytest.raises(RuntimeError, match="reset"):
        env.step(np.zeros(2))


def test_non_finite_and_huge_actions_for_10000_steps():
    env = JugglingEnv(noise=0.05, frame_skip=2)
    env.reset(seed=0)
    bad = [np.nan, np.inf, -np.inf, 1e30, -1e30]
    rng = np.random.default_rng(0)
    clipped = JugglingEnv(noise=0.05, frame_skip=2)
    clipped.reset(seed=0)
    for k in range(10_000):
        a = np.array([bad[k % 5], bad[(k // 5) % 5]], np.float32)
        if k % 7 == 0:
            a[rng.integers(2)] = rng.uniform(-1, 1)
        obs, reward, terminated, truncated, info = env.step(a)
        # NaN counts as 0, +-inf and +-1e30 clip to +-1
        same = np.where(np.isnan(a), 0.0, np.clip(np.nan_to_num(a), -1, 1)).astype(np.float32)
        ref = clipped.step(same)
        np.testing.assert_array_equal(obs, ref[0])
        assert np.all(np.isfinite(obs)) and np.isfinite(reward)
        assert info["action_invalid"] == bool(not np.all(np.isfinite(a)))
        assert env.observation_space.contains(obs)
        if terminated or truncated:
            env.reset()
            clipped.reset()
    assert not any(w.number for w in env.data.warning)


def test_terminates_on_a_drop_and_truncates_after_max_cycles():
    env = JugglingEnv(max_cycles=2)
    env.reset(seed=1)
    steps, catches = 0, []
    while True:
        _, _, terminated, truncated, info = env.step(np.zeros(2, np.float32))
        steps += 1
        if info["reward_catch"]:
            catches.append(steps)
        if terminated or truncated:
            break
    assert truncated and not terminated and info["catches"] == 2 and catches[-1] == steps
    # push the hand 30 cm away once the ball is in the air: it is dropped
    env = JugglingEnv(max_cycles=2, residual_scale=0.3)
    env.reset(seed=1)
    while True:
        a = np.array([0.0 if env.scene.held else 1.0, 0.0], np.float32)
        _, _, terminated, truncated, info = env.step(a)
        if terminated or truncated:
            break
    assert terminated and not truncated and info["reward_drop"] == -10.0
    assert env.scene.state.ball_pos[1] < env.task.floor_z


@pytest.mark.parametrize("noise", [0.0, 0.05, {"release": 0.1, "tracking": 0.003}])
@pytest.mark.parametrize("frame_skip", [1, 3])
@pytest.mark.parametrize("cycle", [0, 5])
def test_zero_action_reproduces_the_analytic_juggler(noise, frame_skip, cycle):
    from motion_envs.models.juggling import BallisticWorld

    env = JugglingEnv(noise=noise, frame_skip=frame_skip, max_cycles=3)
    env.reset(seed=21, options={"cycle": cycle})
    hands, events = [], []
    done = False
    orig = env.scene.step

    def spy(target, armed):
        s = orig(target, armed)
        hands.append(s.hand_pos.copy())
        events.append((s.released, s.caught, s.dropped))
        return s

    env.scene.step = spy
    while not done:
        obs, _, terminated, truncated, info = env.step(np.zeros(2, np.float32))
        np.testing.assert_array_equal(obs[0:2], hands[-1].astype(np.float32))
        done = terminated or truncated
    hands = np.array(hands)
    assert sum(e[1] for e in events) == info["catches"] >= 1
    # the whole episode: the juggler alone in the scene, juggling on
    ref_hands, ref_events = run_juggler_alone(
        env.task, env.noise, 21, cycle, len(hands), JugglingScene(env.task), True
    )
    np.testing.assert_allclose(hands, ref_hands, atol=1e-9, rtol=0)
    assert events == ref_events
    # the first cycle, to the catch: motion-bench's cycle in the pure-model world
    first = next(k for k, e in enumerate(events) if e[1] or e[2]) + 1
    ref_hands, ref_events = run_juggler_alone(
        env.task, env.noise, 21, cycle, len(hands), BallisticWorld(env.task), False
    )
    np.testing.assert_allclose(hands[:first], ref_hands, atol=1e-9, rtol=0)
    assert events[:first] == ref_events


def test_rgb_array_frames(mujoco_gl):
    env = gym.make(ENV_ID, render_mode="rgb_array", width=160, height=120)
    env.reset(seed=0)
    frames = [env.render()]
    for _ in range(6):
        for _ in range(50):
            env.step(np.zeros(2, np.float32))
        frames.append(env.render())
    for f in frames:
        assert f.dtype == np.uint8 and f.shape == (120, 160, 3)
    assert not np.array_equal(frames[0], frames[-1])  # the hand and the ball moved
    env.close()
    env.close()


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"noise": -0.1}, "noise"),
        ({"noise": {"drift": 0.1}}, "noise"),
        ({"noise": "high"}, "noise"),
        ({"max_cycles": 0}, "max_cycles"),
        ({"max_cycles": 2.5}, "max_cycles"),
        ({"residual_scale": 0.0}, "residual_scale"),
        ({"reward_weights": {"style": 1.0}}, "reward_weights"),
        ({"reward_weights": {"catch": -1.0}}, "reward_weights"),
        ({"frame_skip": 0}, "frame_skip"),
        ({"data": 3}, "data"),
        ({"gravity": 0.0}, "gravity"),
        ({"render_mode": "human"}, "render_mode"),
        ({"width": 4}, "width"),
    ],
)
def test_bad_arguments_raise_value_error(kwargs, match):
    with pytest.raises(ValueError, match=match):
        JugglingEnv(**kwargs)


def test_noise_argument_forms():
    assert JugglingEnv(noise=0.05).noise == JugglingNoise(release=0.05, tracking=0.0005)
    assert JugglingEnv(noise=0.0).noise == JugglingNoise()
    assert JugglingEnv(noise={"tracking": 0.01}).noise == JugglingNoise(tracking=0.01)
    env = JugglingEnv(gravity=9.81, max_cycles=2)
    assert env.task == JugglingTask(gravity=9.81)
    env.reset(seed=0)
    assert env.model.opt.gravity[2] == -9.81
    done = False
    while not done:
        _, _, terminated, truncated, info = env.step(np.zeros(2, np.float32))
        done = terminated or truncated
    assert truncated and info["catches"] == 2  # the juggler fitted under real gravity juggles


def test_zero_action_cycles_are_motion_bench_juggling_cycles():
    """Cycle i of ``motion-bench juggling --seed 3 --noise 0.05`` (its runner, with its
    tracking noise) = Juggling-v0 after ``reset(seed=3, options={"cycle": i})``, zero action:
    same catch or drop at the same control step, same hand path as recorded."""
    from motion_envs.models.juggling import run_cycle, run_cycles_fast

    noise = {"release": 0.05, "tracking": 0.0005}
    env = JugglingEnv(noise=noise, max_cycles=1)
    juggler = env.juggler
    n = 12
    fast = run_cycles_fast(copy.deepcopy(juggler), n, env.noise, seed=3)
    outcomes = []
    for i in range(n):
        env.reset(seed=3, options={"cycle": i})
        steps = 0
        hands = []
        while True:
            _, _, terminated, truncated, info = env.step(np.zeros(2, np.float32))
            steps += 1
            hands.append(env.scene.hand_true)
            if terminated or truncated:
                break
        assert (info["catches"] == 1, terminated, steps) == (
            fast[i].caught,
            fast[i].dropped,
            fast[i].steps,
        )
        ref = run_cycle(
            copy.deepcopy(juggler),
            JugglingScene(env.task),
            env.noise,
            cycle_rngs(3, n)[i],
            record=True,
        )
        np.testing.assert_allclose(np.array(hands), ref.hand[1:], atol=1e-9, rtol=0)
        outcomes.append(fast[i].caught)
    assert sum(outcomes) >= n // 2  # mostly caught: the comparison covers catches


def test_users_csv_as_data(tmp_path):
    """``data=PATH`` fits the juggler on the users' recordings; bad paths fail clearly."""
    from motion_envs.datasets.juggling import generate_demonstrations, write_juggling_csv

    path = write_juggling_csv(generate_demonstrations(n_cycles=16, seed=8), tmp_path / "me.csv")
    env = gym.make(ENV_ID, data=str(path), max_cycles=1)
    default = gym.make(ENV_ID, max_cycles=1)
    assert env.observation_space == default.observation_space  # bounds ignore the data
    env.reset(seed=0)
    done = False
    while not done:
        obs, _, terminated, truncated, info = env.step(np.zeros(2, np.float32))
        assert env.observation_space.contains(obs)
        done = terminated or truncated
    assert info["catches"] == 1
    home = env.unwrapped.juggler.home_
    assert not np.allclose(home, default.unwrapped.juggler.home_)  # fitted on the CSV
    with pytest.raises(FileNotFoundError, match=r"nowhere\.csv"):
        JugglingEnv(data=str(tmp_path / "nowhere.csv"))


def test_catch_rates_equal_motion_bench_juggling():
    """``motion-bench juggling --cycles 40 --noise 0.1 --seed 0`` (its run(config)) and 40
    zero-action episodes ``reset(seed=0, options={"cycle": i})``: the same catch rates,
    with and without the eq. 10 correction (which the noise makes matter)."""
    from baselines.juggling_bench import JugglingConfig, run

    n = 40
    doc = run(JugglingConfig(cycles=n, noise=(0.1,), use_dmp=False, progress=False))
    env = JugglingEnv(noise=0.1, max_cycles=1)
    assert doc["catch_rate"] == 1.0
    for row in doc["catch_rates"]:
        env.juggler = env.juggler.variant(correction=row["correction"])
        caught = 0
        for i in range(n):
            env.reset(seed=0, options={"cycle": i})
            done = False
            while not done:
                _, _, terminated, truncated, info = env.step(np.zeros(2, np.float32))
                done = terminated or truncated
            caught += info["catches"]
        assert caught / n == row["catch_rate"], row
    rates = {r["correction"]: r["catch_rate"] for r in doc["catch_rates"]}
    assert rates[False] < rates[True]  # the comparison covers drops too


def test_sb3_ppo_smoke():
    """A tiny PPO run on Juggling-v0 (it trains; no claim about what it learns)."""
    sb3 = pytest.importorskip("stable_baselines3")
    env = JugglingEnv(max_cycles=1)
    model = sb3.PPO("MlpPolicy", env, n_steps=64, batch_size=32, n_epochs=1, seed=0, device="cpu")
    model.learn(total_timesteps=128)
    action, _ = model.predict(env.reset(seed=0)[0], deterministic=True)
    assert env.action_space.contains(action)


def test_record_video_of_one_cycle(tmp_path, mujoco_gl):
    pytest.importorskip("moviepy", reason="RecordVideo needs moviepy (the test extra)")
    from gymnasium.wrappers import RecordVideo

    env = gym.make(ENV_ID, render_mode="rgb_array", width=96, height=96, frame_skip=8, max_cycles=1)
    assert env.metadata["render_fps"] == 25
    folder = tmp_path / "videos"
    env = RecordVideo(env, str(folder), episode_trigger=lambda e: e == 0, disable_logger=True)
    env.reset(seed=0)
    done = False
    while not done:
        _, _, terminated, truncated, _ = env.step(np.zeros(2, np.float32))
        done = terminated or truncated
    env.close()
    videos = list(folder.glob("*.mp4"))
    assert len(videos) == 1 and videos[0].stat().st_size > 1000
