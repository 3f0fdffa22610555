"""Learned regressors: recovery, determinism, nested selection, model files, bench rows."""

from __future__ import annotations

import json
import struct

import numpy as np
import pytest

torch = pytest.importorskip("torch")

from baselines.learned.batched_mlp import MLPConfig, train_networks  # noqa: E402
from baselines.learned.mlp_model import ResidualMLP  # noqa: E402
from baselines.learned.model_file import (  # noqa: E402
    LearnedModelFileError,
    read_model_file,
    write_model_file,
)
from baselines.learned.nested import inner_folds, nested_mlp  # noqa: E402
from baselines.learned.orientation import (  # noqa: E402
    ridge_nested,
    sine_curves,
    sine_targets,
)

TINY = MLPConfig(hidden=16, max_epochs=40, lr=2e-2, weight_decays=(1e-3, 1e-1), inner_splits=3)


def _synthetic(n_groups: int = 6, per_group: int = 30, seed: int = 0):
    """Targets with a known nonlinear correction of the conditions, plus noise."""
    rng = np.random.default_rng(seed)
    N = n_groups * per_group
    X = rng.uniform(-1, 1, size=(N, 3))
    Y = np.column_stack([np.sin(2 * X[:, 0]), X[:, 1] ** 2, 0.5 * X[:, 0] * X[:, 2]])
    Y = Y + 0.05 * rng.normal(size=Y.shape)
    groups = np.repeat(np.arange(n_groups).astype(str), per_group)
    return X, Y, groups


def _loso(groups):
    return [(np.flatnonzero(groups != g), np.flatnonzero(groups == g)) for g in np.unique(groups)]


def test_mlp_recovers_a_known_correction():
    X, Y, groups = _synthetic()
    res = nested_mlp(X, Y, groups, _loso(groups), TINY)
    mse_mlp = np.mean((res.predictions - Y) ** 2)
    mse_null = np.mean((Y - Y.mean(axis=0)) ** 2)
    assert mse_mlp < 0.3 * mse_null
    assert all(c["epochs"] > 0 for c in res.chosen)


def test_ridge_recovers_a_linear_correction():
    rng = np.random.default_rng(1)
    X = rng.normal(size=(120, 4))
    Y = X @ rng.normal(size=(4, 6)) + 0.01 * rng.normal(size=(120, 6))
    groups = np.repeat(np.arange(6), 20)
    pred, chosen = ridge_nested(X, Y, groups, _loso(groups))
    assert np.mean((pred - Y) ** 2) < 0.01 * np.mean((Y - Y.mean(0)) ** 2)
    assert len(chosen) == 6


def test_zero_initialised_output_starts_at_the_nominal():
    X, Y, _groups = _synthetic()
    masks = np.ones((2, X.shape[0]), bool)
    out = train_networks(
        X,
        Y,
        masks,
        None,
        np.zeros(2),
        TINY,
        np.zeros(2, np.int64),
        bases=np.array(["mean", "zero"]),
    )
    assert np.allclose(out.predictions[0], Y.mean(axis=0), atol=1e-5)
    assert np.all(out.predictions[1] == 0.0)


def test_training_is_deterministic_and_seeded():
    X, Y, groups = _synthetic(n_groups=4, per_group=15)
    folds = _loso(groups)
    a = nested_mlp(X, Y, groups, folds, TINY)
    b = nested_mlp(X, Y, groups, folds, TINY)
    assert np.array_equal(a.predictions, b.predictions, equal_nan=True)
    assert a.chosen == b.chosen
    c = nested_mlp(X, Y, groups, folds, MLPConfig(**{**TINY.__dict__, "seed": 1}))
    assert not np.array_equal(a.predictions, c.predictions)
    assert a.predictions.shape == Y.shape


def test_inner_folds_only_hold_training_rows():
    groups = np.repeat(np.arange(5), 4)
    train = np.flatnonzero(groups != 2)
    for fit, val in inner_folds(train, groups, 3):
        assert not np.isin(2, groups[fit]) and not np.isin(2, groups[val])
        assert np.intersect1d(fit, val).size == 0
    with pytest.raises(ValueError, match="2 training groups"):
        inner_folds(np.flatnonzero(groups == 0), groups, 3)


def _poisoned(X, Y, groups, held):
    """Same data, the held-out group's targets replaced by a loud signal in x."""
    Y2 = Y.copy()
    rows = groups == held
    Y2[rows] = 50.0 * X[rows, :1] * np.ones((1, Y.shape[1]))
    return Y2


