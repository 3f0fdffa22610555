"""Issue 36, "Nothing lost, nothing hung": each audit finding as the user's call.

Outputs never replace what is not a regular output file (an input, a FIFO, a device, a
symbolic link); every CLI input file is read by the safe reader (no hang on a FIFO or
``/dev/zero``); every recording is held to physical bounds whatever the path; env
arguments are bounded by what the models can do; run folders load or fail in one line.
Commands run as subprocesses with a 60 s bound: a hang fails the test.
"""

from __future__ import annotations

import errno
import json
import os
import shutil
import subprocess
import sys
import time
import warnings
import zipfile
from pathlib import Path

import ezc3d
import numpy as np
import pytest

from motion_envs.datasets.mocap import ImportOptions, import_position
from tests.test_mocap import RATE, marker_points, synthetic_movement, write_c3d, write_tsv

ROOT = Path(__file__).resolve().parents[1]
ENV = {**os.environ, "PYTHONPATH": str(ROOT)}
HANG = 60  # s: the audit's bound


def cli(
    *args: str, cwd: Path | None = None, timeout: float = HANG
) -> subprocess.CompletedProcess[str]:
    """``motion-bench ARGS`` in a subprocess (``timeout`` s bound, default :data:`HANG`:
    a hang raises TimeoutExpired)."""
    return subprocess.run(
        [sys.executable, "-m", "baselines.cli", *args],
        capture_output=True,
        text=True,
        env=ENV,
        cwd=cwd or ROOT,
        timeout=timeout,
    )


def one_line(proc: subprocess.CompletedProcess[str], status: int = 2) -> str:
    line = proc.stderr.strip()
    assert proc.returncode == status, (proc.returncode, proc.stderr)
    assert line.count("\n") == 0 and "Traceback" not in line, line
    return line


def import_line(path: Path, out: Path, *options: str) -> str:
    """The one error line of ``motion-bench import PATH --kind position OPTIONS --out OUT``."""
    return one_line(cli("import", str(path), "--kind", "position", *options, "--out", str(out)))


@pytest.fixture(scope="module")
def tsv(tmp_path_factory) -> Path:
    """A Qualisys TSV of the synthetic reaches (three markers, mm)."""
    _, rot, pos = synthetic_movement()
    path = tmp_path_factory.mktemp("rec") / "rec.tsv"
    write_tsv(path, marker_points(rot, pos) * 1000.0, ["O", "X", "P"])
    return path


def fifo(path: Path) -> Path:
    if not hasattr(os, "mkfifo"):
        pytest.skip("no FIFOs on this platform")
    os.mkfifo(path)
    return path


# -- 1. one output rule ---------------------------------------------------------------------------
def test_import_out_same_as_the_input_is_refused_and_the_recording_kept(tsv, tmp_path):
    rec = tmp_path / "rec.tsv"
    shutil.copy(tsv, rec)
    before = rec.read_bytes()
    line = import_line(rec, rec, "--marker", "O")
    assert "argument --out" in line and "is the input" in line
    assert rec.read_bytes() == before
    # the same file under another name (a hard link) is the same input
    os.link(rec, tmp_path / "alias.csv")
    line = import_line(rec, tmp_path / "alias.csv", "--marker", "O")
    assert "is the input" in line and rec.read_bytes() == before


@pytest.mark.parametrize("kind", ["fifo", "symlink", "device"])
def test_import_out_that_is_not_a_regular_file_is_refused(tsv, tmp_path, kind):
    if kind == "fifo":
        out = fifo(tmp_path / "out.csv")
    elif kind == "symlink":
        target = tmp_path / "precious.txt"
        target.write_text("keep me")
        out = tmp_path / "out.csv"
        out.symlink_to(target)
    else:
        out = Path("/dev/null")
    line = import_line(tsv, out, "--marker", "O")
    assert "argument --out" in line
    if kind == "fifo":
        assert out.is_fifo()
    elif kind == "symlink":
        assert out.is_symlink() and (tmp_path / "precious.txt").read_text() == "keep me"
    else:
        assert out.is_char_device()


