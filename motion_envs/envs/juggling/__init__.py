"""``MotionEnvs/Juggling-v0``: the environment, its MuJoCo scene and the scene's MJCF.

The public names of small private modules: ``_env`` (:class:`JugglingEnv`, the registered
entry point ``motion_envs.envs.juggling:JugglingEnv``), ``_scene`` (:class:`JugglingScene`,
the MuJoCo world, compiled from ``juggling.xml`` beside them). The default fit the
environment acts on (``load_juggler``, ``juggler_demonstrations``, ``TRACKING_NOISE``,
``FIT_SEED``, ``FIT_TEST_FRACTION``) lives in :mod:`motion_envs.models.juggling` and is
re-exported here for code that imported it from this module's former place.
"""

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
from motion_envs.models.juggling import (
    FIT_SEED,
    FIT_TEST_FRACTION,
    TRACKING_NOISE,
    cycle_rngs,
    juggler_demonstrations,
    load_juggler,
)

__all__ = [
    "CYCLE_TIME_LIMIT",
    "DEFAULT_JUGGLING_REWARD_WEIGHTS",
    "FIT_SEED",
    "FIT_TEST_FRACTION",
    "HAND_SPEED_MARGIN",
    "OBS_DIM",
    "POSITION_MARGIN",
    "SCENE_XML",
    "TRACKING_NOISE",
    "JugglingEnv",
    "JugglingScene",
    "check_task",
    "cycle_rngs",
    "juggler_demonstrations",
    "load_juggler",
    "load_juggling_model",
]
