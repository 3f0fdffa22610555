"""The contract every registered environment id keeps (``motion_envs.ENV_IDS``).

In the style of Gymnasium's ``tests/envs/test_envs.py`` and dm_control's
``suite/tests/domains_test.py``: each test is parametrised over every id, so a newly
registered id is checked by construction; what an id needs beyond ``gym.make(id)`` (a
stochastic configuration, how its zero action reads as the nominal) is one row of
:data:`CASES`, and :func:`test_every_id_has_a_contract_case` fails until the row exists.
The per-environment test modules keep only what is special to one environment.
"""

from __future__ import annotations

import ast
import copy
import dataclasses
import inspect
import pickle
import random
import re
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from _helpers import run_juggler_alone
from gymnasium.envs.registration import load_env_creator

import motion_envs

ENV_IDS = motion_envs.ENV_IDS

# Warnings the checkers may raise that say nothing about an environment's correctness
# (every other warning is an error): SB3 recommends a symmetric, normalised observation
# space, ours has [0, 1] entries (tau, one-hot) by design; gym.make of an outdated
# version (-v0) notes that a newer one is registered (Gymnasium's own deprecation notice).
ALLOWED_WARNINGS = (
    r"(?s).*(symmetric|normaliz|normalis).*observation.*",
    r"(?s).*is out of date\. You should consider upgrading to version.*",
)

# Known defects, one strict xfail each (an id that starts passing fails the suite until
# its mark is removed).
RENDER_XFAIL: dict[str, str] = {}


# -- how each environment reads its nominal under the zero action -----------------------


def _replay_nominal(
    env: gym.Env, per_step_error: Callable[[Any, int], np.ndarray]
) -> tuple[np.ndarray, np.ndarray]:
    """Replay envs: zero-action episodes on the first and the last trajectory; their
    per-step ``info['error']`` and ``info['max_error']`` against the nominal's, computed
    from the task's grids (what ``motion-bench`` scores offline)."""
    grids = env.unwrapped.task.grids
    got, expected = [], []
    for l in sorted({0, env.unwrapped.task.n_trajectories - 1}):
        env.reset(options={"trajectory": l})
        terminated = truncated = False
        while not (terminated or truncated):
            _, _, terminated, truncated, info = env.step(np.zeros(env.action_space.shape))
            got.append(info["error"])
        assert terminated
        got.append(info["max_error"])
        expected.extend(per_step_error(grids, l))
        expected.append(grids.max_errors()[l])
    return np.array(got), np.array(expected)


def _orientation_nominal(env: gym.Env) -> tuple[np.ndarray, np.ndarray]:
    # the residual error |r_k - rhat_k| of the nominal orientation n_k = e_k expmap(rhat_k)
    return _replay_nominal(
        env, lambda g, l: np.linalg.norm(g.residuals[l] - g.predicted_residuals[l], axis=-1)
    )


def _position_nominal(env: gym.Env) -> tuple[np.ndarray, np.ndarray]:
    return _replay_nominal(env, lambda g, l: np.linalg.norm(g.human[l] - g.nominal[l], axis=-1))


def _zero_action_hands(env: gym.Env, seed: int) -> list[np.ndarray]:
    """``info['hand']`` of every step of a zero-action juggling episode (>= 1 catch)."""
    env.reset(seed=seed)
    hands = []
    terminated = truncated = False
    while not (terminated or truncated):
        _, _, terminated, truncated, info = env.step(np.zeros(2, np.float32))
        hands.append(info["hand"])
    assert info["catches"] >= 1
    return hands


def _juggling_nominal(env: gym.Env) -> tuple[np.ndarray, np.ndarray]:
    """A zero-action episode's hand path (``info['hand']``) against the analytic juggler
    alone in a fresh MuJoCo scene, juggling on as the environment does."""
    from motion_envs.envs.juggling import JugglingScene

    juggling = env.unwrapped
    hands = _zero_action_hands(env, 21)
    expected, _ = run_juggler_alone(
        juggling.task,
        juggling.noise,
        21,
        0,
        len(hands) * juggling.frame_skip,
        JugglingScene(juggling.task),
        continuous=True,
    )
    return np.array(hands), expected[juggling.frame_skip - 1 :: juggling.frame_skip]


