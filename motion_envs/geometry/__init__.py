"""Pure-numpy geometry: unit quaternions, Bézier curves, sine series.

Every function works on batches (leading axes) and states its formula in the docstring.
"""

from motion_envs.geometry import bezier, quaternion

__all__ = ["bezier", "quaternion"]