@pytest.mark.slow  # a whole position benchmark before the refused write
def test_an_output_folder_holding_the_input_does_not_replace_it(tmp_path):
    """``position --data out/results.csv --out out``: the run would write out/results.csv;
    the input is protected and the write refused in one line."""
    from motion_envs.datasets import load_position_dataset

    out = tmp_path / "out"
    out.mkdir()
    data = load_position_dataset("lasa").to_csv(out / "results.csv")
    before = Path(data).read_bytes()
    proc = cli(
        *("position", "--data", str(data), "--out", str(out), "--n-sines", "2"),
        *("--no-progress", "--learned", "off"),
        timeout=600,
    )
    line = one_line(proc)
    assert "is the input" in line and "refusing to overwrite" in line
    assert Path(data).read_bytes() == before


def test_atomic_write_refuses_links_and_devices_and_names_a_full_disk(tmp_path):
    from motion_envs._io import UserFileError, atomic_write, atomic_write_text

    target = tmp_path / "real.txt"
    target.write_text("keep")
    (tmp_path / "link.txt").symlink_to(target)
    with pytest.raises(UserFileError, match="symbolic link"):
        atomic_write_text(tmp_path / "link.txt", "new")
    assert target.read_text() == "keep"

    def full(fh):
        raise OSError(errno.ENOSPC, "No space left on device")

    with pytest.raises(OSError) as info:
        atomic_write(tmp_path / "out.json", full)
    assert info.value.errno == errno.ENOSPC and str(tmp_path / "out.json") in str(info.value)
    assert list(tmp_path.iterdir()) == [target, tmp_path / "link.txt"] or sorted(
        p.name for p in tmp_path.iterdir()
    ) == ["link.txt", "real.txt"]


def test_a_second_train_into_a_locked_run_folder_stops_at_once(tmp_path):
    out = tmp_path / "run"
    holder = subprocess.Popen(
        [
            sys.executable,
            "-c",
            "import sys, time\nfrom motion_envs._io import folder_lock\n"
            f"with folder_lock({str(out)!r}):\n    print('locked', flush=True)\n    time.sleep(60)",
        ],
        stdout=subprocess.PIPE,
        text=True,
        env=ENV,
        cwd=ROOT,
    )
    try:
        assert holder.stdout is not None and holder.stdout.readline().strip() == "locked"
        t0 = time.monotonic()
        line = one_line(
            cli(
                "train",
                "--algo",
                "ppo",
                "--env",
                "MotionEnvs/PositionReach-v1",
                "--timesteps",
                "100",
                "--out",
                str(out),
            )
        )
        assert "being written by another process" in line
        assert time.monotonic() - t0 < HANG
    finally:
        holder.kill()
        holder.wait()


# -- 2. one input rule -------------------------------------------------------------------------
def _odd_inputs(tmp_path: Path) -> dict[str, Path]:
    link = tmp_path / "zero.csv"
    link.symlink_to("/dev/zero")
    return {"fifo": fifo(tmp_path / "pipe.csv"), "dev": Path("/dev/zero"), "link": link}


@pytest.mark.parametrize(
    "args",
    [
        ["juggling", "--analyse", "{}"],
        ["juggling", "--data", "{}"],
        ["orientation", "--data", "{}"],
        ["position", "--data", "{}"],
        ["import", "{}", "--kind", "position", "--marker", "O", "--out", "OUT"],
        ["train", "--algo", "ppo", "--env", "MotionEnvs/PositionReach-v1", "--config", "{}"],
        ["calibrate-cohort", "--target", "{}"],
    ],
    ids=lambda a: " ".join(a[:2]),
)
@pytest.mark.slow  # three subprocess jobs per option
def test_fifos_devices_and_links_to_them_are_one_line_never_a_hang(tmp_path, args):
    for name, path in _odd_inputs(tmp_path).items():
        argv = [a.replace("{}", str(path)).replace("OUT", str(tmp_path / "o.csv")) for a in args]
        line = one_line(cli(*argv))
        assert "does not exist" not in line, (name, line)  # says what it is instead
        assert str(path) in line, (name, line)


