"""motion-envs: human-like motion models, datasets, Gymnasium environments.

Quaternions are stored scalar first, ``(w, x, y, z)``, everywhere in this package.
"""

__version__ = "0.1.0"

__all__ = ["__version__"]
