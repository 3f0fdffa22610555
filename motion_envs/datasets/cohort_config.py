"""Configuration of the virtual (simulated) cohort: YAML schema, validation and look-up.

A cohort configuration is a YAML file; the shipped ones live inside the package at
``motion_envs/datasets/cohorts/*.yaml`` (so an installed package finds them), and the
repository's ``configs/cohorts`` is a symbolic link to that folder (one file on disk,
``tests/test_packaged_configs.py``). :func:`resolve_cohort_config` accepts

* a path to a YAML file (anything ending in ``.yaml``/``.yml`` or an existing file), or
* a name such as ``"faraway2008"``: ``configs/cohorts/NAME.yaml`` of the source checkout
  when it exists (a user's own file there, or through the link the shipped one),
  otherwise the package's.

Every key is documented in ``configs/cohorts/faraway2008.yaml``. Unknown keys and
out-of-range values raise ``ValueError`` naming the key. Angles in the file are in
degrees, residual scales in radians, times in seconds.
"""

from __future__ import annotations

import copy
import os
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING, Any

import yaml

if TYPE_CHECKING:
    from importlib.resources.abc import Traversable

from motion_envs._io import atomic_write_text, check_regular_file, read_regular_text

#: Largest cohort config file read (bytes; the shipped ones are a few KiB).
MAX_CONFIG_BYTES = 1 << 20

__all__ = [
    "CALIBRATED_PARAMETERS",
    "DEFAULT_COHORT",
    "REPO_CONFIG_DIR",
    "YAML_HEADER",
    "CohortConfig",
    "available_cohorts",
    "load_cohort_config",
    "package_config_dir",
    "resolve_cohort_config",
]

#: Name of the calibrated cohort used by ``--data cohort``.
DEFAULT_COHORT = "faraway2008"

#: Parameters fitted by ``motion-bench calibrate-cohort``, as (section path, key). All
#: are scales (>= 0) except ``residual.decay`` (>= 0, the spectral decay exponent).
CALIBRATED_PARAMETERS: tuple[str, ...] = (
    "residual.common.scale",
    "residual.task.scale",
    "residual.subject.scale",
    "residual.subject_task.scale",
    "residual.trial.scale",
    "residual.decay",
    "speed_profile.spread",
)

#: ``configs/cohorts`` of the source checkout (a link to the package's folder; absent in
#: an installed package).
REPO_CONFIG_DIR = Path(__file__).resolve().parents[2] / "configs" / "cohorts"

#: Comment block written at the top of every saved cohort YAML (documents each key).
YAML_HEADER = """\
Virtual cohort configuration for motion-envs. SIMULATED DATA, not a recording: a seeded
generative model of Faraway & Choe's (2008) reaching experiment (their data are not public).
Model: see motion_envs/datasets/cohort.py. The one file: motion_envs/datasets/cohorts/NAME.yaml
(shipped in the package; the repository's configs/cohorts/ is a link to that folder).
Written by code (motion-bench calibrate-cohort); comments other than this header are lost.

name, seed: cohort name (dataset name "cohort:NAME") and the root random seed.
design.n_subjects: subjects; sex alternates female (0) / male (1) by index.
design.sampling_hz: sampling rate (the paper's 25 Hz); sample k is at t = k / hz.
design.replicates: replicate names of every task (push, pull).
design.dropout: probability that a trajectory is lost (the paper kept 1088 of 1400).
design.age_range, design.height_cm.{female,male}: age uniform in [min, max] years;
  height normal [mean, sd] in cm.
design.start_rotvec_deg: fixed start orientation (palm down on the thigh), rotation vector.
design.pods (pitch), design.blocks ([pitch, yaw]), design.grips (roll): degrees; the end
  orientation of task POD-BLOCK-GRIP is q_s * R_y(pod) * expmap(0, pitch, yaw) * R_x(grip).
design.requested_tasks: the 35 of 60 tasks performed (the 35 with the smallest rotation).
design.endpoint_jitter_deg: per-axis sd of a per-trial rotation of the end orientation.
durations: D = max(min_s, (base_s + per_radian_s * angle) * exp(u_subject + u_task +
  u_trial)) with normal u of sd subject_sd, task_sd, trial_sd (seconds, radians).
speed_profile: alpha(tau) = Beta CDF I_tau(a_l, b_l); log a_l = log a + spread * (sqrt(s)
  z_subject + sqrt(1 - s) z_trial), s = subject_share; same for b.            [spread: calibrated]
residual: r = common + task + subject + subject_task + trial, sine series
  sum_{k=1..harmonics} f_k sin(k pi tau) (zero at tau = 0, 1), in radians.
residual.decay: random series draw f_k ~ N(0, scale^2 w_k), w_k proportional to k^-decay
  (sum 1); larger is smoother.                                                  [calibrated]
residual.noise_rad: sd of white measurement noise (rotation vector per sample).
residual.common: fixed coefficients (one 3-vector per harmonic) times scale; the downward
  tilt of the hand is a rotation about +y.                                [scale: calibrated]
residual.task: scale and variance shares of the pod, block, grip and task-specific
  (interaction) random series.                                            [scale: calibrated]
residual.subject, residual.subject_task, residual.trial: scales of the subject, subject x
  task and trial random series.                                          [scales: calibrated]
calibration: record of the last calibration (targets, achieved values, optimiser).
"""

