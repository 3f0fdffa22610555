"""Property-based fuzzing (hypothesis) of every input surface in ``fuzz_registry``.

Properties: only the documented error types escape; each example finishes within a
time bound (hypothesis' ``deadline``); no NaN/inf leaves without an error; valid inputs
round-trip. Completeness: a public loader or env id missing from the registry fails.
"""

from __future__ import annotations

import argparse
import importlib
import math
import pkgutil
import warnings

import numpy as np
import pytest
from fuzz_registry import (
    CLI_NON_NUMERIC_TYPES,
    CLI_NUMERIC_OPTIONS,
    ENVS,
    LOADERS,
    MAX_FILE_BYTES,
)
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import motion_envs

FAST = settings(
    max_examples=25,
    deadline=3000,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
    derandomize=True,
)


def _resolve(target: str):
    module, _, qual = target.partition(":")
    obj = importlib.import_module(module)
    for part in qual.split("."):
        obj = getattr(obj, part)
    return obj


# -- completeness -----------------------------------------------------------------------
def _public_loaders() -> set[str]:
    found = set()
    for pkg_name in ("motion_envs.datasets", "motion_envs.models"):
        pkg = importlib.import_module(pkg_name)
        modules = [pkg_name] + [m.name for m in pkgutil.walk_packages(pkg.__path__, pkg_name + ".")]
        for name in modules:
            if any(part.startswith("_") for part in name.split(".")):
                continue
            with warnings.catch_warnings():
                warnings.simplefilter("error", DeprecationWarning)
                try:
                    mod = importlib.import_module(name)
                except DeprecationWarning:  # a shim re-exporting another module's names
                    continue
            for attr in getattr(mod, "__all__", ()):
                if attr.startswith(("load_", "read_")):
                    obj = getattr(mod, attr)
                    found.add(f"{obj.__module__}:{obj.__qualname__}")
    return found


def test_every_public_loader_is_in_the_registry():
    listed = set()
    for loader in LOADERS:
        obj = _resolve(loader.target)
        listed.add(f"{obj.__module__}:{obj.__qualname__}")
    missing = _public_loaders() - listed
    assert not missing, f"add these loaders to tests/fuzz_registry.py: {sorted(missing)}"


def test_every_env_id_is_in_the_registry():
    assert set(ENVS) == set(motion_envs.ENV_IDS)


def test_every_numeric_cli_option_is_in_the_registry():
    from baselines.cli import build_parser

    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    numeric = set()
    for name, sp in sub.choices.items():
        for action in sp._actions:
            if action.option_strings and action.type is not None:
                kind = getattr(action.type, "__name__", str(action.type))
                if kind not in CLI_NON_NUMERIC_TYPES:
                    numeric.add((name, action.option_strings[-1]))
    assert numeric == set(CLI_NUMERIC_OPTIONS)


# -- strategies ---------------------------------------------------------------------------
NUMBERS = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(min_value=-(10**400), max_value=10**400),
    st.sampled_from(["", "nan", "inf", "-inf", "1e300", "1e-300", "NA", "None", "abc", "0x10"]),
)
CELL = NUMBERS.map(str)
LABEL = st.text(alphabet=st.characters(blacklist_categories=["Cs"]), max_size=6)


@st.composite
def csv_texts(draw, header: tuple[str, ...]) -> bytes:
    """A CSV of ``header`` with mostly sane, sometimes absurd cells, blank lines, junk."""
    n = draw(st.integers(0, 30))
    rows = [",".join(header)]
    for k in range(n):
        cells = []
        for col in header:
            if col in ("trajectory", "subject", "task", "recording"):
                cells.append(draw(st.sampled_from(["a", "a", "b", "NA", "None", ""])))
            elif col == "phase":
                cells.append(draw(st.sampled_from(["toss", "go_down", "catch", "return", "x"])))
            elif col == "t":
                cells.append(draw(st.sampled_from([str(k * 0.005), str(k * 0.005), "1e300"])))
            else:
                cells.append(draw(st.one_of(st.floats(-2, 2).map(repr), CELL, st.just("0.5"))))
        rows.append(",".join(cells))
        if draw(st.booleans()) and draw(st.booleans()):
            rows.append("")
    text = "\n".join(rows).encode()
    return draw(st.one_of(st.just(text), st.binary(max_size=64).map(lambda b: text + b)))


HEADERS = {
    "csv": [
        ("trajectory", "subject", "task", "t", "qw", "qx", "qy", "qz"),
        ("trajectory", "subject", "task", "t", "x", "y"),
        ("trajectory", "subject", "task", "t", "x", "y", "z"),
    ],
    "juggling_csv": [
        ("t", "x", "z", "ball_x", "ball_z"),
        ("t", "x", "z", "ball_x", "ball_z", "phase", "recording"),
    ],
}