def _coefficient_nominal(step_id: str) -> Callable[[gym.Env], tuple[np.ndarray, np.ndarray]]:
    """Coefficient envs: the zero action's ``-reward`` and ``info['max_error']`` on the first
    and last trajectory against the ``info['max_error']`` of a zero-action episode of the
    step environment ``step_id`` (``-v1``, the same split and nominal)."""

    def nominal(env: gym.Env) -> tuple[np.ndarray, np.ndarray]:
        task = env.unwrapped.task
        step_env = gym.make(step_id, split=task.split, nominal=task.nominal)
        got, expected = [], []
        for l in sorted({0, task.n_trajectories - 1}):
            env.reset(options={"trajectory": l})
            _, reward, terminated, _, info = env.step(np.zeros(env.action_space.shape))
            assert terminated
            got.extend([-reward, info["max_error"]])
            step_env.reset(options={"trajectory": l})
            done = False
            while not done:
                _, _, done, _, step_info = step_env.step(np.zeros(step_env.action_space.shape))
            expected.extend([step_info["max_error"]] * 2)
        return np.array(got), np.array(expected)

    return nominal


def _juggling_v1_nominal(env: gym.Env) -> tuple[np.ndarray, np.ndarray]:
    """A zero-action episode's hand path against the env's controller alone, in a fresh
    world and sensor, seeded as the env documents (``SeedSequence(seed).spawn(3)``)."""
    import math

    from motion_envs.envs.juggling import JugglingV1World
    from motion_envs.models.juggling import BallSensor, make_controller, v1_juggler

    v1 = env.unwrapped
    hands = _zero_action_hands(env, 21)
    juggler = v1_juggler(v1.gravity)
    ctrl = make_controller(v1.controller_name, juggler, v1.delay_steps * v1.task.dt)
    world = JugglingV1World(v1.task, v1.release_speed_std, math.radians(v1.release_angle_std))
    sensor = BallSensor(v1.delay_steps, v1.position_std, v1.velocity_std)
    w_ss, s_ss, c_ss = np.random.SeedSequence(21).spawn(3)
    true = world.reset(juggler.home_, rng=np.random.default_rng(w_ss))
    m = sensor.reset(true.ball_pos, true.ball_vel, np.random.default_rng(s_ss))
    state = dataclasses.replace(true, ball_pos=m.position, ball_vel=m.velocity)
    ctrl.reset(state, np.random.default_rng(c_ss))
    expected = []
    for _ in hands:
        target, armed = ctrl.command(state)
        true = world.step(target, armed)
        m = sensor.measure(true.ball_pos, true.ball_vel, true.held)
        state = dataclasses.replace(true, ball_pos=m.position, ball_vel=m.velocity)
        expected.append(true.hand_pos)
    return np.array(hands), np.array(expected)


