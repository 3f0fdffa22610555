"""``MotionEnvs/Juggling-v0`` and ``-v1``: the environments, their MuJoCo scenes and MJCFs.

The public names of small private modules: ``_env`` (:class:`JugglingEnv`, the registered
entry point ``motion_envs.envs.juggling:JugglingEnv``), ``_scene`` (:class:`JugglingScene`,
the MuJoCo world, compiled from ``juggling.xml`` beside them); ``_v1_env``
(:class:`JugglingV1Env`, entry point ``motion_envs.envs.juggling:JugglingV1Env``) and
``_v1_scene`` (:class:`JugglingV1World`: contacts, an actuated hand, compiled from
``juggling_v1.xml``); ``_cascade_env`` (:class:`CascadeEnv`, ``MotionEnvs/Cascade-v0``,
entry point ``motion_envs.envs.juggling:CascadeEnv``) and ``_cascade_scene``
(:class:`CascadeWorld`: two hands, three balls, compiled from ``cascade.xml``); the native
vector environments ``_vector`` (:class:`JugglingVectorEnv`, the episode bookkeeping),
``_v1_vector`` (:class:`JugglingV1VectorEnv`) and ``_cascade_vector``
(:class:`CascadeVectorEnv`), batched, with ``_compiled``: the worlds' control periods
compiled by numba.
The default fit the environment acts on (``load_juggler``, ``juggler_demonstrations``,
``TRACKING_NOISE``, ``FIT_SEED``, ``FIT_TEST_FRACTION``) lives in
:mod:`motion_envs.models.juggling` and is re-exported here for code that imported it
from this module's former place.
"""

from motion_envs.envs.juggling._cascade_env import (
    CASCADE_HISTORY,
    CASCADE_OBS_DIM,
    CASCADE_TIME_PER_CATCH,
    DEFAULT_CASCADE_REWARD_WEIGHTS,
    CascadeEnv,
)
from motion_envs.envs.juggling._cascade_scene import (
    CASCADE_SCENE_XML,
    CascadeWorld,
    load_cascade_model,
)
from motion_envs.envs.juggling._cascade_vector import CascadeVectorEnv
from motion_envs.envs.juggling._env import (
    CYCLE_TIME_LIMIT,
    DEFAULT_JUGGLING_REWARD_WEIGHTS,
    HAND_SPEED_MARGIN,
    OBS_DIM,
    POSITION_MARGIN,
    JugglingEnv,
)
from motion_envs.envs.juggling._scene import (
    SCENE_XML,
    JugglingScene,
    check_task,
    load_juggling_model,
)
from motion_envs.envs.juggling._v1_env import (
    DEFAULT_V1_REWARD_WEIGHTS,
    HISTORY,
    V1_CYCLE_TIME,
    V1_OBS_DIM,
    JugglingV1Env,
)
from motion_envs.envs.juggling._v1_scene import (
    CAPTURE_SPEED,
    HAND_ACCEL_LIMIT,
    HAND_MASS,
    HAND_SPEED_LIMIT,
    SERVO_OMEGA,
    SUBSTEPS,
    V1_SCENE_XML,
    JugglingPhysics,
    JugglingV1World,
    load_juggling_v1_model,
)
from motion_envs.envs.juggling._v1_vector import JugglingV1VectorEnv
from motion_envs.envs.juggling._vector import JugglingVectorEnv
from motion_envs.models.juggling import (
    FIT_SEED,
    FIT_TEST_FRACTION,
    PAPER_GRAVITY,
    TRACKING_NOISE,
    cycle_rngs,
    juggler_demonstrations,
    load_juggler,
)

__all__ = [
    "CAPTURE_SPEED",
    "CASCADE_HISTORY",
    "CASCADE_OBS_DIM",
    "CASCADE_SCENE_XML",
    "CASCADE_TIME_PER_CATCH",
    "CYCLE_TIME_LIMIT",
    "DEFAULT_CASCADE_REWARD_WEIGHTS",
    "DEFAULT_JUGGLING_REWARD_WEIGHTS",
    "DEFAULT_V1_REWARD_WEIGHTS",
    "FIT_SEED",
    "FIT_TEST_FRACTION",
    "HAND_ACCEL_LIMIT",
    "HAND_MASS",
    "HAND_SPEED_LIMIT",
    "HAND_SPEED_MARGIN",
    "HISTORY",
    "OBS_DIM",
    "PAPER_GRAVITY",
    "POSITION_MARGIN",
    "SCENE_XML",
    "SERVO_OMEGA",
    "SUBSTEPS",
    "TRACKING_NOISE",
    "V1_CYCLE_TIME",
    "V1_OBS_DIM",
    "V1_SCENE_XML",
    "CascadeEnv",
    "CascadeVectorEnv",
    "CascadeWorld",
    "JugglingEnv",
    "JugglingPhysics",
    "JugglingScene",
    "JugglingV1Env",
    "JugglingV1VectorEnv",
    "JugglingV1World",
    "JugglingVectorEnv",
    "check_task",
    "cycle_rngs",
    "juggler_demonstrations",
    "load_cascade_model",
    "load_juggler",
    "load_juggling_model",
    "load_juggling_v1_model",
]
