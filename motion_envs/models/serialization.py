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

A model class takes part by subclassing :class:`SerializableModel`, implementing
``_get_state()`` / ``_set_state()`` (or the whole ``_from_state()``) and declaring its
:class:`StateSchema`; it is registered under its class name. A class that implements
neither ``_set_state`` nor ``_from_state`` is abstract and cannot be loaded; a class whose
name starts with ``_`` (a private base class) is not registered. :func:`load_model`
finds every class of ``motion_envs.models`` in a fresh process (it imports the
package's modules when a name is not registered yet).

**What is valid** (checked by :func:`check_document`, the same function on save and on
load, so a file :func:`save_model` writes always loads and a file it could not have
written is rejected): a JSON object (strict JSON: no ``NaN``/``Infinity``, no number
beyond float64's range, integers within int64, at most :data:`MAX_DEPTH` levels deep)
with the fields above; ``format_version`` the integer 1; ``model`` a registered,
concrete class; every array a ``float64`` (finite) or ``int64`` array whose ``data``
is a flat list of ``prod(shape)`` numbers; and ``params``, ``arrays`` and
``attributes`` holding exactly the keys of the class's schema, each of the declared
type and number of dimensions. Anything else raises :class:`ModelFileError` naming the
file and the field (e.g. ``arrays.control_points_.data[4]``).

Writes go through :func:`motion_envs._io.atomic_write_text`: a failed or interrupted
write never leaves half a file.
"""

from __future__ import annotations

import importlib
import json
import math
import os
import pkgutil
import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar, NoReturn, TypeVar

import numpy as np
from numpy.typing import NDArray

from motion_envs._io import UserFileError, atomic_write_text, read_regular_file, strict_json_loads
from motion_envs.models.estimator import Estimator

__all__ = [
    "FORMAT_NAME",
    "FORMAT_VERSION",
    "MAX_DEPTH",
    "ModelFileError",
    "SerializableModel",
    "StateSchema",
    "atomic_write_text",
    "check_document",
    "load_model",
    "model_classes",
    "save_model",
]

FORMAT_NAME = "motion-envs-model"
FORMAT_VERSION = 1
#: Deepest nesting of JSON containers a model file may have.
MAX_DEPTH = 32
#: Largest model file read, in bytes (a guard against reading a huge unrelated file).
MAX_BYTES = 1 << 30

_INT64 = (-(2**63), 2**63 - 1)
_REGISTRY: dict[str, type[SerializableModel]] = {}

M = TypeVar("M", bound="SerializableModel")

#: JSON value kinds of a schema: ``"int"``, ``"float"``, ``"str"``, ``"bool"``,
#: ``"str_list"`` (a list of strings) or ``"int_or_str"``.
_KINDS = ("int", "float", "str", "bool", "str_list", "int_or_str")


class ModelFileError(ValueError):
    """A model file is missing, unreadable, corrupt, truncated, of another format or
    version, names an unknown or abstract class, or holds a field of the wrong kind,
    shape or value. The message names the file and the field."""


#: A model's saved state: ``(params, arrays, attributes)``.
State = tuple[dict[str, Any], dict[str, NDArray[Any]], dict[str, Any]]


@dataclass(frozen=True)
class StateSchema:
    """The state a model class saves: the kind of each parameter and attribute
    (one of ``"int"``, ``"float"``, ``"str"``, ``"bool"``, ``"str_list"``,
    ``"float_list"``, ``"int_or_str"``) and the ``(dtype, ndim)`` of each array (dtype
    ``"float64"`` or ``"int64"``). ``optional_params`` may be absent from a file (files
    written before the parameter existed); the class's ``_from_state`` supplies the
    default."""

    params: Mapping[str, str] = field(default_factory=dict)
    arrays: Mapping[str, tuple[str, int]] = field(default_factory=dict)
    attributes: Mapping[str, str] = field(default_factory=dict)
    optional_params: frozenset[str] = frozenset()


class SerializableModel(Estimator):
    """Mixin for models that save to and load from the JSON model format.

    Subclasses implement :meth:`_get_state` returning ``(params, arrays, attributes)``
    and :meth:`_set_state` setting the fitted attributes from ``arrays`` and
    ``attributes`` on the model :meth:`_from_params` built (raising ``ValueError``
    naming the field for inconsistent values), and set ``state_schema``. A class whose
    rebuilding does not split that way overrides the classmethod :meth:`_from_state`.
    """

    _model_name: ClassVar[str]
    #: The saved state's schema; None only for abstract classes.
    state_schema: ClassVar[StateSchema | None] = None

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        cls._model_name = cls.__name__
        if not cls.__name__.startswith("_"):  # a private base class is no file's model
            _REGISTRY[cls.__name__] = cls

    def _get_state(self) -> State:
        raise NotImplementedError

    @classmethod
    def _from_state(
        cls: type[M],
        params: dict[str, Any],
        arrays: dict[str, NDArray[Any]],
        attributes: dict[str, Any],
    ) -> M:
        """The fitted model: :meth:`_from_params`, then :meth:`_set_state`."""
        model = cls._from_params(params)
        model._set_state(arrays, attributes)
        return model

    @classmethod
    def _from_params(cls: type[M], params: dict[str, Any]) -> M:
        """The unfitted model the saved ``params`` describe (``cls(**params)``)."""
        return cls(**params)

    def _set_state(self, arrays: dict[str, NDArray[Any]], attributes: dict[str, Any]) -> None:
        raise NotImplementedError

    @classmethod
    def is_loadable(cls) -> bool:
        """True for a concrete class: it rebuilds itself and declares its schema."""
        own = cls._from_state.__func__  # type: ignore[attr-defined]
        base = SerializableModel._from_state.__func__  # type: ignore[attr-defined]
        sets = cls._set_state is not SerializableModel._set_state
        return (own is not base or sets) and cls.state_schema is not None

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


def model_classes() -> dict[str, type[SerializableModel]]:
    """Every model class of ``motion_envs.models`` (and any other imported), by name.

    Imports the modules of the ``motion_envs.models`` package, so the registry is
    complete in a fresh process.
    """
    # the package's folder, read without importing its __init__ (an import back up)
    package = __name__.rpartition(".")[0]
    with warnings.catch_warnings():  # the deprecated juggling_* modules warn on import
        warnings.simplefilter("ignore", DeprecationWarning)
        for info in pkgutil.iter_modules([str(Path(__file__).parent)], prefix=package + "."):
            importlib.import_module(info.name)
    return dict(_REGISTRY)


# ---------------------------------------------------------------------------------------
# checking a document: the same function serves save (before writing) and load
# ---------------------------------------------------------------------------------------


class _Invalid:
    """A JSON token the format does not allow, kept in place so its field can be named."""

    def __init__(self, what: str) -> None:
        self.what = what


def _parse_float(text: str) -> float | _Invalid:
    value = float(text)
    return value if math.isfinite(value) else _Invalid(f"{text[:40]} is beyond float64's range")


def _parse_int(text: str) -> int | _Invalid:
    if len(text.lstrip("-")) > 19:
        return _Invalid(f"an integer of {len(text.lstrip('-'))} digits is beyond int64")
    value = int(text)
    return value if _INT64[0] <= value <= _INT64[1] else _Invalid(f"{text} is beyond int64")


def _parse_constant(text: str) -> _Invalid:
    return _Invalid(f"{text} is not allowed (strict JSON)")


def _depth(value: Any, limit: int) -> int:
    """Nesting depth of JSON containers, stopping once past ``limit`` (no recursion)."""
    stack = [(value, 1)]
    deepest = 0
    while stack:
        item, d = stack.pop()
        if isinstance(item, (dict, list)):
            deepest = max(deepest, d)
            if deepest > limit:
                return deepest
            children = item.values() if isinstance(item, dict) else item
            stack.extend((child, d + 1) for child in children)
    return deepest


def _find_invalid(value: Any, where: str) -> tuple[str, str] | None:
    stack = [(value, where)]
    while stack:
        item, path = stack.pop()
        if isinstance(item, _Invalid):
            return path, item.what
        if isinstance(item, dict):
            stack.extend((v, f"{path}.{k}" if path else str(k)) for k, v in item.items())
        elif isinstance(item, list):
            stack.extend((v, f"{path}[{i}]") for i, v in enumerate(item))
    return None


def _is_int(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _kind_ok(kind: str, value: Any) -> bool:
    if kind == "int":
        return _is_int(value)
    if kind == "float":
        return _is_number(value) and math.isfinite(value)
    if kind == "str":
        return isinstance(value, str)
    if kind == "bool":
        return isinstance(value, bool)
    if kind == "str_list":
        return isinstance(value, list) and all(isinstance(v, str) for v in value)
    if kind == "float_list":
        return isinstance(value, list) and all(_is_number(v) and math.isfinite(v) for v in value)
    if kind == "int_or_str":
        return _is_int(value) or isinstance(value, str)
    raise AssertionError(f"unknown schema kind {kind!r}")


def _check_array(
    name: str, obj: Any, dtype: str, ndim: int, fail: Callable[[str, str], NoReturn]
) -> None:
    where = f"arrays.{name}"
    if not isinstance(obj, dict) or set(obj) != {"dtype", "shape", "data"}:
        fail(where, "must be an object with exactly 'dtype', 'shape' and 'data'")
    if obj["dtype"] != dtype:
        fail(f"{where}.dtype", f"must be {dtype!r}; got {obj['dtype']!r}")
    shape = obj["shape"]
    if not isinstance(shape, list) or not all(_is_int(n) and n >= 0 for n in shape):
        fail(f"{where}.shape", f"must be a list of integers >= 0; got {shape!r}"[:200])
    if len(shape) != ndim:
        fail(f"{where}.shape", f"must have {ndim} dimensions; got {shape!r}")
    data = obj["data"]
    if not isinstance(data, list):
        fail(f"{where}.data", "must be a flat list of numbers")
    size = math.prod(shape)
    if len(data) != size:
        fail(f"{where}.data", f"has {len(data)} values; shape {shape} needs {size}")
    check, what = (_is_int, "an integer") if dtype == "int64" else (_is_number, "a number")
    for i, v in enumerate(data):
        if not check(v):
            fail(f"{where}.data[{i}]", f"must be {what}; got {type(v).__name__}")


def check_document(doc: Any, where: str) -> type[SerializableModel]:
    """Check a model document (format in the module docstring); returns its class.

    Raises :class:`ModelFileError` ``"<where>: field <field>: <problem>"``.
    """

    def fail(field_name: str, problem: str) -> NoReturn:
        raise ModelFileError(f"{where}: field {field_name}: {problem}")

    if not isinstance(doc, dict):
        raise ModelFileError(f"{where} is not a motion-envs model file (not a JSON object)")
    if _depth(doc, MAX_DEPTH) > MAX_DEPTH:
        raise ModelFileError(f"{where}: JSON nested deeper than {MAX_DEPTH} levels")
    bad = _find_invalid(doc, "")
    if bad is not None:
        fail(*bad)
    if doc.get("format") != FORMAT_NAME:
        raise ModelFileError(
            f"{where} is not a motion-envs model file (missing 'format': {FORMAT_NAME!r})"
        )
    version = doc.get("format_version")
    if not _is_int(version):
        fail("format_version", f"must be the integer {FORMAT_VERSION}; got {version!r}"[:200])
    if version != FORMAT_VERSION:
        raise ModelFileError(
            f"{where} has format_version {version!r}; this motion-envs reads version "
            f"{FORMAT_VERSION}"
        )
    extra = set(doc) - {"format", "format_version", "model", "params", "arrays", "attributes"}
    if extra:
        fail(sorted(extra)[0], "is not a field of the format")
    name = doc.get("model")
    if not isinstance(name, str):
        fail("model", f"must be a class name; got {type(name).__name__}")
    classes = _REGISTRY if name in _REGISTRY else model_classes()
    if name not in classes:
        fail("model", f"unknown model class {name!r}; known: {sorted(classes)}")
    cls = classes[name]
    if not cls.is_loadable():
        fail("model", f"{name} is an abstract class; a file holds a concrete model")
    schema = cls.state_schema
    assert schema is not None
    for section in ("params", "arrays", "attributes"):
        if not isinstance(doc.get(section), dict):
            fail(section, "must be an object")
        expected = getattr(schema, section)
        missing = sorted(set(expected) - set(doc[section]))
        if section == "params":
            missing = [key for key in missing if key not in schema.optional_params]
        if missing:
            fail(f"{section}.{missing[0]}", f"is missing ({name} needs {sorted(expected)})")
        unknown = sorted(set(doc[section]) - set(expected))
        if unknown:
            fail(f"{section}.{unknown[0]}", f"is not a field of {name}")
    for key, kind in schema.params.items():
        if key not in doc["params"]:
            continue  # an optional parameter (checked above)
        if not _kind_ok(kind, doc["params"][key]):
            fail(f"params.{key}", f"must be of kind {kind}; got {doc['params'][key]!r}"[:200])
    for key, kind in schema.attributes.items():
        value = doc["attributes"][key]
        if not _kind_ok(kind, value):
            fail(f"attributes.{key}", f"must be of kind {kind}; got {value!r}"[:200])
    for key, (dtype, ndim) in schema.arrays.items():
        _check_array(key, doc["arrays"][key], dtype, ndim, fail)
    return cls


def _encode_array(name: str, value: NDArray[Any]) -> dict[str, Any]:
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


def _decode_array(obj: dict[str, Any]) -> NDArray[Any]:
    dtype = np.float64 if obj["dtype"] == "float64" else np.int64
    return np.asarray(obj["data"], dtype=dtype).reshape(tuple(obj["shape"]))


def save_model(model: SerializableModel, path: str | os.PathLike[str]) -> Path:
    """Serialise a fitted model to ``path`` in the versioned JSON format (atomic).

    The document is checked with :func:`check_document` before anything is written, so
    what is saved always loads; an invalid state raises ``ValueError``.
    """
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
    check_document(_parse(text, f"model to save to {path}"), f"model to save to {path}")
    return atomic_write_text(path, text + "\n")


def _parse(text: str, where: str) -> Any:
    try:
        return strict_json_loads(
            text,
            where,
            parse_float=_parse_float,
            parse_int=_parse_int,
            parse_constant=_parse_constant,
        )
    except UserFileError as exc:
        raise ModelFileError(str(exc)) from None


def load_model(path: str | os.PathLike[str]) -> SerializableModel:
    """Load any model saved with :func:`save_model`.

    Raises :class:`ModelFileError` (a ``ValueError``), naming the file and the field,
    for every file :func:`save_model` could not have written: see the module docstring.
    No other exception escapes for a bad file.
    """
    p = str(path)
    try:
        raw = read_regular_file(path, max_bytes=MAX_BYTES)
    except UserFileError as exc:
        raise ModelFileError(f"model file {exc}") from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        raise ModelFileError(f"{p} is not a motion-envs model file (not UTF-8 text)") from None
    doc = _parse(text, p)
    cls = check_document(doc, p)
    arrays = {k: _decode_array(v) for k, v in doc["arrays"].items()}
    try:
        return cls._from_state(doc["params"], arrays, doc["attributes"])
    except (KeyError, TypeError, ValueError, IndexError, OverflowError) as exc:
        raise ModelFileError(f"{p}: cannot rebuild {cls.__name__}: {exc}") from None
