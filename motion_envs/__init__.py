"""motion-envs: human-like motion models, datasets, Gymnasium environments.

Quaternions are stored scalar first, ``(w, x, y, z)``, everywhere in this package.
"""

__version__ = "0.1.0"

from motion_envs.envs import ENV_IDS  # registers the Gymnasium environments

__all__ = ["ENV_IDS", "__version__"]