def _juggling_v2_nominal(env: gym.Env) -> tuple[np.ndarray, np.ndarray]:
    """A zero-action episode's hand path against the analytic juggler alone, in a fresh
    world, camera and estimator, seeded as the env documents (``spawn(5)``: world,
    camera, controller, delay, drag)."""
    import math

    from motion_envs.envs.juggling import JugglingV1World, WorldSpec
    from motion_envs.models.juggling import (
        V2_LEVELS,
        CameraSensor,
        make_v2_controller,
        v1_juggler,
    )

    v2 = env.unwrapped
    lv = V2_LEVELS[v2.level]
    # the default juggler drops most balls: the first seed from 21 with a catch
    seed = next(s for s in range(21, 200) if v2.nominal_episode(s)["catches"] >= 1)
    hands = _zero_action_hands(env, seed)
    juggler = v1_juggler(9.81)
    ctrl = make_v2_controller(v2.controller_name, juggler, 9.81, lv.mean_delay)
    spec = WorldSpec.of(
        v2.task, capture_speed=lv.capture_speed, air_density=1.2, impact_capture=True,
        contact_damping=0.2,
    )  # fmt: skip
    world = JugglingV1World(
        v2.task, lv.release_speed_std, math.radians(lv.release_angle_std), spec=spec
    )
    camera = CameraSensor(v2.task.dt, lv.frame_rate, lv.jitter_std, lv.drop_prob,
                          lv.occlusion_radius, lv.position_std)  # fmt: skip
    streams = np.random.SeedSequence(seed).spawn(5)
    w, c, k, d, g = (np.random.default_rng(s) for s in streams)
    delay, drag = float(d.uniform(*lv.delay)), float(g.uniform(*lv.drag))
    true = world.reset(juggler.home_, rng=w)
    world.set_drag(0, drag)
    camera.reset(delay, c)
    ctrl.estimator.reset(drag, delay)
    blind = dict(ball_pos=true.hand_pos, ball_vel=true.hand_vel)
    state = dataclasses.replace(true, **blind)
    ctrl.reset(state, k)
    expected = []
    for _ in hands:
        target, armed = ctrl.command(state)
        true = world.step(target, armed)
        hand = (float(true.hand_pos[0]), float(true.hand_pos[1]))
        frames = camera.record(int(world.k[0]), tuple(true.ball_pos.tolist()), hand, true.held)
        if true.released:
            ctrl.estimator.released(true.time, *hand)
        ctrl.estimator.add(frames)
        state = dataclasses.replace(true, ball_pos=true.hand_pos, ball_vel=true.hand_vel)
        expected.append(true.hand_pos)
    return np.array(hands), np.array(expected)


def _cascade_nominal(env: gym.Env) -> tuple[np.ndarray, np.ndarray]:
    """A zero-action Cascade-v0 episode's hand paths (``info['hands']``) against the
    controller alone in a fresh world and sensor, seeded as the env documents."""
    import math

    from motion_envs.envs.juggling import CascadeWorld
    from motion_envs.models.juggling import CascadeSensor, cascade_fit, make_cascade_controller

    c = env.unwrapped
    env.reset(seed=21)
    got = []
    terminated = truncated = False
    while not (terminated or truncated):
        _, _, terminated, truncated, info = env.step(np.zeros(4, np.float32))
        got.append(info["hands"].ravel())
    assert info["catches"] >= 1
    fit = cascade_fit(c.gravity)
    ctrl = make_cascade_controller(c.controller_name, fit, c.delay_steps * c.task.dt, c.dwell_ratio)
    world = CascadeWorld(c.task, c.release_speed_std, math.radians(c.release_angle_std))
    sensor = CascadeSensor(c.delay_steps, c.position_std, c.velocity_std, c.task.dt)
    w_ss, s_ss, c_ss = np.random.SeedSequence(21).spawn(3)
    true = world.reset(ctrl.home, start=ctrl.start(), rng=np.random.default_rng(w_ss))
    state = sensor.reset(true, np.random.default_rng(s_ss), c.task.gravity)
    ctrl.reset(state, np.random.default_rng(c_ss))
    expected = []
    for _ in got:
        targets, armed = ctrl.command(state)
        true = world.step(targets, armed)
        state = sensor.measure(true)
        expected.append(true.hand_pos.ravel())
    return np.array(got), np.array(expected)


