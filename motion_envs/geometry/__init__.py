"""Pure-numpy geometry: unit quaternions, Bézier curves, sine series.

Every function works on batches (leading axes) and states its formula in the docstring.
"""

from motion_envs.geometry import bezier, quaternion, sine_series

__all__ = ["bezier", "quaternion", "sine_series"]
