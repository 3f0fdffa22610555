"""``type=`` checkers of the agent sub-commands (``train``, ``agent``, ``sweep``).

Each raises :class:`argparse.ArgumentTypeError`, which the parser reports as one line
``motion-bench CMD: error: argument --opt: ...`` with exit status 2, before any training,
evaluation or Ray start (see :mod:`baselines.options`).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import yaml

from baselines import options
from baselines.agents.yaml_files import YamlLoader, read_yaml

__all__ = ["check_env_kwargs", "env_id", "env_kwarg", "run_folder", "yaml_file"]


def env_id(text: str) -> str:
    """A registered ``MotionEnvs/...`` environment id (e.g. ``MotionEnvs/OrientationReach-v1``)."""
    import gymnasium as gym

    import motion_envs  # noqa: F401  (registers the environments)

    ids = sorted(k for k in gym.envs.registry if k.startswith("MotionEnvs/"))
    if text not in ids:
        raise argparse.ArgumentTypeError(f"expected one of {ids}; got {text!r}")
    return text


def env_kwarg(text: str) -> str:
    """One ``KEY=VALUE`` item: an identifier, ``=``, a plain YAML value (checked fully later)."""
    key, sep, raw = text.partition("=")
    if not sep or not key.isidentifier():
        raise argparse.ArgumentTypeError(f"expected KEY=VALUE; got {text!r}")
    try:
        yaml.load(raw, Loader=YamlLoader)
    except yaml.YAMLError:
        raise argparse.ArgumentTypeError(f"cannot read the value of {text!r}") from None
    return text


@options.reads_files
def yaml_file(text: str) -> Path:
    """An existing, readable YAML file whose top level is a mapping (read within the
    bounds of :func:`baselines.agents.yaml_files.read_yaml`: size, nesting, aliases)."""
    path = options.input_file(text)
    try:
        doc, _ = read_yaml(path)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    if not isinstance(doc, dict):
        raise argparse.ArgumentTypeError(f"{text}: expected a YAML mapping at the top level")
    return path


@options.reads_files
def run_folder(text: str) -> Path:
    """An existing run folder written by ``motion-bench train`` (holds ``run.json``);
    its contents (hashes, version) are checked when it is loaded."""
    path = Path(text)
    if not path.exists():
        raise argparse.ArgumentTypeError(f"{text} does not exist")
    if not path.is_dir():
        raise argparse.ArgumentTypeError(f"{text} is a file, not a run folder")
    if not (path / "run.json").is_file():
        raise argparse.ArgumentTypeError(
            f"{text} holds no run.json (not a run folder of motion-bench train)"
        )
    return path


def check_env_kwargs(env_id: str, kwargs: dict[str, object]) -> None:
    """Raise :class:`~baselines.options.ConfigError` (``--env-kwargs``) naming any keyword
    the environment's constructor does not take, before anything is built."""
    from baselines.agents.vec import constructor_keywords

    keywords = constructor_keywords(env_id)
    if keywords is None:
        return
    unknown = sorted(set(kwargs) - keywords)
    if unknown:
        known = sorted(keywords - {"render_mode"})
        raise options.ConfigError(
            "env_kwargs", f"{env_id} takes no {unknown}; its keywords are {known}"
        )
