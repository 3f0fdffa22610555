"""Model files of the learned regressors: safetensors weights with a JSON header.

A file is a standard ``.safetensors`` file (8-byte little-endian header length, JSON
header, raw tensor bytes; no pickle, so loading cannot run code). Its ``__metadata__``
holds one entry, ``"motion_envs"``, a JSON document::

    {
      "format": "motion-envs-learned",
      "format_version": 1,
      "architecture": {"kind": "residual-mlp", "n_inputs": p, "hidden": h,
                        "n_outputs": m, "activation": "tanh"},
      "features": {...},          # feature encoding (names, task levels, target basis)
      "normalisation": {...},     # which tensors hold it (x_mean, x_scale, y_base, y_scale)
      "training_data_sha256": "...",
      "weights_sha256": "...",    # over every tensor's bytes, names sorted
      "extra": {...}              # what nested selection chose, etc.
    }

:func:`read_model_file` rejects, with :class:`LearnedModelFileError` naming the file and
the field: a missing file, a folder, a FIFO or device (never read: it could block or
never end), a file over :data:`MAX_FILE_BYTES`, a truncated or corrupt file (bad length
prefix, bad JSON, duplicate JSON keys, a header of the wrong JSON types, tensor bytes that
do not match ``weights_sha256``), a tensor that is not a float or holds NaN/inf, another
format, another ``format_version``, and an architecture that does not match the tensors'
shapes (checked per tensor by the model that loads it).
Writes are atomic (:func:`motion_envs._io.atomic_write_bytes`).
"""

from __future__ import annotations

import hashlib
import json
import os
import struct
from pathlib import Path
from typing import Any

import numpy as np

from motion_envs._io import UserFileError, atomic_write_bytes, read_regular_file, strict_json_loads

__all__ = [
    "FORMAT",
    "FORMAT_VERSION",
    "LearnedModelFileError",
    "data_hash",
    "model_file_error",
    "read_model_file",
    "write_model_file",
]

FORMAT = "motion-envs-learned"
FORMAT_VERSION = 1
_MAX_HEADER = 100_000_000
#: Largest model file read (bytes): the learned models are kilobytes; this bounds a mistake.
MAX_FILE_BYTES = 1 << 30


class LearnedModelFileError(ValueError):
    """A learned-model file is missing, truncated, corrupt, or of another format/version."""


def data_hash(*arrays: np.ndarray) -> str:
    """SHA-256 of arrays' shapes, dtypes and bytes (identifies the training data)."""
    h = hashlib.sha256()
    for a in arrays:
        a = np.ascontiguousarray(a)
        h.update(f"{a.dtype.str}{a.shape}".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def _weights_hash(tensors: dict[str, np.ndarray]) -> str:
    h = hashlib.sha256()
    for name in sorted(tensors):
        a = np.ascontiguousarray(tensors[name])
        h.update(f"{name}{a.dtype.str}{a.shape}".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def write_model_file(
    path: str | os.PathLike[str], tensors: dict[str, np.ndarray], header: dict[str, Any]
) -> Path:
    """Write ``tensors`` and the JSON ``header`` (format fields added) atomically."""
    from safetensors.numpy import save

    tensors = {k: np.ascontiguousarray(v) for k, v in tensors.items()}
    doc = {
        "format": FORMAT,
        "format_version": FORMAT_VERSION,
        **header,
        "weights_sha256": _weights_hash(tensors),
    }
    data = save(tensors, metadata={"motion_envs": json.dumps(doc, allow_nan=False)})
    return atomic_write_bytes(path, data)


def model_file_error(path: str, msg: str) -> LearnedModelFileError:
    """The error for file ``path``: ``"{path}: {msg}"`` (raise it)."""
    return LearnedModelFileError(f"{path}: {msg}")


def read_model_file(
    path: str | os.PathLike[str], expected_kind: str | None = None
) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
    """Read ``(tensors, header)``; raises :class:`LearnedModelFileError` (module docstring)."""
    from safetensors.numpy import load

    p = str(path)
    try:
        data = read_regular_file(path, max_bytes=MAX_FILE_BYTES)
    except UserFileError as exc:
        raise LearnedModelFileError(f"model file {exc}") from None
    if len(data) < 8:
        raise model_file_error(p, f"truncated: {len(data)} bytes, not a safetensors file")
    (n,) = struct.unpack("<Q", data[:8])
    if n > _MAX_HEADER or 8 + n > len(data):
        raise model_file_error(p, f"truncated or corrupt: header length {n} exceeds the file size")
    try:
        raw = strict_json_loads(data[8 : 8 + n], f"{p}: safetensors header")
        meta = raw.get("__metadata__") if isinstance(raw, dict) else None
        if not isinstance(meta, dict) or not isinstance(meta.get("motion_envs"), str):
            raise model_file_error(p, "not a motion-envs learned model (no 'motion_envs' metadata)")
        header = strict_json_loads(meta["motion_envs"], f"{p}: 'motion_envs' metadata")
    except UserFileError as exc:
        raise LearnedModelFileError(str(exc)) from None
    if not isinstance(header, dict):
        raise model_file_error(p, "the 'motion_envs' metadata is not a JSON object")
    if not isinstance(header, dict) or header.get("format") != FORMAT:
        raise model_file_error(
            p, f"field 'format' is {header.get('format')!r}, expected {FORMAT!r}"
        )
    if header.get("format_version") != FORMAT_VERSION:
        raise model_file_error(
            p,
            f"field 'format_version' is {header.get('format_version')!r}; this motion-envs "
            f"reads version {FORMAT_VERSION}",
        )
    try:
        tensors = load(data)
    except Exception as exc:  # safetensors raises its own error type
        raise model_file_error(p, f"corrupt tensor data ({exc})") from None
    if _weights_hash(tensors) != header.get("weights_sha256"):
        raise model_file_error(
            p, "field 'weights_sha256' does not match the tensor bytes (corrupt file)"
        )
    for name, tensor in tensors.items():
        if tensor.dtype.kind != "f":
            raise model_file_error(p, f"tensor {name!r} has dtype {tensor.dtype}, not a float")
        if not np.isfinite(tensor).all():
            raise model_file_error(p, f"tensor {name!r} holds NaN or infinite values")
    for field in ("features", "extra", "normalisation"):
        if not isinstance(header.get(field, {}), dict):
            raise model_file_error(p, f"field {field!r} is not a JSON object")
    arch = header.get("architecture")
    if not isinstance(arch, dict):
        raise model_file_error(p, "field 'architecture' is missing")
    if expected_kind is not None and arch.get("kind") != expected_kind:
        raise model_file_error(
            p, f"field 'architecture.kind' is {arch.get('kind')!r}, expected {expected_kind!r}"
        )
    return tensors, header
