"""Cascade-v0's vector environment: ``N`` cascades in one object.

:class:`CascadeVectorEnv` is ``gym.make_vec("MotionEnvs/Cascade-v0", N)``: the episode
bookkeeping of :class:`~motion_envs.envs.juggling._vector.JugglingVectorEnv` (seeds, the
three autoreset modes, batched infos) over ``N`` single
:class:`~motion_envs.envs.juggling.CascadeEnv`, each stepped by its own ``step``:
bit-identical to ``SyncVectorEnv`` (tested), without its per-step overhead, but not
batched (the cascade's world is not compiled yet).
"""

from __future__ import annotations

from motion_envs.envs.juggling._cascade_env import CascadeEnv
from motion_envs.envs.juggling._vector import JugglingVectorEnv

__all__ = ["CascadeVectorEnv"]


class CascadeVectorEnv(JugglingVectorEnv):
    """``num_envs`` Cascade-v0 episodes (see the module docstring).

    Parameters
    ----------
    num_envs : int
        Number of sub-environments.
    autoreset_mode : AutoresetMode or str
        ``NEXT_STEP`` (default), ``SAME_STEP`` or ``DISABLED``.
    **kwargs
        :class:`~motion_envs.envs.juggling.CascadeEnv`'s keyword arguments.
    """

    single_class = CascadeEnv