def _cascade_v1_nominal(env: gym.Env) -> tuple[np.ndarray, np.ndarray]:
    """A zero-action Cascade-v1 episode's hand paths against the pattern's juggler alone,
    in a fresh world with air and the capture at impact, a fresh camera per ball and a
    fresh view, seeded as the env documents (``spawn(6)``: world, controller, start,
    delay, drags, cameras)."""
    import math

    from motion_envs.envs.juggling import CascadeWorld, WorldSpec
    from motion_envs.models.juggling import (
        V2_LEVELS,
        CameraSensor,
        CascadeBallView,
        catch_height,
        pattern_controller,
        pattern_spec,
    )

    c = env.unwrapped
    lv = V2_LEVELS[c.level]
    seed = next(s for s in range(21, 200) if c.play(s)[0] >= 1)  # an episode with a catch
    env.reset(seed=seed)
    got = []
    terminated = truncated = False
    while not (terminated or truncated):
        _, _, terminated, truncated, info = env.step(np.zeros(4, np.float32))
        got.append(info["hands"].ravel())
    assert info["catches"] >= 1
    spec = pattern_spec(c.pattern.name)
    ctrl = pattern_controller(spec, "juggler", 9.81)
    view = CascadeBallView(spec.balls, "arrival", 9.81, lv.mean_delay, catch_height(ctrl))
    world_spec = WorldSpec.of(
        c.task, hands=2, balls=spec.balls, capture_speed=lv.capture_speed, air_density=1.2,
        impact_capture=True, contact_damping=0.2,
    )  # fmt: skip
    world = CascadeWorld(c.task, lv.release_speed_std, math.radians(lv.release_angle_std),
                         spec.balls, spec=world_spec)  # fmt: skip
    w, k, st, d, g, cam = np.random.SeedSequence(seed).spawn(6)
    delay = float(np.random.default_rng(d).uniform(*lv.delay))
    drags = np.random.default_rng(g).uniform(*lv.drag, size=spec.balls)
    scatter = (lv.release_speed_std, math.radians(lv.release_angle_std))
    start = ctrl.start(scatter, np.random.default_rng(st))
    true = world.reset(ctrl.home, start=start, rng=np.random.default_rng(w))
    cameras = []
    for i, ss in enumerate(cam.spawn(spec.balls)):
        world.set_drag(i, float(drags[i]))
        cameras.append(CameraSensor(c.task.dt, lv.frame_rate, lv.jitter_std, lv.drop_prob,
                                    lv.occlusion_radius, lv.position_std))  # fmt: skip
        cameras[-1].reset(delay, np.random.default_rng(ss))
    view.reset(ctrl.start(), drags, delay)
    state = view.view(true)
    ctrl.reset(state, np.random.default_rng(k))
    expected = []
    for _ in got:
        targets, armed = ctrl.command(state)
        true = world.step(targets, armed)
        frames = []
        for i, camera in enumerate(cameras):
            b = true.ball_pos[i]
            near = min(true.hand_pos, key=lambda h, b=b: math.hypot(*(b - h)))
            frames.append(camera.record(int(world.k[0]), (float(b[0]), float(b[1])),
                                        (float(near[0]), float(near[1])),
                                        true.holder[i] >= 0))  # fmt: skip
        view.record(true, frames)
        state = view.view(true)
        expected.append(true.hand_pos.ravel())
    return np.array(got), np.array(expected)


@dataclass(frozen=True)
class Case:
    """What the contract needs to know about one environment (all its versions).

    ``kwargs``: a configuration that draws from the seed (tests of determinism and
    pickling need the seed to matter); ``action_scale``: the seeded random actions'
    bound (small enough that episodes last); ``nominal``: a zero-action run returning
    ``(what the environment did, what its nominal does)``; ``checked``: further
    configurations the checkers also run on.
    """

    nominal: Callable[[gym.Env], tuple[np.ndarray, np.ndarray]]
    kwargs: dict[str, Any] = field(default_factory=dict)
    action_scale: float = 1.0
    checked: tuple[dict[str, Any], ...] = ()


