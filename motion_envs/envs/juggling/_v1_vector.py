"""Juggling-v1's native vector environment: the ``N`` episodes stepped as one batch.

:class:`JugglingV1VectorEnv` is ``gym.make_vec("MotionEnvs/Juggling-v1", N)``: the
batch of ``N`` (:class:`~motion_envs.envs.juggling._v1_batch.V1Batch`) through the same
kernels that step a single environment (its batch of one), with the episode bookkeeping
of :class:`~motion_envs.envs.juggling._vector.JugglingVectorEnv`. Each sub-environment is
bit-identical to ``JugglingV1Env`` seeded with ``seed + i`` (as under ``SyncVectorEnv``;
tested for the three autoreset modes). ``backend="numba"`` (the default when installed)
runs the compiled kernels, ``"python"`` the same functions as plain Python.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from motion_envs.envs.juggling._v1_batch import Columns, V1Batch
from motion_envs.envs.juggling._v1_env import JugglingV1Env
from motion_envs.envs.juggling._vector import JugglingVectorEnv

__all__ = ["JugglingV1VectorEnv"]


class JugglingV1VectorEnv(JugglingVectorEnv):
    """``num_envs`` Juggling-v1 episodes stepped together (see the module docstring and
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
        :class:`~motion_envs.envs.juggling.JugglingV1Env`'s keyword arguments.
    """

    single_class = JugglingV1Env
    _batched = True
    _python_batch = True

    def _setup_arrays(self) -> None:
        self._batch = V1Batch(self.envs, self.backend, self.threads)
        for i, env in enumerate(self.envs):  # each episode is a row of this batch
            env._batch, env._rows = self._batch, np.array([i], dtype=np.int64)

    def _step_batch(self, envs: NDArray[np.int64], actions: NDArray[np.float64]) -> tuple[
        NDArray[np.float32], NDArray[np.float64], NDArray[np.bool_], NDArray[np.bool_], Columns
    ]:  # fmt: skip
        obs, out = self._batch.step(envs, actions)
        return obs, out[:, 0], out[:, 17] > 0.0, out[:, 18] > 0.0, self._batch.columns(out)
