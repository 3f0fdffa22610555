"""Bad model files, learned (safetensors) and analytic (JSON): one documented error each.

Regression tests for the hardening audit: devices, FIFOs and folders are refused before
any byte is read; malformed headers, duplicate keys, NaN/inf weights and tensors of the
wrong shape or dtype are refused at load time (not later inside ``predict``).
"""

from __future__ import annotations

import json
import os
import struct
import threading
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("safetensors")

from baselines.learned.mlp_model import KIND, ResidualMLP
from baselines.learned.model_file import (
    LearnedModelFileError,
    read_model_file,
    write_model_file,
)
from motion_envs._io import UserFileError, read_regular_file, strict_json_loads
from motion_envs.models.serialization import ModelFileError, load_model

N_IN, HIDDEN, N_OUT = 3, 4, 2


def _tensors(**changes: np.ndarray) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(0)
    base = {
        "W1": rng.standard_normal((N_IN, HIDDEN)),
        "b1": rng.standard_normal(HIDDEN),
        "W2": rng.standard_normal((HIDDEN, N_OUT)),
        "b2": rng.standard_normal(N_OUT),
        "x_mean": np.zeros(N_IN),
        "x_scale": np.ones(N_IN),
        "y_base": np.zeros(N_OUT),
        "y_scale": np.ones(1),
    }
    base = {k: v.astype(np.float32) for k, v in base.items()}
    base.update(changes)
    return base


def _header(**changes: object) -> dict[str, object]:
    doc: dict[str, object] = {
        "architecture": {
            "kind": KIND,
            "n_inputs": N_IN,
            "hidden": HIDDEN,
            "n_outputs": N_OUT,
            "activation": "tanh",
        },
        "features": {},
        "extra": {"chosen": {}},
    }
    doc.update(changes)
    return doc


def _raw_safetensors(path: Path, header_json: bytes, body: bytes = b"") -> Path:
    path.write_bytes(struct.pack("<Q", len(header_json)) + header_json + body)
    return path


def test_a_valid_file_loads_and_predicts(tmp_path):
    path = write_model_file(tmp_path / "ok.safetensors", _tensors(), _header())
    model = ResidualMLP.load(path)
    assert model.predict(np.zeros((2, N_IN))).shape == (2, N_OUT)


@pytest.mark.parametrize("loader", ["learned", "json"])
def test_dev_zero_is_refused_without_reading(loader):
    if not Path("/dev/zero").exists():
        pytest.skip("no /dev/zero here")
    error = LearnedModelFileError if loader == "learned" else ModelFileError
    with pytest.raises(error, match="/dev/zero is a character device"):
        read_model_file("/dev/zero") if loader == "learned" else load_model("/dev/zero")


@pytest.mark.parametrize("loader", ["learned", "json"])
def test_a_fifo_is_refused_without_blocking(tmp_path, loader):
    if not hasattr(os, "mkfifo"):
        pytest.skip("no FIFOs on this platform")
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    outcome: list[BaseException] = []

    def attempt() -> None:
        try:
            read_model_file(fifo) if loader == "learned" else load_model(fifo)
        except BaseException as exc:  # recorded and checked below
            outcome.append(exc)

    worker = threading.Thread(target=attempt, daemon=True)
    worker.start()
    worker.join(5.0)
    assert not worker.is_alive(), "reading a FIFO blocked"
    assert len(outcome) == 1 and "FIFO" in str(outcome[0])
    assert isinstance(outcome[0], (LearnedModelFileError, ModelFileError))


@pytest.mark.parametrize("loader", ["learned", "json"])
def test_a_folder_and_a_missing_file(tmp_path, loader):
    load = read_model_file if loader == "learned" else load_model
    error = LearnedModelFileError if loader == "learned" else ModelFileError
    with pytest.raises(error, match="is a directory"):
        load(tmp_path)
    with pytest.raises(error, match="does not exist"):
        load(tmp_path / "nothing.json")


def test_the_size_bound_counts_bytes_read(tmp_path):
    path = tmp_path / "big"
    path.write_bytes(b"x" * 101)
    assert read_regular_file(path, max_bytes=101) == b"x" * 101
    with pytest.raises(UserFileError, match="larger than 100 bytes"):
        read_regular_file(path, max_bytes=100)


def test_strict_json_refuses_duplicates_constants_and_depth():
    with pytest.raises(UserFileError, match="duplicate key 'a'"):
        strict_json_loads('{"a": 1, "b": {"a": 2, "a": 3}}', "f")
    with pytest.raises(UserFileError, match="NaN is not allowed"):
        strict_json_loads('{"a": NaN}', "f")
    with pytest.raises(UserFileError, match="nested deeper"):
        strict_json_loads("[" * 100_000 + "]" * 100_000, "f")
    assert strict_json_loads('{"a": [1, 2.5]}', "f") == {"a": [1, 2.5]}


