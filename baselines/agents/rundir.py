"""The run folder of ``motion-bench train`` and loading it back, checked.

A run folder holds

* ``agent.zip``: the policy chosen on the validation split (SB3's own format);
  ``final_agent.zip``: the policy at the end of training;
* ``normalization.npz`` / ``final_normalization.npz``: VecNormalize's running statistics
  of the observations and returns at that checkpoint (plain arrays, read with
  ``allow_pickle=False``), absent without normalisation;
* ``config.json``: the resolved hyper-parameters, algorithm, environment id and kwargs;
* ``run.json``: the manifest: format, motion-envs and SB3 versions, the command, the seed,
  the validation results, the SHA-256 of every file above and its own
  (``manifest_sha256``: of the manifest's canonical JSON without that key);
* ``evaluations.csv`` and ``tb/`` (TensorBoard).

:func:`load_run` rebuilds the model from ``config.json`` and loads only the network
weights from the zip (SB3's ``load_from_zip_file(load_data=False)``, i.e.
``torch.load(weights_only=True)``, then
:meth:`~stable_baselines3.common.base_class.BaseAlgorithm.set_parameters` of those
arrays), so nothing is unpickled (sb3-contrib's ARS, whose own ``set_parameters`` of a
path would unpickle the zip's ``data``, included); a modified file, a missing
file, a file that is not what it should be (JSON read strictly by
:func:`motion_envs._io.strict_json_loads`, every file a regular file read within
:data:`MAX_FILE_BYTES`) or a run written by another motion-envs version raises a one-line
``ValueError`` naming the folder and the file, whatever the reader underneath raised.
The folder is written under :func:`motion_envs._io.folder_lock`: a second ``train`` into
the same ``--out`` gets one line at once.
"""

from __future__ import annotations

import contextlib
import hashlib
import io
import json
import math
import os
import pickle
import shutil
import tempfile
import warnings
import zipfile
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from motion_envs._io import (
    UserFileError,
    atomic_write,
    atomic_write_text,
    check_output,
    current_umask,
    folder_lock,
    read_regular_file,
    strict_json_loads,
)

__all__ = [
    "FORMAT",
    "MAX_FILE_BYTES",
    "LoadedRun",
    "ObsNormalizer",
    "file_sha256",
    "load_run",
    "manifest_sha256",
    "read_run_json",
    "save_model",
    "staged_run_folder",
    "write_json",
    "write_manifest",
]

#: ``run.json["format"]`` of the folders this module writes.
FORMAT = "motion-envs-agent/1"
#: Largest file of a run folder read back (bytes): agents of the bounded networks of
#: ``baselines.agents.config`` are far smaller.
MAX_FILE_BYTES = 2**31
#: Largest JSON file of a run folder (bytes).
MAX_JSON_BYTES = 64 * 2**20
#: What reading a tampered file can raise underneath (SB3, torch, numpy, zipfile), each
#: turned into one ``ValueError`` line naming the file.
_READ_ERRORS: tuple[type[BaseException], ...] = (
    ArithmeticError,
    AttributeError,
    EOFError,
    ImportError,
    LookupError,
    OSError,
    RecursionError,
    RuntimeError,
    TypeError,
    ValueError,
    pickle.UnpicklingError,
    zipfile.BadZipFile,
)


@contextlib.contextmanager
def staged_run_folder(out: Path) -> Iterator[Path]:
    """A fresh empty folder beside ``out``, renamed to ``out`` when the block ends normally
    and removed when it raises (an interrupted run leaves nothing behind).

    ``out`` must not exist or be an empty folder (``ValueError`` naming it otherwise). The
    rename is atomic and refuses a non-empty ``out``, so of two runs started into one
    folder the second to finish gets a ``ValueError``, its files are removed, and the
    first's folder is untouched.
    """
    out = Path(out)
    try:
        check_output(out, folder=True)
    except UserFileError as exc:
        raise ValueError(f"--out {exc}") from None
    if out.exists() and (not out.is_dir() or any(out.iterdir())):
        raise ValueError(
            f"--out {out} is not an empty folder (it may hold a run); choose another folder"
        )
    with folder_lock(out):  # a second writer of out gets one line now, not after training
        with _staged(out) as staging:
            yield staging


@contextlib.contextmanager
def _staged(out: Path) -> Iterator[Path]:
    staging = Path(tempfile.mkdtemp(prefix=f".{out.name}.partial-", dir=out.parent))
    try:
        os.chmod(staging, 0o777 & ~current_umask())  # mkdtemp's 0o700 is for temporaries
        yield staging
        try:
            os.replace(staging, out)  # POSIX rename(2): fails unless out is absent or empty
        except OSError:
            raise ValueError(
                f"--out {out} was filled by another run while this one trained; this run "
                "is discarded (choose another folder)"
            ) from None
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise


def write_json(path: Path, obj: Any) -> None:
    """Write ``obj`` as indented JSON atomically (temporary file, then rename)."""
    atomic_write_text(path, json.dumps(obj, indent=2, sort_keys=False) + "\n")


def save_model(model: Any, path: Path) -> None:
    """Save an SB3 model's zip to ``path`` atomically.

    SB3's ``save`` accepts an open binary file; it writes into the temporary file that
    :func:`motion_envs._io.atomic_write` creates in the same folder, which then replaces
    ``path``, so a run folder never holds a half-written agent.
    """
    atomic_write(path, model.save, binary=True)


def file_sha256(path: Path) -> str:
    """Hex SHA-256 of a regular file's bytes (at most :data:`MAX_FILE_BYTES`;
    ``UserFileError``, a ``ValueError``, otherwise)."""
    return hashlib.sha256(read_regular_file(path, max_bytes=MAX_FILE_BYTES)).hexdigest()


def manifest_sha256(doc: Mapping[str, Any]) -> str:
    """SHA-256 of a manifest's canonical JSON (sorted keys, no ``manifest_sha256``)."""
    body = {k: v for k, v in doc.items() if k != "manifest_sha256"}
    text = json.dumps(body, sort_keys=True, separators=(",", ":"), allow_nan=False)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


@dataclass(frozen=True)
class ObsNormalizer:
    """VecNormalize's observation transform at one checkpoint:
    ``clip((obs - mean) / sqrt(var + epsilon), -clip_obs, clip_obs)``; identity when
    ``mean`` is None."""

    mean: NDArray[np.float64] | None = None
    var: NDArray[np.float64] | None = None
    epsilon: float = 1e-8
    clip_obs: float = 10.0

    def __call__(self, obs: NDArray[np.floating]) -> NDArray[np.float32]:
        if self.mean is None or self.var is None:
            return np.asarray(obs, dtype=np.float32)
        out = np.clip(
            (obs - self.mean) / np.sqrt(self.var + self.epsilon), -self.clip_obs, self.clip_obs
        )
        return out.astype(np.float32)

    @classmethod
    def from_vec_normalize(cls, venv: Any) -> ObsNormalizer:
        """A snapshot (copies) of a ``VecNormalize``'s observation statistics, or identity."""
        if venv is None or not venv.norm_obs:
            return cls()
        return cls(
            venv.obs_rms.mean.copy(),
            venv.obs_rms.var.copy(),
            float(venv.epsilon),
            float(venv.clip_obs),
        )

    @staticmethod
    def save_vec_normalize(venv: Any, path: Path) -> None:
        """All running statistics of a ``VecNormalize`` as a plain ``.npz`` (atomic)."""
        arrays = {
            "obs_mean": venv.obs_rms.mean,
            "obs_var": venv.obs_rms.var,
            "obs_count": np.float64(venv.obs_rms.count),
            "ret_mean": np.asarray(venv.ret_rms.mean, dtype=np.float64),
            "ret_var": np.asarray(venv.ret_rms.var, dtype=np.float64),
            "ret_count": np.float64(venv.ret_rms.count),
            "epsilon": np.float64(venv.epsilon),
            "clip_obs": np.float64(venv.clip_obs),
            "clip_reward": np.float64(venv.clip_reward),
            "norm_obs": np.bool_(venv.norm_obs),
            "norm_reward": np.bool_(venv.norm_reward),
        }
        atomic_write(path, lambda fh: np.savez(fh, **arrays), binary=True)

    @classmethod
    def load(cls, path: Path) -> ObsNormalizer:
        """The observation transform stored by :meth:`save_vec_normalize`."""
        try:
            raw = io.BytesIO(read_regular_file(path, max_bytes=MAX_FILE_BYTES))
            with np.load(raw, allow_pickle=False) as z:
                if not bool(z["norm_obs"]):
                    return cls()
                out = cls(
                    np.asarray(z["obs_mean"], dtype=np.float64),
                    np.asarray(z["obs_var"], dtype=np.float64),
                    float(z["epsilon"]),
                    float(z["clip_obs"]),
                )
        except _READ_ERRORS as exc:
            raise ValueError(
                f"{path}: not a normalisation file of motion-bench train "
                f"({type(exc).__name__}: {' '.join(str(exc).split())[:200]})"
            ) from None
        assert out.mean is not None and out.var is not None
        if (
            out.mean.ndim != 1
            or out.mean.shape != out.var.shape
            or not (np.isfinite(out.mean).all() and np.isfinite(out.var).all())
            or (out.var < 0).any()
            or not (math.isfinite(out.epsilon) and out.epsilon > 0)
            or not (math.isfinite(out.clip_obs) and out.clip_obs > 0)
        ):
            raise ValueError(
                f"{path}: not a normalisation file of motion-bench train (statistics of "
                "mismatched shapes or not finite, a negative variance or epsilon/clip <= 0)"
            )
        return out


