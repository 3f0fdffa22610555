"""The text outputs of ``motion-bench juggling``: the printed report, ``results.csv``
and the JSON-ready results document."""

from __future__ import annotations

import csv
import io
import math
from typing import Any

import numpy as np

from motion_envs.datasets.juggling import SIMULATED_LABEL


def clean_json(value: Any) -> Any:
    """``value`` for JSON: non-finite floats as None, numpy scalars as Python ones, keys
    starting with ``_`` (arrays for the plots) left out."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {str(k): clean_json(v) for k, v in value.items() if not str(k).startswith("_")}
    if isinstance(value, (list, tuple)):
        return [clean_json(v) for v in value]
    if isinstance(value, (np.floating, np.integer, np.bool_)):
        return clean_json(value.item())
    return value


def report(doc: dict[str, Any]) -> str:
    """The printed catch-rate, per-phase and validation tables."""
    lines = [
        f"juggling benchmark: data {doc['data']}",
        f"world: {doc['world']}; split by demonstration: {doc['split']['n_train_cycles']} "
        f"train / {doc['split']['n_test_cycles']} test cycles; gravity "
        f"{doc['task']['gravity']} m/s^2",
        "",
        f"catch rate, unperturbed: {doc['catch_rate']:.3f}",
        f"{'release noise':>14}{'tracking (m)':>14}{'eq. 10':>8}{'catch rate':>12}",
    ]
    for r in doc["catch_rates"]:
        lines.append(
            f"{r['noise']:>14.2f}{r['tracking']:>14.4f}{'on' if r['correction'] else 'off':>8}"
            f"{r['catch_rate']:>12.3f}"
        )
    mj = [r for r in [doc.get("catch_rate_detail", {}), *doc["catch_rates"]] if "mujoco" in r]
    if mj:
        same = all(r["mujoco"]["agrees_with_pure_model"] for r in mj)
        n_mj = sum(r["mujoco"]["cycles"] for r in mj)
        lines.append(
            f"MuJoCo scene: {n_mj} of these cycles stepped in JugglingScene "
            f"({'identical outcomes' if same else 'OUTCOMES DIFFER'} from the pure model); "
            + ", ".join(f"{r['mujoco']['catch_rate']:.3f}" for r in mj)
        )
    methods = list(next(iter(doc["per_phase"].values()))["methods"])
    lines += [
        "",
        "per phase, held-out demonstrations (m): median over demos of max_t |error| (and of RMSE)",
        f"{'phase':<9}{'N':>3}" + "".join(f"{m:>22}" for m in [*methods, "within-person"]),
    ]
    for phase, v in doc["per_phase"].items():
        cells = [v["methods"][m] for m in methods] + [v["within_person"]]
        lines.append(
            f"{phase:<9}{v['n_sines']:>3}"
            + "".join(f"{c['max_error']:>12.4f} ({c['rmse']:.4f})" for c in cells)
        )
    lines += [
        "",
        "validation of the linear hypothesis (training cycles), non-exact sine coefficients:",
        "  normal: share with Lilliefors p > 0.05; F-test: share with p < 0.05; "
        "CI/|F|, jack/|F|: medians over coefficients",
        f"{'phase':<9}{'coord':>6}{'n':>4}{'normal':>8}{'F-test':>8}{'CI/|F|':>9}{'jack/|F|':>10}",
    ]
    for phase, rows in doc["validation"].items():
        for row in rows:
            if "error" in row:
                lines.append(f"{phase:<9}  {row['error']}")
                continue
            lines.append(
                f"{phase:<9}{'xz'[row['coordinate']]:>6}{row['n_coefficients']:>4}"
                f"{row['normal_frac']:8.2f}{row['ftest_frac']:8.2f}"
                f"{row['ci_rel']:9.2f}{row['jack_rel']:10.2f}"
            )
    t = doc["targets"]
    lines += ["", "acceptance targets:"]
    lines.append(f"  unperturbed catch rate >= 0.99: {_met(t['unperturbed_catch_rate>=0.99'])}")
    lines.append(f"  5 % noise with eq. 10 >= 0.90: {_met(t['noise5_corrected_catch_rate>=0.90'])}")
    for key, text in (
        ("lippi_within_1.5x_within_person", "Lippi within 1.5x within-person variability"),
        ("lippi_ahead_of_minimum_jerk", "Lippi ahead of minimum jerk (max error)"),
    ):
        lines.append(f"  {text}: " + ", ".join(f"{p} {_met(m)}" for p, m in t[key].items()))
    if doc["simulated"]:
        lines.append(f"\nDATA ARE {SIMULATED_LABEL}")
    return "\n".join(lines)


def _met(flag: bool | None) -> str:
    return "n/a" if flag is None else ("met" if flag else "MISSED")


def results_csv(doc: dict[str, Any]) -> str:
    """``results.csv``: one row per catch-rate run and per (phase, method)."""
    buf = io.StringIO()
    w = csv.writer(buf)
    w.writerow(
        ["kind", "phase", "method", "noise", "correction", "catch_rate", "max_error", "rmse"]
    )
    w.writerow(
        ["catch_rate", "", "analytic_juggler", 0.0, True, f"{doc['catch_rate']:.6g}", "", ""]
    )
    for r in doc["catch_rates"]:
        w.writerow(
            [
                "catch_rate",
                "",
                "analytic_juggler",
                r["noise"],
                r["correction"],
                f"{r['catch_rate']:.6g}",
                "",
                "",
            ]
        )
    for phase, v in doc["per_phase"].items():
        for m, c in [*v["methods"].items(), ("within_person", v["within_person"])]:
            w.writerow(
                ["phase_error", phase, m, "", "", "", f"{c['max_error']:.6g}", f"{c['rmse']:.6g}"]
            )
    return buf.getvalue()
