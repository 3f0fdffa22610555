"""``motion-bench`` user errors: checked before any computation, one line naming the
option, exit status 2, no traceback; no abbreviations; --version; clean --help."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from baselines import calibrate_cohort, mocap_import, run_all
from baselines.agents import evaluate as agent_evaluate
from baselines.agents import train as agent_train
from baselines.agents.sweep import cli as agent_sweep
from baselines.cli import SUBCOMMAND_MODULES, build_parser, main
from baselines.juggling_bench import levels as juggling_levels
from baselines.juggling_bench import runner as juggling_runner
from baselines.orientation_bench import runner as orientation_runner
from baselines.position_bench import runner as position_runner
from motion_envs import __version__

ROOT = Path(__file__).resolve().parents[1]
#: The argument prefixes most cases share.
PPO = ["train", "--algo", "ppo", "--env"]
TRAIN = [*PPO, "MotionEnvs/OrientationReach-v1"]
C3D = ["import", "{tmp}/rec.c3d", "--kind"]


@pytest.fixture()
def paths(tmp_path):
    """A file, a folder, a read-only folder and a small valid target JSON."""
    (tmp_path / "file.txt").write_text("not a folder\n")
    (tmp_path / "folder").mkdir()
    ro = tmp_path / "readonly"
    ro.mkdir()
    ro.chmod(0o555)
    (tmp_path / "bad.json").write_text("{not json")
    (tmp_path / "bad.yaml").write_text("default:\n  n_envs: [1\n")
    (tmp_path / "list.yaml").write_text("- 1\n- 2\n")
    (tmp_path / "ok.yaml").write_text("seeds: [0]\n")
    (tmp_path / "run").mkdir()
    (tmp_path / "run" / "run.json").write_text("{}\n")
    (tmp_path / "binary.csv").write_bytes(b"\xff\xfe\x00t,x,z\n")
    (tmp_path / "rec.c3d").write_bytes(b"options are checked before the file is read")
    (tmp_path / "rec.bvh").write_text("options are checked before the file is read\n")
    yield tmp_path
    ro.chmod(0o755)


@pytest.fixture(autouse=True)
def no_computation(monkeypatch):
    """Any computation starting means a check came too late."""

    def started(*args, **kwargs):
        raise AssertionError("the computation started before the error was reported")

    monkeypatch.setattr(orientation_runner, "table1", started)
    monkeypatch.setattr(position_runner, "run_benchmark", started)
    monkeypatch.setattr(calibrate_cohort, "calibrate", started)
    monkeypatch.setattr(juggling_runner, "load_demos", started)
    monkeypatch.setattr(mocap_import, "run", started)
    monkeypatch.setattr(juggling_levels, "juggling_episodes", started)
    monkeypatch.setattr(agent_train, "run", started)
    monkeypatch.setattr(agent_evaluate, "run", started)
    monkeypatch.setattr(agent_sweep, "load_sweep", started)
    monkeypatch.setattr(agent_sweep, "run", started)


# (argv with {tmp} for the fixture folder, expected fragment of the one error line)
CASES = [
    (
        ["orientation", "--data", "{tmp}/missing.csv"],
        "argument --data: expected a built-in orientation dataset ('vr-kitchen', ",
    ),
    (["orientation", "--data", "lasa"], "'lasa' is the built-in position dataset; built-in"),
    (["orientation", "--data", "{tmp}/folder"], "argument --data: {tmp}/folder is a folder"),
    (["orientation", "--out", "{tmp}/file.txt"], "argument --out: {tmp}/file.txt is a file"),
    (["orientation", "--out", "{tmp}/file.txt/sub"], "argument --out:"),
    (["orientation", "--plot-task", "no-such-task"], "argument --plot-task: task 'no-such-task'"),
    (["orientation", "--degree", "two"], "argument --degree: expected an integer >= 1"),
    (["orientation", "--degree", "0"], "argument --degree: expected an integer >= 1"),
    (["orientation", "--split-seed", "1.5"], "argument --split-seed: expected an integer"),
    (["orientation", "--min-deg", "nan"], "argument --min-deg: expected a finite number"),
    (["orientation", "--test-fraction", "1.5"], "argument --test-fraction: expected a number"),
    (["orientation", "--split", "middle"], "argument --split: invalid choice"),
    (["orientation", "--dat", "vr-kitchen"], "unrecognized arguments: --dat"),
    (["orientation", "--min-deg", "179"], "argument --min-deg: 800 of 800 trajectories"),
    (["orientation", "--learned", "fast"], "argument --learned: invalid choice: 'fast'"),
    (["orientation", "--learned"], "argument --learned: expected one argument"),
    (["orientation", "--up", "0,1"], "argument --up: expected three finite numbers 'x,y,z'"),
    (["orientation", "--up", "x,y,z"], "argument --up: expected three finite numbers"),
    (["orientation", "--up", "0,nan,1"], "argument --up: expected three finite numbers"),
    (["orientation", "--up", "0,1,0,0"], "argument --up: expected three finite numbers"),
    (["orientation", "--up", "0,0,0"], "argument --up: expected a non-zero vector"),
    (["orientation", "--up=-0,-0.0,0"], "argument --up: expected a non-zero vector"),
    (
        ["position", "--data", "{tmp}/missing.csv"],
        "argument --data: expected a built-in position dataset ('lasa') or a CSV file",
    ),
    (["position", "--data", "cohort"], "built-in orientation dataset; built-in position"),
    (["juggling", "--data", "lasa"], "built-in juggling datasets: 'simulated'"),
    (["position", "--data", "{tmp}/folder"], "argument --data: {tmp}/folder is a folder"),
    (["position", "--out", "{tmp}/file.txt"], "argument --out: {tmp}/file.txt is a file"),
    (["position", "--n-points", "many"], "argument --n-points: expected an integer >= 5"),
    (["position", "--n-points", "3"], "argument --n-points: expected an integer >= 5"),
    (["position", "--n-sines", "x"], "argument --n-sines: expected 'auto' or an integer"),
    (["position", "--n-weights", "1e3"], "argument --n-weights: expected an integer"),
    (["position", "--conditions", "speed"], "argument --conditions: expected a comma list"),
    (["position", "--n-point", "50"], "unrecognized arguments: --n-point"),
    (["position", "--learned", "none"], "argument --learned: invalid choice: 'none'"),
    (["juggling", "--data", "{tmp}/missing.csv"], "argument --data: {tmp}/missing.csv does not"),
    (["juggling", "--data", "{tmp}/folder"], "argument --data: {tmp}/folder is a folder"),
    (["juggling", "--data", "{tmp}/file.txt"], "argument --data: {tmp}/file.txt: line 1: missing"),
    (
        ["juggling", "--data", "{tmp}/binary.csv"],
        "argument --data: {tmp}/binary.csv is not a UTF-8",
    ),
    (["juggling", "--out", "{tmp}/file.txt"], "argument --out: {tmp}/file.txt is a file"),
    (["juggling", "--out", "{tmp}/file.txt/sub"], "argument --out:"),
    (["juggling", "--cycles", "0"], "argument --cycles: expected an integer >= 1"),
    (["juggling", "--cycles", "1e3"], "argument --cycles: expected an integer >= 1"),
    (["juggling", "--noise", "0.05,x"], "argument --noise: expected a comma list of numbers"),
    (["juggling", "--noise", "1.5"], "argument --noise: expected a comma list of numbers"),
    (["juggling", "--noise", ","], "argument --noise: expected a comma list of numbers"),
    (["juggling", "--tracking", "inf"], "argument --tracking: expected a finite number in"),
    (["juggling", "--tracking", "-0.1"], "argument --tracking: expected a finite number in"),
    (["juggling", "--gravity", "0"], "argument --gravity: expected a finite number in [0.1"),
    # issue 17 item 7: once an OverflowError traceback (1e-300) or "Singular matrix" (1e300)
    (["juggling", "--gravity", "1e-300"], "argument --gravity: expected a finite number in"),
    (["juggling", "--gravity", "1e300"], "argument --gravity: expected a finite number in"),
    (["juggling", "--gravity", "1e400"], "argument --gravity: expected a finite number in"),
    (["juggling", "--noise", "1e400"], "argument --noise: expected a comma list of numbers"),
    (["juggling", "--tracking", "1e300"], "argument --tracking: expected a finite number in"),
    (["orientation", "--min-deg", "1e400"], "argument --min-deg: expected a finite number in"),
    (["orientation", "--min-deg", "1e300"], "argument --min-deg: expected a finite number in"),
    (["juggling", "--gravity", "nan"], "argument --gravity: expected a finite number"),
    (["juggling", "--seed", "-1"], "argument --seed: expected an integer >= 0"),
    (["juggling", "--demo-persons", "0"], "argument --demo-persons: expected an integer >= 1"),
    (["juggling", "--demo-cycles", "2"], "argument --demo-cycles: 2 cycle(s) x 1 person(s)"),
    (["juggling", "--mujoco-cycles", "-3"], "argument --mujoco-cycles: expected an integer"),
    (["juggling", "--world", "moon"], "argument --world: invalid choice"),
    (["juggling", "--cycle", "5"], "unrecognized arguments: --cycle"),
    (["juggling", "--levels", "expert"], "argument --levels: expected a comma list of distinct"),
    (["juggling", "--levels", "easy,easy"], "argument --levels: expected a comma list of distinct"),
    (["juggling", "--levels", ","], "argument --levels: expected a comma list of distinct"),
    (["juggling", "--levels", "easy", "--episodes", "1"], "argument --episodes: expected an"),
    (["juggling", "--levels", "easy", "--max-catches", "0"], "argument --max-catches: expected"),
    (["juggling", "--version", "v2", "--pick-episodes", "1"], "argument --pick-episodes: expected"),
    (
        ["juggling", "--version", "v2", "--pattern", "3", "--pick-episodes", "29"],
        "argument --pick-episodes: must be >= val_episodes (30); got 29",
    ),
    (
        ["juggling", "--version", "v2", "--pick-episodes", "10"],
        "argument --pick-episodes: must be >= val_episodes (30); got 10",
    ),
    (
        ["juggling", "--levels", "easy", "--pick-episodes", "200"],
        "--pick-episodes: needs --version",
    ),
    (["juggling", "--analyse", "{tmp}/missing.csv"], "argument --analyse: {tmp}/missing.csv"),
    (["juggling", "--analyse", "{tmp}/rec.tsv"], "argument --analyse: motion capture file"),
    (["juggling", "--n-balls", "0"], "argument --n-balls: expected an integer >= 1"),
    (["juggling", "--levels", "easy", "--agent", "{tmp}/missing"], "argument --agent: {tmp}/"),
    (
        ["juggling", "--levels", "easy", "--agent", "{tmp}/folder"],
        "argument --agent: {tmp}/folder h",
    ),
    (["all", "--out", "{tmp}/file.txt"], "argument --out: {tmp}/file.txt is a file"),
    (["all", "--only", "nothing"], "argument --only: invalid choice"),
    (["all", "--ou", "x"], "unrecognized arguments: --ou"),
    (["all", "--learned", "slow"], "argument --learned: invalid choice: 'slow'"),
    (["all", "--learn", "off"], "unrecognized arguments: --learn"),
    (["calibrate-cohort", "--max-evaluations", "x"], "argument --max-evaluations: expected"),
    (["calibrate-cohort", "--max-evaluations", "1"], "argument --max-evaluations: expected"),
    (["calibrate-cohort", "--target", "{tmp}/missing.json"], "argument --target:"),
    (["calibrate-cohort", "--target", "{tmp}/bad.json"], "argument --target: {tmp}/bad.json"),
    (["calibrate-cohort", "--config", "no-such-cohort"], "argument --config:"),
    (["calibrate-cohort", "--out", "{tmp}/folder"], "argument --out: {tmp}/folder is a folder"),
    (
        ["calibrate-cohort", "--out", "{tmp}/x.yaml", "--replace-shipped"],
        "argument --replace-shipped: not allowed with argument --out",
    ),
    (["calibrate-cohort", "--check-seeds", "-1"], "argument --check-seeds: expected"),
    (
        ["train", "--algo", "dqn", "--env", "MotionEnvs/OrientationReach-v1"],
        "argument --algo: invalid choice",
    ),
    ([*PPO, "CartPole-v1"], "argument --env: expected one of"),
    (["train", "--algo", "ppo"], "the following arguments are required: --env"),
    ([*TRAIN, "--timesteps", "0"], "argument --timesteps: expected an integer >= 1"),
    ([*TRAIN, "--timesteps", "1e3"], "argument --timesteps: expected an integer >= 1"),
    ([*TRAIN, "--seed", "-1"], "argument --seed: expected an integer >= 0"),
    ([*TRAIN, "--n-envs", "0"], "argument --n-envs: expected an integer >= 1"),
    ([*TRAIN, "--config", "{tmp}/missing.yaml"], "argument --config: {tmp}/missing.yaml does not"),
    ([*TRAIN, "--config", "{tmp}/folder"], "argument --config: {tmp}/folder is a folder"),
    ([*TRAIN, "--config", "{tmp}/bad.yaml"], "argument --config: {tmp}/bad.yaml: line 3: not"),
    ([*TRAIN, "--config", "{tmp}/list.yaml"], "argument --config: {tmp}/list.yaml: expected a"),
    ([*TRAIN, "--config", "{tmp}/binary.csv"], "argument --config: {tmp}/binary.csv: not"),
    ([*TRAIN, "--env-kwargs", "nominal"], "argument --env-kwargs: expected KEY=VALUE"),
    ([*TRAIN, "--env-kwargs", "x-y=1"], "argument --env-kwargs: expected KEY=VALUE"),
    ([*TRAIN, "--env-kwargs", "shapes=[1"], "argument --env-kwargs: cannot read the value"),
    ([*TRAIN, "--env-kwargs", "no_such_kwarg=1"], "argument --env-kwargs:"),
    ([*TRAIN, "--out", "{tmp}/file.txt"], "argument --out: {tmp}/file.txt is a file"),
    ([*TRAIN, "--timestep", "5"], "unrecognized arguments: --timestep"),
    (
        [*PPO, "MotionEnvs/Juggling-v0", "--seed", "999999999"],
        "argument --seed: 999999999 with 4 environments would reset on the validation seeds",
    ),
    (
        ["train", "--algo", "sac", "--env", "MotionEnvs/Juggling-v0", "--env-kwargs", "split=val"],
        "argument --env-kwargs:",
    ),
    (["agent"], "the following arguments are required: DIR"),
    (["agent", "{tmp}/missing"], "argument DIR: {tmp}/missing does not exist"),
    (["agent", "{tmp}/file.txt"], "argument DIR: {tmp}/file.txt is a file"),
    (["agent", "{tmp}/folder"], "argument DIR: {tmp}/folder holds no run.json"),
    (["agent", "{tmp}/run", "--split", "middle"], "argument --split: invalid choice"),
    (["agent", "{tmp}/run", "--episodes", "0"], "argument --episodes: expected an integer"),
    (["agent", "{tmp}/run", "--checkpoint", "x"], "argument --checkpoint: invalid choice"),
    (["agent", "{tmp}/run", "--out", "{tmp}/file.txt"], "argument --out: {tmp}/file.txt"),
    (["agent", "{tmp}/run", "--episode", "3"], "unrecognized arguments: --episode"),
    (["sweep"], "the following arguments are required: --config"),
    (["sweep", "--config", "{tmp}/missing.yaml"], "argument --config: {tmp}/missing.yaml does"),
    (["sweep", "--config", "{tmp}/bad.yaml"], "argument --config: {tmp}/bad.yaml: line 3"),
    (["sweep", "--config", "{tmp}/ok.yaml", "--num-cpus", "0"], "argument --num-cpus: expected"),
    (
        ["sweep", "--config", "{tmp}/ok.yaml", "--num-cpus", "2", "--address", "auto"],
        "argument --num-cpus: applies to a local Ray only",
    ),
    (["sweep", "--config", "{tmp}/ok.yaml", "--out", "{tmp}/file.txt"], "argument --out:"),
    (["sweep", "--config", "{tmp}/ok.yaml", "--num-cpu", "2"], "unrecognized arguments: --num"),
    (["import"], "the following arguments are required: file, --kind, --out"),
    (["import", "{tmp}/no.c3d", "--kind", "position", "--out", "o.csv"], "argument file: {tmp}/no"),
    (["import", "{tmp}/file.txt", "--kind", "position", "--out", "o.csv"], "expected a .c3d, "),
    ([*C3D, "speed", "--out", "o.csv"], "argument --kind: invalid"),
    ([*C3D, "position", "--out", "{tmp}/folder"], "argument --out"),
    ([*C3D, "position", "--out", "o.csv"], "argument --marker: "),
    ([*C3D, "orientation", "--out", "o.csv"], "argument --markers"),
    ([*C3D, "juggling", "--out", "o.csv", "--marker", "H"], "--ball"),
    (["import", "{tmp}/rec.bvh", "--kind", "position", "--out", "o.csv"], "argument --joint: "),
    (
        ["import", "{tmp}/rec.bvh", "--kind", "position", "--out", "o.csv", "--joint", "Hand"],
        "argument --unit: {tmp}/rec.bvh: BVH lengths carry no unit",
    ),
    (
        [*C3D, "juggling", "--out", "o.csv", "--balls", "unlabelled"],
        "argument --balls: unlabelled fragments are read from a Qualisys .tsv file only",
    ),
    ([*C3D, "position", "--max-gap", "-1"], "argument --max-gap: "),
    ([*C3D, "position", "--markers", "A,B"], "argument --markers: "),
    ([*C3D, "position", "--up", "x"], "argument --up: expected one"),
    ([*C3D, "position", "--unit", "ft"], "argument --unit: expected"),
    ([*C3D, "position", "--speed-threshold", "0"], "argument --spe"),
    ([*C3D, "position", "--segments", "{tmp}/no"], "argument --seg"),
    ([*C3D, "position", "--out", "o.csv", "--marke", "O"], "unrecognized arguments: --marke"),
    (["orientation", "--data", "{tmp}/rec.c3d"], "argument --data: {tmp}/rec.c3d: give the three"),
    (["orientation", "--data", "{tmp}/rec.c3d?colour=red"], "unknown import option 'colour'"),
    (["position", "--data", "{tmp}/rec.c3d?max-gap=x"], "option max-gap: expected an integer"),
    (["position", "--data", "{tmp}/no.tsv?marker=O"], "argument --data: motion capture file"),
    (["juggling", "--data", "{tmp}/rec.bvh?joint=Hand"], "BVH lengths carry no unit"),
    (["nonsense"], "argument COMMAND: invalid choice"),
    (["--vers", "all"], "unrecognized arguments: --vers"),
]


@pytest.mark.parametrize(("argv", "fragment"), CASES, ids=[" ".join(c[0]) for c in CASES])
def test_user_errors_are_one_line_exit_2(paths, capsys, argv, fragment):
    argv = [a.replace("{tmp}", str(paths)) for a in argv]
    assert main(argv) == 2
    captured = capsys.readouterr()
    lines = [line for line in captured.err.splitlines() if line.strip()]
    assert len(lines) == 1, captured.err
    assert lines[0].startswith("motion-bench")
    assert fragment.replace("{tmp}", str(paths)) in lines[0]
    assert "Traceback" not in captured.err
    assert captured.out == ""


def _unwritable_folder(paths: Path) -> Path:
    """A folder this user cannot create files in: a mode-555 folder, or /proc for root."""
    ro = paths / "readonly"
    try:
        (ro / "probe").write_text("x")
    except OSError:
        return ro
    (ro / "probe").unlink()
    if Path("/proc").is_dir():
        return Path("/proc")
    pytest.skip("no folder this user cannot write in")


def test_unwritable_out_is_reported_first(paths, capsys):
    ro = _unwritable_folder(paths)
    for argv in (
        ["orientation", "--out", str(ro / "new")],
        [
            "train",
            "--algo",
            "ppo",
            "--env",
            "MotionEnvs/OrientationReach-v1",
            "--out",
            str(ro / "r"),
        ],
        ["all", "--out", str(ro / "new" / "sub")],
        ["calibrate-cohort", "--out", str(ro / "cohort.yaml")],
    ):
        assert main(argv) == 2
        err = capsys.readouterr().err.strip()
        assert err.count("\n") == 0 and "argument --out: cannot write in" in err, err


def test_unreadable_data_is_reported_first(paths, capsys):
    data = paths / "secret.csv"
    data.write_text("trajectory,subject,task,t,qw,qx,qy,qz\n")
    data.chmod(0)
    try:
        data.read_bytes()
    except OSError:
        pass
    else:  # root reads mode-000 files; /proc/self/mem exists but cannot be read at 0
        data = Path("/proc/self/mem")
        if not data.exists():
            pytest.skip("no file this user cannot read")
    assert main(["orientation", "--data", str(data)]) == 2
    assert "argument --data: cannot read" in capsys.readouterr().err


def test_version(capsys):
    assert main(["--version"]) == 0
    assert capsys.readouterr().out.strip() == f"motion-bench {__version__}"


def _helps() -> dict[str, str]:
    parser = build_parser()
    sub = next(a for a in parser._actions if a.dest == "command")
    out = {"motion-bench": parser.format_help()}
    out.update({name: p.format_help() for name, p in sub.choices.items()})
    return out


def test_every_subcommand_is_registered():
    from fuzz_registry import CLI_COMMANDS

    assert set(_helps()) == {"motion-bench", *CLI_COMMANDS}
    assert len(SUBCOMMAND_MODULES) == 9


@pytest.mark.parametrize(
    "name",
    [
        "motion-bench",
        "all",
        "orientation",
        "position",
        "import",
        "calibrate-cohort",
        "train",
        "agent",
        "sweep",
    ],
)
def test_help_is_plain_text_with_each_default_once(name):
    text = _helps()[name]
    for markup in ("``", ":class:", ":func:", ":mod:", ":data:", ":meth:"):
        assert markup not in text, markup
    options = re.split(r"\n  (?=-)", text.split("options:", 1)[1])
    for block in options:
        assert block.count("default") <= 1, block
    assert "(default: None)" not in text and "(default: False)" not in text


def test_no_parser_allows_abbreviations():
    parser = build_parser()
    sub = next(a for a in parser._actions if a.dest == "command")
    assert parser.allow_abbrev is False
    assert all(p.allow_abbrev is False for p in sub.choices.values())


def test_console_error_has_no_traceback_in_a_subprocess(tmp_path):
    out = subprocess.run(
        [sys.executable, "-m", "baselines.cli", "position", "--n-points", "x"],
        capture_output=True,
        text=True,
        cwd=ROOT,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
    )
    assert out.returncode == 2
    assert out.stderr.strip().splitlines() == [
        "motion-bench position: error: argument --n-points: expected an integer >= 5; got 'x'"
    ]


def test_calibrate_writes_to_out_not_the_shipped_config():
    args = build_parser().parse_args(["calibrate-cohort"])
    assert args.out is None and args.replace_shipped is False
    assert calibrate_cohort.default_out("faraway2008") == Path(
        "results/calibrate-cohort/faraway2008.yaml"
    )
    assert run_all.JOBS[0].folder == "orientation-vr-kitchen"


def test_the_written_files_line() -> None:
    """Once ``motion-bench all`` printed "wrote  and results/juggling_v1-levels/results.json"
    for a job that writes one file."""
    from baselines.options import wrote

    assert wrote([Path("a/results.json")]) == "wrote a/results.json"
    assert wrote(["a", "b"]) == "wrote a and b"
    assert wrote(["a", "b", "c"]) == "wrote a, b and c"
    assert wrote([]) == "wrote nothing"
