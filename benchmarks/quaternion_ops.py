"""Batched slerp, multiply, log and exp of millions of quaternions: ours vs scipy vs numpy.

Issue 2, item 8. On the same seeded inputs (``--n`` unit quaternions, default 5 million):

* **ours**: :mod:`motion_envs.geometry.quaternion` (block-wise fast paths), with
  ``validate=False`` where the function has it, and separately the validated call;
* **plain numpy**: the whole-array textbook form of the same formula (the module's
  functions of ``plain_numpy_quaternion.py``, which were the implementation before the fast paths);
* **scipy**: ``scipy.spatial.transform.Rotation``, array in, array out (the ``from_quat``
  / ``as_quat`` conversions are part of the job, since our functions take and return
  arrays): pairwise slerp ``r0 * Rotation.from_rotvec((r0.inv() * r1).as_rotvec() *
  alpha)``, multiply ``r0 * r1``, log ``from_quat(q).as_rotvec()``, exp
  ``from_rotvec(v).as_quat()``. scipy's ``Slerp`` class interpolates ONE key sequence, so
  it is timed on its natural jobs instead: one key pair at ``n`` times, and a sequence of
  1,000 keys at ``n`` times, each against ours doing the same job;
* **copy floor**: ``np.copyto(dst, src)`` of an ``(n, 4)`` float64 array, the bytes of one
  output; no elementwise kernel that writes its output can beat it.

Every output is checked against scipy (equal up to the quaternion sign) before timing.
Each figure is the best of ``--repeats`` runs (``--scipy-repeats`` for the slow scipy
calls). Prints a table, then, as its last line, one JSON object with the figures (M
quaternions per second) and the ratios.

    python benchmarks/quaternion_ops.py [--n 5000000] [--repeats 5] [--scipy-repeats 2]
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation, Slerp

sys.path.insert(0, str(Path(__file__).resolve().parent))

import plain_numpy_quaternion as plain
from _timing import best_time, machine, print_json, print_machine, print_table

from motion_envs.geometry import quaternion as quat

CHECK_N = 200_000  # quaternions compared with scipy before timing
TOLERANCE = 1e-9


def _unit(rng: np.random.Generator, n: int) -> np.ndarray:
    q = rng.normal(size=(n, 4))
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def _xyzw(q: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(q[..., [1, 2, 3, 0]])


def _wxyz(q: np.ndarray) -> np.ndarray:
    return q[..., [3, 0, 1, 2]]


def _max_diff_up_to_sign(a: np.ndarray, b: np.ndarray) -> float:
    plus = np.abs(a - b).max(axis=-1)
    minus = np.abs(a + b).max(axis=-1)
    return float(np.minimum(plus, minus).max())


# scipy, array in and array out (scalar-first in and out, like ours)
def scipy_slerp(q0: np.ndarray, q1: np.ndarray, alpha: np.ndarray) -> np.ndarray:
    r0 = Rotation.from_quat(_xyzw(q0))
    r1 = Rotation.from_quat(_xyzw(q1))
    step = Rotation.from_rotvec((r0.inv() * r1).as_rotvec() * alpha[:, None])
    return _wxyz((r0 * step).as_quat())


def scipy_multiply(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    return _wxyz((Rotation.from_quat(_xyzw(p)) * Rotation.from_quat(_xyzw(q))).as_quat())


def scipy_logmap(q: np.ndarray) -> np.ndarray:
    return Rotation.from_quat(_xyzw(q)).as_rotvec()


def scipy_expmap(v: np.ndarray) -> np.ndarray:
    return _wxyz(Rotation.from_rotvec(v).as_quat())


def _check(name: str, ours: np.ndarray, ref: np.ndarray, up_to_sign: bool) -> float:
    err = _max_diff_up_to_sign(ours, ref) if up_to_sign else float(np.abs(ours - ref).max())
    if not err <= TOLERANCE:
        raise AssertionError(f"{name}: ours differs from scipy by {err:.3g} > {TOLERANCE:g}")
    return err


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=5_000_000, help="quaternions per batch")
    parser.add_argument("--repeats", type=int, default=5, help="runs of ours/numpy/copy")
    parser.add_argument("--scipy-repeats", type=int, default=2, help="runs of scipy calls")
    parser.add_argument("--keys", type=int, default=1000, help="keys of the Slerp sequence")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    if args.n < CHECK_N:
        parser.error(f"--n must be >= {CHECK_N}")

    info = machine()
    print_machine(info)
    rng = np.random.default_rng(args.seed)
    n = args.n
    q0 = _unit(rng, n)
    q1 = _unit(rng, n)
    alpha = rng.random(n)
    v = quat.logmap(_unit(rng, n))  # rotation vectors with angle in [0, pi]
    keys = quat.make_continuous(_unit(rng, args.keys))
    key_times = np.linspace(0.0, 1.0, args.keys)
    print(
        f"n = {n:,} quaternions, seed {args.seed}; best of {args.repeats} (scipy: "
        f"{args.scipy_repeats}); M q/s = million quaternions per second"
    )

    # --- correctness against scipy, before any timing -------------------------------
    c = slice(0, CHECK_N)
    checks = {
        "slerp": _check(
            "slerp",
            quat.slerp(q0[c], q1[c], alpha[c], validate=False),
            scipy_slerp(q0[c], q1[c], alpha[c]),
            up_to_sign=True,
        ),
        "multiply": _check(
            "multiply", quat.multiply(q0[c], q1[c]), scipy_multiply(q0[c], q1[c]), up_to_sign=True
        ),
        "logmap": _check(
            "logmap", quat.logmap(q0[c], validate=False), scipy_logmap(q0[c]), up_to_sign=False
        ),
        "expmap": _check("expmap", quat.expmap(v[c]), scipy_expmap(v[c]), up_to_sign=True),
    }
    one_pair = Slerp([0.0, 1.0], Rotation.from_quat(_xyzw(keys[:2])))
    checks["slerp_one_pair"] = _check(
        "slerp one pair",
        quat.slerp(keys[0], keys[1], alpha[c], validate=False),
        _wxyz(one_pair(alpha[c]).as_quat()),
        up_to_sign=True,
    )
    sequence = Slerp(key_times, Rotation.from_quat(_xyzw(keys)))

    def ours_sequence(t: np.ndarray) -> np.ndarray:
        j1 = np.clip(np.searchsorted(key_times, t, side="right"), 1, key_times.size - 1)
        j0 = j1 - 1
        frac = (t - key_times[j0]) / (key_times[j1] - key_times[j0])
        return quat.slerp(keys[j0], keys[j1], frac, validate=False)

    checks["slerp_key_sequence"] = _check(
        "slerp key sequence",
        ours_sequence(alpha[c]),
        _wxyz(sequence(alpha[c]).as_quat()),
        up_to_sign=True,
    )
    for k, err in checks.items():
        print(f"check vs scipy, {k}: max |difference| {err:.2e} (up to sign)")

    # --- timing -----------------------------------------------------------------
    dst = np.empty_like(q0)
    copy_s = best_time(lambda: np.copyto(dst, q0), max(args.repeats, 7), warmup=1)
    # Two further floors for slerp, same arrays: the memory traffic of reading two (n, 4)
    # inputs and writing one, and numpy's transcendental functions the formula needs
    # (one arctan2 and two tan per pair), on contiguous preallocated arrays.
    alloc_copy_s = best_time(q0.copy, max(args.repeats, 7), warmup=1)
    floor_add_s = best_time(lambda: np.add(q0, q1, out=dst), max(args.repeats, 7), warmup=1)
    x1, x2 = np.ascontiguousarray(q0[:, 1]), np.ascontiguousarray(q0[:, 0])
    xx, o1, o2 = np.stack([alpha, 1.0 - alpha]), np.empty(n), np.empty((2, n))

    def transcendentals() -> None:
        np.arctan2(x1, x2, out=o1)
        np.tan(xx, out=o2)

    floor_trig_s = best_time(transcendentals, max(args.repeats, 7), warmup=1)
    jobs: dict[str, dict[str, tuple[Callable[[], Any], int]]] = {
        "slerp": {
            "ours": (lambda: quat.slerp(q0, q1, alpha, validate=False), args.repeats),
            "ours_validated": (lambda: quat.slerp(q0, q1, alpha), args.repeats),
            "plain_numpy": (lambda: plain.slerp(q0, q1, alpha), args.repeats),
            "scipy": (lambda: scipy_slerp(q0, q1, alpha), args.scipy_repeats),
        },
        "multiply": {
            "ours": (lambda: quat.multiply(q0, q1), args.repeats),
            "plain_numpy": (lambda: plain.multiply(q0, q1), args.repeats),
            "scipy": (lambda: scipy_multiply(q0, q1), args.scipy_repeats),
        },
        "logmap": {
            "ours": (lambda: quat.logmap(q0, validate=False), args.repeats),
            "ours_validated": (lambda: quat.logmap(q0), args.repeats),
            "plain_numpy": (lambda: plain.logmap(q0), args.repeats),
            "scipy": (lambda: scipy_logmap(q0), args.scipy_repeats),
        },
        "expmap": {
            "ours": (lambda: quat.expmap(v), args.repeats),
            "plain_numpy": (lambda: plain.expmap(v), args.repeats),
            "scipy": (lambda: scipy_expmap(v), args.scipy_repeats),
        },
        "slerp_one_pair": {
            "ours": (lambda: quat.slerp(keys[0], keys[1], alpha, validate=False), args.repeats),
            "scipy_Slerp": (lambda: one_pair(alpha).as_quat(), args.scipy_repeats),
        },
        "slerp_key_sequence": {
            "ours": (lambda: ours_sequence(alpha), args.repeats),
            "scipy_Slerp": (lambda: sequence(alpha).as_quat(), args.scipy_repeats),
        },
    }
    seconds: dict[str, dict[str, float]] = {}
    for op, impls in jobs.items():
        seconds[op] = {}
        for impl, (fn, repeats) in impls.items():
            seconds[op][impl] = best_time(fn, repeats, warmup=1 if impl.startswith("ours") else 0)
            print(f"  timed {op:<20} {impl:<16} {seconds[op][impl] * 1e3:9.1f} ms", file=sys.stderr)

    def mqs(s: float) -> float:
        return n / s / 1e6

    rows = [["copy floor (np.copyto)", "copy", copy_s * 1e3, mqs(copy_s), float("nan"), 1.0]]
    rows.append(
        [
            "copy into a new array (q0.copy())",
            "copy+alloc",
            alloc_copy_s * 1e3,
            mqs(alloc_copy_s),
            float("nan"),
            alloc_copy_s / copy_s,
        ]
    )
    rows.append(
        [
            "slerp memory floor (np.add)",
            "add",
            floor_add_s * 1e3,
            mqs(floor_add_s),
            float("nan"),
            floor_add_s / copy_s,
        ]
    )
    rows.append(
        [
            "slerp trig floor (arctan2+2 tan)",
            "trig",
            floor_trig_s * 1e3,
            mqs(floor_trig_s),
            float("nan"),
            floor_trig_s / copy_s,
        ]
    )
    figures: dict[str, Any] = {
        "copy_floor": {"ms": copy_s * 1e3, "mq_per_s": mqs(copy_s)},
        "copy_with_allocation": {"ms": alloc_copy_s * 1e3, "mq_per_s": mqs(alloc_copy_s)},
        "slerp_memory_floor_add": {"ms": floor_add_s * 1e3, "mq_per_s": mqs(floor_add_s)},
        "slerp_trig_floor": {"ms": floor_trig_s * 1e3, "mq_per_s": mqs(floor_trig_s)},
    }
    ratios: dict[str, float] = {}
    for op, impl_s in seconds.items():
        anchor = impl_s.get("scipy", impl_s.get("scipy_Slerp"))
        figures[op] = {}
        for impl, s in impl_s.items():
            vs_scipy = anchor / s
            vs_copy = s / copy_s
            rows.append([op, impl, s * 1e3, mqs(s), vs_scipy, vs_copy])
            figures[op][impl] = {"ms": s * 1e3, "mq_per_s": mqs(s)}
        ours = impl_s["ours"]
        ratios[f"{op}_speedup_vs_scipy"] = anchor / ours
        ratios[f"{op}_times_copy_floor"] = ours / copy_s
        if "plain_numpy" in impl_s:
            ratios[f"{op}_speedup_vs_plain_numpy"] = impl_s["plain_numpy"] / ours
        if "ours_validated" in impl_s:
            ratios[f"{op}_validation_overhead"] = impl_s["ours_validated"] / ours
    print()
    print_table(
        ["operation", "implementation", "ms", "M q/s", "x faster than scipy", "x copy time"],
        rows,
    )
    targets = {
        "slerp_at_least_5x_scipy": ratios["slerp_speedup_vs_scipy"] >= 5.0,
        "slerp_within_10x_copy_floor": ratios["slerp_times_copy_floor"] <= 10.0,
    }
    print()
    print(
        f"targets: slerp >= 5x scipy: {ratios['slerp_speedup_vs_scipy']:.1f}x "
        f"({'met' if targets['slerp_at_least_5x_scipy'] else 'MISSED'}); slerp within 10x of "
        f"the copy floor: {ratios['slerp_times_copy_floor']:.1f}x "
        f"({'met' if targets['slerp_within_10x_copy_floor'] else 'MISSED'})"
    )
    print_json(
        {
            "benchmark": "quaternion_ops",
            "n": n,
            "seed": args.seed,
            "repeats": args.repeats,
            "scipy_repeats": args.scipy_repeats,
            "machine": info,
            "checks_max_abs_diff_vs_scipy": checks,
            "figures": figures,
            "ratios": ratios,
            "targets_met": targets,
        }
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
