"""
Roll the nominal in a reaching environment
==========================================

``gym.make`` a reaching environment, play one episode under the zero action (the agent's
action is a residual on the analytic model's prediction, so zero *is* the model) and one
under a constant push, and compare the paper's criterion, ``info["max_error"]`` (the max
over the episode of the distance to the human demonstration; mm for the LASA shapes).
"""

import gymnasium as gym
import matplotlib.pyplot as plt
import numpy as np

import motion_envs  # noqa: F401  (registers the ids)

env = gym.make("MotionEnvs/PositionReach-v1", render_mode="rgb_array")
print(env.action_space, env.observation_space.shape)


def episode(action: np.ndarray) -> tuple[float, np.ndarray]:
    """Max error of one seeded episode under a constant action, and its last frame."""
    env.reset(seed=0)
    done = False
    while not done:
        _, _, terminated, truncated, info = env.step(action)
        done = terminated or truncated
    return info["max_error"], env.render()


zero = np.zeros(env.action_space.shape, dtype=np.float32)
nominal_error, frame = episode(zero)
push_error, _ = episode(np.full_like(zero, 0.5))
print(f"max error (mm): nominal {nominal_error:.2f}, constant push {push_error:.2f}")
env.close()

fig, ax = plt.subplots(figsize=(4, 4))
ax.imshow(frame)
ax.set_axis_off()
ax.set_title("the nominal's episode (seed 0)")
plt.show()
