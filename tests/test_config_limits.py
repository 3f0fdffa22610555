"""Issue 17 item 2 and 3: agent and sweep YAML configs that once crashed or hung (a
400-digit gamma, 5,000-deep nesting, an alias bomb, ``loguniform: [0, x]``,
``random_seed: [1]``, ``num_samples: 100000000``, a misspelt env id) give one line naming
the file, quickly; a sweep checks every configuration before Ray starts."""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

import pytest

from baselines.agents.config import load_hyperparams
from baselines.agents.sweep import load_sweep

ROOT = Path(__file__).resolve().parents[1]
BOMB = """default:
  env_kwargs:
    a: &a ["x","x","x","x","x","x","x","x","x"]
    b: &b [*a,*a,*a,*a,*a,*a,*a,*a,*a]
    c: &c [*b,*b,*b,*b,*b,*b,*b,*b,*b]
    d: &d [*c,*c,*c,*c,*c,*c,*c,*c,*c]
    e: &e [*d,*d,*d,*d,*d,*d,*d,*d,*d]
    f: &f [*e,*e,*e,*e,*e,*e,*e,*e,*e]
    g: &g [*f,*f,*f,*f,*f,*f,*f,*f,*f]
"""
SWEEP = (
    "search: {search}\nnum_samples: 2\nseeds: [0]\n{extra}space:\n  algo: [ppo]\n"
    "  env_id: [{env}]\n{space}"
)


def sweep_text(search="random", extra="", env="MotionEnvs/OrientationReach-v1", space=""):
    return SWEEP.format(search=search, extra=extra, env=env, space=space)


AGENT_CASES = {
    "gamma_400_digits": ("default:\n  gamma: " + "9" * 400 + "\n", "line 2: default: gamma"),
    "lr_400_digits": ("default:\n  learning_rate: " + "1" * 400 + "\n", "learning_rate"),
    "lr_zero": ("default:\n  learning_rate: 0\n", "learning_rate: must be in (0.0, 1.0]"),
    "gamma_negative": ("default:\n  gamma: -0.1\n", "gamma: must be in [0.0, 1.0]"),
    "n_envs_huge": ("default:\n  n_envs: 100000000\n", "n_envs: must be an integer in [1, 256]"),
    "deep": ("default:\n  env_kwargs:\n    x: " + "[" * 5000 + "]" * 5000 + "\n", "line 3: nested"),
    "bomb": (BOMB, "aliases expand to more than"),
    "recursive": ("default:\n  env_kwargs: &a {x: *a}\n", "line 2"),
    "misspelt_id": (
        "default: {}\nMotionEnvs/PositonReach-v1:\n  n_envs: 4\n",
        "line 2: top-level key 'MotionEnvs/PositonReach-v1' is not a registered environment id;"
        " did you mean 'MotionEnvs/PositionReach-v1'",
    ),
    "nul": ("default:\n  gamma: 0.9\x00\n", "NUL"),
}


def assert_refused_in_one_line(path, text, expected, load, seconds):
    """``load(path)`` of a file holding ``text`` raises, within ``seconds``, one
    ``ValueError`` line that starts with the path and holds ``expected``."""
    path.write_text(text)
    t0 = time.perf_counter()
    with pytest.raises(ValueError) as info:
        load(path)
    assert time.perf_counter() - t0 < seconds
    message = str(info.value)
    assert "\n" not in message and message.startswith(str(path)), message
    assert expected in message, message


@pytest.mark.parametrize("name", sorted(AGENT_CASES))
def test_bad_agent_config_one_line_naming_file(tmp_path, name):
    def load(path):
        return load_hyperparams(path, "ppo", "MotionEnvs/PositionReach-v1")

    assert_refused_in_one_line(tmp_path / f"{name}.yaml", *AGENT_CASES[name], load, 5)


def test_agent_config_size_and_device_bounded(tmp_path):
    big = tmp_path / "big.yaml"
    big.write_text("default:\n  n_envs: 2\n" + "#" * (2 << 20) + "\n")
    with pytest.raises(ValueError, match="larger than"):
        load_hyperparams(big, "ppo", "MotionEnvs/PositionReach-v1")
    with pytest.raises(ValueError, match="not a regular file"):
        load_hyperparams("/dev/zero", "ppo", "MotionEnvs/PositionReach-v1")


SWEEP_CASES = {
    "loguniform_zero": (
        sweep_text(space="  hyperparams:\n    learning_rate: {loguniform: [0, 0.001]}\n"),
        "space.hyperparams.learning_rate: loguniform bounds must be > 0",
    ),
    "uniform_huge": (
        sweep_text(space="  hyperparams:\n    gamma: {uniform: [0.9, 1" + "0" * 400 + "]}\n"),
        "uniform bounds must be finite numbers",
    ),
    "random_seed_list": (sweep_text(extra="random_seed: [1]\n"), "line 4: random_seed"),
    "num_samples_huge": (
        sweep_text().replace("num_samples: 2", "num_samples: 100000000"),
        "line 2: num_samples",
    ),
    "n_envs_huge": (sweep_text(extra="n_envs: 100000\n"), "line 4: n_envs"),
    "deep": ("search: grid\nseeds: [0]\nspace: " + "[" * 5000 + "]" * 5000 + "\n", "line 3"),
    "bomb": (BOMB.replace("default:\n  env_kwargs:", "space:"), "aliases expand"),
    "misspelt_id": (
        sweep_text(search="grid", env="MotionEnvs/PositonReach-v1"),
        "did you mean 'MotionEnvs/PositionReach-v1'",
    ),
    "unknown_env_kwarg": (
        sweep_text(search="grid", space="  env_kwargs:\n    bogus: [1]\n"),
        "takes no ['bogus']",
    ),
    "unknown_env_kwarg_random": (
        sweep_text(space="  env_kwargs:\n    bogus: {uniform: [0, 1]}\n"),
        "takes no ['bogus']",
    ),
    "juggling_n_envs_over_validation_seeds": (
        sweep_text(search="grid", extra="n_envs: 200\n", env="MotionEnvs/Juggling-v0").replace(
            "seeds: [0]", "seeds: [999999990]"
        ),
        "validation seeds",
    ),
}


@pytest.mark.parametrize("name", sorted(SWEEP_CASES))
def test_bad_sweep_one_line_naming_file(tmp_path, name):
    def load(path):
        return load_sweep(path, out=str(tmp_path / "out"))

    assert_refused_in_one_line(tmp_path / f"{name}.yaml", *SWEEP_CASES[name], load, 10)


@pytest.mark.parametrize("path", sorted((ROOT / "configs" / "sweeps").glob("*.yaml")))
def test_shipped_sweeps_pass_the_checks(path):
    assert load_sweep(path, out="unused").configurations


def test_sweep_cli_refuses_unregistered_id_before_ray(tmp_path):
    """Once: Ray started, the trial failed 1.5 min later, RuntimeError traceback, exit 1."""
    path = tmp_path / "typo.yaml"
    path.write_text(sweep_text(search="grid", env="MotionEnvs/OrientatonReach-v1"))
    t0 = time.perf_counter()
    proc = subprocess.run(
        [sys.executable, "-m", "baselines.cli", "sweep", "--config", str(path),
         "--out", str(tmp_path / "out")],
        capture_output=True, text=True, cwd=ROOT, timeout=120,
    )  # fmt: skip
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "OrientatonReach-v1" in lines[0] and "did you mean" in lines[0]
    assert not (tmp_path / "out" / "tune").exists()
    assert time.perf_counter() - t0 < 60
