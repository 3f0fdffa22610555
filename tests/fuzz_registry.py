"""THE registry of the project's input surfaces, fuzzed by ``tests/test_fuzz.py``.

Every public loader (a ``load_*``/``read_*`` name in the ``__all__`` of a module of
``motion_envs.datasets``, ``motion_envs.models`` or ``baselines``), every environment id
of ``motion_envs.ENV_IDS`` with every argument of its constructor (:data:`ENVS`) and of
its vector entry point (:data:`VECTOR_ARGS`), and every option of the ``motion-bench``
CLI (numeric, a file it reads, an output, or a name) is listed here with the kind of
input it takes. ``tests/test_fuzz.py`` fails when a public loader, an env id, an env or
vector argument or a CLI option exists that is not listed, so the next one is covered by
construction.

Sizes a user controls are bounded in the strategies: file bytes (``MAX_FILE_BYTES``),
YAML text and nesting, sample counts, cycle indices.
"""

from __future__ import annotations

from dataclasses import dataclass

#: Largest fuzzed file, bytes (the loaders' own bounds are tested by their modules).
MAX_FILE_BYTES = 4096


@dataclass(frozen=True)
class Loader:
    """A public loader: ``target`` (``module:qualname``), the input it reads, the errors
    it documents."""

    target: str
    kind: str  # "csv", "juggling_csv", "json_model", "safetensors", "yaml", "name"
    errors: tuple[type[BaseException], ...] = (ValueError, FileNotFoundError)
    #: why the loader is listed but not fuzzed with files (e.g. it takes no path)
    not_fuzzed: str = ""


LOADERS: tuple[Loader, ...] = (
    Loader("motion_envs.datasets.orientation:read_orientation_csv", "csv"),
    Loader("motion_envs.datasets.position_csv:read_position_csv", "csv"),
    Loader("motion_envs.datasets.juggling:read_juggling_csv", "juggling_csv"),
    Loader("baselines.juggling_bench.analyse:load_ball_markers", "juggling_csv"),
    Loader("motion_envs.models.juggling:load_juggling_csv", "juggling_csv"),
    Loader("motion_envs.datasets:load_orientation_dataset", "csv"),
    Loader("motion_envs.datasets:load_position_dataset", "csv"),
    Loader("motion_envs.datasets.sample_table:read_csv_text", "csv"),
    Loader(
        "motion_envs.datasets.sample_table:read_sample_table",
        "csv",
        not_fuzzed="the front end of read_orientation_csv/read_position_csv (fuzzed there)",
    ),
    Loader(
        "motion_envs.datasets.sample_table:read_csv_exact",
        "csv",
        not_fuzzed="pandas.read_csv with exact floats: a helper, not a user surface",
    ),
    *(
        Loader(
            f"motion_envs.datasets.mocap.{target}",
            "mocap",
            not_fuzzed="motion capture formats: fuzzed with corrupted C3D, TSV and BVH files "
            "by tests/test_mocap.py (hypothesis), where the files are written",
        )
        for target in (
            "_readers:read_bvh",
            "_readers:read_c3d",
            "_readers:read_qualisys_tsv",
            "_readers:read_recording",
            "_segments:read_segments",
        )
    ),
    Loader("motion_envs.models.serialization:load_model", "json_model"),
    Loader("baselines.learned.mlp_model:ResidualMLP.load", "safetensors"),
    Loader("baselines.learned.model_file:read_model_file", "safetensors"),
    Loader("motion_envs.datasets.cohort_config:load_cohort_config", "yaml"),
    Loader("motion_envs.datasets.cohort:load_cohort", "yaml"),
    Loader("baselines.agents.config:load_hyperparams", "yaml"),
    Loader("baselines.agents.sweep.space:load_sweep", "yaml"),
    Loader(
        "motion_envs.datasets.lasa:load_lasa",
        "name",
        not_fuzzed="the built-in LASA data by shape names (checked by test_lasa.py)",
    ),
    Loader(
        "motion_envs.datasets.registry:load_builtin",
        "name",
        not_fuzzed="the built-in datasets by registered name (each tested by "
        "test_dataset_registry.py); any other text is None, read by the kind's loader",
    ),
    Loader(
        "motion_envs.datasets.vr_kitchen:load_vr_kitchen",
        "name",
        not_fuzzed="the built-in VR-kitchen data (no user input but min_deg)",
    ),
    Loader(
        "motion_envs.models.juggling:load_demonstrations",
        "juggling_csv",
        not_fuzzed="reads its CSV with load_juggling_csv (fuzzed)",
    ),
    Loader(
        "motion_envs.models.juggling:load_juggler",
        "juggling_csv",
        not_fuzzed="reads its CSV with load_juggling_csv (fuzzed), then fits",
    ),
    Loader("baselines.agents.yaml_files:read_yaml", "yaml"),
    Loader("baselines.agents.rundir:load_run", "run_folder"),
    Loader("baselines.agents.rundir:read_run_json", "run_folder"),
    Loader("baselines.agents.rundir:ObsNormalizer.load", "run_folder"),
    Loader(
        "baselines.juggling_bench.runner:load_demos",
        "juggling_csv",
        not_fuzzed="reads its CSV with read_juggling_csv or a recording (both fuzzed)",
    ),
    Loader("baselines.calibrate_cohort:load_targets", "json_targets"),
    Loader(
        "motion_envs.models.juggling.timing:read_pattern_markers",
        "mocap",
        not_fuzzed="needs the marker names; fuzzed with corrupted CSV and Qualisys TSV files "
        "by tests/test_cascade_human_timing.py (hypothesis)",
    ),
)

