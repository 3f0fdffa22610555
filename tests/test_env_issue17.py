"""Issue 17's environment reproductions (items 6, 7, 8, 10, 11), each a regression test.

Juggling-v1 is left to its own module's tests (its files move in a parallel branch).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from motion_envs.envs.juggling import JugglingEnv

HUGE = 10**400  # an int beyond float64's range: float(HUGE) raises OverflowError
REACHING = ["MotionEnvs/OrientationReach-v0", "MotionEnvs/PositionReach-v0"]


# -- item 7: numeric arguments and actions ----------------------------------------------
@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"residual_scale": HUGE}, "residual_scale"),
        ({"gravity": HUGE}, "gravity"),
        ({"gravity": 1e-300}, "gravity"),
        ({"noise": HUGE}, "noise"),
        ({"noise": {"release": HUGE}}, r"noise\['release'\]"),
        ({"noise": {"tracking": 1e300}}, r"noise\['tracking'\]"),
        ({"reward_weights": {"catch": HUGE}}, r"reward_weights\['catch'\]"),
        ({"max_cycles": HUGE}, "max_cycles"),
        ({"frame_skip": HUGE}, "frame_skip"),
        ({"width": HUGE}, "width"),
        ({"residual_scale": 2.0}, "residual_scale"),
    ],
)
def test_juggling_huge_numbers_raise_value_error_naming_the_argument(kwargs, name):
    with pytest.raises(ValueError, match=name) as info:
        JugglingEnv(**kwargs)
    assert len(str(info.value)) < 200  # the 400 digits are abbreviated


@pytest.mark.parametrize(
    "kwargs",
    [
        {"residual_scale": HUGE},
        {"val_fraction": HUGE},
        {"test_fraction": HUGE},
        {"split_seed": HUGE},
    ],
)
@pytest.mark.parametrize("env_id", REACHING)
def test_reaching_huge_numbers_raise_value_error(env_id, kwargs):
    import gymnasium as gym

    with pytest.raises(ValueError, match=next(iter(kwargs))):
        gym.make(env_id, **kwargs)


BAD_ACTIONS = [
    np.array([1j, 0.0]),
    {"x": 0.0, "z": 0.0},
    np.array([None, None], dtype=object),
    [[0.0], [0.0, 1.0]],
    np.array([True, False]),
    "ab",
    np.zeros(3),
    [HUGE, 0],
]


@pytest.mark.parametrize("action", BAD_ACTIONS, ids=lambda a: type(a).__name__)
def test_juggling_step_rejects_non_real_actions_with_value_error(action):
    env = JugglingEnv(max_cycles=1)
    env.reset(seed=0)
    with pytest.raises(ValueError, match="action must"):
        env.step(action)
    env.step(np.zeros(2))  # the episode is intact


@pytest.mark.parametrize("env_id", REACHING)
@pytest.mark.parametrize("action", BAD_ACTIONS[:5], ids=lambda a: type(a).__name__)
def test_reaching_step_rejects_the_same_actions(env_id, action):
    import gymnasium as gym

    env = gym.make(env_id).unwrapped
    env.reset(seed=0)
    with pytest.raises(ValueError, match="action must"):
        env.step(action)


def test_every_env_uses_the_one_action_check():
    """The shared check in ``envs._common`` is the only one: no env converts its action
    with ``np.asarray(action, dtype=...)`` itself."""
    import pathlib

    import motion_envs.envs as envs

    root = pathlib.Path(envs.__file__).parent
    for path in [root / "juggling" / "_env.py", root / "_reach.py", root / "_native_vector.py"]:
        text = path.read_text()
        assert "as_action(" in text or "clipped_pair(" in text, path  # built on as_action
        assert "np.asarray(action" not in text, path
    # the native vector envs check their actions in their shared base only
    for path in [root / "_reach_vector.py", root / "juggling" / "_vector.py"]:
        text = path.read_text()
        assert "_check_actions(" in text and "np.asarray(action" not in text, path


def test_nan_action_is_zero_and_flagged():
    env = JugglingEnv(max_cycles=1)
    env.reset(seed=0)
    _, reward, *_, info = env.step(np.array([math.nan, 0.0]))
    assert info["action_invalid"] and math.isfinite(reward)


# -- item 11: autoreset_mode= as a keyword of make_vec for Juggling-v0 -----------------
@pytest.mark.filterwarnings("ignore::DeprecationWarning")
@pytest.mark.parametrize("mode", ["NextStep", "SameStep", "Disabled"])
def test_juggling_make_vec_takes_autoreset_mode_like_sync(mode):
    import gymnasium as gym
    from gymnasium.vector import AutoresetMode

    kw = {"max_cycles": 1, "frame_skip": 40, "residual_scale": 0.3}
    env = gym.make_vec("MotionEnvs/Juggling-v0", num_envs=2, autoreset_mode=mode, **kw)
    ref = gym.make_vec(
        "MotionEnvs/Juggling-v0",
        num_envs=2,
        vectorization_mode="sync",
        vector_kwargs={"autoreset_mode": AutoresetMode(mode)},
        **kw,
    )
    assert env.metadata["autoreset_mode"] == AutoresetMode(mode)
    o1, _ = env.reset(seed=3)
    o2, _ = ref.reset(seed=3)
    np.testing.assert_array_equal(o1, o2)
    rng = np.random.default_rng(0)
    for _ in range(30):
        a = rng.uniform(-1, 1, (2, 2))
        r1, r2 = env.step(a), ref.step(a)
        for x, y in zip(r1[:4], r2[:4], strict=True):
            np.testing.assert_array_equal(x, y)
        assert r1[4].keys() == r2[4].keys()
        if mode == "Disabled" and (r1[2] | r1[3]).any():
            mask = r1[2] | r1[3]
            env.reset(options={"reset_mask": mask})
            ref.reset(options={"reset_mask": mask})


@pytest.mark.filterwarnings("ignore::DeprecationWarning")
def test_the_docs_cleanrl_recipe_runs_on_juggling():
    """docs/using-envs.md's CleanRL recipe, with the juggling id."""
    import gymnasium as gym
    from gymnasium.vector import AutoresetMode
    from gymnasium.wrappers import vector as vw

    envs = gym.make_vec(
        "MotionEnvs/Juggling-v0",
        num_envs=2,
        autoreset_mode=AutoresetMode.SAME_STEP,
        max_cycles=1,
        frame_skip=50,
    )
    envs = vw.RecordEpisodeStatistics(vw.ClipAction(envs))
    envs.reset(seed=1)
    envs.action_space.seed(0)
    seen = False
    for _ in range(60):
        *_, infos = envs.step(envs.action_space.sample())
        if "episode" in infos:
            seen = True
            assert np.isfinite(infos["episode"]["r"][infos["_episode"]]).all()
    assert seen


