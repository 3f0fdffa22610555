"""Property-based fuzzing (hypothesis) of every input surface in ``fuzz_registry``.

Properties: only the documented error types escape; each example finishes within a
time bound (hypothesis' ``deadline``); no NaN/inf leaves without an error; valid inputs
round-trip. Completeness: a public loader, an env id, an argument of an env constructor
or of a vector entry point, or a ``motion-bench`` option missing from the registry fails.
Surfaces: the CSV, model, config and run-folder loaders; motion capture text files with
numeric extremes and repeated names; segments tables; ``FILE?query`` data strings; every
CLI option that reads a file (FIFOs, devices, symbolic links to them, folders) and every
``--out`` (FIFOs, devices, symbolic links, inputs); every env and vector argument.
"""

from __future__ import annotations

import argparse
import importlib
import inspect
import json
import math
import os
import pkgutil
import tempfile
import threading
import warnings
from pathlib import Path

import numpy as np
import pytest
from fuzz_registry import (
    CLI_FILE_OPTIONS,
    CLI_FILE_TYPES,
    CLI_NAME_TYPES,
    CLI_NON_NUMERIC_TYPES,
    CLI_NUMERIC_OPTIONS,
    CLI_OUTPUT_OPTIONS,
    CLI_OUTPUT_TYPES,
    ENVS,
    LOADERS,
    MAX_FILE_BYTES,
    VECTOR_ARGS,
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
    for pkg_name in ("motion_envs.datasets", "motion_envs.models", "baselines"):
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


def _entry(ep):
    if callable(ep):
        return ep
    return _resolve(ep)


def _parameters(func) -> set[str]:
    return {
        p.name
        for p in inspect.signature(func).parameters.values()
        if p.kind not in (p.VAR_KEYWORD, p.VAR_POSITIONAL)
    }


@pytest.mark.parametrize("env_id", sorted(ENVS))
def test_every_env_argument_is_in_the_registry(env_id):
    import gymnasium as gym

    spec = gym.spec(env_id)
    taken = _parameters(_entry(spec.entry_point))
    assert set(_spec(env_id)["kwargs"]) == taken, "list them in tests/fuzz_registry.py ENVS"


@pytest.mark.parametrize("env_id", sorted(ENVS))
def test_every_vector_argument_is_in_the_registry(env_id):
    import gymnasium as gym

    vector = gym.spec(env_id).vector_entry_point
    assert vector is not None
    missing = _parameters(_entry(vector)) - set(VECTOR_ARGS)
    assert not missing, f"add to VECTOR_ARGS in tests/fuzz_registry.py: {sorted(missing)}"


def _cli_actions():
    from baselines.cli import build_parser

    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    for name, sp in sub.choices.items():
        for action in sp._actions:
            if action.type is not None:
                yield name, (action.option_strings or [action.dest])[-1], action.type


def test_every_cli_option_is_classified_and_file_options_are_marked():
    """Each option with a checker is numeric, a file the command reads (its checker
    marked ``reads_files``), an output or a name: exactly one, and the lists agree."""
    files, outputs = set(), set()
    for command, option, check in _cli_actions():
        kind = getattr(check, "__name__", str(check))
        marked = getattr(check, "reads_files", False)
        assert marked == (kind in CLI_FILE_TYPES), (command, option, kind)
        if marked:
            files.add((command, option))
        if kind in CLI_OUTPUT_TYPES:
            outputs.add((command, option))
        groups = [kind in CLI_FILE_TYPES, kind in CLI_OUTPUT_TYPES, kind in CLI_NAME_TYPES]
        assert sum(groups) <= 1, kind
    assert files == set(CLI_FILE_OPTIONS)
    assert outputs == set(CLI_OUTPUT_OPTIONS)


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
#: Odd files a ``data=`` or a CLI option may name: a FIFO nobody writes, a device, a
#: symbolic link to a device, a folder (made once per test session).
_ODD = Path(tempfile.mkdtemp(prefix="fuzz-odd-"))
if hasattr(os, "mkfifo"):
    os.mkfifo(_ODD / "fifo.csv")
    os.mkfifo(_ODD / "fifo.tsv")
(_ODD / "zero.csv").symlink_to("/dev/zero")
(_ODD / "zero.tsv").symlink_to("/dev/zero")
(_ODD / "folder.csv").mkdir()
ODD_FILES = [*sorted(str(p) for p in _ODD.iterdir()), "/dev/zero", "/dev/null"]

COUNT = st.one_of(
    st.integers(-2, 4),
    st.sampled_from([2**24 - 1, 2**24, 10**9, 2**63]),
    NUMBERS,
    st.just(2.0),
    st.just(True),
)
VALUES = {
    "positive": st.one_of(st.floats(1e-3, 2.0), NUMBERS, st.none(), st.just(1j)),
    "fraction": st.one_of(st.floats(0.05, 0.5), NUMBERS, st.just("0.3")),
    "seed": st.one_of(st.integers(0, 2**64), NUMBERS, st.just(True)),
    "angle": st.one_of(st.floats(0, 30), NUMBERS),
    "small_int": st.one_of(st.integers(-2, 12), NUMBERS, st.just(2.0)),
    "optional_int": st.one_of(st.none(), st.integers(-2, 12), NUMBERS),
    "size": st.one_of(st.integers(8, 64), NUMBERS),
    "flag": st.one_of(st.booleans(), NUMBERS, st.none(), st.text(max_size=3)),
    "name": st.one_of(
        st.sampled_from(["train", "test", "val", "easy", "hard", "slerp", "sine", "rgb_array"]),
        st.text(max_size=8),
        NUMBERS,
        st.none(),
    ),
    # gym.make reads render_mode itself first (a number fails inside Gymnasium, before
    # the environment's check): strings and None
    "render_mode": st.one_of(
        st.none(), st.sampled_from(["rgb_array", "human"]), st.text(max_size=8)
    ),
    "names": st.one_of(
        st.none(),
        st.lists(st.sampled_from(["Angle", "GShape", "x", ""]), max_size=3),
        st.text(max_size=5),
        NUMBERS,
    ),
    "weights": st.one_of(
        st.none(),
        st.dictionaries(
            st.sampled_from(["error", "catch", "drop", "likeness", "action", "x"]),
            NUMBERS,
            max_size=3,
        ),
        NUMBERS,
        st.text(max_size=4),
    ),
    "data": st.one_of(
        st.sampled_from(
            [
                "vr-kitchen",
                "lasa",
                "simulated",
                "missing.csv",
                "missing.c3d?marker=a",
                "x.tsv?bad",
                "",
                *ODD_FILES,
                *(f + "?marker=a" for f in ODD_FILES if f.endswith(".tsv")),
            ]
        ),
        st.none(),
        NUMBERS,
    ),
    # the ends of Juggling-v1's and Cascade-v0's ranges (models.juggling.gravity_range)
    "gravity": st.one_of(
        st.sampled_from([1e-300, 1e-6, 1e-3, 0.0013, 0.0081, 9.81, 35.9, 36.1, 100.0]), NUMBERS
    ),
    "count": COUNT,
    "optional_count": st.one_of(st.none(), COUNT),
    # a release-anchored estimate's delay rule: a callable, or anything else
    "rule": st.one_of(
        st.none(), st.just(lambda flights, gravity: 0.15), NUMBERS, st.text(max_size=3)
    ),
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
#: Errors a constructor documents per kind of argument (a file that does not exist is a
#: ``FileNotFoundError``).
KIND_ERRORS = {"data": (ValueError, FileNotFoundError)}


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
        env = _within(60, lambda: gym.make(env_id, **{kind[0]: value}).unwrapped)
    except KIND_ERRORS.get(kind[1], ValueError) as exc:
        assert "\n" not in str(exc)
        return
    obs, _ = env.reset(seed=0)
    assert np.isfinite(obs).all()
    env.close()


def _within(seconds: float, func):
    """``func()``, failing the test if it has not returned after ``seconds`` (a hang)."""
    box: dict[str, object] = {}

    def run():
        try:
            box["value"] = func()
        except BaseException as exc:  # re-raised in the test's thread
            box["error"] = exc

    worker = threading.Thread(target=run, daemon=True)
    worker.start()
    worker.join(seconds)
    assert not worker.is_alive(), f"no answer within {seconds} s (a hang)"
    if "error" in box:
        raise box["error"]  # type: ignore[misc]
    return box.get("value")


@pytest.mark.filterwarnings("ignore::DeprecationWarning")
@pytest.mark.parametrize("env_id", FUZZED_IDS)
@settings(FAST, max_examples=8, deadline=None)
@given(data=st.data())
def test_vector_arguments_raise_only_value_error(env_id, data):
    """``gym.make_vec``'s own arguments (``num_envs``, ``threads``, ``autoreset_mode``,
    ...): a one-line ``ValueError`` (``num_envs`` beyond memory included) or a vector env
    whose first observations are finite, within a time bound."""
    import gymnasium as gym

    vector = gym.spec(env_id).vector_entry_point
    names = sorted(_parameters(_entry(vector)) & set(VECTOR_ARGS))
    name = data.draw(st.sampled_from(names))
    value = data.draw(VALUES[VECTOR_ARGS[name]])
    kwargs = {name: value} if name == "num_envs" else {"num_envs": 2, name: value}
    try:
        venv = _within(60, lambda: gym.make_vec(env_id, **kwargs))
    except ValueError as exc:
        assert "\n" not in str(exc)
        return
    obs, _ = venv.reset(seed=0)
    assert np.isfinite(obs).all()
    venv.close()


@pytest.fixture(scope="module")
def made_envs():
    import gymnasium as gym

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        envs = {i: gym.make(i).unwrapped for i in FUZZED_IDS}
    # one step each before the timed examples: a compiled kernel's first call (numba's
    # compilation or cache load) is not what hypothesis' deadline is there to measure
    for env in envs.values():
        env.reset(seed=0)
        env.step(np.zeros(env.action_space.shape, dtype=env.action_space.dtype))
    return envs


ACTIONS = st.one_of(
    st.lists(st.floats(allow_nan=True, allow_infinity=True), min_size=0, max_size=5).map(np.array),
    st.lists(st.floats(-10, 10), min_size=2, max_size=4).map(np.array),
    st.lists(NUMBERS, max_size=4),
    st.sampled_from([None, {"a": 1}, "ab", 1j, np.array([1j, 0]), np.array([True, False])]),
)


#: Info entries documented as NaN where they do not apply (Juggling-v2's and Cascade-v1's
#: per-catch task error: the hand that did not catch, or a timing outside the catch phase;
#: its catch speed likewise): NaN allowed there, never an infinity.
NAN_DOCUMENTED = frozenset({"task_error", "catch_speed"})


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
        floats = {
            k: np.asarray(v)
            for k, v in info.items()
            if isinstance(v, (float, np.ndarray)) and np.asarray(v).dtype.kind == "f"
        }
        assert all(np.isfinite(v).all() for k, v in floats.items() if k not in NAN_DOCUMENTED)
        assert not any(np.isinf(v).any() for k, v in floats.items() if k in NAN_DOCUMENTED)
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
    actions = sub.choices[command]._actions
    return next(a for a in actions if option in a.option_strings or option == a.dest).type


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


@pytest.mark.parametrize("pattern", ["3" * 65, "3" * 300, "53" * 40])
def test_long_siteswaps_are_refused_before_running(pattern):
    check = _checker("juggling", "--pattern")
    with pytest.raises(argparse.ArgumentTypeError, match="at most 64"):
        check(pattern)


# -- the CLI's file options and outputs -----------------------------------------------------------
@pytest.mark.parametrize(("command", "option"), CLI_FILE_OPTIONS)
@pytest.mark.parametrize("odd", ODD_FILES, ids=lambda p: Path(p).name)
def test_cli_file_options_refuse_fifos_devices_and_links_in_one_line(command, option, odd):
    """Every option that reads a file, given a FIFO without a writer, ``/dev/zero``, a
    symbolic link to it, a folder or ``/dev/null``: one line (argparse's exit 2) within
    seconds, whatever the option does with names (``FILE?query`` included)."""
    check = _checker(command, option)
    texts = [odd]
    if Path(odd).suffix in (".tsv", ".csv"):
        texts.append(odd + "?marker=a&ball=b&markers=a,b,c")
    for text in texts:
        try:
            _within(20, lambda text=text: check(text))
        except (argparse.ArgumentTypeError, ValueError) as exc:
            assert "\n" not in str(exc).strip(), str(exc)
            continue
        pytest.fail(f"{command} {option} {text} was accepted")


@pytest.mark.parametrize(("command", "option"), CLI_OUTPUT_OPTIONS)
@pytest.mark.parametrize("odd", ["fifo.csv", "zero.csv", "/dev/null", "link"])
def test_cli_outputs_refuse_what_they_would_replace(tmp_path, command, option, odd):
    """An ``--out`` that is a FIFO, a device, or a symbolic link (to a file or a folder)
    is refused in one line before anything runs: never replaced by a regular file."""
    if odd == "link":
        target = tmp_path / "target"
        target.mkdir()
        (tmp_path / "link").symlink_to(target)
        odd = str(tmp_path / "link")
    elif not odd.startswith("/"):
        odd = str(_ODD / odd)
    check = _checker(command, option)
    with pytest.raises(argparse.ArgumentTypeError) as info:
        check(odd)
    assert "\n" not in str(info.value)


@settings(FAST, max_examples=30)
@given(
    query=st.lists(
        st.tuples(
            st.sampled_from(
                [
                    "marker",
                    "markers",
                    "ball",
                    "balls",
                    "unit",
                    "up",
                    "max-gap",
                    "segments",
                    "speed-threshold",
                    "x",
                    "",
                ]
            ),
            st.one_of(NUMBERS.map(str), st.text(max_size=6), st.sampled_from(ODD_FILES)),
        ),
        max_size=4,
    ),
    suffix=st.sampled_from([".tsv", ".c3d", ".bvh"]),
    kind=st.sampled_from(["orientation", "position", "juggling"]),
)
def test_data_query_strings_give_one_line_or_a_source(tmp_path, query, suffix, kind):
    """``--data 'FILE?option=value&...'``: one ``ArgumentTypeError`` line naming the
    option, or the string back (the file then exists)."""
    from baselines import options

    rec = tmp_path / f"rec{suffix}"
    rec.write_text("FREQUENCY\t100\n")
    text = str(rec) + "?" + "&".join(f"{k}={v}" for k, v in query)
    try:
        out = _within(20, lambda: options.mocap_data(text, kind))
    except argparse.ArgumentTypeError as exc:
        assert "\n" not in str(exc)
        return
    assert out == text


# -- motion capture text files: numeric extremes and repeated names ------------------------------
EXTREME = st.one_of(
    st.sampled_from(["1e-310", "1e308", "3e38", "1e-38", "inf", "nan", "-5", "0", "120", "100"]),
    NUMBERS.map(str),
)


@st.composite
def tsv_texts(draw) -> str:
    names = draw(
        st.lists(
            st.sampled_from(["hand", "ball", "hand", "x", "Unidentified 1"]), min_size=1, max_size=3
        )
    )
    n = draw(st.integers(0, 12))
    head = [
        f"NO_OF_FRAMES\t{draw(st.one_of(st.just(str(n)), EXTREME))}",
        f"FREQUENCY\t{draw(st.one_of(st.just('100'), EXTREME))}",
        "MARKER_NAMES\t" + "\t".join(names),
    ]
    value = st.one_of(st.floats(-2000, 2000).map(repr), EXTREME)
    rows = ["\t".join(draw(value) for _ in range(3 * len(names))) for _ in range(n)]
    return "\n".join(head + rows) + "\n"


@st.composite
def bvh_texts(draw) -> str:
    joint = draw(st.sampled_from(["hand", "root"]))
    n = draw(st.integers(1, 6))
    offset = st.one_of(st.floats(-100, 100).map(repr), EXTREME)
    lines = [
        "HIERARCHY",
        "ROOT root",
        "{",
        f"  OFFSET {draw(offset)} 0 0",
        "  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation",
        f"  JOINT {joint}",
        "  {",
        f"    OFFSET 0 {draw(offset)} 0",
        "    CHANNELS 3 Zrotation Xrotation Yrotation",
        "    End Site",
        "    {",
        "      OFFSET 0 1 0",
        "    }",
        "  }",
        "}",
        "MOTION",
        f"Frames: {n}",
        f"Frame Time: {draw(st.one_of(st.just('0.01'), EXTREME))}",
    ]
    channel = st.one_of(st.floats(-90, 90).map(repr), EXTREME)
    lines += [" ".join(draw(channel) for _ in range(9)) for _ in range(n)]
    return "\n".join(lines) + "\n"


def _physical(dataset) -> None:
    """Times finite and sampled at a plausible rate, positions within a capture volume."""
    from motion_envs.datasets.mocap import MAX_ABS_POSITION_M, MAX_RATE_HZ

    for t in dataset.times:
        assert np.isfinite(t).all() and np.all(np.diff(t) >= 1.0 / MAX_RATE_HZ - 1e-12)
    for y in getattr(dataset, "positions", ()):
        assert np.isfinite(y).all() and np.abs(y).max() <= MAX_ABS_POSITION_M


@settings(FAST, max_examples=60)
@given(data=st.data())
def test_mocap_extremes_and_repeated_names_raise_one_line_or_are_physical(tmp_path, data):
    """TSV and BVH with absurd rates, frame counts, values and repeated names, through
    the one import every path uses: a one-line ``ValueError`` naming the file, or a
    dataset whose times and positions are physical."""
    from motion_envs.datasets.mocap import ImportOptions, import_position

    fmt = data.draw(st.sampled_from(["tsv", "bvh"]))
    path = tmp_path / f"rec.{fmt}"
    path.write_text(data.draw(tsv_texts() if fmt == "tsv" else bvh_texts()))
    opts = ImportOptions(marker="hand") if fmt == "tsv" else ImportOptions(joint="hand", unit="cm")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # the unit warning of tiny positions
        try:
            ds, _ = _within(30, lambda: import_position(path, opts))
        except ValueError as exc:
            message = str(exc)
            assert "\n" not in message and str(path) in message, message
            return
    _physical(ds)


@settings(FAST, max_examples=25)
@given(
    rows=st.lists(st.tuples(EXTREME, EXTREME, st.sampled_from(["a", "a", "b", ""])), max_size=6),
    many=st.sampled_from([0, 0, 10_001]),
)
def test_segments_tables_raise_one_line(tmp_path, rows, many):
    """A segments table with absurd times, repeated names or too many rows: one line
    naming the table, within seconds."""
    from motion_envs.datasets.mocap import read_segments

    lines = ["start,end,trajectory"] + [",".join(r) for r in rows]
    lines += [f"{k},{k + 0.5},m{k}" for k in range(many)]
    path = tmp_path / "segments.csv"
    path.write_text("\n".join(lines) + "\n")
    try:
        out = _within(20, lambda: read_segments(path))
    except ValueError as exc:
        assert "\n" not in str(exc) and str(path) in str(exc), str(exc)
        return
    assert all(math.isfinite(r.start) and r.end > r.start for r in out)


# -- run folders ----------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def run_folder(tmp_path_factory):
    pytest.importorskip("stable_baselines3")
    from _helpers import train_tiny_run

    return train_tiny_run(tmp_path_factory.mktemp("fuzz-run") / "run")


def _rehash(folder: Path) -> None:
    """Recompute every SHA-256 of ``run.json`` (its own included), as a careful tamperer."""
    from baselines.agents.rundir import file_sha256, manifest_sha256

    manifest = json.loads((folder / "run.json").read_text())
    if isinstance(manifest, dict) and isinstance(manifest.get("files"), dict):
        for name in list(manifest["files"]):
            if (folder / name).is_file():
                manifest["files"][name] = file_sha256(folder / name)
        manifest["manifest_sha256"] = manifest_sha256(manifest)
    (folder / "run.json").write_text(json.dumps(manifest))


JSON_VALUES = st.recursive(
    st.one_of(
        st.none(),
        st.booleans(),
        st.integers(-(2**70), 2**70),
        st.text(max_size=6),
        st.floats(allow_nan=False),
    ),
    lambda inner: st.one_of(
        st.lists(inner, max_size=3), st.dictionaries(st.text(max_size=6), inner, max_size=3)
    ),
    max_leaves=8,
)


@pytest.mark.filterwarnings("ignore")
@settings(FAST, max_examples=30, deadline=None)
@given(data=st.data())
def test_tampered_run_folders_give_one_line(run_folder, tmp_path_factory, data):
    """A run folder whose files were changed and whose hashes were recomputed (run.json's
    own included): ``load_run`` loads it or raises one ``ValueError`` line naming the
    folder, never UnpicklingError, TypeError, RuntimeError or RecursionError."""
    import shutil
    import zipfile

    from baselines.agents.rundir import load_run

    folder = tmp_path_factory.mktemp("tampered") / "run"
    shutil.copytree(run_folder, folder)
    target = data.draw(
        st.sampled_from(["config.json", "agent.zip", "normalization.npz", "run.json", "deep"])
    )
    if target == "config.json":
        doc = json.loads((folder / target).read_text())
        key = data.draw(st.sampled_from(["algo", "env_id", "seed", "hyperparams", "x"]))
        doc[key] = data.draw(JSON_VALUES)
        (folder / target).write_text(json.dumps(doc))
    elif target == "agent.zip":
        member = data.draw(st.sampled_from(["policy.pth", "data", "pytorch_variables.pth", "x"]))
        payload = data.draw(st.one_of(st.binary(max_size=256), st.just(b"\x80\x04cos\nsystem\n.")))
        with zipfile.ZipFile(folder / target, "a") as z:
            z.writestr(member, payload)
    elif target == "normalization.npz":
        arrays = {
            "obs_mean": data.draw(
                st.sampled_from([np.zeros(3), np.full(41, np.nan), np.ones((2, 2))])
            ),
            "obs_var": data.draw(st.sampled_from([np.ones(41), -np.ones(41), np.ones(3)])),
            "epsilon": np.float64(data.draw(st.sampled_from([1e-8, 0.0, np.inf]))),
            "clip_obs": np.float64(10.0),
            "norm_obs": np.bool_(True),
        }
        with open(folder / target, "wb") as fh:
            np.savez(fh, **arrays)
    elif target == "run.json":
        doc = json.loads((folder / target).read_text())
        doc[data.draw(st.sampled_from(["format", "files", "seed", "algo"]))] = data.draw(
            JSON_VALUES
        )
        (folder / target).write_text(json.dumps(doc))
    else:  # JSON nested past the parser's limit
        (folder / "config.json").write_text("[" * 100_000 + "]" * 100_000)
    _rehash(folder)
    try:
        load_run(folder)
    except ValueError as exc:
        assert "\n" not in str(exc) and str(folder) in str(exc), str(exc)
