"""The juggling code's structure: one home for the world's rules (one ball and a batch
agree bit for bit), the former import paths gone, the fitted juggler apart from
its per-episode controller."""

from __future__ import annotations

import importlib
import math
import sys
from dataclasses import fields

import numpy as np
import pytest

from motion_envs.datasets import juggling as dj
from motion_envs.datasets.juggling import JugglingNoise, JugglingTask, rules
from motion_envs.models import juggling as mj

# -- the rules: one ball and a batch ----------------------------------------------------


def _batch_inputs(n=4000, seed=0):
    rng = np.random.default_rng(seed)
    return {
        "x": rng.normal(size=n),
        "x_prev": rng.normal(size=n),
        "z": rng.normal(size=n),
        "z_prev": rng.normal(size=n),
        "z_prev2": rng.normal(size=n),
        "dt2": rng.uniform(1e-3, 1e-2, size=n),
        "t_r": rng.uniform(0, 2, size=n),
        "time": rng.uniform(0, 4, size=n),
        "vx": rng.normal(size=n),
        "vz": rng.normal(size=n),
        "fx": 1 + 0.1 * rng.normal(size=n),
        "fz": 1 + 0.1 * rng.normal(size=n),
        "dist": rng.uniform(0, 0.12, size=n),
        "left": rng.random(n) < 0.5,
        "dropped": rng.random(n) < 0.3,
        "held": rng.random(n) < 0.5,
        "caught": rng.random(n) < 0.3,
        "armed": rng.random(n) < 0.5,
        "acc": rng.normal(scale=5, size=n),
    }


def _rules(v, dt, task):
    """Every rule on the inputs ``v`` (floats and bools, or arrays)."""
    return [
        rules.hand_velocity(v["x"], v["x_prev"], dt),
        rules.hand_acceleration(v["z"], v["z_prev"], v["z_prev2"], dt),
        rules.hand_acceleration(v["z"], v["z_prev"], v["z_prev2"], dt, v["dt2"]),
        rules.release_fires(v["armed"], v["acc"], task.toss_threshold),
        *rules.release_velocity(v["vx"], v["vz"], v["fx"], v["fz"]),
        *rules.flight((v["t_r"], v["x"], v["z"], v["vx"], v["vz"]), v["time"], task.gravity),
        rules.catch_fires(v["dist"], v["left"], v["dropped"], task.catch_radius),
        rules.has_left(v["dist"], v["left"], v["caught"], task.catch_radius),
        rules.drop_fires(v["z"], v["held"], task.floor_z),
    ]


def test_rules_on_one_ball_equal_the_batch_bit_for_bit():
    task, dt = JugglingTask(), JugglingTask().dt
    batch = _batch_inputs()
    want = _rules(batch, dt, task)
    for i in range(0, len(batch["x"]), 37):
        one = {k: (bool(a[i]) if a.dtype == bool else float(a[i])) for k, a in batch.items()}
        got = _rules(one, dt, task)
        for g, w in zip(got, want, strict=True):
            assert type(g) in (bool, float, np.bool_)  # Python scalars in, scalars out
            assert g == w[i] or (math.isnan(g) and math.isnan(w[i]))


def test_rules_against_their_definitions():
    """Independent truth tables and formulas (written here, not imported)."""
    task = JugglingTask()
    rc, thr = task.catch_radius, task.toss_threshold
    # catch: has left, within the radius, not dropped
    for left in (False, True):
        for dropped in (False, True):
            for dist in (0.5 * rc, rc, 2 * rc):
                want = left and dist <= rc and not dropped
                assert rules.catch_fires(dist, left, dropped, rc) == want
                assert rules.has_left(dist, left, want, rc) == (left or (not want and dist > rc))
    assert rules.release_fires(True, -thr - 1e-9, thr) and not rules.release_fires(True, -thr, thr)
    assert not rules.release_fires(False, -10 * thr, thr)
    assert rules.drop_fires(task.floor_z - 1e-9, False, task.floor_z)
    assert not rules.drop_fires(task.floor_z - 1.0, True, task.floor_z)  # a held ball
    # the flight is the closed form of the task (ballistic_position / _velocity)
    x, z, vx, vz = rules.flight((0.3, 0.1, 1.2, -0.2, 0.7), 1.1, task.gravity)
    np.testing.assert_allclose(
        [x, z], dj.ballistic_position([0.1, 1.2], [-0.2, 0.7], 0.8, task.gravity), atol=1e-15
    )
    np.testing.assert_allclose(
        [vx, vz], dj.ballistic_velocity([-0.2, 0.7], 0.8, task.gravity), atol=1e-15
    )
    # hand acceleration: second difference, a parabola gives its curvature
    dt = task.dt
    t = np.array([0.0, dt, 2 * dt])
    zz = 1.0 + 0.5 * t - 2.0 * t**2
    assert rules.hand_acceleration(zz[2], zz[1], zz[0], dt) == pytest.approx(-4.0, rel=1e-9)


def test_worlds_expose_the_episode_noise_as_public_fields():
    from motion_envs.envs.juggling import JugglingScene

    noise = JugglingNoise(release=0.1, tracking=1e-3)
    for world in (mj.BallisticWorld(), JugglingScene()):
        assert isinstance(world, mj.JugglingWorld)
        world.reset([0.2, 1.0], noise=noise, rng=np.random.default_rng(3))
        factor, track = mj.draw_episode_noise(noise, np.random.default_rng(3))
        np.testing.assert_array_equal(np.asarray(world.release_factor), factor)
        np.testing.assert_array_equal(world.tracking_noise, track)