def test_bad_autoreset_mode_is_a_value_error():
    import gymnasium as gym

    with pytest.raises(ValueError, match="autoreset_mode must"):
        gym.make_vec("MotionEnvs/Juggling-v0", num_envs=2, autoreset_mode="Sometimes")


# -- item 6: reset(options={"cycle": N}) is O(1) and bit-identical to the spawned cycles --
def test_cycle_rng_is_the_spawned_cycle():
    from motion_envs.models.juggling import cycle_rng, cycle_rngs

    for seed in (0, 3, 2**40 + 7):
        ref = cycle_rngs(seed, 12)
        for i in (0, 1, 5, 11):
            got = cycle_rng(seed, i)
            for g, r in zip(got, ref[i], strict=True):
                np.testing.assert_array_equal(g.random(8), r.random(8))


def test_reset_to_a_huge_cycle_is_fast_and_bounded():
    import time

    env = JugglingEnv(max_cycles=1)
    start = time.perf_counter()
    _, info = env.reset(seed=0, options={"cycle": 10**7})
    env.reset(seed=0, options={"cycle": 2**63 - 1})
    assert time.perf_counter() - start < 1.0 and info["cycle"] == 10**7
    for bad in (2**63, -1, 1.5, "3", True):
        with pytest.raises(ValueError, match=r"options\['cycle'\]"):
            env.reset(seed=0, options={"cycle": bad})


# -- item 8: native vector infos on the autoreset step equal SyncVectorEnv's ------------
#: The single environments' reset text: not in the native infos (numbers only, issue 38;
#: the env's ``trajectory_labels`` at ``trajectory_index`` give it, tested in
#: test_env_inputs).
_TEXT = ("trajectory_id", "task", "subject")


