"""Snapshot every user-visible output, then compare two snapshots bit for bit.

A refactor that moves code must not change what users get. This script records a
manifest of SHA-256 digests of:

* every file ``motion-bench all`` writes (``results.json`` with its timing fields removed,
  CSV files as bytes, PNG/GIF files by their decoded pixels, so that a different PNG
  encoder setting does not count as a change);
* seeded rollouts of every registered environment id (zero action and a seeded random
  action; observations, rewards, ends and numeric infos), single and, where the id has a
  native vector env, ``gym.make_vec`` with 4 copies.

Usage, from the repository root with the project installed::

    python tools/output_identity.py snapshot --out /tmp/before   # on the old commit
    python tools/output_identity.py snapshot --out /tmp/after    # on the new commit
    python tools/output_identity.py compare /tmp/before /tmp/after

``compare`` prints every entry that differs (or is missing) and exits 1 if any does.
``snapshot --skip-bench`` records only the rollouts (seconds instead of about a minute).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np

#: Keys of ``results.json`` whose values are wall-clock measurements or the output folder's
#: path (``command`` names ``--out``), not results.
TIMING_KEYS = {"seconds", "elapsed", "timing", "timings", "command"}

ROLLOUT_STEPS = 120
NO_BARS = ("--no-progress",)


def _strip_timings(value: Any) -> Any:
    if isinstance(value, dict):
        return {
            k: _strip_timings(v)
            for k, v in value.items()
            if k not in TIMING_KEYS
            and not k.endswith(("_seconds", "_s"))
            and not k.startswith("seconds_")
        }
    if isinstance(value, list):
        return [_strip_timings(v) for v in value]
    return value


def _digest(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def file_digest(path: Path) -> str | None:
    """Digest of one output file by kind; None for files that hold only timings or logs."""
    suffix = path.suffix.lower()
    if suffix == ".json":
        doc = _strip_timings(json.loads(path.read_text(encoding="utf-8")))
        return _digest(json.dumps(doc, sort_keys=True).encode())
    if suffix in {".png", ".gif"}:
        from PIL import Image, ImageSequence

        with Image.open(path) as im:
            frames = [np.asarray(f.convert("RGBA")) for f in ImageSequence.Iterator(im)]
        return _digest(b"".join(f.tobytes() for f in frames) + str(len(frames)).encode())
    if suffix in {".html", ".log", ".txt"}:
        return None  # report.html and logs embed timings and dates
    return _digest(path.read_bytes())


def _array_bytes(value: Any) -> bytes:
    arr = np.asarray(value)
    if arr.dtype == object:
        return repr(value).encode()
    return arr.tobytes() + str(arr.shape).encode() + str(arr.dtype).encode()


def _info_bytes(info: dict[str, Any]) -> bytes:
    parts = []
    for key in sorted(info):
        value = info[key]
        if isinstance(value, dict):
            parts.append(key.encode() + _info_bytes(value))
        elif isinstance(value, (int, float, bool, np.ndarray, np.generic, list, tuple)):
            parts.append(key.encode() + _array_bytes(value))
    return b"|".join(parts)


def rollout_digest(env_id: str, vector: bool, policy: str) -> str:
    """Digest of a seeded rollout of ``env_id`` (``policy``: ``zero`` or ``random``)."""
    import gymnasium as gym

    import motion_envs  # noqa: F401  (registers the ids)

    env: Any = (
        gym.make_vec(env_id, num_envs=4, vectorization_mode="vector_entry_point")
        if (vector)
        else gym.make(env_id)
    )
    h = hashlib.sha256()
    try:
        obs, info = env.reset(seed=7)
        h.update(_array_bytes(obs) + _info_bytes(info))
        space = env.action_space
        space.seed(11)
        for _ in range(ROLLOUT_STEPS):
            action = np.zeros(space.shape, space.dtype) if policy == "zero" else space.sample()
            obs, reward, terminated, truncated, info = env.step(action)
            h.update(_array_bytes(obs) + _array_bytes(reward))
            h.update(_array_bytes(terminated) + _array_bytes(truncated) + _info_bytes(info))
            if not vector and (terminated or truncated):
                obs, info = env.reset()
                h.update(_array_bytes(obs) + _info_bytes(info))
    finally:
        env.close()
    return h.hexdigest()


def has_native_vector(env_id: str) -> bool:
    import gymnasium as gym

    import motion_envs  # noqa: F401

    return gym.spec(env_id).vector_entry_point is not None


def snapshot(out: Path, skip_bench: bool, reuse: bool = False) -> dict[str, str]:
    import motion_envs

    manifest: dict[str, str] = {}
    if not skip_bench:
        results = out / "results"
        if not reuse:
            subprocess.run(
                [sys.executable, "-m", "baselines.cli", "all", "--out", str(results), *NO_BARS],
                check=True,
            )
        for path in sorted(results.rglob("*")):
            if path.is_file():
                digest = file_digest(path)
                if digest is not None:
                    manifest[f"bench/{path.relative_to(results).as_posix()}"] = digest
    for env_id in motion_envs.ENV_IDS:
        for policy in ("zero", "random"):
            for vector in (False, True) if has_native_vector(env_id) else (False,):
                key = f"rollout/{env_id}/{'vector' if vector else 'single'}/{policy}"
                try:
                    manifest[key] = rollout_digest(env_id, vector, policy)
                except Exception as exc:  # recorded, so that compare names it
                    manifest[key] = f"error: {type(exc).__name__}: {exc}"
    return manifest


def compare(before: dict[str, str], after: dict[str, str]) -> list[str]:
    """Lines naming every entry that differs or exists on one side only."""
    lines = []
    for key in sorted(set(before) | set(after)):
        if key not in after:
            lines.append(f"missing after: {key}")
        elif key not in before:
            lines.append(f"new after:     {key}")
        elif before[key] != after[key]:
            lines.append(f"differs:       {key}")
        if after.get(key, "").startswith("error:"):
            lines.append(f"  {after[key]}")
    return lines


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = parser.add_subparsers(dest="cmd", required=True)
    snap = sub.add_parser("snapshot", help="record a manifest of the outputs")
    snap.add_argument("--out", type=Path, required=True, help="folder for results + manifest")
    snap.add_argument("--skip-bench", action="store_true", help="rollouts only")
    snap.add_argument(
        "--reuse", action="store_true", help="hash the results already in --out (no new run)"
    )
    cmp_ = sub.add_parser("compare", help="compare two snapshot folders")
    cmp_.add_argument("before", type=Path)
    cmp_.add_argument("after", type=Path)
    args = parser.parse_args(argv)
    if args.cmd == "snapshot":
        args.out.mkdir(parents=True, exist_ok=True)
        manifest = snapshot(args.out, args.skip_bench, args.reuse)
        (args.out / "manifest.json").write_text(json.dumps(manifest, indent=1, sort_keys=True))
        print(f"{len(manifest)} entries -> {args.out / 'manifest.json'}")
        return 0
    before = json.loads((args.before / "manifest.json").read_text())
    after = json.loads((args.after / "manifest.json").read_text())
    lines = compare(before, after)
    print("\n".join(lines) if lines else f"identical: {len(before)} entries")
    return 1 if lines else 0


if __name__ == "__main__":
    sys.exit(main())
