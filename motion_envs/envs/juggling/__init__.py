"""``MotionEnvs/Juggling-v0``, ``-v1`` and ``Cascade-v0``: the environments and their worlds.

The public names of small private modules: ``_env`` (:class:`JugglingEnv`, the registered
entry point ``motion_envs.envs.juggling:JugglingEnv``, the paper's kinematic setting) and
``_scene`` (:class:`JugglingScene`, compiled from ``juggling.xml`` beside them). The one
world of actuated hands and balls that Juggling-v1 and Cascade-v0 share: ``_world_spec``
(:class:`WorldSpec`, what a world is: hands, balls, the task's constants, the hands' and
the catch's limits), ``_world_mjcf`` (:func:`world_mjcf`, its MJCF), ``_world``
(:class:`HandsWorld`, the world on MuJoCo) and ``_period`` (the one control period: servo,
physics, grasp rule, release, plain Python and compiled by numba in ``_compiled``); ``_v1_scene``
(:class:`JugglingV1World`, one hand and one ball) and ``_cascade_scene``
(:class:`CascadeWorld`, two hands and a pattern's balls) are its batches of one with their
task's state types; ``_v1_env`` (:class:`JugglingV1Env`, and ``OneBallEnv``, what it
shares with Juggling-v2), ``_v2_env`` (:class:`JugglingV2Env`: a hidden delay, a
position-only camera, air drag, the capture at impact; stepped by Juggling-v1's batch of
one, ``V2Batch``), ``_cascade_env``
(:class:`CascadeEnv`) and ``_cascade_v1_env`` (:class:`CascadeV1Env`: Cascade-v0's
patterns at Juggling-v2's human levels) the environments; ``_batch`` (the worlds' state
as one batch) and
``_v1_batch`` (Juggling-v1's step for a batch, written once in ``_v1_step``: the single
environment is its batch of one), ``_cascade_batch`` (Cascade-v0's, written once in
``_cascade_step``; the same); the native vector environments ``_vector``
(:class:`JugglingVectorEnv`, the episode bookkeeping), ``_v1_vector``
(:class:`JugglingV1VectorEnv`) and ``_cascade_vector`` (:class:`CascadeVectorEnv`), each
its id's batch of N.
The default fit the environment acts on (``load_juggler``, ``juggler_demonstrations``,
``TRACKING_NOISE``, ``FIT_SEED``, ``FIT_TEST_FRACTION``) lives in
:mod:`motion_envs.models.juggling` and is re-exported here.
"""

from motion_envs.envs.juggling._cascade_env import (
    CASCADE_HISTORY,
    CASCADE_OBS_DIM,
    CASCADE_TIME_PER_CATCH,
    DEFAULT_CASCADE_REWARD_WEIGHTS,
    CascadeEnv,
    cascade_obs_dim,
)
from motion_envs.envs.juggling._cascade_scene import CascadeWorld
from motion_envs.envs.juggling._cascade_v1_env import (
    CASCADE_V1_FRAMES,
    CascadeV1Env,
    cascade_v1_obs_dim,
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
from motion_envs.envs.juggling._v1_scene import JugglingV1World
from motion_envs.envs.juggling._v1_vector import JugglingV1VectorEnv
from motion_envs.envs.juggling._v2_env import AIR_DENSITY, FRAMES, V2_OBS_DIM, JugglingV2Env
from motion_envs.envs.juggling._vector import (
    PHASE_NAMES,
    JugglingVectorEnv,
    NumericInfo,
    numeric_info,
)
from motion_envs.envs.juggling._world import HandsWorld
from motion_envs.envs.juggling._world_mjcf import load_world_model, world_mjcf
from motion_envs.envs.juggling._world_spec import (
    CAPTURE_SPEED,
    HAND_ACCEL_LIMIT,
    HAND_MASS,
    HAND_SPEED_LIMIT,
    MAX_BALLS,
    SERVO_OMEGA,
    SUBSTEPS,
    WorldSpec,
)
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
    "AIR_DENSITY",
    "CAPTURE_SPEED",
    "CASCADE_HISTORY",
    "CASCADE_OBS_DIM",
    "CASCADE_TIME_PER_CATCH",
    "CASCADE_V1_FRAMES",
    "CYCLE_TIME_LIMIT",
    "DEFAULT_CASCADE_REWARD_WEIGHTS",
    "DEFAULT_JUGGLING_REWARD_WEIGHTS",
    "DEFAULT_V1_REWARD_WEIGHTS",
    "FIT_SEED",
    "FIT_TEST_FRACTION",
    "FRAMES",
    "HAND_ACCEL_LIMIT",
    "HAND_MASS",
    "HAND_SPEED_LIMIT",
    "HAND_SPEED_MARGIN",
    "HISTORY",
    "MAX_BALLS",
    "OBS_DIM",
    "PAPER_GRAVITY",
    "PHASE_NAMES",
    "POSITION_MARGIN",
    "SCENE_XML",
    "SERVO_OMEGA",
    "SUBSTEPS",
    "TRACKING_NOISE",
    "V1_CYCLE_TIME",
    "V1_OBS_DIM",
    "V2_OBS_DIM",
    "CascadeEnv",
    "CascadeV1Env",
    "CascadeVectorEnv",
    "CascadeWorld",
    "HandsWorld",
    "JugglingEnv",
    "JugglingScene",
    "JugglingV1Env",
    "JugglingV1VectorEnv",
    "JugglingV1World",
    "JugglingV2Env",
    "JugglingVectorEnv",
    "NumericInfo",
    "WorldSpec",
    "cascade_obs_dim",
    "cascade_v1_obs_dim",
    "check_task",
    "cycle_rngs",
    "juggler_demonstrations",
    "load_juggler",
    "load_juggling_model",
    "load_world_model",
    "numeric_info",
    "world_mjcf",
]
