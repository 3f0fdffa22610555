"""Cost of the geometry input check: the quaternion functions now vs at an earlier commit.

Issue 8: ``expmap``, ``logmap``, ``conjugate`` and ``multiply`` reject NaN, infinite and
wrongly shaped input through one shared check. This script loads
``motion_envs/geometry/quaternion.py`` as it was at ``--before`` (``git show``) beside the
current module and times both in the same process, interleaved (best of
``--repeats``), on one quaternion (per-call overhead) and on ``--n`` quaternions. Prints
a table, then one JSON object with the figures and the after/before ratios.

    python benchmarks/quaternion_check_cost.py [--before 4771c98] [--n 1000000] [--repeats 7]
"""

from __future__ import annotations

import argparse
import importlib.util
import subprocess
import sys
import tempfile
import timeit
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _timing import machine, print_json, print_machine, print_table

from motion_envs.geometry import quaternion as current

ROOT = Path(__file__).resolve().parents[1]


def _module_at(rev: str, folder: Path) -> ModuleType:
    source = subprocess.run(
        ["git", "-C", str(ROOT), "show", f"{rev}:motion_envs/geometry/quaternion.py"],
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    path = folder / "quaternion_before.py"
    path.write_text(source)
    spec = importlib.util.spec_from_file_location("quaternion_before", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _jobs(p: np.ndarray, q: np.ndarray, v: np.ndarray) -> dict[str, Any]:
    return {
        "multiply": lambda m: m.multiply(p, q),
        "conjugate": lambda m: m.conjugate(q),
        "expmap": lambda m: m.expmap(v),
        "logmap": lambda m: m.logmap(q),
        "logmap(validate=False)": lambda m: m.logmap(q, validate=False),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--before", default="4771c98", help="git revision to compare with")
    parser.add_argument("--n", type=int, default=1_000_000, help="quaternions per batch")
    parser.add_argument("--repeats", type=int, default=7, help="interleaved runs (best taken)")
    args = parser.parse_args()
    info = machine()
    print_machine(info)
    with tempfile.TemporaryDirectory() as tmp:
        before = _module_at(args.before, Path(tmp))
        rng = np.random.default_rng(0)
        rows, figures = [], {}
        for n in (1, args.n):
            q = rng.normal(size=(n, 4))
            q /= np.linalg.norm(q, axis=1, keepdims=True)
            p = rng.normal(size=(n, 4))
            p /= np.linalg.norm(p, axis=1, keepdims=True)
            v = rng.normal(size=(n, 3))
            jobs = _jobs(p, q, v)
            number = 2000 if n == 1 else 1
            for name, job in jobs.items():
                best = {"before": float("inf"), "after": float("inf")}
                for _ in range(args.repeats):
                    for label, module in (("before", before), ("after", current)):
                        t = timeit.timeit(lambda: job(module), number=number) / number  # noqa: B023
                        best[label] = min(best[label], t)
                ratio = best["after"] / best["before"]
                rows.append(
                    [
                        name,
                        n,
                        f"{best['before'] * 1e6:.2f}",
                        f"{best['after'] * 1e6:.2f}",
                        f"{ratio:.3f}",
                    ]
                )
                figures[f"{name}@{n}"] = {**best, "after_over_before": ratio}
    print_table(["operation", "n", "before (us)", "after (us)", "after/before"], rows)
    print_json(
        {
            "benchmark": "quaternion_check_cost",
            "before": args.before,
            "n": args.n,
            "repeats": args.repeats,
            "machine": info,
            "figures": figures,
        }
    )


if __name__ == "__main__":
    main()
