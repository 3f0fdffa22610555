"""Learned-residual regressors competing with the papers' analytic models.

* :mod:`baselines.learned.batched_mlp`: small torch MLPs, many trained at once (one per
  fold and candidate), with nested selection by group (torch imported only there);
* :mod:`baselines.learned.nested`: the nested cross-validation bookkeeping (folds by
  group, selection on inner validation folds only);
* :mod:`baselines.learned.orientation`: features and targets of the orientation rows,
  and the ridge regressor (scikit-learn);
* :mod:`baselines.learned.position`: the ``ridge`` and ``mlp`` columns of LASA;
* :mod:`baselines.learned.model_file`: safetensors weights with a JSON header.
* :mod:`baselines.learned.delay_estimator`: a learned delay rule for the juggling envs'
  release-anchored estimate (ridge or a small MLP, chosen by grouped K-fold CV over
  training episodes), the row ``learned_estimator_catch``.

Importing this package does not import torch; :func:`torch_available` says whether the
torch rows can run.
"""

from __future__ import annotations

import importlib.util
from typing import Any

__all__ = [
    "LEARNED_MODES",
    "QUICK_MLP",
    "add_learned_option",
    "mlp_config",
    "sklearn_missing_reason",
    "torch_available",
    "torch_missing_reason",
]

#: Budgets of the learned rows and columns (``--learned``): ``full`` (nested selection
#: over every candidate), ``quick`` (:data:`QUICK_MLP`: one candidate, 30 epochs, 2
#: inner folds), ``off`` (none).
LEARNED_MODES: tuple[str, ...] = ("full", "quick", "off")


def add_learned_option(parser: Any, what: str, note: str) -> None:
    """Add ``--learned`` (:data:`LEARNED_MODES`, default ``full``) to a sub-command's
    ``parser``; its help: ``what`` the budget covers, the modes, then ``note``."""
    parser.add_argument(
        "--learned",
        choices=LEARNED_MODES,
        default="full",
        help=f"{what} (docs/learned.md); quick: one MLP candidate, 30 epochs, 2 inner folds; "
        f"off: none; {note}",
    )


def torch_available() -> bool:
    """True when torch can be imported (the ``rl`` extra)."""
    return importlib.util.find_spec("torch") is not None


def torch_missing_reason() -> str | None:
    """``None`` when torch is importable, else a one-line reason with the fix."""
    if torch_available():
        return None
    return "torch is not installed (pip install 'motion-envs[rl]' with a CPU torch build)"


def sklearn_missing_reason() -> str | None:
    """``None`` when scikit-learn is importable, else a one-line reason with the fix."""
    if importlib.util.find_spec("sklearn") is not None:
        return None
    return "scikit-learn is not installed (pip install 'motion-envs[learned]')"


def mlp_config(mode: str) -> Any:
    """The :class:`~baselines.learned.batched_mlp.MLPConfig` of budget ``mode``
    (``full`` or ``quick``; imports torch)."""
    from baselines.learned.batched_mlp import MLPConfig

    if mode == "full":
        return MLPConfig()
    if mode == "quick":
        return __getattr__("QUICK_MLP")
    raise ValueError(f"learned budget must be 'full' or 'quick'; got {mode!r}")


def __getattr__(name: str) -> Any:  # lazy: QUICK_MLP needs torch only when used
    if name == "QUICK_MLP":
        from baselines.learned.batched_mlp import MLPConfig

        #: The ``--learned quick`` budget: one candidate, 30 epochs, 2 inner folds.
        return MLPConfig(max_epochs=30, weight_decays=(0.1,), bases=("mean",), inner_splits=2)
    raise AttributeError(name)
