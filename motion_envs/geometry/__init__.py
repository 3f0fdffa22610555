"""Pure-numpy geometry: unit quaternions, Bézier curves, sine series, Beta speed profiles,
minimum-jerk movements.

Every function works on batches (leading axes) and states its formula in the docstring.
"""

from motion_envs.geometry import beta_profile, bezier, jerk, quaternion, sine_series

__all__ = ["beta_profile", "bezier", "jerk", "quaternion", "sine_series"]
