"""Model files: every corrupt file raises ModelFileError naming the file and the field,
save and load agree on what is valid, and the registry is complete in a fresh process."""

from __future__ import annotations

import copy
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from motion_envs.geometry import quaternion as quat
from motion_envs.models.bezier_models import (
    LinearBezierModel,
    NullBezierModel,
    SubjectBezierModel,
    TaskBezierModel,
)
from motion_envs.models.orientation_model import OrientationModel
from motion_envs.models.serialization import (
    ModelFileError,
    SerializableModel,
    check_document,
    load_model,
    model_classes,
    save_model,
)
from motion_envs.models.sine_regression import SineSeriesRegression

ROOT = Path(__file__).resolve().parents[1]


def _curves(seed: int = 0, n: int = 12) -> np.ndarray:
    rng = np.random.default_rng(seed)
    tau = np.linspace(0.0, 1.0, 20)
    base = np.sin(np.pi * tau)[None, :, None]
    return base * rng.normal(size=(n, 1, 3)) * 0.1


def fitted_models() -> list[SerializableModel]:
    R = _curves()
    labels = np.array(["a", "b", "c"] * 4)
    rng = np.random.default_rng(1)
    y = [np.cumsum(rng.normal(size=(30, 2)), axis=0) for _ in range(6)]
    q = np.stack([t[0] for t in y])
    return [
        NullBezierModel(2).fit(R),
        TaskBezierModel(3).fit(R, tasks=labels),
        SubjectBezierModel(2, unseen="global").fit(R, subjects=labels),
        LinearBezierModel(2).fit(R, predictors={"age": rng.normal(size=12)}),
        SineSeriesRegression(n_sines=3).fit(q, y, times="normalised"),
        OrientationModel(degree=3, by="task").fit(labels, _turns(), rate=50.0),
    ]


def _turns() -> list[np.ndarray]:
    """12 short SIMULATED rotations about z with a bump about x, 11 samples each."""
    s = np.linspace(0.0, 1.0, 11)[:, None]
    return [quat.expmap(np.hstack([0.1 * i * np.sin(np.pi * s), 0 * s, s])) for i in range(12)]


@pytest.fixture(scope="module")
def saved(tmp_path_factory) -> dict[str, dict]:
    """A valid document of each model class."""
    folder = tmp_path_factory.mktemp("models")
    return {
        type(m).__name__: json.loads(m.save(folder / f"{type(m).__name__}.json").read_text())
        for m in fitted_models()
    }


def _set(doc: dict, path: tuple, value) -> dict:
    out = copy.deepcopy(doc)
    node = out
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = value
    return out


def _nested(depth: int) -> str:
    return "[" * depth + "]" * depth