def _meta(doc_text: str) -> bytes:
    return json.dumps({"__metadata__": {"motion_envs": doc_text}}).encode()


MALFORMED_HEADERS = [
    ("header is a list", b"[1, 2]", "no 'motion_envs' metadata"),
    ("metadata is a list", b'{"__metadata__": [1]}', "no 'motion_envs' metadata"),
    ("metadata value is a number", b'{"__metadata__": {"motion_envs": 5}}', "no 'motion_envs'"),
    ("motion_envs doc is a list", _meta("[1, 2]"), "not a JSON object"),
    ("deeply nested header", b'{"a": ' + b"[" * 50_000 + b"]" * 50_000 + b"}", "nested deeper"),
    ("duplicate header key", b'{"__metadata__": {}, "__metadata__": {}}', "duplicate key"),
    (
        "duplicate metadata key",
        _meta('{"format": "motion-envs-learned", "format": "x"}'),
        "duplicate key 'format'",
    ),
    ("header not UTF-8", b'{"a": "\xff"}', "not UTF-8"),
]


@pytest.mark.parametrize(
    ("name", "header", "fragment"), MALFORMED_HEADERS, ids=[c[0] for c in MALFORMED_HEADERS]
)
def test_malformed_headers_raise_the_documented_error(tmp_path, name, header, fragment):
    path = _raw_safetensors(tmp_path / "bad.safetensors", header)
    with pytest.raises(LearnedModelFileError, match=fragment) as info:
        read_model_file(path)
    assert str(path) in str(info.value)


@pytest.mark.parametrize("field", ["extra", "features", "normalisation"])
def test_header_fields_of_the_wrong_type(tmp_path, field):
    path = write_model_file(tmp_path / "f.safetensors", _tensors(), _header(**{field: [1]}))
    with pytest.raises(LearnedModelFileError, match=f"field '{field}' is not a JSON object"):
        ResidualMLP.load(path)


BAD_TENSORS = [
    ("NaN weight", {"W1": np.full((N_IN, HIDDEN), np.nan, np.float32)}, "NaN or infinite"),
    ("inf bias", {"b2": np.array([np.inf, 0.0], np.float32)}, "NaN or infinite"),
    ("integer tensor", {"b1": np.zeros(HIDDEN, np.int32)}, "not a float"),
    ("float64 tensor", {"b1": np.zeros(HIDDEN, np.float64)}, "expected float32"),
    ("b1 too long", {"b1": np.zeros(HIDDEN + 1, np.float32)}, "'b1'"),
    ("b2 too short", {"b2": np.zeros(N_OUT - 1, np.float32)}, "'b2'"),
    ("x_mean wrong length", {"x_mean": np.zeros(N_IN + 2, np.float32)}, "'x_mean'"),
    ("x_scale matrix", {"x_scale": np.ones((N_IN, 1), np.float32)}, "'x_scale'"),
    ("y_base wrong length", {"y_base": np.zeros(N_OUT + 1, np.float32)}, "'y_base'"),
    ("y_scale vector", {"y_scale": np.ones(3, np.float32)}, "'y_scale'"),
    ("W1 three-dimensional", {"W1": np.zeros((N_IN, HIDDEN, 1), np.float32)}, "'W1'"),
    ("W2 a vector", {"W2": np.zeros(HIDDEN, np.float32)}, "'W2'"),
    ("zero x_scale", {"x_scale": np.zeros(N_IN, np.float32)}, "'x_scale' must be positive"),
]


@pytest.mark.parametrize(
    ("name", "changes", "fragment"), BAD_TENSORS, ids=[c[0] for c in BAD_TENSORS]
)
def test_bad_tensors_are_refused_at_load(tmp_path, name, changes, fragment):
    path = write_model_file(tmp_path / "t.safetensors", _tensors(**changes), _header())
    with pytest.raises(LearnedModelFileError, match=fragment) as info:
        ResidualMLP.load(path)
    assert str(path) in str(info.value)


def test_duplicate_keys_in_a_json_model_file(tmp_path):
    from motion_envs.models.bezier_models import NullBezierModel
    from motion_envs.models.serialization import save_model

    rng = np.random.default_rng(1)
    curves = rng.standard_normal((6, 20, 3)) * 0.01
    path = save_model(NullBezierModel(degree=2).fit(curves), tmp_path / "m.json")
    text = path.read_text()
    path.write_text(
        text.replace('"format_version": 1,', '"format_version": 1, "format_version": 1,')
    )
    with pytest.raises(ModelFileError, match="duplicate key 'format_version'"):
        load_model(path)
