"""Native vector environments: ``N`` episodes stepped together, in one compiled loop.

The classes are defined with their kinds (:mod:`~motion_envs.envs.orientation_reach`,
:mod:`~motion_envs.envs.position_reach`) over one core
(:class:`~motion_envs.envs._reach_vector.ReachVectorEnv`) and re-exported here, the
registrations' ``vector_entry_point``.

``gym.make_vec(id, num_envs=N)`` builds these (the registration's
``vector_entry_point``; ``vectorization_mode="vector_entry_point"`` says so explicitly).
Sub-environment ``i`` is bit-identical to a single environment made with the same
arguments and seeded with ``seed + i`` (as :class:`gymnasium.vector.SyncVectorEnv` seeds
its copies): the step arithmetic and the reward are the same kernels
(:mod:`motion_envs.envs._kernels`), each sub-environment draws its trajectories from its
own generator (the same sequence as ``Generator.integers`` one call per reset), and
episodes end and restart as under ``SyncVectorEnv`` with the same ``autoreset_mode``:

* ``AutoresetMode.NEXT_STEP`` (default): the step after an episode's end resets that
  sub-environment, ignores its action and returns reward 0, not terminated/truncated;
* ``AutoresetMode.SAME_STEP``: the step that ends an episode returns the first
  observation of the next one; the last observation and infos are in
  ``infos["final_obs"]`` (object array) and ``infos["final_info"]`` (masked by
  ``infos["_final_obs"]``/``infos["_final_info"]``), as CleanRL-style loops expect;
* ``AutoresetMode.DISABLED``: no autoreset; reset ended sub-environments with
  ``reset(options={"reset_mask": mask})`` before stepping them again.

This bookkeeping is written once for every native vector environment of the package
(:class:`~motion_envs.envs._native_vector.NativeVectorEnv`): ``seed`` is an int (``seed +
i``), a list of ``N`` seeds or None (each sub-environment keeps its generator);
``reset_mask`` is a bool array ``(N,)`` with a ``True`` entry, and the first reset
resets every sub-environment; anything else is a one-line ``ValueError``.

Pass the mode as ``gym.make_vec(id, N, autoreset_mode=AutoresetMode.SAME_STEP)`` (or
its value ``"SameStep"``); Gymnasium forwards only keyword arguments, not
``vector_kwargs``, to a ``vector_entry_point``. ``max_episode_steps`` (from the
registration) truncates like ``TimeLimit``.

Backends (``backend=``, see :mod:`motion_envs.envs._kernels`): ``"numba"`` runs the
whole step as one compiled loop (:mod:`motion_envs.envs._fused`), ``"numpy"`` as
batched numpy calls; ``"auto"`` (default) takes numba when installed. Both are
bit-identical to ``SyncVectorEnv`` (tested).

``infos`` follow the vector convention: ``infos[key]`` is an ``(N,)`` array and
``infos["_" + key]`` marks the sub-environments it applies to (entries outside the mask
are unspecified, not necessarily 0 as under ``SyncVectorEnv``). A reset (and an
autoreset, in the step's infos) reports the single environments' reset keys as
``SyncVectorEnv`` batches them: ``trajectory_index`` (int64, 0 outside the mask) and
``trajectory_id``, ``task`` (and ``subject`` for orientation) as object arrays of
``str`` (None outside the mask); steps without a reset carry none of them.
Observations, rewards, flags and infos are new arrays every step. Bad arguments raise
the same ``ValueError`` as the single environment's (the checks of
:mod:`motion_envs.envs._common`); a non-numeric ``actions`` (dict, string, complex)
raises ``ValueError``.

The text of the single environments' reset infos is not in the vector infos, so that
every value there is numeric (array converters such as Gymnasium's ``NumpyToTorch``
take them): ``venv.trajectory_labels[key][infos["trajectory_index"][i]]`` gives it back.

Juggling-v0 has no native vector environment: its ``vector_entry_point``,
:func:`juggling_vector_env`, builds a :class:`gymnasium.vector.SyncVectorEnv` of
``gym.make(id, **kwargs)`` copies, so ``gym.make_vec(id, N, autoreset_mode=...)`` takes
the same keyword as the reaching ids (it would otherwise reach the single
environment's constructor and be refused); each copy reports its ``phase`` as an index
of :data:`~motion_envs.envs.juggling.PHASE_NAMES`, as the native juggling vector envs
do (:class:`~motion_envs.envs.juggling.NumericInfo`).
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym

from motion_envs.envs._common import check_autoreset_mode, check_num_envs, env_footprint
from motion_envs.envs._reach_vector import ReachVectorEnv
from motion_envs.envs.orientation_reach import OrientationReachVectorEnv
from motion_envs.envs.position_reach import PositionReachVectorEnv

__all__ = [
    "OrientationReachVectorEnv",
    "PositionReachVectorEnv",
    "ReachVectorEnv",
    "cascade_v1_vector_env",
    "juggling_v0_vector_env",
    "juggling_v2_vector_env",
    "juggling_vector_env",
]


def juggling_vector_env(
    env_id: str,
    num_envs: int = 1,
    autoreset_mode: Any = gym.vector.AutoresetMode.NEXT_STEP,
    **kwargs: Any,
) -> gym.vector.SyncVectorEnv:
    """``SyncVectorEnv`` of ``num_envs`` copies of ``gym.make(env_id, **kwargs)`` with
    ``autoreset_mode`` (an ``AutoresetMode`` or its value)."""
    from motion_envs.envs.juggling import NumericInfo  # MuJoCo: only when asked for

    check_num_envs(num_envs)
    mode = check_autoreset_mode(autoreset_mode)
    probe = gym.make(env_id, **kwargs)  # checks the arguments; its footprint bounds num_envs
    n = check_num_envs(num_envs, env_footprint(probe.unwrapped))
    probe.close()
    env_fns = [lambda: NumericInfo(gym.make(env_id, **kwargs)) for _ in range(n)]
    return gym.vector.SyncVectorEnv(env_fns, autoreset_mode=mode)


def juggling_v0_vector_env(num_envs: int = 1, **kwargs: Any) -> gym.vector.SyncVectorEnv:
    """The ``vector_entry_point`` of ``MotionEnvs/Juggling-v0`` (:func:`juggling_vector_env`)."""
    return juggling_vector_env("MotionEnvs/Juggling-v0", num_envs, **kwargs)


def juggling_v2_vector_env(num_envs: int = 1, **kwargs: Any) -> gym.vector.SyncVectorEnv:
    """The ``vector_entry_point`` of ``MotionEnvs/Juggling-v2`` (:func:`juggling_vector_env`:
    its infos' phase as a number)."""
    return juggling_vector_env("MotionEnvs/Juggling-v2", num_envs, **kwargs)


def cascade_v1_vector_env(num_envs: int = 1, **kwargs: Any) -> gym.vector.SyncVectorEnv:
    """The ``vector_entry_point`` of ``MotionEnvs/Cascade-v1`` (:func:`juggling_vector_env`:
    its infos' phase as a number)."""
    return juggling_vector_env("MotionEnvs/Cascade-v1", num_envs, **kwargs)
