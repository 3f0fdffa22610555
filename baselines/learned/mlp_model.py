"""A fitted residual MLP as an estimator: ``fit`` / ``predict`` / ``save`` / ``load``.

:class:`ResidualMLP` wraps one network of :mod:`baselines.learned.batched_mlp`. ``fit``
chooses the weight decay, base and epochs by inner folds over ``groups`` (subjects)
of the data it is given (:func:`baselines.learned.nested.nested_mlp` with one outer fold
holding every row), then trains on every row. ``save`` writes a safetensors model file
(:mod:`baselines.learned.model_file`); ``load`` checks it and rebuilds the network.
Predictions after ``save`` -> ``load`` are bit-identical.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from baselines.learned.model_file import (
    data_hash,
    model_file_error,
    read_model_file,
    write_model_file,
)

__all__ = ["KIND", "ResidualMLP"]

KIND = "residual-mlp"
_TENSORS = ("W1", "b1", "W2", "b2", "x_mean", "x_scale", "y_base", "y_scale")


def _tensor_shapes(n_in: int, hidden: int, n_out: int) -> dict[str, tuple[int, ...]]:
    """The shape of every tensor of a network with these sizes (what ``fit`` stores)."""
    return {
        "W1": (n_in, hidden),
        "b1": (hidden,),
        "W2": (hidden, n_out),
        "b2": (n_out,),
        "x_mean": (n_in,),
        "x_scale": (n_in,),
        "y_base": (n_out,),
        "y_scale": (1,),
    }


class ResidualMLP:
    """One residual MLP (architecture in :mod:`baselines.learned.batched_mlp`).

    Parameters
    ----------
    config:
        :class:`~baselines.learned.batched_mlp.MLPConfig` (default: its defaults).
    features:
        JSON-able description of the feature encoding and target (stored in the file).

    Fitted attributes: ``params_`` (name -> float32 array), ``chosen_``,
    ``training_data_sha256_``.
    """

    def __init__(self, config: Any | None = None, features: dict[str, Any] | None = None):
        from baselines.learned.batched_mlp import MLPConfig

        self.config = config if config is not None else MLPConfig()
        self.features = dict(features or {})

    def fit(self, X: ArrayLike, Y: ArrayLike, groups: ArrayLike) -> ResidualMLP:
        """Fit to conditions ``(N, p)``, targets ``(N, m)`` and groups ``(N,)``; returns self."""
        from baselines.learned.nested import nested_mlp

        X = np.asarray(X, dtype=np.float64)
        Y = np.asarray(Y, dtype=np.float64)
        if X.ndim != 2 or Y.ndim != 2 or X.shape[0] != Y.shape[0]:
            raise ValueError(f"X must be (N, p) and Y (N, m); got {X.shape} and {Y.shape}")
        everything = np.arange(X.shape[0])
        res = nested_mlp(X, Y, np.asarray(groups), [(everything, everything)], self.config)
        self.params_ = {k: np.ascontiguousarray(v) for k, v in res.params[0].items()}
        self.chosen_ = res.chosen[0]
        self.training_data_sha256_ = data_hash(X, Y)
        return self

    def predict(self, X: ArrayLike) -> NDArray[np.float64]:
        """Predicted targets ``(N, m)``."""
        import torch

        from baselines.learned.batched_mlp import deterministic_torch, forward

        if not hasattr(self, "params_"):
            raise RuntimeError("ResidualMLP is not fitted; call fit() or load() first")
        X = np.asarray(X, dtype=np.float32)
        p = self.params_["W1"].shape[0]
        if X.ndim != 2 or X.shape[1] != p:
            raise ValueError(f"X must have shape (N, {p}); got {X.shape}")
        with deterministic_torch(), torch.no_grad():
            params = {k: torch.from_numpy(v.copy())[None] for k, v in self.params_.items()}
            params["y_scale"] = params["y_scale"].reshape(1)
            out = forward(params, torch.from_numpy(X)[None])
        return out[0].numpy().astype(np.float64)

    def architecture(self) -> dict[str, Any]:
        """The architecture fields of the model file."""
        W1, W2 = self.params_["W1"], self.params_["W2"]
        return {
            "kind": KIND,
            "n_inputs": int(W1.shape[0]),
            "hidden": int(W1.shape[1]),
            "n_outputs": int(W2.shape[1]),
            "activation": "tanh",
        }

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write the model file (atomic); returns the path."""
        if not hasattr(self, "params_"):
            raise RuntimeError("ResidualMLP is not fitted; nothing to save")
        header = {
            "architecture": self.architecture(),
            "features": self.features,
            "normalisation": {
                "inputs": "(x - x_mean) / x_scale",
                "outputs": "y_base + y_scale * network(x)",
            },
            "training_data_sha256": self.training_data_sha256_,
            "extra": {"chosen": self.chosen_, "config": repr(self.config)},
        }
        return write_model_file(path, {k: self.params_[k] for k in _TENSORS}, header)

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> ResidualMLP:
        """Read a model file written by :meth:`save` (checks in :mod:`.model_file`)."""
        tensors, header = read_model_file(path, expected_kind=KIND)
        p = str(path)
        missing = [k for k in _TENSORS if k not in tensors]
        if missing:
            raise model_file_error(p, f"tensors {missing} are missing")
        arch = header["architecture"]
        for name in ("W1", "W2"):
            if tensors[name].ndim != 2:
                raise model_file_error(
                    p, f"tensor {name!r} has shape {tensors[name].shape}, expected a matrix"
                )
        (n_in, hidden), n_out = tensors["W1"].shape, tensors["W2"].shape[1]
        expected = {"n_inputs": n_in, "hidden": hidden, "n_outputs": n_out}
        for field, value in expected.items():
            if arch.get(field) != value:
                raise model_file_error(
                    p,
                    f"field 'architecture.{field}' is {arch.get(field)!r} but the weights "
                    f"have {value}",
                )
        for name, shape in _tensor_shapes(n_in, hidden, n_out).items():
            if tensors[name].shape != shape or tensors[name].dtype != np.float32:
                raise model_file_error(
                    p,
                    f"tensor {name!r} is {tensors[name].dtype}{list(tensors[name].shape)}, "
                    f"expected float32{list(shape)}",
                )
        if not (tensors["x_scale"] > 0).all():
            raise model_file_error(p, "tensor 'x_scale' must be positive")
        if arch.get("activation") != "tanh":
            raise model_file_error(
                p, f"field 'architecture.activation' is {arch.get('activation')!r}"
            )
        model = cls(features=header.get("features"))
        model.params_ = {k: tensors[k] for k in _TENSORS}
        model.chosen_ = header.get("extra", {}).get("chosen", {})
        model.training_data_sha256_ = header.get("training_data_sha256", "")
        return model