def test_import_segments_fifo_and_query_string_fifo(tmp_path, tsv):
    pipe = fifo(tmp_path / "segments.csv")
    line = import_line(tsv, tmp_path / "o.csv", "--marker", "O", "--segments", str(pipe))
    assert "FIFO" in line
    tsv_pipe = fifo(tmp_path / "rec.tsv")
    line = one_line(cli("position", "--data", f"{tsv_pipe}?marker=O"))
    assert "FIFO" in line


def test_analyse_a_long_first_line_is_bounded(tmp_path):
    big = tmp_path / "big.csv"
    big.write_bytes(b"t" + b"x" * (1 << 17))  # one line of 128 KiB, no newline
    line = one_line(cli("juggling", "--analyse", str(big)))
    assert "line 1 is longer than" in line


# -- 3. physical bounds of every recording -------------------------------------------------------
def _tsv_text(
    frequency: str = "120",
    value: str | None = None,
    names=("O", "X", "P"),
    frames: str | None = None,
) -> str:
    _, rot, pos = synthetic_movement()
    pts = marker_points(rot, pos)[:200] * 1000.0
    n = pts.shape[0]
    rows = [
        "\t".join([str(i + 1), repr(i / 120), *(repr(float(v)) for v in row)])
        for i, row in enumerate(pts.reshape(n, -1))
    ]
    if value is not None:
        rows[5] = rows[5].rsplit("\t", 1)[0] + "\t" + value
    head = [
        f"NO_OF_FRAMES\t{frames or n}",
        f"FREQUENCY\t{frequency}",
        "MARKER_NAMES\t" + "\t".join(names),
        "\t".join(["Frame", "Time", *(f"{m} {a}" for m in names for a in "XYZ")]),
    ]
    return "\n".join(head + rows) + "\n"


@pytest.mark.parametrize(
    ("text", "match"),
    [
        (_tsv_text(frequency="1e-310"), "frame rate"),
        (_tsv_text(frequency="3e38"), "frame rate"),
        (_tsv_text(value="1e308"), "does not fit a human body"),
        (_tsv_text(names=("O", "X", "O")), "appear more than once"),
        (_tsv_text(frames="-5"), "NO_OF_FRAMES"),
    ],
    ids=["rate-1e-310", "rate-3e38", "value-1e308", "duplicate-marker", "frames--5"],
)
def test_import_refuses_unphysical_tsv_in_one_line(tmp_path, text, match):
    rec = tmp_path / "rec.tsv"
    rec.write_text(text)
    out = tmp_path / "o.csv"
    line = import_line(rec, out, "--marker", "O")
    assert match in line and str(rec) in line
    assert not out.exists()


def test_bvh_frame_time_1e308_and_duplicate_joint_are_refused(tmp_path):
    from tests.test_mocap import write_bvh

    t = np.arange(20) / RATE
    write_bvh(tmp_path / "a.bvh", t, np.zeros((20, 3)), np.zeros((20, 3, 3)))
    text = (tmp_path / "a.bvh").read_text()
    slow = tmp_path / "slow.bvh"
    slow.write_text(text.replace(f"Frame Time: {1 / RATE!r}", "Frame Time: 1e308"))
    dup = tmp_path / "dup.bvh"
    dup.write_text(text.replace("JOINT Hand", "JOINT Chest"))
    for path, match in ((slow, "frame rate"), (dup, "appear more than once")):
        line = import_line(path, tmp_path / "o.csv", "--joint", "Chest", "--unit", "cm")
        assert match in line and str(path) in line