# key -> (type, check) for the leaves of the schema; sections are nested dicts.
_SCHEMA: dict[str, Any] = {
    "name": str,
    "description": str,
    "simulated": bool,
    "seed": int,
    "design": {
        "n_subjects": int,
        "sampling_hz": float,
        "replicates": list,
        "dropout": float,
        "age_range": list,
        "height_cm": {"female": list, "male": list},
        "start_rotvec_deg": list,
        "pods": dict,
        "blocks": dict,
        "grips": dict,
        "requested_tasks": list,
        "endpoint_jitter_deg": float,
    },
    "durations": {
        "base_s": float,
        "per_radian_s": float,
        "subject_sd": float,
        "task_sd": float,
        "trial_sd": float,
        "min_s": float,
    },
    "speed_profile": {"a": float, "b": float, "spread": float, "subject_share": float},
    "residual": {
        "harmonics": int,
        "decay": float,
        "noise_rad": float,
        "common": {"scale": float, "coefficients": list},
        "task": {"scale": float, "weights": dict},
        "subject": {"scale": float},
        "subject_task": {"scale": float},
        "trial": {"scale": float},
    },
    "calibration": dict,
}

_OPTIONAL = {"description", "calibration"}


def _check_section(raw: Any, schema: dict[str, Any], where: str) -> None:
    if not isinstance(raw, dict):
        raise ValueError(f"cohort config: {where or 'top level'} must be a mapping")
    unknown = sorted(set(raw) - set(schema))
    if unknown:
        raise ValueError(
            f"cohort config: unknown key(s) {unknown} in {where or 'top level'}; "
            f"expected {sorted(schema)}"
        )
    for key, kind in schema.items():
        path = f"{where}.{key}" if where else key
        if key not in raw:
            if key in _OPTIONAL:
                continue
            raise ValueError(f"cohort config: missing key {path!r}")
        value = raw[key]
        if isinstance(kind, dict):
            _check_section(value, kind, path)
        elif kind is float:
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise ValueError(f"cohort config: {path!r} must be a number; got {value!r}")
        elif kind is int:
            if isinstance(value, bool) or not isinstance(value, int):
                raise ValueError(f"cohort config: {path!r} must be an integer; got {value!r}")
        elif not isinstance(value, kind):
            raise ValueError(
                f"cohort config: {path!r} must be a {kind.__name__}; got {type(value).__name__}"
            )


def _require(cond: bool, key: str, expected: str, value: Any) -> None:
    if not cond:
        raise ValueError(f"cohort config: {key!r} must be {expected}; got {value!r}")


