"""Fit and generation time of the sine-series model vs DMP and ProMP, same process, LASA.

For each shape, all 7 demonstrations are resampled to ``--n-points`` samples of
normalised time; each method is fitted on them ``--repeats`` times and generates one
trajectory (start and goal of demonstration 0) ``--repeats`` times. We report the median
time per call over repeats, then the median across shapes, and the ratios peer / sine
series. The sine-series fit uses a fixed ``--n-sines``; the cross-validated choice of
``N`` (leave-one-out over candidates 0..15) is timed separately.

Prints a table, then, as its last line, one JSON object with the figures and ratios.

    python benchmarks/position_timing.py [--shapes Angle Sine ...] [--repeats 5]
"""

from __future__ import annotations

import argparse
import json
import platform
import statistics
import sys
import time
from collections.abc import Callable
from datetime import datetime, timezone

import numpy as np
from _timing import cpu_model  # benchmarks/ is on sys.path when run as a script

from baselines.peers import DMPPeer, ProMPPeer, peers_missing_reason
from motion_envs.datasets.lasa import load_lasa
from motion_envs.datasets.resampling import resample_positions
from motion_envs.geometry import sine_series as ss
from motion_envs.models.sine_regression import SineSeriesRegression, select_n_sines


def _median_time(fn: Callable[[], object], repeats: int) -> float:
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--shapes", nargs="+", default=["Angle", "CShape", "GShape", "Sine", "Worm"]
    )
    parser.add_argument("--n-points", type=int, default=200)
    parser.add_argument("--n-sines", type=int, default=10)
    parser.add_argument("--n-weights", type=int, default=10)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args(argv)

    missing = peers_missing_reason()
    if missing:
        print(f"movement_primitives cannot be used ({missing}); timing the sine series only",
              file=sys.stderr)  # fmt: skip
    ds = load_lasa(args.shapes)
    y_all, _ = resample_positions(ds, args.n_points)
    per: dict[str, dict[str, list[float]]] = {}

    def record(method: str, what: str, seconds: float) -> None:
        per.setdefault(method, {}).setdefault(what, []).append(seconds)

    tau = np.linspace(0.0, 1.0, args.n_points)
    for shape in args.shapes:
        y = y_all[ds.tasks == shape]
        q = y[:, 0]  # conditions: start (LASA ends are all at the origin)
        start, goal = y[0, 0], y[0, -1]
        model = SineSeriesRegression(args.n_sines).fit(q, list(y), times="normalised")
        record("lippi", "fit", _median_time(lambda y=y, q=q: SineSeriesRegression(
            args.n_sines).fit(q, list(y), times="normalised"), args.repeats))  # fmt: skip
        record("lippi", "generate", _median_time(
            lambda m=model, s=start, g=goal: ss.evaluate(m.predict_coefficients(s, s, g), tau),
            args.repeats))  # fmt: skip
        record("lippi", "cv", _median_time(
            lambda y=y, q=q: select_n_sines(
                list(y), q, candidates=range(16), times="normalised"), 1))  # fmt: skip
        if missing:
            continue
        for name, cls in (("dmp", DMPPeer), ("promp", ProMPPeer)):
            peer = cls(args.n_weights).fit(y)
            record(name, "fit", _median_time(lambda c=cls, y=y: c(args.n_weights).fit(y),
                                             args.repeats))  # fmt: skip
            record(name, "generate", _median_time(lambda p=peer, s=start, g=goal: p.predict(s, g),
                                                  args.repeats))  # fmt: skip

    ms = {m: {w: 1e3 * statistics.median(v) for w, v in d.items()} for m, d in per.items()}
    ratios = {
        f"{m}_{w}_over_lippi": ms[m][w] / ms["lippi"][w]
        for m in ("dmp", "promp")
        if m in ms
        for w in ("fit", "generate")
    }
    print(f"fit on 7 demos / generate one trajectory, {args.n_points} points, "
          f"median over {args.repeats} repeats and {len(args.shapes)} shapes (ms)")  # fmt: skip
    print(f"{'method':<8}{'fit':>12}{'generate':>12}")
    for m, d in ms.items():
        print(f"{m:<8}{d['fit']:12.3f}{d['generate']:12.3f}")
    print(f"lippi N by leave-one-out CV over 0..15: {ms['lippi']['cv']:.1f} ms per shape")
    for k, v in ratios.items():
        print(f"{k:<28} x{v:.1f}")
    doc = {
        "benchmark": "position_timing",
        "date": datetime.now(timezone.utc).strftime("%Y-%m-%d"),
        "machine": {"cpu": cpu_model(), "python": platform.python_version()},
        "shapes": args.shapes,
        "n_points": args.n_points,
        "n_sines": args.n_sines,
        "n_weights_per_dim": args.n_weights,
        "repeats": args.repeats,
        "ms": ms,
        "ratios": ratios,
        "peers": missing is None,
    }
    print(json.dumps(doc))
    return 0


if __name__ == "__main__":
    sys.exit(main())