@pytest.fixture(scope="module")
def c3d_in_metres(tmp_path_factory) -> Path:
    """A C3D of millimetre data that declares ``m`` (the audit's 1,198 m hand)."""
    _, rot, pos = synthetic_movement()
    path = tmp_path_factory.mktemp("c3d") / "rec.c3d"
    write_c3d(path, marker_points(rot, pos), ["O", "X", "P"])
    c3d = ezc3d.c3d(str(path))
    c3d["parameters"]["POINT"]["UNITS"]["value"] = ["m"]
    c3d.write(str(path))
    return path


def test_c3d_declaring_metres_for_millimetres_is_refused_on_every_path(c3d_in_metres, tmp_path):
    rec = c3d_in_metres
    line = import_line(rec, tmp_path / "o.csv", "--marker", "O", "--up", "y")
    assert "does not fit a human body" in line and "give unit mm" in line
    line = one_line(cli("position", "--data", f"{rec}?marker=O&up=y"))
    assert "does not fit a human body" in line
    import gymnasium as gym

    import motion_envs  # noqa: F401

    with pytest.raises(ValueError, match="does not fit a human body"):
        gym.make("MotionEnvs/PositionReach-v1", data=f"{rec}?marker=O&up=y")
    # the same file with its unit given is a valid input
    ds, _ = import_position(rec, ImportOptions(marker="O", up="y", unit="mm"))
    assert np.abs(np.concatenate(ds.positions)).max() < 2.0


def test_c3d_rates_outside_motion_capture_are_refused(tmp_path):
    _, rot, pos = synthetic_movement()
    for rate in (3e38, 1e-38):
        path = tmp_path / f"r{rate:g}.c3d"
        write_c3d(path, marker_points(rot, pos)[:100], ["O", "X", "P"])
        c3d = ezc3d.c3d(str(path))
        c3d["parameters"]["POINT"]["RATE"]["value"] = [rate]
        c3d.write(str(path))
        with pytest.raises(ValueError, match="frame rate") as info:
            import_position(path, ImportOptions(marker="O", up="y"))
        assert "\n" not in str(info.value)


def test_metres_declared_as_millimetres_warn(tmp_path):
    _, rot, pos = synthetic_movement()
    path = tmp_path / "m.tsv"
    write_tsv(path, marker_points(rot, pos), ["O", "X", "P"])  # metres, read as mm
    with pytest.warns(UserWarning, match="too small for a human body"):
        import_position(path, ImportOptions(marker="O"))


def test_a_large_segments_table_is_refused_fast(tmp_path, tsv):
    table = tmp_path / "segments.csv"
    table.write_text(
        "start,end\n" + "".join(f"{k * 0.01},{k * 0.01 + 0.5}\n" for k in range(200_000))
    )
    t0 = time.monotonic()
    line = import_line(tsv, tmp_path / "o.csv", "--marker", "O", "--segments", str(table))
    assert "10000 movements" in line and time.monotonic() - t0 < HANG


# -- 4. env arguments bounded by the models -----------------------------------------------------
@pytest.mark.parametrize("env_id", ["MotionEnvs/Juggling-v1", "MotionEnvs/Cascade-v0"])
@pytest.mark.parametrize("gravity", [1e-300, 1e-6, 1e-3])
def test_too_weak_gravity_is_one_line_at_once(env_id, gravity):
    import gymnasium as gym

    import motion_envs  # noqa: F401

    t0 = time.monotonic()
    with pytest.raises(ValueError, match="too weak") as info:
        gym.make(env_id, gravity=gravity)
    assert "\n" not in str(info.value) and time.monotonic() - t0 < 5