def _same_infos(a, b, where=""):
    """``a`` (native) equal to ``b`` (SyncVectorEnv's) but for the reset text."""
    b = {k: v for k, v in b.items() if k.lstrip("_") not in _TEXT}
    assert set(a) == set(b), (where, sorted(set(a) ^ set(b)))
    for key in a:
        if isinstance(a[key], dict):
            _same_infos(a[key], b[key], f"{where}/{key}")
        elif key.startswith("_") or key in ("final_obs",):
            mask = np.asarray(a[key])
            if key == "final_obs":
                for x, y in zip(a[key], b[key], strict=True):
                    assert (x is None) == (y is None)
                    if x is not None:
                        np.testing.assert_array_equal(x, y)
            else:
                np.testing.assert_array_equal(mask, b[key], err_msg=f"{where}/{key}")
    for key in a:
        if not key.startswith("_") and "_" + key in a and not isinstance(a[key], dict):
            m = np.asarray(a["_" + key])
            if key != "final_obs":
                np.testing.assert_array_equal(np.asarray(a[key])[m], np.asarray(b[key])[m])


@pytest.mark.filterwarnings("ignore::DeprecationWarning")
@pytest.mark.parametrize("mode", ["NextStep", "SameStep"])
@pytest.mark.parametrize("env_id", REACHING)
@pytest.mark.parametrize("num_envs", [1, 3, 9])
def test_native_infos_equal_sync_on_the_autoreset_step(env_id, mode, num_envs):
    """Every sub-environment ends on the same step (zero actions, 50 steps): the native
    infos had ``error``, ``tau``, ``reward_*`` with all-False masks that Sync has not."""
    import gymnasium as gym
    from gymnasium.vector import AutoresetMode

    nat = gym.make_vec(env_id, num_envs=num_envs, autoreset_mode=mode)
    syn = gym.make_vec(
        env_id,
        num_envs=num_envs,
        vectorization_mode="sync",
        vector_kwargs={"autoreset_mode": AutoresetMode(mode)},
    )
    _, i1 = nat.reset(seed=0)
    _, i2 = syn.reset(seed=0)
    _same_infos(i1, i2, "reset")
    zeros = np.zeros(nat.action_space.shape)
    for t in range(105):
        r1, r2 = nat.step(zeros), syn.step(zeros)
        for x, y in zip(r1[:4], r2[:4], strict=True):
            np.testing.assert_array_equal(x, y, err_msg=f"step {t}")
        _same_infos(r1[4], r2[4], f"step {t}")


# -- item 10: without OpenGL, Juggling-v0 renders with matplotlib (one warning) ---------
def test_juggling_render_falls_back_to_matplotlib(monkeypatch):
    import warnings

    from motion_envs.envs import rendering

    monkeypatch.setattr(rendering, "_mujoco_failure", "no OpenGL here (test)")
    monkeypatch.setattr(rendering, "_warned", set())
    env = JugglingEnv(render_mode="rgb_array", width=64, height=48, max_cycles=1)
    env.reset(seed=0)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        first = env.render()
        env.step(np.zeros(2))
        second = env.render()
    assert [str(w.message) for w in caught] == [
        "juggling frames are drawn with matplotlib: MuJoCo offscreen rendering is "
        "unavailable: no OpenGL here (test)"
    ]
    for frame in (first, second):
        assert frame.shape == (48, 64, 3) and frame.dtype == np.uint8
        assert frame.std() > 0  # a drawing, not a blank
    env.close()


# -- item 6: Juggling-v0's defects mended ------------------------------------------------
def test_swept_distance_oracle():
    """Closest approach of a segment to the origin, against a dense sampling."""
    from motion_envs.datasets.juggling import rules

    rng = np.random.default_rng(1)
    d0, d1 = rng.normal(size=(200, 2)), rng.normal(size=(200, 2))
    s = np.linspace(0.0, 1.0, 20001)[:, None, None]
    dense = np.linalg.norm(d0 + s * (d1 - d0), axis=2).min(axis=0)
    got = rules.swept_distance(d0[:, 0], d0[:, 1], d1[:, 0], d1[:, 1])
    assert np.all(got <= dense + 1e-15)  # the exact minimum is below every sample
    np.testing.assert_allclose(got, dense, atol=1e-6)  # the sampling grid's error
    one = [float(rules.swept_distance(*a, *b)) for a, b in zip(d0, d1, strict=True)]
    np.testing.assert_array_equal(one, got)  # one ball and a batch alike, bit for bit
    assert rules.swept_distance(0.3, 0.4, 0.3, 0.4) == 0.5  # no motion: the distance