#: Environment ids: every constructor argument (name -> kind of value fuzzed, see
#: ``VALUES`` in ``tests/test_fuzz.py``); ``same_as`` shares another id's arguments.
_REACH_COMMON = {
    "data": "data",
    "split": "name",
    "nominal": "name",
    "residual_scale": "positive",
    "test_fraction": "fraction",
    "split_seed": "seed",
    "render_mode": "render_mode",
    "width": "size",
    "height": "size",
    "val_fraction": "fraction",
    "calibration": "small_int",
}
#: A Juggling-v1 level and the sensor and release noise it sets (Cascade-v0 takes them too).
_JUGGLING_LEVEL = {
    "level": "name",
    "latency": "fraction",
    "position_std": "fraction",
    "velocity_std": "fraction",
    "release_speed_std": "fraction",
    "release_angle_std": "angle",
}
#: What every juggling env with a controller and a residual action takes.
_JUGGLING_RESIDUAL = {
    "controller": "name",
    "max_catches": "small_int",
    "residual_scale": "positive",
    "residual_phases": "phases",
    "reward_weights": "weights",
    "render_mode": "render_mode",
    "width": "size",
    "height": "size",
}
#: Juggling-v2's arguments (Cascade-v1 takes them and a pattern).
_JUGGLING_V2 = {
    "level": "name",
    "delay_offset": "fraction",
    "tracker_gain": "fraction",
    "timing_scale": "fraction",
    "observe_task_error": "flag",
    "delay_rule": "rule",
    "anchor_frames": "small_int",
    **_JUGGLING_RESIDUAL,
}
ENVS: dict[str, dict[str, object]] = {
    "MotionEnvs/OrientationReach-v0": {
        "kwargs": {
            **_REACH_COMMON,
            "degree": "small_int",
            "reward_weights": "weights",
            "min_deg": "angle",
            "observe_timing": "flag",
            "split_by": "name",
            "fold": "optional_int",
            "val_folds": "small_int",
            "val_fold": "small_int",
        },
    },
    "MotionEnvs/PositionReach-v0": {
        "kwargs": {
            **_REACH_COMMON,
            "shapes": "names",
            "n_sines": "small_int",
            "reward_weights": "weights",
            "observe_timing": "flag",
        },
    },
    "MotionEnvs/OrientationReach-v1": {"same_as": "MotionEnvs/OrientationReach-v0"},
    "MotionEnvs/PositionReach-v1": {"same_as": "MotionEnvs/PositionReach-v0"},
    "MotionEnvs/Juggling-v0": {
        "kwargs": {
            "residual_scale": "positive",
            "gravity": "positive",
            "noise": "fraction",
            "max_cycles": "small_int",
            "frame_skip": "small_int",
            "reward_weights": "weights",
            "data": "data",
            "render_mode": "render_mode",
            "width": "size",
            "height": "size",
        },
        "reset_options": {"cycle": "seed"},
    },
    "MotionEnvs/Juggling-v1": {
        "kwargs": {
            **_JUGGLING_LEVEL,
            "gravity": "gravity",
            **_JUGGLING_RESIDUAL,
        },
    },
    "MotionEnvs/Juggling-v2": {"kwargs": _JUGGLING_V2},
    "MotionEnvs/Cascade-v1": {
        "kwargs": {**_JUGGLING_V2, "pattern": "name", "anchor_start": "flag"}
    },
    "MotionEnvs/Cascade-v0": {
        "kwargs": {
            **_JUGGLING_LEVEL,
            "pattern": "name",
            "tunables": "name",
            "dwell_ratio": "fraction",
            "gravity": "gravity",
            "frame_skip": "small_int",
            **_JUGGLING_RESIDUAL,
        },
    },
    "MotionEnvs/OrientationCoefficients-v0": {
        "kwargs": {
            **_REACH_COMMON,
            "degree": "small_int",
            "n_sines": "small_int",
            "min_deg": "angle",
            "fold": "optional_int",
            "val_folds": "small_int",
            "val_fold": "small_int",
        },
    },
    "MotionEnvs/PositionCoefficients-v0": {
        "kwargs": {
            **{k: v for k, v in _REACH_COMMON.items() if k != "calibration"},
            "shapes": "names",
            "nominal_sines": "small_int",
            "n_sines": "small_int",
        },
    },
}

