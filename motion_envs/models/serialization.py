"""Saving and loading fitted models as versioned JSON, written atomically.

File format (``motion-envs-model``, version 1), one JSON object::

    {
      "format": "motion-envs-model",
      "format_version": 1,
      "model": "<registered class name>",
      "params": {...},                       # constructor arguments (JSON values)
      "arrays": {"name": {"dtype": "float64", "shape": [...], "data": [...]}, ...},
      "attributes": {...}                    # other fitted attributes (JSON values)
    }

Floats are written with Python's shortest round-trip ``repr``, so a float64 array read
back is bit-identical to the one written. No pickle: a model file cannot run code.

A model class takes part by subclassing :class:`SerializableModel` and implementing
``_get_state()`` / ``_set_state()``; it is registered under its class name.
Writes go to a temporary file in the same folder, are flushed to disk, then renamed
over the target (``os.replace``), so a failed write never leaves half a file.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any, ClassVar, TypeVar

import numpy as np

from motion_envs._io import atomic_write_text

__all__ = [
    "FORMAT_NAME",
    "FORMAT_VERSION",
    "ModelFileError",
    "SerializableModel",
    "atomic_write_text",
    "load_model",
    "save_model",
]

FORMAT_NAME = "motion-envs-model"
FORMAT_VERSION = 1

_REGISTRY: dict[str, type[SerializableModel]] = {}

M = TypeVar("M", bound="SerializableModel")


class ModelFileError(ValueError):
    """A model file is missing, truncated, corrupt, of another format or version."""


class SerializableModel:
    """Mixin for models that save to and load from the JSON model format.

    Subclasses implement :meth:`_get_state` returning ``(params, arrays, attributes)``
    and the classmethod :meth:`_from_state` rebuilding a fitted model from them.
    """

    _model_name: ClassVar[str]

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        cls._model_name = cls.__name__
        _REGISTRY[cls.__name__] = cls

    def _get_state(self) -> tuple[dict[str, Any], dict[str, np.ndarray], dict[str, Any]]:
        raise NotImplementedError

    @classmethod
    def _from_state(
        cls: type[M],
        params: dict[str, Any],
        arrays: dict[str, np.ndarray],
        attributes: dict[str, Any],
    ) -> M:
        raise NotImplementedError

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Save the fitted model to ``path`` (JSON, atomic write). Returns the path."""
        return save_model(self, path)

    @classmethod
    def load(cls: type[M], path: str | os.PathLike[str]) -> M:
        """Load a model saved by :meth:`save`; :class:`ModelFileError` if it is not a ``cls``."""
        model = load_model(path)
        if not isinstance(model, cls):
            raise ModelFileError(f"{path} holds a {type(model).__name__}, not a {cls.__name__}")
        return model


def _encode_array(name: str, value: np.ndarray) -> dict[str, Any]:
    arr = np.asarray(value)
    if arr.dtype.kind == "f":
        arr = arr.astype(np.float64)
        if not np.all(np.isfinite(arr)):
            raise ValueError(f"array {name!r} contains NaN or infinite values; refusing to save")
        dtype = "float64"
    elif arr.dtype.kind in "iub":
        arr = arr.astype(np.int64)
        dtype = "int64"
    else:
        raise TypeError(f"array {name!r} has unsupported dtype {arr.dtype}")
    return {"dtype": dtype, "shape": list(arr.shape), "data": arr.ravel().tolist()}


def _decode_array(name: str, obj: Any, path: str) -> np.ndarray:
    try:
        dtype = {"float64": np.float64, "int64": np.int64}[obj["dtype"]]
        shape = tuple(int(n) for n in obj["shape"])
        arr = np.asarray(obj["data"], dtype=dtype)
        return arr.reshape(shape)
    except (KeyError, TypeError, ValueError) as exc:
        raise ModelFileError(f"{path}: array {name!r} is malformed ({exc})") from exc


def save_model(model: SerializableModel, path: str | os.PathLike[str]) -> Path:
    """Serialise a fitted model to ``path`` in the versioned JSON format (atomic)."""
    if not isinstance(model, SerializableModel):
        raise TypeError(f"model must be a SerializableModel; got {type(model).__name__}")
    params, arrays, attributes = model._get_state()
    doc = {
        "format": FORMAT_NAME,
        "format_version": FORMAT_VERSION,
        "model": model._model_name,
        "params": params,
        "arrays": {k: _encode_array(k, v) for k, v in arrays.items()},
        "attributes": attributes,
    }
    text = json.dumps(doc, allow_nan=False, indent=1)
    return atomic_write_text(path, text + "\n")


def load_model(path: str | os.PathLike[str]) -> SerializableModel:
    """Load any model saved with :func:`save_model`.

    Raises :class:`ModelFileError` (a ``ValueError``) with the reason when the file is
    truncated or not JSON, is of another format, has an unsupported ``format_version``
    or names an unknown model class.
    """
    p = str(path)
    try:
        text = Path(path).read_text(encoding="utf-8")
    except FileNotFoundError:
        raise ModelFileError(f"model file {p} does not exist") from None
    except UnicodeDecodeError as exc:
        raise ModelFileError(f"{p} is not a motion-envs model file (not UTF-8 text)") from exc
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as exc:
        raise ModelFileError(
            f"{p} is corrupt or truncated: not valid JSON ({exc.msg} at line {exc.lineno})"
        ) from exc
    if not isinstance(doc, dict) or doc.get("format") != FORMAT_NAME:
        raise ModelFileError(
            f"{p} is not a motion-envs model file (missing 'format': {FORMAT_NAME!r})"
        )
    version = doc.get("format_version")
    if version != FORMAT_VERSION:
        raise ModelFileError(
            f"{p} has format_version {version!r}; this motion-envs reads version {FORMAT_VERSION}"
        )
    name = doc.get("model")
    if name not in _REGISTRY:
        raise ModelFileError(f"{p} names unknown model class {name!r}; known: {sorted(_REGISTRY)}")
    for key in ("params", "arrays", "attributes"):
        if not isinstance(doc.get(key), dict):
            raise ModelFileError(f"{p} is malformed: {key!r} must be an object")
    arrays = {k: _decode_array(k, v, p) for k, v in doc["arrays"].items()}
    try:
        return _REGISTRY[name]._from_state(doc["params"], arrays, doc["attributes"])
    except (KeyError, TypeError, ValueError) as exc:
        raise ModelFileError(f"{p}: cannot rebuild {name} ({exc})") from exc