def test_a_ball_cannot_pass_through_the_hand_between_samples():
    """A ball tossed at 26 m/s falls back 13 cm per 5 ms; the hand waits halfway between
    two samples of its path, 6.5 cm from both (catch radius 6 cm): the sampled test let
    it pass through, the swept one catches it, in both worlds."""
    from motion_envs.datasets.juggling import JugglingTask, rules
    from motion_envs.envs.juggling import JugglingScene
    from motion_envs.models.juggling import BallisticWorld

    task = JugglingTask(gravity=9.81)
    for world in (BallisticWorld(task), JugglingScene(task)):
        world.reset((0.2, 1.0))
        z = 1.0
        for dz in (0.05, 0.14, 0.13):  # the last one decelerates: the release
            z += dz
            state = world.step((0.2, z), True)
        assert state.released and state.ball_vel[1] > 20
        release = (state.time, *state.ball_pos, *state.ball_vel)
        k = np.arange(1, 3000)
        bz = rules.flight(release, state.time + k * task.dt, task.gravity)[1]
        down = np.flatnonzero((bz[:-1] >= z) & (bz[1:] < z))[0]
        z_hand = 0.5 * (bz[down] + bz[down + 1])
        assert min(abs(bz[down] - z_hand), abs(bz[down + 1] - z_hand)) > task.catch_radius
        for _ in range(down + 5):
            state = world.step((0.2, z_hand), False)
            if state.caught or state.dropped:
                break
        assert state.caught, type(world).__name__


def test_a_held_ball_below_the_floor_ends_the_episode_as_a_drop():
    """Random actions (seed 1, residual_scale 0.3, frame_skip 10) had the juggler hold
    the ball below the floor for 3972 steps, until the 200 s limit."""
    env = JugglingEnv(residual_scale=0.3, max_cycles=10, frame_skip=10)
    env.reset(seed=1)
    rng = np.random.default_rng(1)
    while True:
        _, _, terminated, truncated, info = env.step(rng.uniform(-1, 1, 2))
        state = env._state
        if not (terminated or truncated):
            assert not (state.held and state.ball_pos[1] < env.task.floor_z)
        else:
            break
    assert info["time"] < 200.0


def test_a_hand_far_outside_the_workspace_ends_the_episode():
    env = JugglingEnv(max_cycles=10, residual_scale=1.0)
    env.reset(seed=0)
    for _ in range(40000):
        _, _, terminated, truncated, info = env.step(np.array([1.0, 1.0]))
        assert np.all(np.abs(info["hand"] - np.array(env.task.home)) < 10.5)
        if terminated or truncated:
            break
    assert terminated or truncated


def test_a_constant_action_does_not_jump_the_hand_at_phase_starts():
    """The offset is added once: with a constant action the hand moves as the zero-action
    hand shifted by the offset (no 2x offset jump at a phase start)."""
    scale = 0.05
    env = JugglingEnv(max_cycles=2, residual_scale=scale)
    env.reset(seed=0)
    hands, phases = [env.scene.hand_true], []
    for _ in range(3000):
        *_, terminated, truncated, info = env.step(np.array([1.0, 0.0]))
        hands.append(info["hand"])
        phases.append(info["phase"])
        if terminated or truncated:
            break
    steps = np.linalg.norm(np.diff(np.array(hands), axis=0), axis=1)
    starts = [k for k in range(1, len(phases)) if phases[k] != phases[k - 1]]
    assert starts
    assert steps[1:].max() < 0.5 * scale  # no jump of the offset at any step


def test_info_hand_is_the_true_hand():
    env = JugglingEnv(noise={"tracking": 0.01}, max_cycles=1)
    _, info = env.reset(seed=0)
    np.testing.assert_array_equal(info["hand"], env.scene.hand_true)
    for _ in range(20):
        *_, info = env.step(np.zeros(2))
    np.testing.assert_array_equal(info["hand"], env.scene.hand_true)
    assert np.linalg.norm(info["hand"] - info["hand_observed"]) > 0  # the tracking noise