# -- the fitted model and the per-episode controller ------------------------------------


@pytest.fixture(scope="module")
def juggler():
    demos = dj.generate_demonstrations(n_cycles=20, seed=5)
    return mj.AnalyticJuggler(n_sines=6).fit(demos)


def _snapshot(model):
    return {
        p: (f.end_mean.copy(), f.end_cov.copy(), f.model.F_.copy())
        for p, f in model.phases_.items()
    }


def test_runs_and_variants_do_not_change_the_fitted_model(juggler):
    before = _snapshot(juggler.model)
    phases, home = juggler.phases_, juggler.home_.copy()
    off = juggler.variant(correction=False)
    assert off.model is juggler.model and juggler.correction and not off.correction
    noise = JugglingNoise(release=0.1, tracking=5e-4)
    for j in (juggler, off):
        mj.run_cycles_fast(j, 8, noise, seed=1)
        mj.run_cycles(j, 3, noise, seed=1)
    assert juggler.phases_ is phases
    np.testing.assert_array_equal(juggler.home_, home)
    for p, arrays in _snapshot(juggler.model).items():
        for a, b in zip(arrays, before[p], strict=True):
            np.testing.assert_array_equal(a, b)


def test_controllers_are_independent_episodes(juggler):
    """Two controllers of one model, stepped interleaved, equal each run alone."""
    world_a, world_b = mj.BallisticWorld(juggler.task), mj.BallisticWorld(juggler.task)
    (wa, ja), (wb, jb) = mj.cycle_rngs(4, 2)
    alone = [
        mj.run_cycle(juggler, mj.BallisticWorld(juggler.task), JugglingNoise(), r, True, True)
        for r in mj.cycle_rngs(4, 2)
    ]
    ca, cb = juggler.controller(), juggler.controller()
    sa = world_a.reset(juggler.home_, rng=wa)
    sb = world_b.reset(juggler.home_, rng=wb)
    ca.reset(sa, ja)
    cb.reset(sb, jb)
    hands_a, hands_b = [juggler.home_], [juggler.home_]
    for _ in range(len(alone[0].hand) - 1):
        ta, arm_a = ca.command(sa)
        tb, arm_b = cb.command(sb)
        sa, sb = world_a.step(ta, arm_a), world_b.step(tb, arm_b)
        hands_a.append(ta)
        hands_b.append(tb)
    np.testing.assert_array_equal(np.asarray(hands_a), alone[0].hand)
    np.testing.assert_array_equal(np.asarray(hands_b)[: len(alone[1].hand)], alone[1].hand)


def test_control_options_are_the_juggler_arguments():
    names = {f.name for f in fields(mj.ControlOptions)}
    assert names == {"correction", "correction_tolerance", "release_after", "reach_tolerance"}
    j = mj.AnalyticJuggler(correction=False, release_after=0.3)
    assert j.options == mj.ControlOptions(correction=False, release_after=0.3)


def test_benchmark_defaults_are_the_default_fit():
    from baselines.juggling_bench import JugglingConfig

    c = JugglingConfig()
    assert (c.seed, c.test_fraction, c.tracking, c.demo_cycles) == (
        mj.FIT_SEED,
        mj.FIT_TEST_FRACTION,
        mj.TRACKING_NOISE,
        mj.DEMO_CYCLES,
    )


# -- no compatibility modules ---------------------------------------------------------------

#: The former modules (the package is unreleased: they were removed, not kept as shims).
REMOVED = (
    "motion_envs.datasets.juggling_task",
    "motion_envs.datasets.juggling_demos",
    "motion_envs.datasets.juggling_csv",
    "motion_envs.models.juggling_world",
    "motion_envs.models.juggling_juggler",
    "motion_envs.models.juggling_run",
    "motion_envs.models.juggling_segmentation",
    "motion_envs.models.juggling_sensor",
    "motion_envs.models.juggling_levels",
    "motion_envs.envs.juggling_scene",
    "motion_envs.envs.juggling_v1",
    "motion_envs.envs.juggling_v1_scene",
    "motion_envs.envs.coefficients",
    "motion_envs.models.nominal",
    "baselines.learned_rows",
)


@pytest.mark.parametrize("old", REMOVED)
def test_former_module_is_gone(old):
    sys.modules.pop(old, None)
    with pytest.raises(ModuleNotFoundError, match=old.rpartition(".")[2]):
        importlib.import_module(old)


def test_registered_entry_point_imports_without_warning():
    import warnings

    import gymnasium as gym

    import motion_envs  # noqa: F401

    assert gym.spec("MotionEnvs/Juggling-v0").entry_point == "motion_envs.envs.juggling:JugglingEnv"
    assert (
        gym.spec("MotionEnvs/Juggling-v1").entry_point == "motion_envs.envs.juggling:JugglingV1Env"
    )
    with warnings.catch_warnings():
        warnings.simplefilter("error", DeprecationWarning)
        module = importlib.import_module("motion_envs.envs.juggling")
    from motion_envs.envs.juggling._env import JugglingEnv

    assert module.JugglingEnv is JugglingEnv
    for name in ("load_juggler", "juggler_demonstrations", "TRACKING_NOISE", "cycle_rngs"):
        assert getattr(module, name) is getattr(mj, name)