# (name, model class, how to corrupt the text of a valid file, expected fragment)
TEXT_CASES = [
    ("truncated", "NullBezierModel", lambda t: t[: len(t) // 2], "corrupt or truncated"),
    ("empty", "NullBezierModel", lambda t: "", "corrupt or truncated"),
    ("nan", "NullBezierModel", lambda t: t.replace('"data": [', '"data": [NaN, ', 1), "NaN"),
    (
        "infinity",
        "NullBezierModel",
        lambda t: t.replace('"data": [', '"data": [Infinity, ', 1),
        "arrays.control_points_.data[0]: Infinity",
    ),
    (
        "minus infinity",
        "TaskBezierModel",
        lambda t: t.replace('"data": [', '"data": [-Infinity, ', 1),
        "-Infinity",
    ),
    (
        "beyond float64",
        "NullBezierModel",
        lambda t: t.replace('"data": [', '"data": [1e400, ', 1),
        "arrays.control_points_.data[0]: 1e400 is beyond float64",
    ),
    (
        "400-digit integer",
        "NullBezierModel",
        lambda t: t.replace('"n_points_": 20', '"n_points_": ' + "9" * 400),
        "attributes.n_points_: an integer of 400 digits",
    ),
    (
        "deeply nested",
        "NullBezierModel",
        lambda t: t.replace('"attributes": {', '"attributes": {"x": ' + _nested(5000) + ", ", 1),
        "nested deeper",
    ),
    ("not an object", "NullBezierModel", lambda t: "[1, 2]", "not a JSON object"),
]

# (name, model class, path in the document, new value, expected fragment)
DOC_CASES = [
    ("format_version float", "NullBezierModel", ("format_version",), 1.0, "format_version"),
    ("format_version string", "NullBezierModel", ("format_version",), "1", "format_version"),
    ("format_version bool", "NullBezierModel", ("format_version",), True, "format_version"),
    ("format_version 2", "NullBezierModel", ("format_version",), 2, "format_version 2"),
    ("format_version list", "NullBezierModel", ("format_version",), [1], "format_version"),
    ("unknown class", "NullBezierModel", ("model",), "EvilModel", "unknown model class"),
    ("abstract class", "NullBezierModel", ("model",), "BezierResidualModel", "abstract"),
    ("base class", "NullBezierModel", ("model",), "SerializableModel", "model"),
    ("class not a string", "NullBezierModel", ("model",), ["NullBezierModel"], "field model"),
    ("list for scalar", "NullBezierModel", ("params", "degree"), [2], "params.degree"),
    ("dict for scalar", "NullBezierModel", ("attributes", "n_points_"), {}, "n_points_"),
    ("string for int", "SineSeriesRegression", ("params", "n_sines"), "3", "params.n_sines"),
    ("bool for int", "NullBezierModel", ("params", "degree"), True, "params.degree"),
    ("float for int", "NullBezierModel", ("attributes", "n_points_"), 20.5, "n_points_"),
    ("negative degree", "NullBezierModel", ("params", "degree"), -1, "degree"),
    ("zero n_sines", "SineSeriesRegression", ("params", "n_sines"), -2, "n_sines"),
    ("missing param", "NullBezierModel", ("params",), {}, "params.degree"),
    ("extra param", "NullBezierModel", ("params", "evil"), 1, "params.evil"),
    ("params a list", "NullBezierModel", ("params",), [], "field params"),
    ("arrays a string", "NullBezierModel", ("arrays",), "x", "field arrays"),
    (
        "wrong dtype",
        "NullBezierModel",
        ("arrays", "control_points_", "dtype"),
        "int64",
        "arrays.control_points_.dtype",
    ),
    (
        "unknown dtype",
        "NullBezierModel",
        ("arrays", "control_points_", "dtype"),
        "object",
        "arrays.control_points_.dtype",
    ),
    (
        "wrong shape",
        "NullBezierModel",
        ("arrays", "control_points_", "shape"),
        [3, 1],
        "arrays.control_points_",
    ),
    (
        "wrong ndim",
        "NullBezierModel",
        ("arrays", "control_points_", "shape"),
        [3],
        "arrays.control_points_.shape",
    ),
    (
        "negative shape",
        "NullBezierModel",
        ("arrays", "control_points_", "shape"),
        [-1, -3],
        "arrays.control_points_.shape",
    ),
    (
        "data and shape disagree",
        "NullBezierModel",
        ("arrays", "control_points_", "data"),
        [1.0, 2.0],
        "arrays.control_points_.data",
    ),
    (
        "nested data",
        "NullBezierModel",
        ("arrays", "control_points_", "data"),
        [[0.0, 0.0, 0.0]],
        "arrays.control_points_.data",
    ),
    (
        "string in data",
        "NullBezierModel",
        ("arrays", "control_points_", "data"),
        ["x", 0.0, 0.0],
        "arrays.control_points_.data[0]",
    ),
    (
        "float in int array",
        "TaskBezierModel",
        ("arrays", "group_sizes_", "data"),
        [4.5, 4, 4],
        "arrays.group_sizes_.data[0]",
    ),
    (
        "groups not sorted",
        "TaskBezierModel",
        ("attributes", "groups_"),
        ["c", "b", "a"],
        "attributes.groups_",
    ),
    ("groups of numbers", "TaskBezierModel", ("attributes", "groups_"), [1, 2, 3], "groups_"),
    ("by of another class", "TaskBezierModel", ("params", "by"), "subject", "params.by"),
    ("bad unseen", "TaskBezierModel", ("params", "unseen"), "maybe", "unseen"),
    ("F shape", "SineSeriesRegression", ("arrays", "F", "shape"), [1, 1], "arrays.F"),
    ("rank out of range", "SineSeriesRegression", ("attributes", "rank"), 99, "rank"),
    ("extra top-level field", "NullBezierModel", ("pickle",), "x", "pickle"),
]


@pytest.mark.parametrize(
    ("name", "cls", "corrupt", "fragment"), TEXT_CASES, ids=[c[0] for c in TEXT_CASES]
)
def test_corrupt_text_raises_model_file_error(saved, tmp_path, name, cls, corrupt, fragment):
    path = tmp_path / "model.json"
    path.write_text(corrupt(json.dumps(saved[cls], indent=1)))
    with pytest.raises(ModelFileError) as info:
        load_model(path)
    assert str(path) in str(info.value)
    assert fragment in str(info.value)


@pytest.mark.parametrize(
    ("name", "cls", "path", "value", "fragment"), DOC_CASES, ids=[c[0] for c in DOC_CASES]
)
def test_corrupt_field_raises_model_file_error(saved, tmp_path, name, cls, path, value, fragment):
    file = tmp_path / "model.json"
    file.write_text(json.dumps(_set(saved[cls], path, value)))
    with pytest.raises(ModelFileError) as info:
        load_model(file)
    assert str(file) in str(info.value)
    assert fragment in str(info.value)


@pytest.mark.parametrize(
    ("name", "content"),
    [
        ("non-UTF-8", b'{"format": "motion-envs-model", "x": "\xff\xfe"}'),
        ("binary", bytes(range(256))),
    ],
)
def test_undecodable_files(tmp_path, name, content):
    path = tmp_path / "m.json"
    path.write_bytes(content)
    with pytest.raises(ModelFileError, match="not UTF-8"):
        load_model(path)


def test_a_directory_and_a_missing_file(tmp_path):
    with pytest.raises(ModelFileError, match="is a directory"):
        load_model(tmp_path)
    with pytest.raises(ModelFileError, match="does not exist"):
        load_model(tmp_path / "missing.json")


def test_save_and_load_agree(saved, tmp_path):
    """Every valid state saves and loads; a state that would not load is not saved."""
    for model in fitted_models():
        path = save_model(model, tmp_path / "m.json")
        doc = json.loads(path.read_text())
        assert check_document(doc, "x") is type(model)
        assert type(load_model(path)) is type(model)
    broken = NullBezierModel(2).fit(_curves())
    broken.n_points_ = [20]  # a list where an int belongs
    with pytest.raises(ValueError, match="n_points_"):
        save_model(broken, tmp_path / "broken.json")
    assert not (tmp_path / "broken.json").exists()
    broken.n_points_ = 10**30  # beyond int64: JSON could hold it, the loader would not
    with pytest.raises(ValueError, match="n_points_"):
        save_model(broken, tmp_path / "broken.json")


def test_every_concrete_class_has_a_schema_and_round_trips(tmp_path):
    classes = model_classes()
    loadable = {name for name, cls in classes.items() if cls.is_loadable()}
    assert loadable >= {type(m).__name__ for m in fitted_models()}
    assert "BezierResidualModel" not in loadable


@pytest.mark.parametrize("index", [0, 4])  # one class of each model module
def test_registry_is_complete_in_a_fresh_process(tmp_path, index):
    model = fitted_models()[index]
    path = model.save(tmp_path / "m.json")
    code = (
        "from motion_envs.models.serialization import load_model;"
        f"m = load_model({str(path)!r}); print(type(m).__name__)"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, check=True
    )
    assert out.stdout.split()[0] == type(model).__name__


json_values = st.recursive(
    st.none()
    | st.booleans()
    | st.integers(min_value=-(10**30), max_value=10**30)
    | st.floats(allow_nan=True, allow_infinity=True)
    | st.text(max_size=5),
    lambda inner: (
        st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=5), inner, max_size=3)
    ),
    max_leaves=8,
)