#: Arguments of the vector entry points (``gym.make_vec``) beyond the single env's
#: (name -> kind of value fuzzed).
VECTOR_ARGS: dict[str, str] = {
    "num_envs": "count",
    "max_episode_steps": "optional_count",
    "autoreset_mode": "name",
    "backend": "name",
    "threads": "optional_count",
}

#: ``motion-bench`` options whose values are numbers or lists of numbers (sub-command,
#: option); every other option's checker is a path, an id or a name.
CLI_NUMERIC_OPTIONS: tuple[tuple[str, str], ...] = (
    ("orientation", "--min-deg"),
    ("orientation", "--split-seed"),
    ("orientation", "--test-fraction"),
    ("orientation", "--degree"),
    ("orientation", "--up"),
    ("position", "--n-points"),
    ("position", "--n-sines"),
    ("position", "--n-weights"),
    ("position", "--test-fraction"),
    ("position", "--split-seed"),
    ("juggling", "--cycles"),
    ("juggling", "--noise"),
    ("juggling", "--tracking"),
    ("juggling", "--seed"),
    ("juggling", "--demo-cycles"),
    ("juggling", "--demo-persons"),
    ("juggling", "--gravity"),
    ("juggling", "--mujoco-cycles"),
    ("juggling", "--episodes"),
    ("juggling", "--max-catches"),
    ("juggling", "--pick-episodes"),
    ("juggling", "--n-balls"),
    ("juggling", "--pattern"),
    ("calibrate-cohort", "--max-evaluations"),
    ("calibrate-cohort", "--check-seeds"),
    ("train", "--timesteps"),
    ("train", "--seed"),
    ("train", "--n-envs"),
    ("agent", "--episodes"),
    ("sweep", "--num-cpus"),
    ("import", "--unit"),
    ("import", "--max-gap"),
    ("import", "--speed-threshold"),
    ("import", "--min-duration"),
    ("import", "--min-pause"),
)

#: Options that name a file (or a run folder) the command reads: their checkers are
#: marked ``baselines.options.reads_files`` (THE input rule: regular files only, opened
#: non-blocking, bounded) and fuzzed with FIFOs, devices and symbolic links to them.
CLI_FILE_OPTIONS: tuple[tuple[str, str], ...] = (
    ("orientation", "--data"),
    ("position", "--data"),
    ("juggling", "--data"),
    ("juggling", "--agent"),
    ("juggling", "--analyse"),
    ("import", "file"),
    ("import", "--segments"),
    ("calibrate-cohort", "--target"),
    ("calibrate-cohort", "--config"),
    ("train", "--config"),
    ("agent", "run_dir"),
    ("sweep", "--config"),
)

#: Every ``motion-bench`` sub-command.
CLI_COMMANDS: tuple[str, ...] = (
    "all",
    "orientation",
    "position",
    "juggling",
    "import",
    "calibrate-cohort",
    "train",
    "agent",
    "sweep",
)
#: Options naming what the command writes (THE output rule, ``motion_envs._io.check_output``).
CLI_OUTPUT_OPTIONS: tuple[tuple[str, str], ...] = tuple((c, "--out") for c in CLI_COMMANDS)

#: Checkers (``type=`` names) of options that take ids or names: neither numbers nor files.
CLI_NAME_TYPES = frozenset(
    {
        "calibration_option",
        "conditions_option",
        "_levels",
        "env_id",
        "env_kwarg",
        "level_names",
        # motion-bench import: marker, joint and label names, axis letters, units
        "marker",
        "markers",
        "joint",
        "relative_to",
        "ball",
        "balls",
        "up",
        "subject",
        "task",
        "lateral",
    }
)

#: Checkers of file options and outputs (see above), by ``type=`` name.
CLI_FILE_TYPES = frozenset(
    {
        "orientation_data",
        "position_data",
        "juggling_data",
        "analyse_source",
        "run_folder",
        "_source",
        "segments",
        "target_option",
        "config_option",
        "yaml_file",
        "sweep_file",
    }
)
CLI_OUTPUT_TYPES = frozenset({"output_folder", "output_file"})
#: Every non-numeric checker (what the numeric-option completeness test skips).
CLI_NON_NUMERIC_TYPES = CLI_NAME_TYPES | CLI_FILE_TYPES | CLI_OUTPUT_TYPES
