"""The configuration of ``motion-bench juggling``: :class:`JugglingConfig`, its range
checks (:func:`check_config`) and the benchmark's acceptance targets."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from baselines import options
from motion_envs.datasets.juggling import MIN_SPLIT_CYCLES, JugglingTask
from motion_envs.datasets.registry import dataset_names
from motion_envs.models.juggling import DEMO_CYCLES, FIT_SEED, FIT_TEST_FRACTION, TRACKING_NOISE

#: The benchmark's acceptance targets, checked in ``results["targets"]``.
TARGET_UNPERTURBED = 0.99
TARGET_NOISE5_CORRECTED = 0.90
TARGET_VARIABILITY_RATIO = 1.5

VIDEO_CAPTION = "analytic juggler in the MuJoCo scene (SIMULATED)"


#: Complete cycles a run needs (:func:`~motion_envs.datasets.juggling.split_cycles`).
MIN_CYCLES = MIN_SPLIT_CYCLES


@dataclass(frozen=True)
class JugglingConfig:
    """Everything ``motion-bench juggling`` needs (the CLI maps its flags onto this).

    ``data``: None (or the built-in name ``"simulated"``) for the SIMULATED demonstrations,
    else the path of a juggling CSV. ``noise``: release-velocity noise levels (relative
    std), each in [0, 1); ``tracking``: hand tracking noise std (m). ``world``:
    ``"mujoco"`` or ``"model"``.
    """

    cycles: int = 1000
    noise: tuple[float, ...] = (0.05, 0.10)
    tracking: float = TRACKING_NOISE
    seed: int = FIT_SEED
    data: str | None = None
    demo_cycles: int = DEMO_CYCLES
    demo_persons: int = 1
    test_fraction: float = FIT_TEST_FRACTION
    n_sines: int | str = "auto"
    n_points: int = 150
    dmp_weights: int = 10
    use_dmp: bool = True
    figure_cycles: int = 3
    world: str = "mujoco"
    mujoco_cycles: int = 100
    mujoco_noise_cycles: int = 25
    progress: bool = True
    task: JugglingTask = field(default_factory=JugglingTask)


def check_config(config: JugglingConfig) -> None:
    """Raise :class:`baselines.options.ConfigError` naming the first field out of range.

    Called by :func:`run` before any computation (the CLI's checkers catch the same values
    earlier, naming the option).
    """
    if config.cycles < 1:
        raise options.ConfigError("cycles", f"must be >= 1; got {config.cycles}")
    if config.world not in ("mujoco", "model"):
        raise options.ConfigError("world", f"must be 'mujoco' or 'model'; got {config.world!r}")
    for level in config.noise:
        if not (math.isfinite(level) and 0 <= level < 1):
            raise options.ConfigError("noise", f"levels must be in [0, 1); got {level}")
    if not (math.isfinite(config.tracking) and config.tracking >= 0):
        raise options.ConfigError("tracking", f"must be finite and >= 0; got {config.tracking}")
    if config.seed < 0:
        raise options.ConfigError("seed", f"must be >= 0; got {config.seed}")
    for name in ("demo_persons", "figure_cycles", "n_points", "dmp_weights"):
        if getattr(config, name) < 1:
            raise options.ConfigError(name, f"must be >= 1; got {getattr(config, name)}")
    for name in ("mujoco_cycles", "mujoco_noise_cycles"):
        if getattr(config, name) < 0:
            raise options.ConfigError(name, f"must be >= 0; got {getattr(config, name)}")
    if (
        config.data in (None, *dataset_names("juggling"))
        and config.demo_cycles * config.demo_persons < MIN_CYCLES
    ):
        raise options.ConfigError(
            "demo_cycles",
            f"{config.demo_cycles} cycle(s) x {config.demo_persons} person(s) of SIMULATED "
            f"demonstrations; at least {MIN_CYCLES} complete cycles are needed (2 to test, "
            "6 to fit each phase's regression on 4 boundary conditions and an intercept)",
        )
