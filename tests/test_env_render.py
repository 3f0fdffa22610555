"""Rendering of the reaching environments: rgb_array frames over an episode, the MuJoCo hand
frame, RecordVideo (the first frame and render() without a mode of every id:
``test_env_contract.py``)."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import motion_envs  # noqa: F401

ORIENTATION = "MotionEnvs/OrientationReach-v0"
POSITION = "MotionEnvs/PositionReach-v0"
SHAPES = ["GShape"]


def _frames(env: gym.Env, steps: int) -> list[np.ndarray]:
    env.reset(seed=0)
    frames = [env.render()]
    for _ in range(steps):
        env.step(np.full(env.action_space.shape, 0.8, np.float32))
        frames.append(env.render())
    return frames


@pytest.mark.parametrize(("env_id", "kwargs"), [(ORIENTATION, {}), (POSITION, {"shapes": SHAPES})])
def test_rgb_array_frames(env_id, kwargs):
    env = gym.make(env_id, render_mode="rgb_array", width=160, height=120, **kwargs)
    frames = _frames(env, 10)
    for f in frames:
        assert f.dtype == np.uint8 and f.shape == (120, 160, 3)
    assert not np.array_equal(frames[0], frames[-1])  # the agent moved
    assert len({f.tobytes() for f in frames}) > 5
    env.close()
    env.close()


def test_orientation_uses_the_mujoco_hand_frame(mujoco_gl):
    from motion_envs.envs.rendering import HandFrameRenderer

    renderer = HandFrameRenderer(96, 96, backend="mujoco")
    q = np.tile([1.0, 0.0, 0.0, 0.0], (50, 1))
    frame = renderer.render(q, q, q[:1], 0)
    assert frame.shape == (96, 96, 3) and frame.dtype == np.uint8
    # turning the agent's frame by 90 degrees changes the picture
    turned = np.array([[np.cos(np.pi / 4), 0.0, 0.0, np.sin(np.pi / 4)]])
    assert not np.array_equal(frame, renderer.render(q, q, turned, 0))
    renderer.close()
    renderer.close()


def test_matplotlib_fallback_of_the_hand_frame():
    from motion_envs.envs.rendering import HandFrameRenderer

    renderer = HandFrameRenderer(100, 80, backend="matplotlib")
    assert renderer.backend == "matplotlib"
    q = np.tile([1.0, 0.0, 0.0, 0.0], (50, 1))
    frame = renderer.render(q, q, q[:3], 2)
    assert frame.shape == (80, 100, 3) and frame.dtype == np.uint8
    with pytest.raises(ValueError, match="backend"):
        HandFrameRenderer(backend="opengl")


def test_vector_env_renders_every_sub_env():
    env = gym.make_vec(
        POSITION,
        num_envs=2,
        vectorization_mode="vector_entry_point",
        render_mode="rgb_array",
        width=64,
        height=64,
        shapes=SHAPES,
    )
    env.reset(seed=0)
    env.step(np.zeros((2, 2), np.float32))
    frames = env.render()
    assert len(frames) == 2 and all(f.shape == (64, 64, 3) for f in frames)


@pytest.mark.parametrize(("env_id", "kwargs"), [(ORIENTATION, {}), (POSITION, {"shapes": SHAPES})])
def test_record_video(tmp_path, env_id, kwargs):
    pytest.importorskip("moviepy", reason="RecordVideo needs moviepy (the test extra)")
    from gymnasium.wrappers import RecordVideo

    env = gym.make(env_id, render_mode="rgb_array", width=96, height=96, **kwargs)
    folder = tmp_path / "videos"
    env = RecordVideo(env, str(folder), episode_trigger=lambda e: e == 0, disable_logger=True)
    env.reset(seed=0)
    done = False
    while not done:
        _, _, terminated, truncated, _ = env.step(env.action_space.sample())
        done = terminated or truncated
    env.close()
    videos = list(folder.glob("*.mp4"))
    assert len(videos) == 1 and videos[0].stat().st_size > 1000