def test_nested_selection_never_sees_the_held_out_group():
    X, Y, groups = _synthetic(n_groups=5, per_group=20, seed=3)
    held = "4"
    fold = [(np.flatnonzero(groups != held), np.flatnonzero(groups == held))]
    Y2 = _poisoned(X, Y, groups, held)
    # ridge: the held-out group would change the choice if it were used ...
    everything = np.arange(X.shape[0])
    _, with_it = ridge_nested(X, Y2, groups, [(everything, everything)])
    _, clean = ridge_nested(X, Y, groups, [(everything, everything)])
    assert with_it != clean
    # ... but as the held-out group it changes neither the choice nor the predictions
    p1, c1 = ridge_nested(X, Y, groups, fold)
    p2, c2 = ridge_nested(X, Y2, groups, fold)
    assert c1 == c2 and np.array_equal(p1, p2, equal_nan=True)
    # the same for the MLP (weight decay, base and epochs)
    m_all = nested_mlp(X, Y2, groups, [(everything, everything)], TINY)
    m_clean = nested_mlp(X, Y, groups, [(everything, everything)], TINY)
    assert m_all.chosen != m_clean.chosen
    m1 = nested_mlp(X, Y, groups, fold, TINY)
    m2 = nested_mlp(X, Y2, groups, fold, TINY)
    assert m1.chosen == m2.chosen
    assert np.array_equal(m1.predictions, m2.predictions, equal_nan=True)


def test_sine_targets_round_trip_and_zero_ends():
    rng = np.random.default_rng(4)
    coef = rng.normal(size=(5, 24))
    curves = sine_curves(coef, 50)
    assert np.all(curves[:, 0] == 0) and np.all(curves[:, -1] == 0)
    assert np.allclose(sine_targets(curves, 8), coef, atol=1e-10)


# -- model files ------------------------------------------------------------------------


@pytest.fixture(scope="module")
def fitted(tmp_path_factory):
    X, Y, groups = _synthetic(n_groups=4, per_group=15)
    model = ResidualMLP(TINY, features={"names": ["a", "b", "c"]}).fit(X, Y, groups)
    path = tmp_path_factory.mktemp("model") / "mlp.safetensors"
    model.save(path)
    return model, path, X


def test_model_file_round_trip_is_identical(fitted):
    model, path, X = fitted
    again = ResidualMLP.load(path)
    assert np.array_equal(again.predict(X), model.predict(X))
    assert again.features == {"names": ["a", "b", "c"]}
    _tensors, header = read_model_file(path)
    assert header["architecture"]["hidden"] == 16
    assert len(header["training_data_sha256"]) == 64
    assert not list(path.parent.glob(".*.tmp"))  # atomic write left no temporary


def _rewrite_header(path, out, change):
    data = path.read_bytes()
    (n,) = struct.unpack("<Q", data[:8])
    raw = json.loads(data[8 : 8 + n])
    meta = json.loads(raw["__metadata__"]["motion_envs"])
    change(meta)
    raw["__metadata__"]["motion_envs"] = json.dumps(meta)
    head = json.dumps(raw).encode()
    head += b" " * (-len(head) % 8)
    out.write_bytes(struct.pack("<Q", len(head)) + head + data[8 + n :])
    return out


