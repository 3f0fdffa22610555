"""Learned-residual regressors competing with the papers' analytic models.

* :mod:`baselines.learned.batched_mlp`: small torch MLPs, many trained at once (one per
  fold and candidate), with nested selection by group (torch imported only there);
* :mod:`baselines.learned.nested`: the nested cross-validation bookkeeping (folds by
  group, selection on inner validation folds only);
* :mod:`baselines.learned.orientation`: features and targets of the orientation rows,
  and the ridge regressor (scikit-learn);
* :mod:`baselines.learned.position`: the ``ridge`` and ``mlp`` columns of LASA;
* :mod:`baselines.learned.model_file`: safetensors weights with a JSON header.

Importing this package does not import torch; :func:`torch_available` says whether the
torch rows can run.
"""

from __future__ import annotations

import importlib.util

__all__ = ["torch_available", "torch_missing_reason"]


def torch_available() -> bool:
    """True when torch can be imported (the ``rl`` extra)."""
    return importlib.util.find_spec("torch") is not None


def torch_missing_reason() -> str | None:
    """``None`` when torch is importable, else a one-line reason with the fix."""
    if torch_available():
        return None
    return "torch is not installed (pip install 'motion-envs[rl]' with a CPU torch build)"