@dataclass(frozen=True)
class CohortConfig:
    """A validated cohort configuration (the parsed YAML, read-only by convention).

    Use :meth:`get` / :meth:`with_values` for dotted keys such as
    ``"residual.trial.scale"``; :meth:`to_yaml` writes it back.
    """

    data: dict[str, Any]
    source: str = "<memory>"

    def __post_init__(self) -> None:
        self.validate()

    @property
    def name(self) -> str:
        return str(self.data["name"])

    @property
    def seed(self) -> int:
        return int(self.data["seed"])

    def get(self, key: str) -> Any:
        """Value at a dotted key, e.g. ``get("design.n_subjects")``."""
        node: Any = self.data
        for part in key.split("."):
            if not isinstance(node, dict) or part not in node:
                raise ValueError(f"cohort config has no key {key!r}")
            node = node[part]
        return node

    def with_values(self, **values: Any) -> CohortConfig:
        """A copy with dotted keys replaced: ``with_values(**{"design.n_subjects": 40})``."""
        data = copy.deepcopy(self.data)
        for key, value in values.items():
            parts = key.split(".")
            node = data
            for part in parts[:-1]:
                if part not in node or not isinstance(node[part], dict):
                    raise ValueError(f"cohort config has no key {key!r}")
                node = node[part]
            if parts[-1] not in node:
                raise ValueError(f"cohort config has no key {key!r}")
            node[parts[-1]] = value
        return CohortConfig(data, source=self.source)

    def validate(self) -> None:
        """Check the schema and every range; raise ``ValueError`` naming the key."""
        d = self.data
        _check_section(d, _SCHEMA, "")
        _require(d["simulated"] is True, "simulated", "true (a cohort is simulated data)", d)
        _require(d["seed"] >= 0, "seed", "an integer >= 0", d["seed"])
        des = d["design"]
        _require(des["n_subjects"] >= 1, "design.n_subjects", ">= 1", des["n_subjects"])
        _require(des["sampling_hz"] > 0, "design.sampling_hz", "> 0", des["sampling_hz"])
        _require(
            len(des["replicates"]) >= 1 and len(set(des["replicates"])) == len(des["replicates"]),
            "design.replicates",
            "a non-empty list of distinct names",
            des["replicates"],
        )
        _require(0.0 <= des["dropout"] < 1.0, "design.dropout", "in [0, 1)", des["dropout"])
        lo_hi = des["age_range"]
        _require(
            len(lo_hi) == 2 and 0 < lo_hi[0] <= lo_hi[1],
            "design.age_range",
            "[min, max] with 0 < min <= max",
            lo_hi,
        )
        for sex in ("female", "male"):
            ms = des["height_cm"][sex]
            _require(
                len(ms) == 2 and ms[0] > 0 and ms[1] >= 0,
                f"design.height_cm.{sex}",
                "[mean, sd] with mean > 0, sd >= 0",
                ms,
            )
        _require(len(des["start_rotvec_deg"]) == 3, "design.start_rotvec_deg", "3 numbers", None)
        for key, width in (("pods", 1), ("blocks", 2), ("grips", 1)):
            table = des[key]
            _require(len(table) >= 1, f"design.{key}", "a non-empty mapping", table)
            for label, value in table.items():
                vals = value if isinstance(value, list) else [value]
                _require(
                    len(vals) == width and all(isinstance(v, (int, float)) for v in vals),
                    f"design.{key}.{label}",
                    f"{width} angle(s) in degrees",
                    value,
                )
                _require(
                    "-" not in str(label), f"design.{key}.{label}", "a name without '-'", label
                )
        tasks = set(self.all_tasks())
        req = des["requested_tasks"]
        bad = [t for t in req if t not in tasks]
        _require(not bad, "design.requested_tasks", "names POD-BLOCK-GRIP of the design", bad)
        _require(len(set(req)) == len(req) and req, "design.requested_tasks", "distinct", req)
        _require(
            0 <= des["endpoint_jitter_deg"] < 45, "design.endpoint_jitter_deg", "in [0, 45)", None
        )
        dur = d["durations"]
        for key in ("base_s", "min_s"):
            _require(dur[key] > 0, f"durations.{key}", "> 0", dur[key])
        for key in ("per_radian_s", "subject_sd", "task_sd", "trial_sd"):
            _require(dur[key] >= 0, f"durations.{key}", ">= 0", dur[key])
        sp = d["speed_profile"]
        for key in ("a", "b"):
            _require(sp[key] > 0, f"speed_profile.{key}", "> 0", sp[key])
        _require(sp["spread"] >= 0, "speed_profile.spread", ">= 0", sp["spread"])
        _require(0 <= sp["subject_share"] <= 1, "speed_profile.subject_share", "in [0, 1]", None)
        res = d["residual"]
        _require(1 <= res["harmonics"] <= 12, "residual.harmonics", "in 1..12", res["harmonics"])
        _require(res["decay"] >= 0, "residual.decay", ">= 0", res["decay"])
        _require(res["noise_rad"] >= 0, "residual.noise_rad", ">= 0", res["noise_rad"])
        for comp in ("common", "task", "subject", "subject_task", "trial"):
            s = res[comp]["scale"]
            _require(s >= 0, f"residual.{comp}.scale", ">= 0", s)
        coef = res["common"]["coefficients"]
        _require(
            1 <= len(coef) <= res["harmonics"]
            and all(isinstance(c, list) and len(c) == 3 for c in coef),
            "residual.common.coefficients",
            "a list of 1..harmonics vectors of 3 numbers (one per sine harmonic)",
            coef,
        )
        weights = res["task"]["weights"]
        _require(
            set(weights) == {"pod", "block", "grip", "interaction"}
            and all(isinstance(v, (int, float)) and v >= 0 for v in weights.values())
            and sum(weights.values()) > 0,
            "residual.task.weights",
            "variance shares {pod, block, grip, interaction} >= 0, not all 0",
            weights,
        )

    def all_tasks(self) -> list[str]:
        """All ``POD-BLOCK-GRIP`` task names of the design, in design order."""
        des = self.data["design"]
        return [f"{p}-{b}-{g}" for p in des["pods"] for b in des["blocks"] for g in des["grips"]]

    def calibrated_values(self) -> dict[str, float]:
        """The values of :data:`CALIBRATED_PARAMETERS`."""
        return {key: float(self.get(key)) for key in CALIBRATED_PARAMETERS}

    def to_yaml(self) -> str:
        """The configuration as YAML text (keys in schema order)."""
        return yaml.safe_dump(self.data, sort_keys=False, default_flow_style=None, width=100)

    def save(self, path: str | os.PathLike[str], header: str = YAML_HEADER) -> Path:
        """Write the YAML atomically, ``header`` lines prepended as comments."""
        lines = "".join(f"# {line}".rstrip() + "\n" for line in header.splitlines())
        target = Path(path)
        atomic_write_text(target, lines + self.to_yaml())
        return target


