"""The reading of the learned columns of ``motion-bench position``.

Criterion: the papers' max error; per shape the median over its held-out
demonstrations, then the median across shapes (the printed table). The targets compare
the better of ``ridge``/``mlp`` with ``null`` (ratio <= 0.93) and ``lippi`` (<= 0.90);
the 95% interval resamples shapes with replacement.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from baselines.learned.reading import bootstrap_ratio_power, format_comparison

__all__ = ["TARGETS", "format_position_reading", "position_comparisons"]

#: (analytic column, target ratio of the better learned column).
TARGETS: tuple[tuple[str, float], ...] = (("null", 0.93), ("lippi", 0.90))
_ANALYTIC = ("line", "null", "lippi")


def position_comparisons(doc: dict[str, Any], n_boot: int = 2000) -> list[dict[str, Any]]:
    """Ratios of the learned columns to the analytic ones (see the module docstring)."""
    methods = doc["methods"]
    learned = [m for m in ("ridge", "mlp") if m in methods]
    if not learned:
        return []
    shapes = list(doc["per_shape"])

    def values(m: str) -> np.ndarray:
        return np.array([doc["per_shape"][s]["criteria"][m]["max_error"] for s in shapes])

    summary = doc["summary_median_across_shapes"]
    better = min(learned, key=lambda m: summary[m]["max_error"])
    analytic = [m for m in _ANALYTIC if m in methods]
    best = min(analytic, key=lambda m: summary[m]["max_error"])
    pairs: list[tuple[str, str, float | None]] = [
        (better, a, t) for a, t in TARGETS if a in methods
    ]
    pairs += [(m, best, None) for m in learned if (m, best) not in {(x, y) for x, y, _ in pairs}]
    out = []
    for m, a, target in pairs:
        va, vb = values(m), values(a)
        ratio, lo, hi, detectable = bootstrap_ratio_power(va, vb, np.array(shapes), n_boot)
        out.append(
            {
                "learned": m,
                "best_analytic": a,
                "ratio": ratio,
                "ratio_ci95": [lo, hi],
                "detectable_ratios": list(detectable),
                "target_ratio": target,
                "met": bool(ratio <= target) if target is not None else None,
                "subjects_better": int(np.sum(va < vb)),
                "n_subjects": len(shapes),
                "per_group_ratio": dict(zip(shapes, (va / vb).tolist(), strict=True)),
            }
        )
    return out


def format_position_reading(doc: dict[str, Any], comparisons: list[dict[str, Any]]) -> str:
    """A short honest reading of the learned columns (max error criterion)."""
    lines = [
        "",
        "learned vs analytic (max error, median across shapes; ratio < 1: learned better):",
    ]
    lines += [format_comparison(c, "shapes", (6, 6)) for c in comparisons]
    for m, why in doc["learned"]["skipped"].items():
        lines.append(f"  {m}: skipped ({why})")
    lines.append(
        f"  ridge + mlp fitting and selection (all folds): "
        f"{doc['learned']['seconds_ridge_and_mlp']:.1f} s"
    )
    return "\n".join(lines)