def _finite_everywhere(value, depth=0) -> bool:
    """No NaN/inf in any float array or float reachable from ``value`` (2 levels)."""
    if isinstance(value, float):
        return math.isfinite(value)
    if isinstance(value, np.ndarray):
        return value.dtype.kind != "f" or bool(np.isfinite(value).all())
    if depth > 2:
        return True
    if isinstance(value, (list, tuple)):
        return all(_finite_everywhere(v, depth + 1) for v in value)
    if hasattr(value, "__dict__"):
        return all(_finite_everywhere(v, depth + 1) for v in vars(value).values())
    return True


# -- CSV loaders ----------------------------------------------------------------------------
CSV_LOADERS = [ld for ld in LOADERS if ld.kind in HEADERS and not ld.not_fuzzed]


@pytest.mark.parametrize("loader", CSV_LOADERS, ids=lambda ld: ld.target)
@FAST
@given(data=st.data())
def test_csv_loaders_raise_only_documented_errors(tmp_path, loader, data):
    header = data.draw(st.sampled_from(HEADERS[loader.kind]))
    raw = data.draw(st.one_of(csv_texts(header), st.binary(max_size=MAX_FILE_BYTES)))
    path = tmp_path / "fuzz.csv"
    path.write_bytes(raw)
    func = _resolve(loader.target)
    args = ("fuzz",) if loader.target.endswith("read_csv_text") else ()
    try:
        out = func(path, *args)
    except loader.errors as exc:
        assert "\n" not in str(exc).strip(), str(exc)  # one line
        return
    assert _finite_everywhere(out), "a loader returned NaN/inf without an error"


# -- model files -------------------------------------------------------------------------------
@FAST
@given(
    raw=st.one_of(
        st.binary(max_size=MAX_FILE_BYTES),
        st.recursive(
            st.one_of(st.none(), st.booleans(), NUMBERS, st.text(max_size=8)),
            lambda inner: st.one_of(
                st.lists(inner, max_size=4), st.dictionaries(st.text(max_size=8), inner, max_size=4)
            ),
            max_leaves=20,
        ).map(lambda doc: repr(doc).replace("'", '"').encode()),
    )
)
def test_json_model_loader_raises_only_model_file_error(tmp_path, raw):
    from motion_envs.models.serialization import ModelFileError, load_model

    path = tmp_path / "m.json"
    path.write_bytes(raw)
    try:
        load_model(path)
    except ModelFileError:
        pass


@FAST
@given(raw=st.binary(max_size=MAX_FILE_BYTES), header=st.binary(max_size=200))
def test_safetensors_loaders_raise_only_their_error(tmp_path, raw, header):
    from baselines.learned.mlp_model import ResidualMLP
    from baselines.learned.model_file import LearnedModelFileError

    path = tmp_path / "m.safetensors"
    n = len(header).to_bytes(8, "little")
    path.write_bytes(n + header + raw)
    try:
        ResidualMLP.load(path)
    except (LearnedModelFileError, FileNotFoundError):
        pass


@FAST
@given(
    data=st.lists(
        st.lists(st.floats(-1e6, 1e6, allow_subnormal=False), min_size=10, max_size=10),
        min_size=5,
        max_size=8,
    ),
    labels=st.lists(st.sampled_from(["NA", "None", "a", "null", "b"]), min_size=3, max_size=3),
)
def test_valid_position_csv_round_trips(tmp_path, data, labels):
    """Any finite positions in range, any labels (``NA`` included), read back bit for bit."""
    from motion_envs.datasets.position_csv import PositionDataset, read_position_csv

    arr = np.array(data)
    ds = PositionDataset(
        name="x",
        positions=(arr[:, :2].copy(),),
        times=(np.arange(len(arr)) * 0.01,),
        trajectory_ids=np.array([labels[0]]),
        subjects=np.array([labels[1]]),
        tasks=np.array([labels[2]]),
        replicates=np.array([0]),
    )
    back = read_position_csv(ds.to_csv(tmp_path / "p.csv"))
    np.testing.assert_array_equal(back.positions[0], ds.positions[0])
    assert back.trajectory_ids.tolist() == [labels[0]] and back.tasks.tolist() == [labels[2]]


# -- configs -----------------------------------------------------------------------------------
YAML = st.recursive(
    st.one_of(st.none(), st.booleans(), NUMBERS.map(str), st.text(max_size=8)),
    lambda inner: st.one_of(
        st.lists(inner, max_size=3), st.dictionaries(st.text(max_size=8), inner, max_size=3)
    ),
    max_leaves=12,
)


@pytest.mark.parametrize(
    "target",
    [ld.target for ld in LOADERS if ld.kind == "yaml"],
)
@FAST
@given(data=st.data())
def test_config_loaders_raise_only_documented_errors(tmp_path, target, data):
    import yaml

    doc = data.draw(YAML)
    junk = st.binary(max_size=256).map(lambda b: b.decode("latin-1"))
    text = data.draw(st.one_of(st.just(yaml.safe_dump(doc)), junk))
    path = tmp_path / "c.yaml"
    path.write_text(text, encoding="utf-8")
    func = _resolve(target)
    try:
        if target.endswith("load_hyperparams"):
            func(path, "ppo", "MotionEnvs/PositionReach-v0")
        else:
            func(path)
    except (ValueError, FileNotFoundError):
        pass