def package_config_dir() -> Traversable:
    """The folder of the cohort configs shipped inside the package."""
    return resources.files("motion_envs.datasets") / "cohorts"


def available_cohorts() -> list[str]:
    """Names of the shipped cohort configurations."""
    names = {p.name[:-5] for p in package_config_dir().iterdir() if p.name.endswith(".yaml")}
    if REPO_CONFIG_DIR.is_dir():
        names |= {p.stem for p in REPO_CONFIG_DIR.glob("*.yaml")}
    return sorted(names)


def resolve_cohort_config(config: str | os.PathLike[str]) -> Path:
    """Path of a cohort YAML given a name (``"faraway2008"``) or a path (see module doc)."""
    text = os.fspath(config)
    path = Path(text)
    if path.suffix.lower() in (".yaml", ".yml") or os.path.lexists(path):
        if not os.path.lexists(path):
            raise FileNotFoundError(f"cohort config file {path} does not exist")
        return check_regular_file(path, max_bytes=MAX_CONFIG_BYTES)  # no FIFO or device
    if not text or "/" in text or "\\" in text:
        raise ValueError(f"config must be a cohort name or a path to a YAML file; got {text!r}")
    repo = REPO_CONFIG_DIR / f"{text}.yaml"
    if repo.is_file():
        return repo
    packaged = package_config_dir() / f"{text}.yaml"
    if packaged.is_file():
        return Path(str(packaged))
    raise ValueError(
        f"unknown cohort {text!r}; expected one of {available_cohorts()} or a path to a YAML file"
    )


def load_cohort_config(config: str | os.PathLike[str] = DEFAULT_COHORT) -> CohortConfig:
    """Read and validate a cohort configuration by name or path."""
    path = resolve_cohort_config(config)
    try:
        data = yaml.safe_load(read_regular_text(path, max_bytes=MAX_CONFIG_BYTES))
    except yaml.YAMLError as exc:
        raise ValueError(f"{path}: not valid YAML: {exc}") from exc
    try:
        return CohortConfig(data, source=str(path))
    except ValueError as exc:
        raise ValueError(f"{path}: {exc}") from exc
