"""Native vector environments under every AutoresetMode and backend, against SyncVectorEnv."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode

import motion_envs  # noqa: F401  (registers the ids)
from motion_envs.envs import _kernels as K

ORIENTATION = "MotionEnvs/OrientationReach-v0"
POSITION = "MotionEnvs/PositionReach-v0"
SHAPES = ["Angle", "CShape", "GShape"]
CASES = [
    (ORIENTATION, {"nominal": "bezier-task", "reward_weights": {"geodesic": 0.5, "action": 0.1}}),
    (POSITION, {"shapes": SHAPES, "reward_weights": {"action": 0.3}}),
]
TEXT_KEYS = ("trajectory_id", "task", "subject")
BACKENDS = [b for b in K.VECTOR_BACKENDS if b != "numba" or K.numba_available()]


def _actions(env: gym.vector.VectorEnv, steps: int, seed: int = 0) -> np.ndarray:
    shape = (steps, env.num_envs, *env.single_action_space.shape)
    # a quarter of the entries out of bounds, to exercise the clipping
    return np.random.default_rng(seed).uniform(-1.5, 1.5, size=shape).astype(np.float32)


def assert_same_infos(native: dict, reference: dict, where: str = "infos") -> None:
    """Every key of the reference with the same mask and the same values under the mask;
    ``final_obs`` entry by entry; ``final_info`` recursively. The reset infos' text
    (``trajectory_id``, ``task``, ``subject``) is not in the native infos: it is the
    env's ``trajectory_labels`` at ``trajectory_index`` (compared; tested in
    test_env_inputs)."""
    for key, value in reference.items():
        if key.startswith("_"):
            continue
        if key in TEXT_KEYS:
            assert key not in native and "trajectory_index" in reference, f"{where}: {key}"
            continue
        assert key in native, f"{where}: {key!r} missing"
        mask = reference["_" + key]
        np.testing.assert_array_equal(native["_" + key], mask, err_msg=f"{where}: _{key}")
        if key == "final_obs":
            for i in np.flatnonzero(mask):
                np.testing.assert_array_equal(native[key][i], value[i])
        elif key == "final_info":
            assert_same_infos(native[key], value, where=f"{where}['final_info']")
        else:
            np.testing.assert_array_equal(
                np.asarray(native[key])[mask], value[mask], err_msg=f"{where}: {key}"
            )
    for key in native:  # a key the reference lacks applies to no sub-environment
        if not key.startswith("_") and key not in reference:
            assert not native["_" + key].any(), f"{where}: extra key {key!r}"


def assert_same_step(native, reference) -> None:
    for name, x, y in zip(
        ("obs", "reward", "terminated", "truncated"), native[:4], reference[:4], strict=True
    ):
        assert x.dtype == y.dtype, name
        np.testing.assert_array_equal(x, y, err_msg=name)
    assert_same_infos(native[4], reference[4])


def make_pair(env_id, kwargs, num_envs, mode, backend="auto", max_episode_steps=None):
    """The native vector env of ``env_id`` and a ``SyncVectorEnv`` of its single envs."""
    extra = {} if max_episode_steps is None else {"max_episode_steps": max_episode_steps}
    native = gym.make_vec(
        env_id,
        num_envs=num_envs,
        vectorization_mode="vector_entry_point",
        autoreset_mode=mode,
        backend=backend,
        **kwargs,
        **extra,
    )
    sync = gym.make_vec(
        env_id,
        num_envs=num_envs,
        vectorization_mode="sync",
        vector_kwargs={"autoreset_mode": mode},
        **kwargs,
        **extra,
    )
    return native, sync


def step_against_sync(native, sync, steps: int) -> None:
    """Reset both with seed 42 and step them with the same random actions (a quarter out
    of bounds): the same observations, rewards, ends and infos at every step, and several
    autoresets."""
    obs_n, info_n = native.reset(seed=42)
    obs_s, info_s = sync.reset(seed=42)
    np.testing.assert_array_equal(obs_n, obs_s)
    assert_same_infos(info_n, info_s)
    ended = 0
    for a in _actions(native, steps):
        out_n, out_s = native.step(a), sync.step(a)
        assert_same_step(out_n, out_s)
        ended += int(np.count_nonzero(out_s[2] | out_s[3]))
    assert ended >= 2 * native.num_envs  # several autoresets happened


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("mode", [AutoresetMode.NEXT_STEP, AutoresetMode.SAME_STEP])
@pytest.mark.parametrize(("num_envs", "max_episode_steps"), [(3, None), (9, 17)])
@pytest.mark.parametrize(("env_id", "kwargs"), CASES)
def test_autoreset_modes_bit_identical_to_sync(
    env_id, kwargs, num_envs, max_episode_steps, mode, backend
):
    native, sync = make_pair(env_id, kwargs, num_envs, mode, backend, max_episode_steps)
    assert native.metadata["autoreset_mode"] == mode == sync.metadata["autoreset_mode"]
    assert native.unwrapped.backend == backend
    step_against_sync(native, sync, 140)
    native.close()
    sync.close()


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize(("env_id", "kwargs"), CASES)
def test_disabled_mode_matches_sync_with_manual_resets(env_id, kwargs, backend):
    mode = AutoresetMode.DISABLED
    native, sync = make_pair(env_id, kwargs, 4, mode, backend, max_episode_steps=13)
    assert native.metadata["autoreset_mode"] == mode
    np.testing.assert_array_equal(native.reset(seed=7)[0], sync.reset(seed=7)[0])
    acts = _actions(native, 120, seed=3)
    for t, a in enumerate(acts):
        out_n, out_s = native.step(a), sync.step(a)
        assert_same_step(out_n, out_s)
        done = out_s[2] | out_s[3]
        if done.any():
            if t == 12:  # stepping an ended sub-environment is an error, and changes nothing
                with pytest.raises(RuntimeError, match="reset_mask"):
                    native.step(a)
            obs_n, info_n = native.reset(options={"reset_mask": done})
            obs_s, info_s = sync.reset(options={"reset_mask": done.copy()})
            np.testing.assert_array_equal(obs_n, obs_s)
            np.testing.assert_array_equal(info_n["_trajectory_index"], done)
            np.testing.assert_array_equal(
                info_n["trajectory_index"][done], info_s["trajectory_index"][done]
            )


@pytest.mark.skipif(not K.numba_available(), reason="numba not installed")
@pytest.mark.parametrize(("env_id", "kwargs"), CASES)
def test_numba_and_numpy_backends_agree_bit_for_bit(env_id, kwargs):
    """Large batch (the numpy path's batched kernels, not its scalar fallback)."""
    envs = [
        gym.make_vec(env_id, num_envs=64, backend=b, autoreset_mode="SameStep", **kwargs)
        for b in ("numba", "numpy")
    ]
    obs = [env.reset(seed=5)[0] for env in envs]
    np.testing.assert_array_equal(*obs)
    for a in _actions(envs[0], 110, seed=11):
        a[::7] = 0.0  # the zero action: the nominal itself
        assert_same_step(envs[0].step(a), envs[1].step(a))


def test_make_vec_defaults_to_the_native_env_with_next_step():
    env = gym.make_vec(ORIENTATION, num_envs=2)
    assert type(env).__name__ == "OrientationReachVectorEnv"
    assert env.metadata["autoreset_mode"] == AutoresetMode.NEXT_STEP
    env = gym.make_vec(ORIENTATION, num_envs=2, autoreset_mode="SameStep")
    assert env.metadata["autoreset_mode"] == AutoresetMode.SAME_STEP


def test_bad_autoreset_mode_and_backend_name_the_argument():
    with pytest.raises(ValueError, match="autoreset_mode must be"):
        gym.make_vec(ORIENTATION, num_envs=2, autoreset_mode="sometimes")
    with pytest.raises(ValueError, match="backend must be"):
        gym.make_vec(ORIENTATION, num_envs=2, backend="cuda")


def test_vector_kwargs_and_wrappers_fail_with_what_to_do():
    """Gymnasium refuses ``vector_kwargs``/``wrappers`` for a vector entry point before our
    code runs; its messages point at the remedies the README gives."""
    with pytest.raises(gym.error.Error, match="only through kwargs"):
        gym.make_vec(ORIENTATION, 2, vector_kwargs={"autoreset_mode": AutoresetMode.SAME_STEP})
    with pytest.raises(gym.error.Error, match="vector_entry_point"):
        gym.make_vec(ORIENTATION, 2, wrappers=[gym.wrappers.ClipAction])


def test_wrappers_work_with_sync_and_vector_wrappers_with_native():
    from gymnasium.wrappers import vector as vw

    sync = gym.make_vec(
        POSITION, 2, vectorization_mode="sync", wrappers=[gym.wrappers.ClipAction], shapes=SHAPES
    )
    native = vw.RecordEpisodeStatistics(
        vw.NormalizeObservation(gym.make_vec(POSITION, 2, shapes=SHAPES))
    )
    sync.reset(seed=0)
    native.reset(seed=0)
    episodes = 0
    for a in _actions(native, 60):
        sync.step(a)
        *_, info = native.step(a)
        if "episode" in info:
            episodes += int(info["_episode"].sum())
            assert np.all(info["episode"]["l"][info["_episode"]] == 50)
    assert episodes == 2


def test_pooled_draws_equal_one_integers_call_per_reset():
    """The vector envs draw trajectories in blocks; numpy gives the same sequence."""
    for n in (1, 2, 7, 55, 1088, 2**31 + 5):
        one = np.random.default_rng(3)
        block = np.random.default_rng(3)
        assert [int(one.integers(n)) for _ in range(200)] == block.integers(n, size=200).tolist()