CASES: dict[str, Case] = {
    "MotionEnvs/OrientationReach": Case(
        _orientation_nominal,
        {"nominal": "bezier-task"},
        checked=({"calibration": 5, "split": "test"},),
    ),
    "MotionEnvs/PositionReach": Case(_position_nominal, {"shapes": ["Angle", "CShape", "GShape"]}),
    "MotionEnvs/OrientationCoefficients": Case(
        _coefficient_nominal("MotionEnvs/OrientationReach-v1"),
        {"nominal": "bezier-task"},
        checked=({"calibration": 5, "split": "test"},),
    ),
    "MotionEnvs/PositionCoefficients": Case(
        _coefficient_nominal("MotionEnvs/PositionReach-v1"),
        {"shapes": ["Angle", "CShape", "GShape"]},
    ),
    "MotionEnvs/Juggling": Case(
        _juggling_nominal,
        {"noise": 0.05},
        action_scale=0.2,
        checked=({"noise": 0.1, "frame_skip": 3}, {"noise": {"release": 0.05, "tracking": 0.002}}),
    ),
    # a version whose arguments differ from its family's has its own case
    "MotionEnvs/Juggling-v1": Case(
        _juggling_v1_nominal,
        {"level": "medium", "max_catches": 2},
        action_scale=0.2,
        checked=(
            {"level": "hard", "max_catches": 1},
            {"level": "easy", "gravity": 1.0},
            {"level": "medium", "residual_phases": ["go_down", "catch"]},
        ),
    ),
    "MotionEnvs/Juggling-v2": Case(
        _juggling_v2_nominal,
        {"level": "medium", "controller": "juggler_oracle", "max_catches": 2},
        action_scale=0.2,
        checked=(
            {"level": "easy", "controller": "juggler_mean_delay", "max_catches": 1},
            {"level": "hard", "controller": "juggler_delay_estimator"},
            {"level": "medium", "residual_phases": ["catch"]},
            {"controller": "juggler_mean_delay_catch", "observe_task_error": True},
            {"controller": "juggler_delay_estimator_catch", "delay_offset": -0.01},
        ),
    ),
    "MotionEnvs/Cascade-v1": Case(
        _cascade_v1_nominal,
        {"level": "medium", "max_catches": 2},
        action_scale=0.2,
        checked=(
            {"level": "easy", "pattern": "5", "controller": "juggler_mean_delay"},
            {"level": "hard", "controller": "juggler_oracle", "max_catches": 1},
            {"level": "medium", "controller": "fixed_point", "residual_phases": ["catch"]},
            {"level": "easy", "controller": "juggler_mean_delay_catch", "observe_task_error": True},
            {"level": "easy", "pattern": "5", "controller": "juggler_delay_estimator"},
            {"level": "medium", "controller": "juggler_delay_estimator_catch", "max_catches": 2},
            {"level": "hard", "controller": "juggler_delay_estimator_catch", "delay_offset": 0.02},
        ),
    ),
    "MotionEnvs/Cascade": Case(
        _cascade_nominal,
        {"level": "medium", "max_catches": 2},
        action_scale=0.2,
        checked=(
            {"level": "hard", "max_catches": 1},
            {"level": "easy", "dwell_ratio": 0.6},
            {"level": "medium", "frame_skip": 3},
            {"level": "medium", "residual_phases": ["catch"]},
        ),
    ),
}


def case(env_id: str) -> Case:
    return CASES.get(env_id) or CASES[env_id.rsplit("-v", 1)[0]]


# -- helpers ------------------------------------------------------------------------------


def _actions(env: gym.Env, n: int, scale: float, seed: int = 123) -> np.ndarray:
    shape = (n, *env.action_space.shape)
    return (scale * np.random.default_rng(seed).uniform(-1, 1, size=shape)).astype(np.float32)


def _rollout(env: gym.Env, seed: int, actions: np.ndarray) -> list[tuple[Any, ...]]:
    """Every ``reset`` and ``step`` return of a rollout from ``reset(seed=seed)``."""
    return [env.reset(seed=seed), *_continue(env, actions)]


def _continue(env: gym.Env, actions: np.ndarray) -> list[tuple[Any, ...]]:
    """Every ``step`` return, and ``reset`` (without a seed) at the episodes' ends."""
    out: list[tuple[Any, ...]] = []
    for a in actions:
        step = env.step(a)
        out.append(step)
        if step[2] or step[3]:
            out.append(env.reset())
    return out


