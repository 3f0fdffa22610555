"""The whole of Faraway & Choe's Table 1 on the real ``vr-kitchen`` data: how long it takes.

Issue 2, item 8. Times :func:`motion_envs.models.criteria.table1` on ``vr-kitchen``
(default ``--min-deg``, as ``motion-bench orientation`` runs it):

* **import**: a fresh interpreter importing numpy, scipy and pandas, and one importing
  ``motion_envs.models.criteria`` and ``motion_envs.datasets`` (which pull those in);
* **load**: reading the CSV files and packing/validating the trajectories (``.ragged``);
* **table1**: every criterion (26 rows, incl. the leave-one-out rows), load excluded;
* **load + table1**: both, as a user pays them (import excluded);
* the stages of ``table1``: empirical residuals, average speed profile, residuals
  against it, and everything else (Bézier fits, models, leave-one-out rows);
* anchor, same run: ``table1`` with the quaternion functions swapped for their
  whole-array textbook forms (the implementation before the block-wise fast paths),
  whose criteria must equal ours to 1e-12.

Target: Table 1 under 1 s. Prints a table, then, as its last line, one JSON object.

    python benchmarks/table1_vr_kitchen.py [--repeats 7]
"""

from __future__ import annotations

import argparse
import contextlib
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import plain_numpy_quaternion as plain
from _timing import best_time, machine, print_json, print_machine, print_table

from motion_envs.datasets import load_orientation_dataset
from motion_envs.datasets.vr_kitchen import DEFAULT_MIN_DEG
from motion_envs.geometry import quaternion as quat
from motion_envs.models.criteria import table1
from motion_envs.models.slerp_residual import slerp_residuals
from motion_envs.models.speed_profile import average_speed_profile

TARGET_S = 1.0
IMPORTS = {
    "numpy + scipy + pandas": "import numpy, scipy.spatial.transform, scipy.special, pandas",
    "motion_envs (criteria + datasets)": "import motion_envs.models.criteria, motion_envs.datasets",
}


def import_seconds(statement: str, repeats: int) -> float:
    """Best wall time of ``statement`` in a fresh interpreter (disk cache warm)."""
    code = f"import time; t = time.perf_counter(); {statement}; print(time.perf_counter() - t)"
    best = float("inf")
    for _ in range(repeats):
        out = subprocess.run(
            [sys.executable, "-c", code], capture_output=True, text=True, check=True
        )
        best = min(best, float(out.stdout.strip().splitlines()[-1]))
    return best


@contextlib.contextmanager
def whole_array_quaternions() -> Iterator[None]:
    """Temporarily route slerp/multiply/logmap/expmap to their whole-array forms."""

    def slerp(q0, q1, alpha, validate=True):
        if validate:
            q0, q1 = quat.as_unit(q0, "q0"), quat.as_unit(q1, "q1")
        f = np.float64
        return plain.slerp(np.asarray(q0, f), np.asarray(q1, f), np.asarray(alpha, f))

    def multiply(p, q):
        return plain.multiply(np.asarray(p, np.float64), np.asarray(q, np.float64))

    def logmap(q, name="q", validate=True):
        return plain.logmap(quat.as_unit(q, name) if validate else np.asarray(q))

    def expmap(v, name="v"):
        return plain.expmap(np.asarray(v, np.float64))

    saved = {k: getattr(quat, k) for k in ("slerp", "multiply", "logmap", "expmap")}
    for k, fn in {"slerp": slerp, "multiply": multiply, "logmap": logmap, "expmap": expmap}.items():
        setattr(quat, k, fn)
    try:
        yield
    finally:
        for k, fn in saved.items():
            setattr(quat, k, fn)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--import-repeats", type=int, default=3)
    parser.add_argument("--min-deg", type=float, default=DEFAULT_MIN_DEG)
    args = parser.parse_args(argv)

    info = machine()
    print_machine(info)

    def load():
        ds = load_orientation_dataset("vr-kitchen", min_deg=args.min_deg)
        return ds, ds.ragged

    ds, traj = load()
    L = traj.n_trajectories
    n_samples = int(traj.quaternions.shape[0])
    print(
        f"vr-kitchen, min_deg {args.min_deg:g}: {L} trajectories, {n_samples:,} samples, "
        f"{np.unique(ds.subjects).size} subjects, {np.unique(ds.tasks).size} tasks; best of "
        f"{args.repeats} runs"
    )

    def run_table1():
        return table1(traj, ds.subjects, ds.tasks)

    def load_and_table1():
        d, t = load()
        return table1(t, d.subjects, d.tasks)

    ours = run_table1()
    with whole_array_quaternions():
        before = run_table1()
        before_s = best_time(run_table1, args.repeats)
    diff = max(
        abs(ours.criteria[k] - before.criteria[k])
        for k in ours.criteria
        if np.isfinite(ours.criteria[k])
    )
    if not diff <= 1e-12:
        raise AssertionError(f"criteria differ from the whole-array forms by {diff:.3g}")

    seconds = {
        "load (read CSV + pack)": best_time(load, args.repeats),
        "table1 (load excluded)": best_time(run_table1, args.repeats, warmup=1),
        "load + table1": best_time(load_and_table1, args.repeats),
        "table1, whole-array quaternions": before_s,
    }
    abar = average_speed_profile(traj)
    stages = {
        "  stage: empirical residuals": best_time(lambda: slerp_residuals(traj), args.repeats),
        "  stage: average speed profile": best_time(
            lambda: average_speed_profile(traj), args.repeats
        ),
        "  stage: residuals vs average profile": best_time(
            lambda: slerp_residuals(traj, average_alpha=abar), args.repeats
        ),
    }
    stages["  stage: the rest (fits, models, leave-one-out)"] = seconds[
        "table1 (load excluded)"
    ] - sum(stages.values())
    imports = {name: import_seconds(stmt, args.import_repeats) for name, stmt in IMPORTS.items()}

    table1_s = seconds["table1 (load excluded)"]
    rows = [[f"import: {k}", v * 1e3, float("nan")] for k, v in imports.items()]
    rows += [[k, v * 1e3, v / table1_s] for k, v in seconds.items()]
    rows += [[k, v * 1e3, v / table1_s] for k, v in stages.items()]
    print(f"criteria equal the whole-array forms' to {diff:.1e}")
    print()
    print_table(["what", "ms", "time / table1"], rows)
    met = {
        "table1_load_excluded_under_1s": table1_s < TARGET_S,
        "table1_load_included_under_1s": seconds["load + table1"] < TARGET_S,
    }
    print()
    print(
        f"target: Table 1 under {TARGET_S:g} s: {table1_s:.3f} s load excluded "
        f"({'met' if met['table1_load_excluded_under_1s'] else 'MISSED'}), "
        f"{seconds['load + table1']:.3f} s load included "
        f"({'met' if met['table1_load_included_under_1s'] else 'MISSED'}); import "
        f"{imports['motion_envs (criteria + datasets)']:.2f} s on top"
    )
    print_json(
        {
            "benchmark": "table1_vr_kitchen",
            "min_deg": args.min_deg,
            "n_trajectories": L,
            "n_samples": n_samples,
            "repeats": args.repeats,
            "machine": info,
            "seconds": {k.strip(): v for k, v in (seconds | stages).items()},
            "import_seconds": imports,
            "ratios": {
                "whole_array_over_ours": before_s / table1_s,
                "load_included_over_excluded": seconds["load + table1"] / table1_s,
            },
            "max_abs_diff_vs_whole_array": diff,
            "target_s": TARGET_S,
            "targets_met": met,
        }
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
