"""Virtual cohort scaling: generate and score 1,000 .. 100,000 simulated trajectories.

For each size the cohort ``faraway2008`` is enlarged by adding subjects (same design:
35 tasks x push/pull, 22.3 % lost, so about 54 trajectories per subject) and

* ``generate``: streamed generation in chunks of ``--chunk-subjects`` subjects
  (:func:`motion_envs.datasets.cohort.iter_cohort`), each chunk discarded;
* ``score``: streamed generation + Table 1's in-sample rows for d = 2, 3, 4
  (:func:`motion_envs.models.criteria.score_cohort`: two passes, running sums);
* ``cpu us/tr``: CPU time of this process per trajectory for ``score`` (less sensitive
  than wall time to other jobs on the machine);
* ``peak MB``: peak memory traced by ``tracemalloc`` (numpy arrays included) during a
  separate ``score`` run;
* anchor (sizes up to ``--anchor-max``): the in-memory path, ``generate_cohort`` + the
  lead's ``table1`` (which adds the leave-one-out rows), with its traced peak and the
  largest difference between the two on the rows both compute.

Per-trajectory time should stay flat with size and the streamed peak should not grow
with the number of samples (only O(L) floats for the medians). Prints a table and, as
the last line, one JSON object with the figures.

    python benchmarks/cohort_scaling.py                  # 1e3, 1e4, 1e5
    python benchmarks/cohort_scaling.py --sizes 1000 5000 --anchor-max 5000
"""

from __future__ import annotations

import argparse
import json
import math
import platform
import time
import tracemalloc

from motion_envs.datasets.cohort import generate_cohort, iter_cohort
from motion_envs.datasets.cohort_config import load_cohort_config
from motion_envs.models.criteria import score_cohort, table1


def _config(n_trajectories: int):
    base = load_cohort_config("faraway2008")
    des = base.data["design"]
    per_subject = len(des["requested_tasks"]) * len(des["replicates"]) * (1 - des["dropout"])
    n_sub = max(2, math.ceil(n_trajectories / per_subject))
    return base.with_values(**{"design.n_subjects": n_sub})


def _timed(fn):
    """``(result, wall seconds, CPU seconds of this process)``."""
    t0, c0 = time.perf_counter(), time.process_time()
    out = fn()
    return out, time.perf_counter() - t0, time.process_time() - c0


def _peak_mb(fn) -> tuple[object, float]:
    tracemalloc.start()
    tracemalloc.reset_peak()
    try:
        out = fn()
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    return out, peak / 2**20


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[1000, 10000, 100000])
    parser.add_argument("--chunk-subjects", type=int, default=64)
    parser.add_argument("--anchor-max", type=int, default=10000)
    parser.add_argument("--no-memory", action="store_true", help="skip the tracemalloc runs")
    args = parser.parse_args()

    rows = []
    for size in args.sizes:
        cfg = _config(size)
        chunk = args.chunk_subjects

        def gen_only(cfg=cfg, chunk=chunk):
            n = samples = 0
            for ds in iter_cohort(cfg, chunk_subjects=chunk):
                n += len(ds)
                samples += sum(q.shape[0] for q in ds.quaternions)
            return n, samples

        (n, samples), t_gen, c_gen = _timed(gen_only)
        scores, t_score, c_score = _timed(lambda cfg=cfg, chunk=chunk: score_cohort(cfg, chunk))
        row = {
            "trajectories": n,
            "subjects": int(cfg.get("design.n_subjects")),
            "samples": samples,
            "generate_s": t_gen,
            "score_s": t_score,
            "generate_us_per_traj": 1e6 * t_gen / n,
            "score_us_per_traj": 1e6 * t_score / n,
            "generate_cpu_us_per_traj": 1e6 * c_gen / n,
            "score_cpu_us_per_traj": 1e6 * c_score / n,
            "null_d2": scores["null_d2"],
            "within_subject": scores["within_subject"],
        }
        if not args.no_memory:
            _, row["score_peak_mb"] = _peak_mb(
                lambda cfg=cfg, chunk=chunk: score_cohort(cfg, chunk)
            )
        if n <= args.anchor_max:

            def anchor(cfg=cfg):
                ds = generate_cohort(cfg)
                return table1(ds.ragged, ds.subjects, ds.tasks).criteria

            full, t_anchor, _ = _timed(anchor)
            row["anchor_s"] = t_anchor
            row["anchor_us_per_traj"] = 1e6 * t_anchor / n
            row["max_abs_diff_vs_table1"] = max(
                abs(full[k] - scores[k]) for k in scores if k in full
            )
            if not args.no_memory:
                _, row["anchor_peak_mb"] = _peak_mb(anchor)
        rows.append(row)

    head = (
        f"{'trajectories':>12} {'subjects':>8} {'samples':>10} {'gen s':>7} {'gen us/tr':>9} "
        f"{'score s':>8} {'score us/tr':>11} {'cpu us/tr':>9} {'peak MB':>8} {'anchor s':>9} "
        f"{'anchor MB':>9} {'max |diff|':>10}"
    )
    print(
        "virtual cohort faraway2008, enlarged by subjects; streamed in chunks of "
        f"{args.chunk_subjects} subjects; anchor = generate_cohort + table1 in memory"
    )
    print(head)
    print("-" * len(head))
    for r in rows:

        def opt(key, fmt, r=r):
            return format(r[key], fmt) if key in r else "-"

        print(
            f"{r['trajectories']:>12,} {r['subjects']:>8} {r['samples']:>10,} "
            f"{r['generate_s']:>7.2f} {r['generate_us_per_traj']:>9.0f} {r['score_s']:>8.2f} "
            f"{r['score_us_per_traj']:>11.0f} {r['score_cpu_us_per_traj']:>9.0f} "
            f"{opt('score_peak_mb', '8.1f'):>8} "
            f"{opt('anchor_s', '9.2f'):>9} {opt('anchor_peak_mb', '9.1f'):>9} "
            f"{opt('max_abs_diff_vs_table1', '10.1e'):>10}"
        )
    first, last = rows[0], rows[-1]
    summary = {
        "benchmark": "cohort_scaling",
        "machine": platform.processor() or platform.machine(),
        "chunk_subjects": args.chunk_subjects,
        "rows": rows,
        "score_us_per_traj_ratio_last_vs_first": last["score_us_per_traj"]
        / first["score_us_per_traj"],
        "generate_us_per_traj_ratio_last_vs_first": last["generate_us_per_traj"]
        / first["generate_us_per_traj"],
        "score_cpu_us_per_traj_ratio_last_vs_first": last["score_cpu_us_per_traj"]
        / first["score_cpu_us_per_traj"],
    }
    print(json.dumps(summary))


if __name__ == "__main__":
    main()