def test_gravity_range_from_the_demonstrations_timing():
    """The counts behind the range are the demonstrations' own (independent recount), and
    both worlds build at the ends of their ranges; just outside, one line with the reason."""
    import gymnasium as gym

    import motion_envs  # noqa: F401
    from motion_envs.datasets.juggling import JugglingTask, generate_cascade_demonstrations
    from motion_envs.models.juggling import (
        FIT_SEED,
        PAPER_GRAVITY,
        TIMING_AT_PAPER_GRAVITY,
        gravity_range,
        load_demonstrations,
    )

    task = JugglingTask(gravity=PAPER_GRAVITY)
    for world, demos in (
        ("Juggling-v1", load_demonstrations(None, task)),
        ("Cascade-v0", generate_cascade_demonstrations(n_persons=2, seed=FIT_SEED, task=task)),
    ):
        shortest = min(len(s.times) for s in demos.segments())
        total = sum(len(r.t) for r in demos.recordings)
        assert TIMING_AT_PAPER_GRAVITY[world] == (shortest, total)
    low, high = gravity_range("Cascade-v0")
    assert (round(low, 4), round(high, 2)) == (0.008, 36.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for g in (low * 1.01, high * 0.99):
            env = gym.make("MotionEnvs/Cascade-v0", gravity=g)
            obs, _ = env.reset(seed=0)
            assert np.isfinite(obs).all()
            env.close()
    with pytest.raises(ValueError, match="too strong for Cascade-v0: its shortest phase"):
        gym.make("MotionEnvs/Cascade-v0", gravity=100.0)


def test_num_envs_beyond_memory_is_one_line():
    import gymnasium as gym

    import motion_envs  # noqa: F401

    t0 = time.monotonic()
    with pytest.raises(ValueError, match="more than this machine's") as info:
        gym.make_vec("MotionEnvs/Juggling-v1", num_envs=2**24 - 1)
    assert "\n" not in str(info.value) and time.monotonic() - t0 < HANG


@pytest.mark.parametrize(
    "env_id", ["MotionEnvs/OrientationReach-v1", "MotionEnvs/PositionReach-v0"]
)
def test_data_none_is_one_line(env_id):
    import gymnasium as gym

    import motion_envs  # noqa: F401

    with pytest.raises(ValueError, match="data must be"):
        gym.make(env_id, data=None)


def test_a_long_siteswap_is_refused_before_running():
    line = one_line(cli("juggling", "--pattern", "3" * 300))
    assert "at most 64" in line


# -- 5. configs and run folders ------------------------------------------------------------------
def _config(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "ppo.yaml"
    path.write_text(text)
    return path


@pytest.mark.parametrize(
    ("body", "match"),
    [
        ("policy_kwargs:\n  net_arch: [1e8, 1e8]\n", "at most 64 layers of at most 65536 units"),
        ("policy_kwargs:\n  net_arch: [60000, 60000, 60000]\n", "weights between hidden layers"),
        ("buffer_size: 1e12\n", "buffer_size"),
        ("n_steps: 64\nn_steps: 128\n", "duplicate key 'n_steps'"),
    ],
    ids=["net_arch-1e8", "net_arch-weights", "buffer", "duplicate-key"],
)
def test_train_config_sizes_and_duplicates_refused_before_training(tmp_path, body, match):
    algo = "sac" if "buffer" in body else "ppo"
    cfg = _config(
        tmp_path,
        "MotionEnvs/PositionReach-v1:\n"
        + "".join("  " + line + "\n" for line in body.splitlines()),
    )
    line = one_line(
        cli(
            "train",
            "--algo",
            algo,
            "--env",
            "MotionEnvs/PositionReach-v1",
            "--config",
            str(cfg),
            "--out",
            str(tmp_path / "run"),
        )
    )
    assert match in line, line
    assert not (tmp_path / "run").exists()


def test_integral_floats_are_integers():
    from baselines.agents.config import validate_hyperparams

    hp = validate_hyperparams(
        "ppo", {"n_steps": 1e3, "batch_size": 64.0, "policy_kwargs": {"net_arch": [64.0, 32]}}, "x"
    )
    assert hp["n_steps"] == 1000 and isinstance(hp["n_steps"], int)
    assert hp["batch_size"] == 64 and hp["policy_kwargs"]["net_arch"] == [64, 32]
    with pytest.raises(ValueError, match="integer"):
        validate_hyperparams("ppo", {"n_steps": 64.5}, "x")


@pytest.mark.parametrize(
    ("seeds", "match"),
    [("[0, 0]", "seeds must be distinct"), (str(list(range(100_000))), "at most 1000")],
)
def test_sweep_seeds_repeated_or_too_many(tmp_path, seeds, match):
    from baselines.agents.sweep.space import load_sweep

    path = tmp_path / "s.yaml"
    path.write_text(f"seeds: {seeds}\nspace:\n  algo: ppo\n  env_id: MotionEnvs/PositionReach-v1\n")
    with pytest.raises(ValueError, match=match) as info:
        load_sweep(path)
    assert "\n" not in str(info.value) and "alias" not in str(info.value)


@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    pytest.importorskip("stable_baselines3")
    from _helpers import train_tiny_run

    return train_tiny_run(tmp_path_factory.mktemp("runs") / "run")


def _rehashed(src: Path, dst: Path, change) -> Path:
    from baselines.agents.rundir import file_sha256, manifest_sha256

    shutil.copytree(src, dst)
    change(dst)
    manifest = json.loads((dst / "run.json").read_text())
    for name in manifest["files"]:
        manifest["files"][name] = file_sha256(dst / name)
    manifest["manifest_sha256"] = manifest_sha256(manifest)
    (dst / "run.json").write_text(json.dumps(manifest))
    return dst


def _pickle_in_zip(folder: Path) -> None:
    with zipfile.ZipFile(folder / "agent.zip", "a") as z:
        z.writestr("policy.pth", b"\x80\x04cos\nsystem\n(S'true'\ntR.")


def _config_type(folder: Path) -> None:
    doc = json.loads((folder / "config.json").read_text())
    doc["hyperparams"]["policy_kwargs"] = {"net_arch": {"pi": [64], "vf": [64]}, "x": 1}
    (folder / "config.json").write_text(json.dumps(doc))


def _deep_json(folder: Path) -> None:
    (folder / "config.json").write_text("[" * 50_000 + "]" * 50_000)


def _npz_shape(folder: Path) -> None:
    with open(folder / "normalization.npz", "wb") as fh:
        np.savez(
            fh,
            obs_mean=np.zeros(3),
            obs_var=np.ones(3),
            epsilon=np.float64(1e-8),
            clip_obs=np.float64(10.0),
            norm_obs=np.bool_(True),
        )


@pytest.mark.parametrize(
    "change", [_pickle_in_zip, _config_type, _deep_json, _npz_shape], ids=lambda f: f.__name__
)
def test_a_tampered_run_folder_is_one_line(trained, tmp_path, change):
    """Files changed and every hash recomputed: ``load_run`` (what ``motion-bench agent``
    and ``juggling --agent`` call) raises one ``ValueError`` line naming the folder."""
    from baselines.agents.rundir import load_run

    folder = _rehashed(trained, tmp_path / "run", change)
    with pytest.raises(ValueError) as info:
        load_run(folder)
    assert "\n" not in str(info.value) and str(folder) in str(info.value)


def test_agent_command_on_a_tampered_agent_zip_is_one_line(trained, tmp_path):
    folder = _rehashed(trained, tmp_path / "run", _pickle_in_zip)
    proc = cli("agent", str(folder), "--episodes", "1", timeout=300)
    line = one_line(proc)
    assert str(folder) in line and "UnpicklingError" in line


def test_run_json_itself_is_hashed(trained, tmp_path):
    from baselines.agents.rundir import load_run

    folder = tmp_path / "run"
    shutil.copytree(trained, folder)
    manifest = json.loads((folder / "run.json").read_text())
    manifest["best_val_criterion"] = 0.0  # a better-looking run; file hashes untouched
    (folder / "run.json").write_text(json.dumps(manifest))
    with pytest.raises(ValueError, match=r"run\.json does not match its own SHA-256"):
        load_run(folder)
    loaded = load_run(trained)  # the untouched folder still loads
    assert loaded.env_id == "MotionEnvs/OrientationReach-v1"
