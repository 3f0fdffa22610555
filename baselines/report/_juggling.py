"""The ``report.html`` section of the ``juggling`` benchmark (Lippi, Avizzano & Ruffaldi,
section III-A; simulated data labelled SIMULATED)."""

from __future__ import annotations

import html
import json
import math
from pathlib import Path
from typing import Any

from baselines.report._html import (
    MODELS_DOC,
    Section,
    fmt,
    html_table,
    images,
    validation_table,
)

__all__ = ["juggling_levels_section", "juggling_section"]


# -- juggling (Lippi, Avizzano & Ruffaldi, section III-A) --------------------------------


def juggling_section(folder: Path, job: dict[str, Any]) -> Section:
    doc = json.loads((folder / "results.json").read_text())
    sim = bool(doc.get("simulated"))
    label = "SIMULATED demonstrations" if sim else "recorded demonstrations"
    cycles = doc.get("config", {}).get("cycles")
    runs = [doc["catch_rate_detail"], *doc["catch_rates"]]
    with_mujoco = any("mujoco" in r for r in runs)
    rows = []
    for r in runs:
        row = [
            fmt(float(r["noise"]), 2),
            fmt(float(r["tracking"]), 4),
            "on" if r["correction"] else "off",
            fmt(float(r["catch_rate"])),
            fmt(r.get("dropped")),
        ]
        if with_mujoco:
            mj = r.get("mujoco")
            row.append(
                "&ndash;"
                if not mj or mj.get("catch_rate") is None
                else f"{fmt(float(mj['catch_rate']))} ({fmt(mj['cycles'])} cycles"
                + ("" if mj.get("agrees_with_pure_model") else "; DIFFERS")
                + ")"
            )
        rows.append(row)
    header = [
        "release noise (rel. std)",
        "tracking noise (m)",
        "correction (eq. 10)",
        "catch rate",
        "dropped",
    ]
    if with_mujoco:
        header.append("MuJoCo scene")
    catch_table = html_table(
        header,
        rows,
        f"Catch rate of the analytic juggler over {cycles} seeded cycles per row, fitted on "
        f"{label}",
    )
    per_phase = doc["per_phase"]
    methods = list(next(iter(per_phase.values()))["methods"]) if per_phase else []
    phase_rows = []
    for phase, v in per_phase.items():
        cells = [v["methods"][m] for m in methods] + [v["within_person"]]
        phase_rows.append(
            [html.escape(phase), fmt(v.get("n_sines"))]
            + [f"{fmt(c['max_error'], 4)} ({fmt(c['rmse'], 4)})" for c in cells]
            + [fmt(v.get("lippi_over_within"), 2)]
        )
    phase_table = html_table(
        ["phase", "N (sines)", *methods, "within-person", "lippi / within"],
        phase_rows,
        "Per phase, held-out demonstrations: median over demonstrations of the max over "
        f"time of the position error, m (RMSE in brackets); {label}",
    )
    base = doc["catch_rate"]
    five = next(
        (r for r in doc["catch_rates"] if abs(r["noise"] - 0.05) < 1e-12 and r["correction"]), None
    )
    five_off = next(
        (r for r in doc["catch_rates"] if abs(r["noise"] - 0.05) < 1e-12 and not r["correction"]),
        None,
    )
    ahead = [
        p
        for p, v in per_phase.items()
        if "minimum_jerk" in v["methods"]
        and v["methods"]["lippi"]["max_error"] < v["methods"]["minimum_jerk"]["max_error"]
    ]
    within = [p for p, v in per_phase.items() if v.get("lippi_over_within", math.inf) <= 1.5]
    reading = (
        (
            "The demonstrations are SIMULATED (a seeded model of a person; the paper's "
            "recordings are not public), so these numbers describe the method on that model, "
            "not on people. "
            if sim
            else ""
        )
        + f"Unperturbed, the juggler's catch rate is {fmt(float(base))}"
        + (
            f"; with 5 % release-velocity noise it is {fmt(float(five['catch_rate']))} "
            "with the online correction (eq. 10)"
            + (
                f" and {fmt(float(five_off['catch_rate']))} without it"
                if five_off is not None
                else ""
            )
            if five is not None
            else ""
        )
        + ". "
        + (
            f"Lippi et al.'s regression has a lower max error than the minimum-jerk movement "
            f"in {len(ahead)} of {len(per_phase)} phases and stays within 1.5 times the "
            f"within-person variability in {len(within)} of {len(per_phase)}. "
            if per_phase
            else ""
        )
        + "The paper gives no catch rate or per-phase error to compare with (only that the "
        f"trained system performs the exercise steadily); see {MODELS_DOC}."
    )
    return Section(
        title=job.get("title", folder.name),
        command=job.get("command", ""),
        reading=reading,
        tables=[
            catch_table,
            phase_table,
            *validation_table(
                doc.get("validation") or {},
                "phase",
                f"Validation of the linear hypothesis per phase ({label}, training cycles)",
            ),
        ],
        images=images(
            folder,
            [
                (
                    "juggling_fig6.png",
                    f"Held-out {label} and generated cycles, phases coloured (Fig. 6 style)",
                ),
                ("juggling.gif", "The analytic juggler in the MuJoCo scene (SIMULATED)"),
            ],
        ),
    )


def juggling_levels_section(folder: Path, job: dict[str, Any]) -> Section:
    """Juggling-v1's levels: catch rate with its interval per level and method."""
    doc = json.loads((folder / "results.json").read_text())
    seeds = doc["seeds"]
    rows = []
    for lv in doc["levels"]:
        for name, m in lv["methods"].items():
            lo, hi = m["catch_rate_ci"]
            rows.append(
                [
                    html.escape(lv["level"]),
                    html.escape(name),
                    f"{fmt(m['catch_rate'])} [{fmt(lo)}, {fmt(hi)}]",
                    fmt(m["consecutive_catches_median"], 1),
                    fmt(m["deviation_m"], 4),
                ]
            )
    table = html_table(
        ["level", "method", "catch rate [95 % CI]", "consecutive catches (median)",
         "deviation from held-out demonstrations (m)"],
        rows,
        f"Juggling-v1, {seeds['count']} {seeds['split']} episodes per level and method "
        f"({doc['demonstrations']})",
    )  # fmt: skip
    met = [k for k, t in doc["targets"].items() if t["met"]]
    missed = [k for k, t in doc["targets"].items() if t["met"] is False]
    reading = (
        "The analytic juggler corrects its catch from a delayed view of the ball; the "
        "latency-aware variant predicts the flight forward by the known delay. Targets met: "
        f"{', '.join(met) or 'none'}; missed: {', '.join(missed) or 'none'}."
    )
    return Section(job.get("title", "Juggling-v1 levels"), job.get("command", ""), reading, [table])