def write_manifest(run_dir: Path, manifest: Mapping[str, Any], files: list[str]) -> None:
    """``run.json``: ``manifest`` plus the format, versions and the files' SHA-256."""
    import stable_baselines3

    import motion_envs

    doc = {
        "format": FORMAT,
        "motion_envs_version": motion_envs.__version__,
        "stable_baselines3_version": stable_baselines3.__version__,
        **manifest,
        "files": {name: file_sha256(run_dir / name) for name in files if (run_dir / name).exists()},
    }
    doc["manifest_sha256"] = manifest_sha256(doc)
    write_json(run_dir / "run.json", doc)


@dataclass(frozen=True)
class LoadedRun:
    """A run folder loaded back: the model, its observation transform, config, manifest."""

    run_dir: Path
    model: Any
    normalizer: ObsNormalizer
    config: dict[str, Any]
    manifest: dict[str, Any]

    @property
    def env_id(self) -> str:
        return str(self.config["env_id"])

    @property
    def env_kwargs(self) -> dict[str, Any]:
        return dict(self.config["hyperparams"]["env_kwargs"])

    @property
    def frame_stack(self) -> int:
        """Observations the policy sees at once (``frame_stack``; 1 for runs without)."""
        return int(self.config["hyperparams"].get("frame_stack", 1))

    def predict(self, obs: NDArray[np.floating]) -> NDArray[np.float32]:
        """Deterministic (mean) actions of a batch of the policy's own observations (the
        stack of :attr:`frame_stack` raw ones)."""
        actions, _ = self.model.predict(self.normalizer(obs), deterministic=True)
        return np.asarray(actions, dtype=np.float32)

    def policy(self) -> Callable[[NDArray[np.float32]], NDArray[np.floating]]:
        """Raw observations ``(N, obs_dim)`` to deterministic actions for ONE batch of
        episodes that start together (a fresh stack, :mod:`baselines.agents.memory`)."""
        from baselines.agents.memory import stacked_policy

        return stacked_policy(self.predict, self.frame_stack)


def read_run_json(path: Path, run_dir: Path) -> dict[str, Any]:
    """A JSON object file of a run folder, read strictly (one-line ``ValueError``)."""
    if not os.path.lexists(path):
        raise ValueError(
            f"run folder {run_dir}: {path.name} is missing (not a motion-bench train run?)"
        )
    try:
        doc = strict_json_loads(
            read_regular_file(path, max_bytes=MAX_JSON_BYTES), f"run folder {run_dir}: {path.name}"
        )
    except UserFileError as exc:
        raise ValueError(
            str(exc) if str(exc).startswith("run folder") else f"run folder {run_dir}: {exc}"
        ) from None
    if not isinstance(doc, dict):
        raise ValueError(f"run folder {run_dir}: {path.name} must hold a JSON object")
    return doc


def _inside(name: Any) -> bool:
    """Whether a ``run.json`` file entry names a file inside the run folder (a relative
    path without ``..``, not absolute, no drive)."""
    if not isinstance(name, str) or not name or "\x00" in name or "\\" in name:
        return False
    parts = Path(name).parts
    return not Path(name).is_absolute() and ".." not in parts and ":" not in name