def _leaf_paths(doc, prefix=()):
    if isinstance(doc, dict):
        for k, v in doc.items():
            yield (*prefix, k)
            yield from _leaf_paths(v, (*prefix, k))
    elif isinstance(doc, list):
        for i, v in enumerate(doc[:3]):
            yield (*prefix, i)
            yield from _leaf_paths(v, (*prefix, i))


@settings(
    max_examples=int(os.environ.get("FUZZ_EXAMPLES", "150")),
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)
@given(data=st.data())
def test_fuzzed_files_raise_only_model_file_error(saved, tmp_path, data):
    """Any field replaced by any JSON value, or the text cut and spliced: the file loads
    or raises ModelFileError, never another exception."""
    cls = data.draw(st.sampled_from(sorted(saved)))
    doc = saved[cls]
    path = tmp_path / "fuzz.json"
    if data.draw(st.booleans()):
        where = data.draw(st.sampled_from(list(_leaf_paths(doc))))
        text = json.dumps(_set(doc, where, data.draw(json_values)))
    else:
        text = json.dumps(doc)
        a = data.draw(st.integers(0, len(text)))
        b = data.draw(st.integers(a, min(len(text), a + 20)))
        text = text[:a] + data.draw(st.text(max_size=5)) + text[b:]
    path.write_text(text, encoding="utf-8", errors="surrogatepass")
    try:
        model = load_model(path)
    except ModelFileError as exc:
        assert str(path) in str(exc)
    else:
        assert isinstance(model, SerializableModel)