def test_model_file_rejects_every_corrupt_case(fitted, tmp_path):
    _, path, _ = fitted
    data = path.read_bytes()
    cases = {
        "missing": (tmp_path / "nope.safetensors", "does not exist"),
        "empty": (tmp_path / "empty.safetensors", "truncated"),
        "truncated": (tmp_path / "cut.safetensors", "truncated|corrupt"),
        "bad_header": (tmp_path / "head.safetensors", "corrupt"),
        "flipped_weight": (tmp_path / "flip.safetensors", "weights_sha256"),
        "pickle": (tmp_path / "model.pkl", "truncated|corrupt|not a motion-envs"),
    }
    cases["empty"][0].write_bytes(b"")
    cases["truncated"][0].write_bytes(data[: len(data) // 2])
    head = bytearray(data)
    head[8] = ord("x")  # the header JSON no longer parses
    cases["bad_header"][0].write_bytes(bytes(head))
    flip = bytearray(data)
    flip[-5] ^= 0xFF
    cases["flipped_weight"][0].write_bytes(bytes(flip))
    import pickle

    cases["pickle"][0].write_bytes(pickle.dumps({"W1": np.zeros(3)}))
    for name, (p, match) in cases.items():
        with pytest.raises(LearnedModelFileError, match=match) as info:
            ResidualMLP.load(p)
        assert p.name in str(info.value), name


def test_model_file_rejects_wrong_version_and_architecture(fitted, tmp_path):
    _, path, _ = fitted
    v2 = _rewrite_header(path, tmp_path / "v2.safetensors", lambda m: m.update(format_version=2))
    with pytest.raises(LearnedModelFileError, match="format_version"):
        ResidualMLP.load(v2)
    arch = _rewrite_header(
        path, tmp_path / "arch.safetensors", lambda m: m["architecture"].update(hidden=64)
    )
    with pytest.raises(LearnedModelFileError, match=r"architecture\.hidden"):
        ResidualMLP.load(arch)
    kind = _rewrite_header(
        path, tmp_path / "kind.safetensors", lambda m: m["architecture"].update(kind="cnn")
    )
    with pytest.raises(LearnedModelFileError, match=r"architecture\.kind"):
        ResidualMLP.load(kind)
    other = tmp_path / "other.safetensors"
    from safetensors.numpy import save_file

    save_file({"x": np.zeros(2, np.float32)}, str(other))
    with pytest.raises(LearnedModelFileError, match="not a motion-envs"):
        ResidualMLP.load(other)
    write_model_file(tmp_path / "noarch.safetensors", {"x": np.zeros(2)}, {})
    with pytest.raises(LearnedModelFileError, match="architecture"):
        ResidualMLP.load(tmp_path / "noarch.safetensors")


# -- benchmark rows -----------------------------------------------------------------------


def test_orientation_rows_on_a_small_subset():
    from baselines.learned.rows import LEARNED_ROWS, compare, learned_orientation_rows
    from motion_envs.datasets import load_orientation_dataset

    ds = load_orientation_dataset("vr-kitchen")
    keep = np.isin(ds.subjects, np.unique(ds.subjects)[:3]) & (ds.replicates < 2)
    small = ds.subset(keep)
    rows = learned_orientation_rows(small, mlp_config=MLPConfig(max_epochs=5, inner_splits=2))
    assert list(rows.criteria) == list(LEARNED_ROWS)
    assert all(np.isfinite(v) for v in rows.criteria.values())
    comparisons = compare(rows, small.subjects, n_boot=50)
    assert {c["learned"] for c in comparisons} >= {"mlp_loso", "ridge_loso"}
    no_torch = learned_orientation_rows(small, use_torch=False)
    assert np.isnan(no_torch.criteria["mlp_loso"]) and "mlp_loso" in no_torch.skipped


def test_position_learned_columns_on_two_shapes():
    from baselines.learned.position import learned_position_predictions
    from motion_envs.datasets import load_position_dataset
    from motion_envs.datasets.resampling import resample_positions
    from motion_envs.datasets.splits import position_folds

    ds = load_position_dataset("lasa", ["Angle", "Sine"])
    y, dur = resample_positions(ds, 50)
    folds = [f for f in position_folds(ds) if f[0] == "Angle"]
    preds, chosen = learned_position_predictions(
        y, dur, folds, ["start", "end"], mlp_config=MLPConfig(max_epochs=5)
    )
    scored = np.concatenate([s for _, _, s in folds])
    for m in ("ridge", "mlp"):
        assert preds[m].shape == y[scored].shape
        assert np.allclose(preds[m][:, 0], y[scored, 0]) and np.allclose(
            preds[m][:, -1], y[scored, -1]
        )
    assert len(chosen["ridge"]) == len(folds)


def test_orientation_cli_without_torch_says_so(tmp_path, capsys, monkeypatch):
    import json

    import baselines.learned as learned
    from baselines.cli import main
    from motion_envs.datasets import load_vr_kitchen

    ds = load_vr_kitchen()
    keep = np.isin(ds.subjects, np.unique(ds.subjects)[:3]) & (ds.replicates < 2)
    path = ds.subset(keep).to_csv(tmp_path / "three.csv")
    reason = "torch is not installed (test)"
    monkeypatch.setattr(learned, "torch_missing_reason", lambda: reason)
    out = tmp_path / "o"
    assert main(["orientation", "--data", str(path), "--up", "0,1,0", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert f"mlp_loso: skipped ({reason})" in text
    doc = json.loads((out / "results.json").read_text())
    assert doc["criteria"]["mlp_loso"] is None and doc["criteria"]["ridge_loso"] > 0
    assert main(["orientation", "--data", str(path), "--up", "0,1"]) == 2
    assert "argument --up: expected three finite numbers" in capsys.readouterr().err