# -- environments --------------------------------------------------------------------------------
VALUES = {
    "positive": st.one_of(st.floats(1e-3, 2.0), NUMBERS, st.none(), st.just(1j)),
    "fraction": st.one_of(st.floats(0.05, 0.5), NUMBERS, st.just("0.3")),
    "seed": st.one_of(st.integers(0, 2**64), NUMBERS, st.just(True)),
    "angle": st.one_of(st.floats(0, 30), NUMBERS),
    "small_int": st.one_of(st.integers(-2, 12), NUMBERS, st.just(2.0)),
    "size": st.one_of(st.integers(8, 64), NUMBERS),
    "phases": st.one_of(
        st.lists(st.sampled_from(["toss", "go_down", "catch", "return", "x", ""]), max_size=5),
        st.tuples(st.sampled_from(["catch", "toss"])),
        st.dictionaries(st.sampled_from(["catch", "toss"]), st.integers(), max_size=2),
        st.text(max_size=6),
        st.lists(NUMBERS, max_size=2),
        NUMBERS,
        st.none(),
    ),
}


def _spec(env_id):
    spec = ENVS[env_id]
    return ENVS[spec["same_as"]] if "same_as" in spec else spec


FUZZED_IDS = [i for i in ENVS if "skip" not in ENVS[i]]


@pytest.mark.filterwarnings("ignore::DeprecationWarning")
@pytest.mark.parametrize("env_id", FUZZED_IDS)
@settings(FAST, max_examples=12, deadline=None)
@given(data=st.data())
def test_env_constructors_raise_only_value_error(env_id, data):
    import gymnasium as gym

    kind = data.draw(st.sampled_from(sorted(_spec(env_id)["kwargs"].items())))
    value = data.draw(VALUES[kind[1]])
    try:
        env = gym.make(env_id, **{kind[0]: value}).unwrapped
    except ValueError as exc:
        assert "\n" not in str(exc)
        return
    obs, _ = env.reset(seed=0)
    assert np.isfinite(obs).all()
    env.close()


@pytest.fixture(scope="module")
def made_envs():
    import gymnasium as gym

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        return {i: gym.make(i).unwrapped for i in FUZZED_IDS}


ACTIONS = st.one_of(
    st.lists(st.floats(allow_nan=True, allow_infinity=True), min_size=0, max_size=5).map(np.array),
    st.lists(st.floats(-10, 10), min_size=2, max_size=4).map(np.array),
    st.lists(NUMBERS, max_size=4),
    st.sampled_from([None, {"a": 1}, "ab", 1j, np.array([1j, 0]), np.array([True, False])]),
)


@pytest.mark.parametrize("env_id", FUZZED_IDS)
@settings(FAST, max_examples=40)
@given(actions=st.lists(ACTIONS, min_size=1, max_size=5), seed=st.integers(0, 2**63 - 1))
def test_env_steps_raise_only_value_error_and_stay_finite(made_envs, env_id, actions, seed):
    env = made_envs[env_id]
    env.reset(seed=seed)
    for action in actions:
        try:
            obs, reward, terminated, truncated, info = env.step(action)
        except ValueError:
            continue
        assert np.isfinite(obs).all() and math.isfinite(reward)
        assert all(
            np.isfinite(v).all()
            for v in info.values()
            if isinstance(v, (float, np.ndarray)) and np.asarray(v).dtype.kind == "f"
        )
        if terminated or truncated:
            env.reset(seed=seed)


@pytest.mark.parametrize("env_id", FUZZED_IDS)
@settings(FAST, max_examples=25)
@given(
    options=st.one_of(
        st.none(),
        st.dictionaries(
            st.sampled_from(["cycle", "index", "reset_mask", "x"]), NUMBERS, max_size=2
        ),
    )
)
def test_env_reset_options_raise_only_value_error(made_envs, env_id, options):
    env = made_envs[env_id]
    try:
        obs, _ = env.reset(seed=0, options=options)
    except ValueError:
        return
    assert np.isfinite(obs).all()


# -- the CLI's numeric options -------------------------------------------------------------------
def _checker(command: str, option: str):
    from baselines.cli import build_parser

    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return next(a for a in sub.choices[command]._actions if option in a.option_strings).type


@pytest.mark.parametrize(("command", "option"), CLI_NUMERIC_OPTIONS)
@settings(FAST, max_examples=15)
@given(value=NUMBERS.map(str))
def test_cli_numeric_options_fail_with_one_line_or_parse_finite(command, option, value):
    """The option's checker (what argparse calls) returns a finite value or raises what
    argparse turns into one line and exit 2 (``ArgumentTypeError``/``ValueError``; an
    ``OverflowError`` would escape as a traceback)."""
    check = _checker(command, option)
    try:
        parsed = check(value)
    except (argparse.ArgumentTypeError, ValueError) as exc:
        assert "\n" not in str(exc)
        return
    for v in np.atleast_1d(np.asarray(getattr(parsed, "gravity", parsed), dtype=object)).ravel():
        if isinstance(v, float):
            assert math.isfinite(v)