def load_run(run_dir: str | os.PathLike[str], which: str = "best") -> LoadedRun:
    """Load a run folder (``which="best"``: ``agent.zip``, ``"final"``: ``final_agent.zip``).

    Checks the manifest's format, motion-envs version and own SHA-256 and every file's
    SHA-256 before reading anything else; every error is one ``ValueError`` line naming
    the folder and the file.
    """
    from stable_baselines3.common.save_util import load_from_zip_file

    import motion_envs
    from baselines.agents.config import validate_hyperparams
    from baselines.agents.policies import build_model
    from baselines.agents.vec import make_sb3_vec_env

    run_dir = Path(run_dir)
    if not run_dir.is_dir():
        raise FileNotFoundError(f"run folder {run_dir} does not exist")
    manifest = read_run_json(run_dir / "run.json", run_dir)
    if manifest.get("format") != FORMAT:
        raise ValueError(
            f"run folder {run_dir}: run.json format {manifest.get('format')!r} is not {FORMAT!r}"
        )
    version = manifest.get("motion_envs_version")
    if version != motion_envs.__version__:
        raise ValueError(
            f"run folder {run_dir} was written by motion-envs {version}; this is "
            f"{motion_envs.__version__} (environments may differ): retrain, or install {version}"
        )
    try:
        own = manifest_sha256(manifest)
    except (TypeError, ValueError):  # not serialisable the way it was written
        own = None
    if manifest.get("manifest_sha256") != own:
        raise ValueError(
            f"run folder {run_dir}: run.json does not match its own SHA-256 "
            "(manifest_sha256; modified after training)"
        )
    files = manifest.get("files")
    if not isinstance(files, dict):
        raise ValueError(f"run folder {run_dir}: run.json lists no files")
    prefix = "" if which == "best" else "final_"
    needed = ["config.json", f"{prefix}agent.zip"]
    for name in needed:
        if name not in files:
            raise ValueError(f"run folder {run_dir}: run.json does not list {name}")
    for name, digest in files.items():
        if not _inside(name):
            raise ValueError(
                f"run folder {run_dir}: run.json lists {name!r}, which is not a file name "
                "inside the run folder"
            )
        path = run_dir / name
        if not os.path.lexists(path):
            raise ValueError(f"run folder {run_dir}: {name} is missing")
        try:
            actual = file_sha256(path)
        except UserFileError as exc:
            raise ValueError(f"run folder {run_dir}: {exc}") from None
        if actual != digest:
            raise ValueError(
                f"run folder {run_dir}: {name} does not match its SHA-256 in run.json "
                "(modified after training)"
            )
    config = read_run_json(run_dir / "config.json", run_dir)
    for key in ("algo", "env_id", "seed"):
        if config.get(key) != manifest.get(key):
            raise ValueError(f"run folder {run_dir}: config.json and run.json disagree on {key!r}")
    algo, env_id, seed = config.get("algo"), config.get("env_id"), config.get("seed")
    if not isinstance(algo, str) or not isinstance(env_id, str):
        raise ValueError(f"run folder {run_dir}: config.json: algo and env_id must be names")
    if isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed < 2**63:
        raise ValueError(f"run folder {run_dir}: config.json: seed must be an integer >= 0")
    hp = validate_hyperparams(algo, config.get("hyperparams"), f"{run_dir}/config.json")
    stats = run_dir / f"{prefix}normalization.npz"
    if hp.get("normalize", {}).get("obs") and f"{prefix}normalization.npz" not in files:
        raise ValueError(f"run folder {run_dir}: {stats.name} is missing (normalize.obs is true)")
    normalizer = ObsNormalizer.load(stats) if stats.name in files else ObsNormalizer()
    split = "val" if hp["env_kwargs"].get("val_fraction", 0) > 0 else "train"
    stage = "config.json"
    try:
        env = make_sb3_vec_env(
            env_id, 1, hp["env_kwargs"], split, frame_stack=int(hp.get("frame_stack", 1))
        )
        model = build_model(algo, hp, env, seed)
        stage = f"{prefix}agent.zip"
        try:
            with warnings.catch_warnings():  # torch's note on a tampered pickle: the error says it
                warnings.simplefilter("ignore", UserWarning)
                # the weights only (torch.load(weights_only=True)); not the zip's "data",
                # which SB3 would unpickle (sb3-contrib's ARS.set_parameters of a path does)
                _, params, _ = load_from_zip_file(
                    str(run_dir / stage), device="cpu", load_data=False
                )
                model.set_parameters(params, exact_match=True, device="cpu")
        finally:
            env.close()
    except _READ_ERRORS as exc:
        detail = " ".join(str(exc).split())[:300]
        what = (
            "does not fit config.json's network"
            if stage.endswith("agent.zip")
            else "does not build an agent"
        )
        raise ValueError(
            f"run folder {run_dir}: {stage} {what} ({type(exc).__name__}: {detail})"
        ) from None
    if normalizer.mean is not None and normalizer.mean.shape != env.observation_space.shape:
        raise ValueError(
            f"run folder {run_dir}: {stats.name} holds statistics of shape "
            f"{normalizer.mean.shape}, the environment observes {env.observation_space.shape}"
        )
    return LoadedRun(run_dir, model, normalizer, config, manifest)
