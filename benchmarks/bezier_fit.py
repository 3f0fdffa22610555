"""Least-squares Bézier fit of 1,088 x 50 x 3 residual curves: one shared pseudo-inverse.

Issue 2, item 8. Faraway & Choe fit the interior control points of every slerp residual
curve (1,088 reaches, 50 grid points, 3 tangent coordinates) by least squares. All curves
share the grid, so one ``pinv(B)`` serves them all (:func:`motion_envs.geometry.bezier.fit`).
For degrees 2, 3 and 4 this times, on the same seeded curves (smooth Bézier curves plus
noise, the size of the paper's data):

* ``bezier.fit``: the public call (validation, ``pinv`` of the 50 x (d-1) design, apply);
* ``fit_control_points``: what :func:`motion_envs.models.criteria.table1` calls;
* ``fit_operator``: the ``pinv`` alone;
* applying a precomputed ``pinv`` with ``einsum`` (the first implementation) and with
  ``matmul`` (what ``fit`` does);
* anchors: one ``numpy.linalg.lstsq`` with all 3,264 right-hand sides, and a loop of
  ``lstsq`` per curve (the naive way).

Every method's control points are checked against ``lstsq`` before timing. Target: the
fit under 0.5 ms. Prints a table, then, as its last line, one JSON object.

    python benchmarks/bezier_fit.py [--curves 1088] [--points 50] [--repeats 200]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _timing import best_time, machine, print_json, print_machine, print_table

from motion_envs.geometry import bezier
from motion_envs.models.bezier_models import fit_control_points
from motion_envs.models.slerp_residual import normalised_grid

DEGREES = (2, 3, 4)
TARGET_MS = 0.5
TOLERANCE = 1e-10


def make_curves(n_curves: int, n_points: int, seed: int) -> np.ndarray:
    """Degree-4 Bézier curves (ends at 0, control points ~ N(0, 0.1^2)) plus N(0, 0.01^2)."""
    rng = np.random.default_rng(seed)
    grid = normalised_grid(n_points)
    P = rng.normal(scale=0.1, size=(n_curves, 3, 3))
    return bezier.evaluate(P, grid, 4) + rng.normal(scale=0.01, size=(n_curves, n_points, 3))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--curves", type=int, default=1088)
    parser.add_argument("--points", type=int, default=50)
    parser.add_argument("--repeats", type=int, default=200, help="runs of each fast call")
    parser.add_argument("--loop-repeats", type=int, default=5, help="runs of the lstsq loop")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)

    info = machine()
    print_machine(info)
    Z = make_curves(args.curves, args.points, args.seed)
    grid = normalised_grid(args.points)
    L, n, c = Z.shape
    print(
        f"{L} curves x {n} points x {c} coordinates, seed {args.seed}; best of "
        f"{args.repeats} runs (lstsq loop: {args.loop_repeats})"
    )

    rows: list[list[Any]] = []
    figures: dict[str, dict[str, float]] = {}
    checks: dict[str, float] = {}
    for d in DEGREES:
        B = bezier.bernstein_interior(grid, d)
        op = bezier.fit_operator(grid, d)
        rhs = Z.transpose(1, 0, 2).reshape(n, L * c)

        def lstsq_all(B=B, rhs=rhs, d=d) -> np.ndarray:
            sol = np.linalg.lstsq(B, rhs, rcond=None)[0]
            return sol.reshape(d - 1, L, c).transpose(1, 0, 2)

        def lstsq_loop(B=B) -> np.ndarray:
            return np.stack([np.linalg.lstsq(B, z, rcond=None)[0] for z in Z])

        methods = {
            "bezier.fit": lambda d=d: bezier.fit(Z, grid, d),
            "fit_control_points": lambda d=d: fit_control_points(Z, d),
            "apply pinv (einsum)": lambda op=op: np.einsum("kn,...nc->...kc", op, Z),
            "apply pinv (matmul)": lambda op=op: np.matmul(op, Z),
            "lstsq, all curves": lstsq_all,
            "lstsq loop per curve": lstsq_loop,
        }
        reference = lstsq_all()
        for name, fn in methods.items():
            err = float(np.abs(fn() - reference).max())
            if not err <= TOLERANCE:
                raise AssertionError(f"d={d} {name}: differs from lstsq by {err:.3g}")
            checks[f"d{d} {name}"] = err
        figures[f"d{d}"] = {}
        for name, fn in [*methods.items(), ("fit_operator (pinv only)", None)]:
            if fn is None:
                fn = lambda d=d: bezier.fit_operator(grid, d)  # noqa: E731
            repeats = args.loop_repeats if "loop" in name else args.repeats
            ms = best_time(fn, repeats, warmup=1) * 1e3
            figures[f"d{d}"][name] = ms
        fit_ms = figures[f"d{d}"]["bezier.fit"]
        for name, ms in figures[f"d{d}"].items():
            rows.append([f"d={d}", name, ms, fit_ms and ms / fit_ms])
    print(f"checked against lstsq: max |difference| {max(checks.values()):.2e}")
    print()
    print_table(["degree", "method", "ms", "time / bezier.fit"], rows)
    fit_ms = {d: figures[f"d{d}"]["bezier.fit"] for d in DEGREES}
    met = all(v < TARGET_MS for v in fit_ms.values())
    print()
    print(
        "target: bezier.fit under 0.5 ms: "
        + ", ".join(f"d={d} {ms:.3f} ms" for d, ms in fit_ms.items())
        + (" (met)" if met else " (MISSED)")
    )
    ratios = {
        f"d{d}_lstsq_all_over_fit": figures[f"d{d}"]["lstsq, all curves"] / fit_ms[d]
        for d in DEGREES
    }
    ratios |= {
        f"d{d}_lstsq_loop_over_fit": figures[f"d{d}"]["lstsq loop per curve"] / fit_ms[d]
        for d in DEGREES
    }
    ratios |= {
        f"d{d}_einsum_over_matmul": figures[f"d{d}"]["apply pinv (einsum)"]
        / figures[f"d{d}"]["apply pinv (matmul)"]
        for d in DEGREES
    }
    print_json(
        {
            "benchmark": "bezier_fit",
            "shape": [L, n, c],
            "seed": args.seed,
            "repeats": args.repeats,
            "machine": info,
            "max_abs_diff_vs_lstsq": max(checks.values()),
            "figures_ms": figures,
            "ratios": ratios,
            "target_ms": TARGET_MS,
            "target_met": met,
        }
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
