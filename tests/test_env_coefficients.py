"""What is special to the coefficient (black-box) environments; the common contract (both
checkers, determinism, zero action = the step env's nominal) is ``test_env_contract.py``."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from _helpers import reset_poisoned
from gymnasium.vector import AutoresetMode

import motion_envs  # noqa: F401  (registers the ids)
from motion_envs.envs._coefficients import line_frames

CASES = {
    "MotionEnvs/OrientationCoefficients-v0": {"nominal": "bezier-null"},
    "MotionEnvs/PositionCoefficients-v0": {"shapes": ["Angle", "CShape", "GShape"]},
}


@pytest.mark.parametrize("env_id", list(CASES))
def test_zero_action_curve_is_the_nominal_bit_for_bit(env_id):
    env = gym.make(env_id, **CASES[env_id]).unwrapped
    L = env.task.n_trajectories
    idx = np.arange(L)
    curves = env.curves(idx, np.zeros((L, env.action_space.shape[0])))
    assert np.array_equal(curves, env._base)


@pytest.mark.parametrize("env_id", list(CASES))
def test_score_follows_an_independent_oracle(env_id):
    """Reward = minus max over time of the error, recomputed here from the grids with a
    hand-written sine series and frame (no env code)."""
    from motion_envs.geometry import quaternion as quat
    from motion_envs.models.path_frame import path_frames

    env = gym.make(env_id, **CASES[env_id]).unwrapped
    rng = np.random.default_rng(3)
    g = env.task.grids
    tau = np.linspace(0.0, 1.0, 50)
    for l in (0, env.task.n_trajectories - 1):
        a = rng.uniform(-1, 1, env.action_space.shape).astype(np.float32)
        env.reset(options={"trajectory": l})
        _, reward, terminated, truncated, info = env.step(a)
        assert terminated and not truncated and reward == -info["max_error"]
        w = env._width
        c = env.residual_scale * a.astype(np.float64).reshape(env.n_sines, w)
        p = sum(np.sin((k + 1) * np.pi * tau)[:, None] * c[k] for k in range(env.n_sines))
        if "Orientation" in env_id:
            F, s = path_frames(g.starts[l : l + 1], g.goals[l : l + 1], env.task.up)
            rhat = g.predicted_residuals[l] + s[0] * p @ F[0].T
            # the step kernel's error: |logmap(expmap(rhat)) - r| (rhat within the chart)
            err = np.linalg.norm(quat.logmap(quat.expmap(rhat)) - g.residuals[l], axis=1)
        else:
            y0, y1 = g.human[l, 0], g.human[l, -1]
            d = (y1 - y0) / np.linalg.norm(y1 - y0)
            F = np.array([[d[0], -d[1]], [d[1], d[0]]])
            yhat = g.nominal[l] + np.linalg.norm(y1 - y0) * p @ F.T
            err = np.linalg.norm(yhat - g.human[l], axis=1)
        np.testing.assert_allclose(info["max_error"], err.max(), rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("env_id", list(CASES))
def test_target_actions_beat_the_nominal_on_their_own_episodes(env_id):
    """The least-squares action (an in-sample fit of the human) lowers the criterion."""
    env = gym.make(env_id, **CASES[env_id]).unwrapped
    L = env.task.n_trajectories
    idx = np.arange(L)
    target = env.target_actions()
    nominal = env.score(idx, np.zeros_like(target))
    fitted = env.score(idx, np.clip(target, -1, 1))
    assert np.median(fitted) < 0.5 * np.median(nominal)


def test_line_frames_are_orthonormal_with_the_first_axis_to_the_goal():
    rng = np.random.default_rng(0)
    for D in (2, 3, 5):
        S, G = rng.normal(size=(6, D)), rng.normal(size=(6, D))
        G[0] = S[0]  # degenerate: no displacement
        F, s = line_frames(S, G)
        np.testing.assert_allclose(
            np.einsum("lji,ljk->lik", F, F), np.broadcast_to(np.eye(D), F.shape), atol=1e-12
        )
        d = G - S
        np.testing.assert_allclose(F[1:, :, 0] * s[1:, None], d[1:], atol=1e-12)
        assert s[0] > 0
    F2, _ = line_frames(S[:, :2], G[:, :2])
    assert np.allclose(np.linalg.det(F2), 1.0)


VECTOR_CASES = [
    *[(i, m, CASES[i]) for i in CASES for m in (AutoresetMode.NEXT_STEP, AutoresetMode.SAME_STEP)],
    ("MotionEnvs/OrientationCoefficients-v0", AutoresetMode.NEXT_STEP, {"calibration": 2}),
]


@pytest.mark.parametrize(("env_id", "mode", "kwargs"), VECTOR_CASES)
def test_vector_env_equals_sync_vector_env(env_id, mode, kwargs):
    native = gym.make_vec(env_id, num_envs=3, autoreset_mode=mode, **kwargs)
    sync = gym.make_vec(
        env_id,
        num_envs=3,
        vectorization_mode="sync",
        vector_kwargs={"autoreset_mode": mode},
        **kwargs,
    )
    assert native.observation_space == sync.observation_space
    assert native.action_space == sync.action_space
    rng = np.random.default_rng(0)
    a_out, b_out = [native.reset(seed=4)], [sync.reset(seed=4)]
    for _ in range(9):
        a = rng.uniform(-1.2, 1.2, native.action_space.shape).astype(np.float32)
        a_out.append(native.step(a))
        b_out.append(sync.step(a))
    np.testing.assert_equal(_plain(a_out), _plain(b_out))
    assert "trajectory_id" not in a_out[0][1] and "trajectory_id" in b_out[0][1]


def _plain(x):
    """``x`` with object arrays of arrays (``final_obs``) as lists (comparable), without
    the single environments' reset text (the native infos' ``trajectory_labels``, looked
    up by ``trajectory_index``: tested in test_env_inputs)."""
    if isinstance(x, dict):
        text = ("trajectory_id", "task", "subject")
        return {k: _plain(v) for k, v in x.items() if k.lstrip("_") not in text}
    if isinstance(x, (list, tuple)):
        return [_plain(v) for v in x]
    if isinstance(x, np.ndarray) and x.dtype == object:
        return [_plain(v) for v in x.tolist()]
    return x


def test_vector_env_disabled_mode_needs_a_masked_reset():
    env_id = "MotionEnvs/OrientationCoefficients-v0"
    venv = gym.make_vec(env_id, num_envs=2, autoreset_mode=AutoresetMode.DISABLED)
    venv.reset(seed=0)
    a = np.zeros(venv.action_space.shape, np.float32)
    _, _, terminated, truncated, _ = venv.step(a)
    assert terminated.all() and truncated.all()
    with pytest.raises(RuntimeError, match="reset_mask"):
        venv.step(a)
    venv.reset(options={"reset_mask": np.array([True, True])})
    venv.step(a)


def test_vector_env_scores_given_trajectories_like_the_single_env():
    env_id = "MotionEnvs/PositionCoefficients-v0"
    venv = gym.make_vec(env_id, num_envs=4, **CASES[env_id])
    single = gym.make(env_id, **CASES[env_id])
    venv.reset(seed=0, options={"trajectory": np.array([3, 0, 2, 1])})
    a = np.random.default_rng(1).uniform(-1, 1, venv.action_space.shape).astype(np.float32)
    _, rewards, _, _, _ = venv.step(a)
    for i, l in enumerate([3, 0, 2, 1]):
        single.reset(options={"trajectory": l})
        assert single.step(a[i])[1] == rewards[i]


@pytest.mark.parametrize("bad", [{"n_sines": 0}, {"n_sines": 49}, {"residual_scale": 0.0}])
def test_bad_arguments_raise_naming_them(bad):
    name = next(iter(bad))
    for make in (gym.make, lambda i, **k: gym.make_vec(i, num_envs=2, **k)):
        with pytest.raises(ValueError, match=name):
            make("MotionEnvs/OrientationCoefficients-v0", **bad)


def test_nan_action_raises():
    env = gym.make("MotionEnvs/OrientationCoefficients-v0")
    env.reset(seed=0)
    a = np.zeros(env.action_space.shape, np.float32)
    a[2] = np.nan
    with pytest.raises(ValueError, match="finite"):
        env.step(a)


def test_calibration_summary_never_holds_the_current_trajectory():
    """Poisoned rows: the episode's own calibration features are NaN (and those of every
    trajectory outside its person): the observation stays finite, the drawn reaches are
    the person's others of the split, and the summary is their mean."""
    env = gym.make("MotionEnvs/OrientationCoefficients-v0", calibration=5).unwrapped
    clean = env._calibration.features.copy()
    subjects = np.asarray(env.task.subjects).astype(str)
    env.reset(seed=0)
    for _ in range(300):
        l = int(env.np_random.integers(env.task.n_trajectories))
        obs, info = reset_poisoned(env, clean, subjects, l)
        padded = info["calibration_trajectories"]
        assert padded.shape == (5,)
        drawn = padded[padded >= 0]
        assert np.all(padded[drawn.size :] == -1)
        assert np.all(np.isfinite(obs)) and env.observation_space.contains(obs)
        assert l not in drawn and np.all(subjects[drawn] == subjects[l])
        m = min(5, int(np.sum(subjects == subjects[l])) - 1)
        assert drawn.size == m and len(set(drawn.tolist())) == m
        np.testing.assert_allclose(obs[-10:-1], np.clip(clean[drawn].mean(0), -3, 3), rtol=1e-6)
        assert obs[-1] == np.float32(m / 5)


def test_calibration_draws_are_seeded_and_vary():
    a = gym.make("MotionEnvs/OrientationCoefficients-v0", calibration=3)
    b = gym.make("MotionEnvs/OrientationCoefficients-v0", calibration=3)
    seq_a = [a.reset(seed=11 if i == 0 else None)[0] for i in range(20)]
    seq_b = [b.reset(seed=11 if i == 0 else None)[0] for i in range(20)]
    np.testing.assert_array_equal(seq_a, seq_b)
    same = [a.reset(options={"trajectory": 0})[0] for _ in range(10)]
    assert len({x[-10:].tobytes() for x in same}) > 1  # other draws of the same person