def _assert_checker_clean(check: Callable[[], None]) -> None:
    """Run a checker with every warning an error, but the :data:`ALLOWED_WARNINGS`."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for pattern in ALLOWED_WARNINGS:
            warnings.filterwarnings("ignore", message=pattern)
        check()


def _checker_kwargs(env_id: str) -> list[dict[str, Any]]:
    return [{}, case(env_id).kwargs, *case(env_id).checked]


def _documented_defaults(cls: type) -> dict[str, object]:
    doc = inspect.getdoc(cls) or ""
    section = doc.split("## Arguments", 1)[1].split("## Version History", 1)[0]
    out = {}
    for line in section.splitlines():
        m = re.match(r"\|\s*`(\w+)`\s*\|[^|]*\|\s*`([^`]*)`\s*\|", line)
        if m:
            out[m.group(1)] = ast.literal_eval(m.group(2))
    return out


def _distinct_colours(frame: np.ndarray) -> int:
    return len(np.unique(frame.reshape(-1, frame.shape[-1]), axis=0))


def _edge_fraction(frame: np.ndarray, contrast: int = 24) -> float:
    """Share of neighbouring pixel pairs differing by more than ``contrast`` in a channel:
    drawn objects have edges, an empty scene (a single colour or the sky's smooth
    gradient, whatever its number of colours) has none."""
    f = frame.astype(np.int16)
    dx = np.abs(np.diff(f, axis=1)).max(axis=-1) > contrast
    dy = np.abs(np.diff(f, axis=0)).max(axis=-1) > contrast
    return float((dx.sum() + dy.sum()) / (dx.size + dy.size))


# -- the contract -------------------------------------------------------------------------


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_every_id_has_a_contract_case(env_id):
    assert env_id.rsplit("-v", 1)[0] in CASES, f"add a row for {env_id} to CASES"


def test_every_id_is_registered():
    assert len(set(ENV_IDS)) == len(ENV_IDS)
    assert set(ENV_IDS) <= set(gym.registry)


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_module_form_of_the_id_makes_the_same_env(env_id):
    """``motion_envs:<id>`` imports the package itself (SB3's subprocess workers use it)."""
    env = gym.make("motion_envs:" + env_id)
    plain = gym.make(env_id)
    assert type(env.unwrapped) is type(plain.unwrapped)
    assert env.spec.max_episode_steps == plain.spec.max_episode_steps
    assert env.observation_space == plain.observation_space
    assert env.action_space == plain.action_space
    env.close()


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_gymnasium_check_env_with_warnings_as_errors(env_id):
    from gymnasium.utils.env_checker import check_env

    for kwargs in _checker_kwargs(env_id):
        env = gym.make(env_id, **kwargs).unwrapped
        _assert_checker_clean(lambda env=env: check_env(env, skip_render_check=True))


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_sb3_check_env_with_warnings_as_errors(env_id):
    sb3_checker = pytest.importorskip("stable_baselines3.common.env_checker")
    for kwargs in _checker_kwargs(env_id):
        env = gym.make(env_id, **kwargs).unwrapped
        _assert_checker_clean(lambda env=env: sb3_checker.check_env(env, warn=True))


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_seeded_rollouts_are_identical_and_global_seeds_change_nothing(env_id):
    """Two environments, the same ``reset(seed=...)`` and seeded actions: identical
    observations, rewards, flags and infos over 1000 steps (episode ends included),
    whatever the global seeds; another seed gives another rollout."""
    c = case(env_id)
    env_a, env_b, env_c = (gym.make(env_id, **c.kwargs) for _ in range(3))
    actions = _actions(env_a, 1000, c.action_scale)
    np.random.seed(0)  # noqa: NPY002 (the legacy global seed is what users set)
    random.seed(0)
    a = _rollout(env_a, 7, actions)
    np.random.seed(999)  # noqa: NPY002
    random.seed(999)
    b = _rollout(env_b, 7, actions)
    np.testing.assert_equal(b, a)
    other = _rollout(env_c, 8, actions)
    assert not all(np.array_equal(x[0], y[0]) for x, y in zip(a, other, strict=False))


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_pickled_and_deep_copied_env_continue_identically(env_id):
    """A pickle round trip and a deepcopy in mid-episode (223 steps in: not at an episode
    boundary of the 50-step reaching envs) continue as the original does
    (through episode ends), and independently of it."""
    c = case(env_id)
    env = gym.make(env_id, **c.kwargs)
    actions = _actions(env, 800, c.action_scale, seed=9)
    env.reset(seed=5)
    _continue(env, actions[:223])
    pickled = pickle.loads(pickle.dumps(env))
    copied = copy.deepcopy(env)
    ref = _continue(env, actions[223:])
    np.testing.assert_equal(_continue(pickled, actions[223:]), ref)
    np.testing.assert_equal(_continue(copied, actions[223:]), ref)


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_observations_stay_in_the_spaces(env_id):
    """Observations inside the observation space, finite float rewards and bool flags over
    10000 random steps (200 episodes of a reaching env; one per trajectory and split:
    ``test_env_spaces.py``)."""
    c = case(env_id)
    env = gym.make(env_id, **c.kwargs)
    assert isinstance(env.observation_space, gym.spaces.Box)
    assert isinstance(env.action_space, gym.spaces.Box)
    assert env.observation_space.dtype == np.float32 and env.action_space.dtype == np.float32
    env.action_space.seed(0)
    obs, info = env.reset(seed=0)
    assert env.observation_space.contains(obs) and isinstance(info, dict)
    for _ in range(10_000):
        obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
        assert env.observation_space.contains(obs), obs
        assert isinstance(reward, float) and np.isfinite(reward)
        assert isinstance(terminated, bool) and isinstance(truncated, bool)
        if terminated or truncated:
            obs, _ = env.reset()
            assert env.observation_space.contains(obs), obs


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_zero_action_reproduces_the_nominal(env_id):
    env = gym.make(env_id)
    got, expected = case(env_id).nominal(env)
    assert got.shape == expected.shape and got.size > 0
    np.testing.assert_allclose(got, expected, atol=1e-9, rtol=0)


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_step_before_reset_raises_and_close_twice(env_id):
    env = gym.make(env_id).unwrapped
    with pytest.raises(RuntimeError, match="reset"):
        env.step(np.zeros(env.action_space.shape, np.float32))
    env.close()
    env.close()


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_wrong_action_shape_raises(env_id):
    env = gym.make(env_id)
    (n,) = env.action_space.shape
    for shape in [(n - 1,), (n + 1,), (1, n), (n, 1), ()]:
        env.reset(seed=0)
        with pytest.raises(ValueError, match="shape"):
            env.step(np.zeros(shape, np.float32))


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_documented_arguments_and_sections(env_id):
    """The docstring's argument table states the signature's defaults, and the docstring
    has Gymnasium's sections."""
    cls = load_env_creator(gym.spec(env_id).entry_point)
    params = {
        name: p.default
        for name, p in inspect.signature(cls.__init__).parameters.items()
        if name != "self"
    }
    assert _documented_defaults(cls) == params
    doc = inspect.getdoc(cls) or ""
    for heading in (
        "## Description",
        "## Action Space",
        "## Observation Space",
        "## Rewards",
        "## Starting State",
        "## Episode End",
        "## Arguments",
        "## Version History",
    ):
        assert heading in doc


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_render_without_a_mode_warns_and_returns_none(env_id):
    env = gym.make(env_id).unwrapped
    env.reset(seed=0)
    with pytest.warns(UserWarning, match="render_mode"):
        assert env.render() is None


@pytest.mark.parametrize(
    "env_id",
    [
        pytest.param(i, marks=pytest.mark.xfail(strict=True, reason=RENDER_XFAIL[i]))
        if i in RENDER_XFAIL
        else i
        for i in ENV_IDS
    ],
)
def test_first_rgb_array_frame_shows_the_scene(env_id, request):
    """The frame right after ``reset`` has the requested size and is not blank: it has
    drawn edges and many colours (skipped when MuJoCo's OpenGL rendering is unusable)."""
    env = gym.make(env_id, render_mode="rgb_array", width=160, height=120)
    env.reset(seed=0)
    try:
        frame = env.render()
    except RuntimeError:
        request.getfixturevalue("mujoco_gl")  # skips without a usable OpenGL backend
        raise
    assert frame.dtype == np.uint8 and frame.shape == (120, 160, 3)
    assert _distinct_colours(frame) > 16
    assert _edge_fraction(frame) > 0.005
    env.close()
