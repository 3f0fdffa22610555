"""THE registry of the project's input surfaces, fuzzed by ``tests/test_fuzz.py``.

Every public loader (a ``load_*``/``read_*`` name in the ``__all__`` of a module of
``motion_envs.datasets`` or ``motion_envs.models``), every model-file and config loader
of ``baselines``, every environment id of ``motion_envs.ENV_IDS`` and every numeric
option of the ``motion-bench`` CLI is listed here with the errors it documents and the
kind of input it takes. ``tests/test_fuzz.py`` fails when a public loader or an env id
exists that is not listed, so the next module is covered by construction.

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
)

#: Environment ids: constructor arguments fuzzed (name -> kind of value), action shape.
ENVS: dict[str, dict[str, object]] = {
    "MotionEnvs/OrientationReach-v0": {
        "kwargs": {
            "residual_scale": "positive",
            "test_fraction": "fraction",
            "val_fraction": "fraction",
            "val_folds": "small_int",
            "split_seed": "seed",
            "min_deg": "angle",
            "degree": "small_int",
            "calibration": "small_int",
            "width": "size",
        },
    },
    "MotionEnvs/PositionReach-v0": {
        "kwargs": {
            "residual_scale": "positive",
            "test_fraction": "fraction",
            "split_seed": "seed",
            "n_sines": "small_int",
            "calibration": "small_int",
            "height": "size",
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
            "width": "size",
        },
        "reset_options": {"cycle": "seed"},
    },
    "MotionEnvs/Juggling-v1": {
        "kwargs": {
            "latency": "fraction",
            "position_std": "fraction",
            "release_speed_std": "fraction",
            "gravity": "positive",
            "max_catches": "small_int",
            "residual_scale": "positive",
            "residual_phases": "phases",
            "width": "size",
        },
    },
    "MotionEnvs/Cascade-v0": {
        "kwargs": {
            "latency": "fraction",
            "position_std": "fraction",
            "release_speed_std": "fraction",
            "dwell_ratio": "fraction",
            "max_catches": "small_int",
            "frame_skip": "small_int",
            "residual_scale": "positive",
            "residual_phases": "phases",
            "width": "size",
        },
    },
    "MotionEnvs/OrientationCoefficients-v0": {
        "kwargs": {
            "residual_scale": "positive",
            "n_sines": "small_int",
            "calibration": "small_int",
            "val_folds": "small_int",
            "test_fraction": "fraction",
            "split_seed": "seed",
            "min_deg": "angle",
        },
    },
    "MotionEnvs/PositionCoefficients-v0": {
        "kwargs": {
            "residual_scale": "positive",
            "n_sines": "small_int",
            "test_fraction": "fraction",
            "split_seed": "seed",
        },
    },
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

#: Checkers (``type=`` names) of options that take paths, ids or names, not numbers.
CLI_NON_NUMERIC_TYPES = frozenset(
    {
        "output_folder",
        "output_file",
        "orientation_data",
        "position_data",
        "juggling_data",
        "analyse_source",
        "calibration_option",
        "conditions_option",
        "_levels",
        "target_option",
        "config_option",
        "env_id",
        "yaml_file",
        "env_kwarg",
        "sweep_file",
        "level_names",
        "run_folder",
        # motion-bench import: marker, joint and label names, axis letters, files
        "_source",
        "marker",
        "markers",
        "joint",
        "relative_to",
        "ball",
        "balls",
        "up",
        "segments",
        "subject",
        "task",
        "lateral",
    }
)
