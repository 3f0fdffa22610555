"""Gymnasium environments of motion-envs, registered at import.

``import motion_envs`` registers every id in :data:`ENV_IDS` with ``gymnasium.register``
(Gymnasium no longer reads entry points); ``gym.make("motion_envs:MotionEnvs/...")``
imports the package itself. The environment modules (numpy, scipy, the datasets) are
imported only when an environment is made.

=========================================  ========================================================
id                                         environment
=========================================  ========================================================
``MotionEnvs/OrientationReach-v0``         :class:`~.orientation_reach.OrientationReachEnv`
``MotionEnvs/PositionReach-v0``            :class:`~.position_reach.PositionReachEnv`
``MotionEnvs/OrientationReach-v1``         the same, observing duration and elapsed time
``MotionEnvs/PositionReach-v1``            the same, observing duration and elapsed time
``MotionEnvs/OrientationCoefficients-v0``  one step per movement (:mod:`.orientation_coefficients`)
``MotionEnvs/PositionCoefficients-v0``     one step per movement (:mod:`.position_coefficients`)
``MotionEnvs/Juggling-v0``                 :class:`~.juggling.JugglingEnv` (MuJoCo)
``MotionEnvs/Juggling-v1``                 :class:`~.juggling.JugglingV1Env` (contacts)
``MotionEnvs/Juggling-v2``                 :class:`~.juggling.JugglingV2Env` (delay, camera, drag)
``MotionEnvs/Cascade-v0``                  :class:`~.juggling.CascadeEnv` (three balls, two hands)
``MotionEnvs/Cascade-v1``                  :class:`~.juggling.CascadeV1Env` (human levels)
=========================================  ========================================================

The two reaching environments come with a native vector environment
(:mod:`motion_envs.envs.vector`), which ``gym.make_vec(id, num_envs=N)`` builds by
default: one compiled loop over the sub-environments (numpy without numba), bit-identical
to ``SyncVectorEnv``, with
``autoreset_mode=`` ``NEXT_STEP`` (default), ``SAME_STEP`` or ``DISABLED``. Juggling-v1's
(:class:`~.juggling.JugglingV1VectorEnv`) batches the episodes' control periods and calls
MuJoCo's ``mj_step`` from one compiled loop, and so does Cascade-v0's
(:class:`~.juggling.CascadeVectorEnv`); both are bit-identical to ``SyncVectorEnv``. Processes that
never imported the package (SB3's ``SubprocVecEnv`` workers, ``python -c``) use the
``motion_envs:MotionEnvs/...`` form of an id.
"""

from __future__ import annotations

import gymnasium

__all__ = ["ENV_IDS", "register_envs"]

_SPECS: dict[str, dict[str, object]] = {
    "MotionEnvs/OrientationReach-v0": {
        "entry_point": "motion_envs.envs.orientation_reach:OrientationReachEnv",
        "vector_entry_point": "motion_envs.envs.vector:OrientationReachVectorEnv",
        "max_episode_steps": 50,
    },
    "MotionEnvs/PositionReach-v0": {
        "entry_point": "motion_envs.envs.position_reach:PositionReachEnv",
        "vector_entry_point": "motion_envs.envs.vector:PositionReachVectorEnv",
        "max_episode_steps": 50,
    },
    # v1: the observation also holds the movement's duration and the elapsed time
    "MotionEnvs/OrientationReach-v1": {
        "entry_point": "motion_envs.envs.orientation_reach:OrientationReachEnv",
        "vector_entry_point": "motion_envs.envs.vector:OrientationReachVectorEnv",
        "max_episode_steps": 50,
        "kwargs": {"observe_timing": True},
    },
    "MotionEnvs/PositionReach-v1": {
        "entry_point": "motion_envs.envs.position_reach:PositionReachEnv",
        "vector_entry_point": "motion_envs.envs.vector:PositionReachVectorEnv",
        "max_episode_steps": 50,
        "kwargs": {"observe_timing": True},
    },
    # one step per movement: the context in, residual coefficients out (black-box)
    "MotionEnvs/OrientationCoefficients-v0": {
        "entry_point": "motion_envs.envs.orientation_coefficients:OrientationCoefficientsEnv",
        "vector_entry_point": (
            "motion_envs.envs.orientation_coefficients:OrientationCoefficientsVectorEnv"
        ),
        "max_episode_steps": 1,
    },
    "MotionEnvs/PositionCoefficients-v0": {
        "entry_point": "motion_envs.envs.position_coefficients:PositionCoefficientsEnv",
        "vector_entry_point": (
            "motion_envs.envs.position_coefficients:PositionCoefficientsVectorEnv"
        ),
        "max_episode_steps": 1,
    },
    "MotionEnvs/Juggling-v0": {
        "entry_point": "motion_envs.envs.juggling:JugglingEnv",
        "vector_entry_point": "motion_envs.envs.vector:juggling_v0_vector_env",
    },
    "MotionEnvs/Juggling-v1": {
        "entry_point": "motion_envs.envs.juggling:JugglingV1Env",
        "vector_entry_point": "motion_envs.envs.juggling:JugglingV1VectorEnv",
    },
    "MotionEnvs/Juggling-v2": {
        "entry_point": "motion_envs.envs.juggling:JugglingV2Env",
        "vector_entry_point": "motion_envs.envs.vector:juggling_v2_vector_env",
    },
    "MotionEnvs/Cascade-v0": {
        "entry_point": "motion_envs.envs.juggling:CascadeEnv",
        "vector_entry_point": "motion_envs.envs.juggling:CascadeVectorEnv",
    },
    "MotionEnvs/Cascade-v1": {
        "entry_point": "motion_envs.envs.juggling:CascadeV1Env",
        "vector_entry_point": "motion_envs.envs.vector:cascade_v1_vector_env",
    },
}

#: Every environment id registered by ``import motion_envs``.
ENV_IDS: tuple[str, ...] = tuple(_SPECS)


def register_envs() -> None:
    """Register every id of :data:`ENV_IDS` (idempotent)."""
    for env_id, spec in _SPECS.items():
        if env_id not in gymnasium.registry:
            gymnasium.register(id=env_id, **spec)  # type: ignore[arg-type]


register_envs()
