"""Cascade-v0's native vector environment: the ``N`` episodes stepped as one batch.

:class:`CascadeVectorEnv` is ``gym.make_vec("MotionEnvs/Cascade-v0", N)``: the batch of
``N`` (:class:`~motion_envs.envs.juggling._cascade_batch.CascadeBatch`) through the same
kernels that step a single environment (its batch of one), with the episode bookkeeping
of :class:`~motion_envs.envs.juggling._vector.JugglingVectorEnv`. Each sub-environment is
bit-identical to ``CascadeEnv`` seeded with ``seed + i`` (as under ``SyncVectorEnv``;
tested for the three autoreset modes). ``backend="numba"`` (the default when installed)
runs the compiled kernels, ``"python"`` the same functions as plain Python.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from motion_envs.envs.juggling._cascade_batch import CascadeBatch, Columns
from motion_envs.envs.juggling._cascade_env import CascadeEnv
from motion_envs.envs.juggling._cascade_step import OUT_COLUMNS
from motion_envs.envs.juggling._vector import JugglingVectorEnv

__all__ = ["CascadeVectorEnv"]

_TERMINATED, _TRUNCATED = OUT_COLUMNS.index("terminated"), OUT_COLUMNS.index("truncated")


class CascadeVectorEnv(JugglingVectorEnv):
    """``num_envs`` Cascade-v0 episodes stepped together (see the module docstring and
    :mod:`motion_envs.envs.juggling._vector`).

    Parameters
    ----------
    num_envs : int
        Number of sub-environments.
    autoreset_mode : AutoresetMode or str
        ``NEXT_STEP`` (default), ``SAME_STEP`` or ``DISABLED``.
    backend : str
        ``"auto"`` (numba when installed), ``"numba"`` or ``"python"``.
    threads : int or None
        Threads stepping the worlds' control periods (numba backend); ``None``: the
        CPUs available. The episodes do not depend on it.
    **kwargs
        :class:`~motion_envs.envs.juggling.CascadeEnv`'s keyword arguments.
    """

    single_class = CascadeEnv
    _batched = True
    _python_batch = True

    def _setup_arrays(self) -> None:
        self._batch = CascadeBatch(self.envs, self.backend, self.threads)
        for i, env in enumerate(self.envs):  # each episode is a row of this batch
            env._batch, env._rows = self._batch, np.array([i], dtype=np.int64)

    def _step_batch(self, envs: NDArray[np.int64], actions: NDArray[np.float64]) -> tuple[
        NDArray[np.float32], NDArray[np.float64], NDArray[np.bool_], NDArray[np.bool_], Columns
    ]:  # fmt: skip
        obs, out = self._batch.step(envs, np.ascontiguousarray(actions, dtype=np.float64))
        term, trunc = out[:, _TERMINATED] > 0.0, out[:, _TRUNCATED] > 0.0
        return obs, out[:, 0], term, trunc, self._batch.columns(out)
