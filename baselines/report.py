"""``report.html``: one self-contained page of every benchmark in a results folder.

:func:`build_report` reads what ``motion-bench all`` wrote (``OUT/index.json`` and each
job's folder: ``results.json`` and its PNG plots) and returns one HTML page with, per
benchmark, its tables (the paper's values beside ours where the paper has them), its
plots (PNG embedded as base64, so the page is a single file) and a paragraph reading the
numbers; sections for ``orientation``, ``position`` and ``juggling`` jobs (simulated
data labelled SIMULATED). :func:`write_report` writes it atomically to ``OUT/report.html``.

A benchmark kind is added with :func:`register_section`: a function from the job's
folder and its ``index.json`` entry to a :class:`Section`. The kind of a job is the part
of its folder name before the first ``-`` (``orientation-vr-kitchen`` ->
``orientation``).
"""

from __future__ import annotations

import base64
import csv
import html
import json
import math
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from motion_envs._io import atomic_write_text

__all__ = ["Section", "build_report", "register_section", "write_report"]

MODELS_DOC = "docs/models.md"


@dataclass
class Section:
    """One benchmark's part of the report: HTML fragments, already escaped."""

    title: str
    command: str
    reading: str
    tables: list[str] = field(default_factory=list)
    images: list[tuple[str, bytes]] = field(default_factory=list)  # (caption, PNG bytes)


SectionBuilder = Callable[[Path, dict[str, Any]], Section]
_BUILDERS: dict[str, SectionBuilder] = {}


def register_section(kind: str, builder: SectionBuilder) -> None:
    """Use ``builder(folder, job)`` for jobs whose folder name starts with ``kind-``."""
    _BUILDERS[kind] = builder


def _fmt(value: Any, digits: int = 3) -> str:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "&ndash;"
    if isinstance(value, float):
        return f"{value:.{digits}f}" if abs(value) < 1000 else f"{value:.1f}"
    return html.escape(str(value))


def _table(header: Sequence[str], rows: Sequence[Sequence[str]], caption: str) -> str:
    head = "".join(f"<th>{html.escape(h)}</th>" for h in header)
    body = "\n".join("<tr>" + "".join(f"<td>{c}</td>" for c in row) + "</tr>" for row in rows)
    return (
        f"<table>\n<caption>{html.escape(caption)}</caption>\n"
        f"<thead><tr>{head}</tr></thead>\n<tbody>\n{body}\n</tbody>\n</table>"
    )


def _images(folder: Path, names: Sequence[tuple[str, str]]) -> list[tuple[str, bytes]]:
    return [(caption, (folder / n).read_bytes()) for n, caption in names if (folder / n).exists()]


def _learned_table(doc: dict[str, Any], groups: str) -> list[str]:
    """The learned rows against the best analytic one: ratio, its 95 % bootstrap interval,
    the target and how many ``groups`` (subjects, shapes) the learned row is better on."""
    comparisons = (doc.get("learned") or {}).get("comparisons") or []
    if not comparisons:
        return []
    rows = []
    for c in comparisons:
        lo, hi = (c.get("ratio_ci95") or [None, None])[:2]
        rows.append(
            [
                f"<code>{html.escape(str(c.get('learned')))}</code>",
                f"<code>{html.escape(str(c.get('best_analytic')))}</code>",
                _fmt(c.get("ratio")),
                f"[{_fmt(lo)}, {_fmt(hi)}]",
                _fmt(c.get("target_ratio")),
                "yes" if c.get("met") else "no",
                f"{c.get('subjects_better')} of {c.get('n_subjects')}",
            ]
        )
    return [
        _table(
            ["learned", "best analytic", "ratio", "95 % interval", "target", "met",
             f"{groups} better"],
            rows,
            "Learned vs analytic, out of sample: ratio of the criteria (below 1: the learned "
            "row is better), bootstrap interval over " + groups,
        )
    ]  # fmt: skip


def _validation_table(by_group: dict[str, Any], group: str, caption: str) -> list[str]:
    """The validation of the linear hypothesis (per group and coordinate): share of
    normal residuals, share of significant F-tests, relative CI and jackknife widths."""
    rows = [
        [html.escape(str(name)), "xyz"[int(r["coordinate"])] if int(r["coordinate"]) < 3 else "?"]
        + [_fmt(r.get(k), 2) if k != "n_coefficients" else _fmt(r.get(k)) for k in _VAL_KEYS]
        for name, rs in by_group.items()
        for r in rs or []
    ]
    if not rows:
        return []
    header = [group, "coordinate", "coefficients", "normal residuals", "F-test significant",
              "CI width (rel.)", "jackknife width (rel.)"]  # fmt: skip
    return [_table(header, rows, caption)]


_VAL_KEYS = ("n_coefficients", "normal_frac", "ftest_frac", "ci_rel", "jack_rel")

LEARNED_RATIO_CAPTION = "Learned vs analytic criterion per group, out of sample"


# -- Juggling-v1's levels ----------------------------------------------------------------


def _juggling_levels_section(folder: Path, job: dict[str, Any]) -> Section:
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
                    f"{_fmt(m['catch_rate'])} [{_fmt(lo)}, {_fmt(hi)}]",
                    _fmt(m["consecutive_catches_median"], 1),
                    _fmt(m["deviation_m"], 4),
                ]
            )
    table = _table(
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


# -- orientation (Faraway & Choe, Table 1) ----------------------------------------------


def _orientation_section(folder: Path, job: dict[str, Any]) -> Section:
    from motion_envs.models.paper_values import FARAWAY_CHOE_TABLE1, FARAWAY_CHOE_TABLE1_NOTES

    doc = json.loads((folder / "results.json").read_text())
    labels: dict[str, str] = {}
    if (folder / "results.csv").exists():
        with open(folder / "results.csv", newline="", encoding="utf-8") as fh:
            labels = {row["name"]: row["label"] for row in csv.DictReader(fh)}
    c = doc["criteria"]
    paper = doc.get("paper") or FARAWAY_CHOE_TABLE1
    rows = [
        [
            html.escape(labels.get(name, name)),
            f"<code>{html.escape(name)}</code>",
            _fmt(value),
            _fmt(paper.get(name)),
            html.escape(FARAWAY_CHOE_TABLE1_NOTES.get(name, "")),
        ]
        for name, value in c.items()
    ]
    kind = "SIMULATED" if doc.get("simulated") else "real"
    table = _table(
        ["criterion", "name", "ours (rad)", "paper (rad)", "note"],
        rows,
        f"Faraway & Choe Table 1 on {doc['dataset']} ({kind} data): median over "
        "trajectories of the max over time of the tangent-space error",
    )

    def get(name: str) -> float:
        v = c.get(name)
        return float("nan") if v is None else float(v)

    def cmp(a: str, b: str) -> str:
        return "below" if get(a) < get(b) else "not below"

    approx = [get(f"approximation_d{d}") for d in (2, 3, 4)]
    gain_in = get("null_d2") - get("task_predictor_d2")
    gain_out = get("null_d2_loso") - get("task_predictor_d2_loso")
    reading = (
        f"{doc['n_trajectories']} trajectories of {doc['n_subjects']} subjects and "
        f"{doc['n_tasks']} tasks ({kind} data; {doc['n_dropped']} dropped for rotating "
        "less than the minimum angle). The disagreement between replicates of one subject "
        f"({_fmt(get('within_subject'))} rad) is {cmp('within_subject', 'between_subject')} "
        "that between subjects ("
        f"{_fmt(get('between_subject'))} rad). The slerp with the observed speed profile "
        f"({_fmt(get('slerp_empirical'))}) is {cmp('slerp_empirical', 'slerp_average')} the "
        f"slerp with the mean speed profile of the data ({_fmt(get('slerp_average'))}), the "
        "timing a prediction must assume. Approximating each curve by its own Bézier "
        f"fit gives {', '.join(_fmt(a) for a in approx)} rad for d = 2, 3, 4"
        f"{' (decreasing, as least squares must)' if approx[0] >= approx[1] >= approx[2] else ''}. "
        f"In sample the task model improves on the null model by {_fmt(gain_in)} rad (d = 2); "
        f"with each subject left out the gain is {_fmt(gain_out)} rad"
        + (
            ", so most of the in-sample gain does not carry to new people. "
            if math.isfinite(gain_out) and gain_out < 0.5 * gain_in
            else ". "
        )
        + "The paper's d = 3 null (0.371, worse than d = 2) cannot follow from its "
        f"procedure; see {MODELS_DOC}."
    )
    return Section(
        title=job.get("title", folder.name),
        command=job.get("command", ""),
        reading=html.escape(reading),
        tables=[table, *_learned_table(doc, "subjects")],
        images=_images(
            folder,
            [
                ("residuals.png", "Slerp residual curves of one task with the fitted models"),
                ("learned_ratio.png", LEARNED_RATIO_CAPTION),
            ],
        ),
    )


# -- position (Lippi, Avizzano & Ruffaldi, on LASA) --------------------------------------


def _position_section(folder: Path, job: dict[str, Any]) -> Section:
    doc = json.loads((folder / "results.json").read_text())
    methods = doc["methods"]
    summary = doc["summary_median_across_shapes"]
    unit = doc.get("unit") or "data unit"
    rows = [
        [html.escape(f"{name}: {text}")] + [_fmt(summary[m][name]) for m in methods] + ["&ndash;"]
        for name, text in doc["criteria"].items()
    ]
    table = _table(
        ["criterion", *methods, "paper"],
        rows,
        f"{doc['dataset']}: median across shapes of the per-shape median ({unit}); "
        "Lippi et al. report no figures on this data set",
    )
    per_shape = doc["per_shape"]
    wins: dict[str, int] = {}
    for m in methods:
        if m == "lippi":
            continue
        wins[m] = sum(
            1
            for s in per_shape.values()
            if s["criteria"]["lippi"]["max_error"] < s["criteria"][m]["max_error"]
        )
    win_rows = [[html.escape(m), f"{n} of {len(per_shape)}"] for m, n in wins.items()]
    win_table = _table(
        ["opponent", "shapes where lippi has the lower max error"],
        win_rows,
        "Per-shape comparison of Lippi et al.'s regression with each other method",
    )
    tables = [table, win_table]
    timing = doc.get("timing") or {}
    if "lippi" in timing:
        t_rows = [
            [
                html.escape(m),
                _fmt(v["fit_s_per_call"] * 1e3, 2),
                _fmt(v["predict_s_per_call"] * 1e3, 2),
            ]
            for m, v in timing.items()
            if "fit_s_per_call" in v
        ]
        tables.append(
            _table(["method", "fit (ms)", "generate one (ms)"], t_rows, "Timing on this machine")
        )
    best = min(methods, key=lambda m: summary[m]["max_error"])
    reading = (
        f"{len(per_shape)} shapes; every method predicts each held-out demonstration from "
        f"its start, end and duration. The lowest median max error is {best}'s "
        f"({_fmt(summary[best]['max_error'])} {unit}); the straight line's is "
        f"{_fmt(summary['line']['max_error'])} {unit}"
        + (
            ", so every method that learns the shape helps by a wide margin. "
            if all(
                summary[m]["max_error"] < 0.5 * summary["line"]["max_error"]
                for m in methods
                if m != "line"
            )
            else ". "
        )
        + (
            f"Lippi et al.'s regression beats the mean residual (null) on "
            f"{wins['null']} of {len(per_shape)} shapes"
            if "null" in wins
            else ""
        )
        + (
            ": with few demonstrations per shape the boundary conditions explain little of "
            "the shape, and the regression adds variance the plain mean does not have"
            + (" (every LASA demonstration ends at the origin)" if doc["dataset"] == "lasa" else "")
            + ". "
            if "null" in wins and wins["null"] < len(per_shape) / 2
            else (". " if "null" in wins else "")
        )
        + (
            "Lippi et al. published no figures on this data set (their data was a juggling "
            f"task), so the 'paper' column is empty; see {MODELS_DOC}."
        )
    )
    return Section(
        title=job.get("title", folder.name),
        command=job.get("command", ""),
        reading=html.escape(reading),
        tables=[
            *tables,
            *_learned_table(doc, "shapes"),
            *_validation_table(
                {k: v.get("validation") for k, v in doc.get("per_shape", {}).items()},
                "shape",
                "Validation of the linear hypothesis per shape (all its demonstrations)",
            ),
        ],
        images=_images(
            folder,
            [
                ("shapes.png", "Held-out demonstrations and each method's prediction"),
                ("learned_ratio.png", LEARNED_RATIO_CAPTION),
            ],
        ),
    )


# -- juggling (Lippi, Avizzano & Ruffaldi, section III-A) --------------------------------


def _juggling_section(folder: Path, job: dict[str, Any]) -> Section:
    doc = json.loads((folder / "results.json").read_text())
    sim = bool(doc.get("simulated"))
    label = "SIMULATED demonstrations" if sim else "recorded demonstrations"
    cycles = doc.get("config", {}).get("cycles")
    runs = [doc["catch_rate_detail"], *doc["catch_rates"]]
    with_mujoco = any("mujoco" in r for r in runs)
    rows = []
    for r in runs:
        row = [
            _fmt(float(r["noise"]), 2),
            _fmt(float(r["tracking"]), 4),
            "on" if r["correction"] else "off",
            _fmt(float(r["catch_rate"])),
            _fmt(r.get("dropped")),
        ]
        if with_mujoco:
            mj = r.get("mujoco")
            row.append(
                "&ndash;"
                if not mj or mj.get("catch_rate") is None
                else f"{_fmt(float(mj['catch_rate']))} ({_fmt(mj['cycles'])} cycles"
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
    catch_table = _table(
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
            [html.escape(phase), _fmt(v.get("n_sines"))]
            + [f"{_fmt(c['max_error'], 4)} ({_fmt(c['rmse'], 4)})" for c in cells]
            + [_fmt(v.get("lippi_over_within"), 2)]
        )
    phase_table = _table(
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
        + f"Unperturbed, the juggler's catch rate is {_fmt(float(base))}"
        + (
            f"; with 5 % release-velocity noise it is {_fmt(float(five['catch_rate']))} "
            "with the online correction (eq. 10)"
            + (
                f" and {_fmt(float(five_off['catch_rate']))} without it"
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
        reading=html.escape(reading),
        tables=[
            catch_table,
            phase_table,
            *_validation_table(
                doc.get("validation") or {},
                "phase",
                f"Validation of the linear hypothesis per phase ({label}, training cycles)",
            ),
        ],
        images=_images(
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


register_section("orientation", _orientation_section)
register_section("position", _position_section)
register_section("juggling", _juggling_section)
register_section("juggling_v1", _juggling_levels_section)

_STYLE = """
body { font-family: system-ui, sans-serif; max-width: 1200px; margin: 2em auto; padding: 0 1em;
       color: #222; line-height: 1.45; }
table { border-collapse: collapse; margin: 1em 0; font-size: 0.9em; }
caption { text-align: left; font-weight: 600; padding: 0.3em 0; }
th, td { border: 1px solid #ccc; padding: 0.25em 0.6em; text-align: right; }
th:first-child, td:first-child, td:nth-child(2) { text-align: left; }
img { max-width: 100%; border: 1px solid #eee; }
code { background: #f4f4f4; padding: 0 0.2em; }
.command { color: #555; font-family: monospace; }
.provenance { color: #555; }
"""


def _provenance() -> str:
    """motion-envs version, the git commit of the source (when it is a checkout) and the
    date the page was built (UTC)."""
    import datetime
    import subprocess

    import motion_envs

    commit = "not a git checkout"
    try:
        proc = subprocess.run(
            ["git", "rev-parse", "--short=12", "HEAD"],
            cwd=Path(__file__).resolve().parent,
            capture_output=True,
            text=True,
            timeout=5,
        )
        if proc.returncode == 0 and proc.stdout.strip():
            commit = proc.stdout.strip()
    except (OSError, subprocess.SubprocessError):
        pass
    date = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    return (
        f'<p class="provenance">motion-envs {html.escape(motion_envs.__version__)}, commit '
        f"<code>{html.escape(commit)}</code>, built {date}</p>"
    )


def _mime(data: bytes) -> str:
    return "image/gif" if data[:6] in (b"GIF87a", b"GIF89a") else "image/png"


def build_report(out: str | os.PathLike[str]) -> str:
    """The HTML page of the results folder ``out`` (its ``index.json`` lists the jobs):
    version, commit and date, a table of contents, then one section per job."""
    root = Path(out)
    index = json.loads((root / "index.json").read_text())
    parts = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        "<title>motion-bench report</title>",
        f"<style>{_STYLE}</style></head><body>",
        "<h1>motion-bench report</h1>",
        _provenance(),
        "<p>Every benchmark of <code>motion-bench all</code> on the built-in data. The "
        "models, criteria and the differences from the papers are described in "
        f"<code>{MODELS_DOC}</code>. Simulated data is labelled SIMULATED.</p>",
    ]
    toc: list[str] = []
    body: list[str] = []
    for job in index.get("jobs", []):
        folder = root / job["folder"]
        anchor = html.escape(job["folder"], quote=True)
        kind = job["folder"].split("-", 1)[0]
        builder = _BUILDERS.get(kind)
        title = html.escape(job.get("title", job["folder"]))
        if builder is None or not (folder / "results.json").exists():
            why = "no results" if builder else f"no report section for {kind!r}"
            toc.append(f'<li><a href="#{anchor}">{title}</a></li>')
            body.append(
                f'<section id="{anchor}"><h2>{title}</h2><p>{html.escape(why)} '
                f"(exit code {job.get('exit_code')}).</p></section>"
            )
            continue
        sec = builder(folder, job)
        toc.append(f'<li><a href="#{anchor}">{html.escape(sec.title)}</a></li>')
        body.append(f'<section id="{anchor}"><h2>{html.escape(sec.title)}</h2>')
        body.append(
            f'<p class="command">{html.escape(sec.command)} ({job.get("seconds", "?")} s)</p>'
        )
        body.append(f"<p>{sec.reading}</p>")
        body.extend(sec.tables)
        for caption, data in sec.images:
            b64 = base64.b64encode(data).decode("ascii")
            body.append(
                f'<figure><img alt="{html.escape(caption)}" src="data:{_mime(data)};base64,'
                f'{b64}"><figcaption>{html.escape(caption)}</figcaption></figure>'
            )
        body.append("</section>")
    parts.append('<nav><h2>Contents</h2><ol class="toc">' + "".join(toc) + "</ol></nav>")
    parts.extend(body)
    parts.append("</body></html>")
    return "\n".join(parts) + "\n"


def write_report(out: str | os.PathLike[str]) -> Path:
    """Build the report of ``out`` and write it atomically to ``out/report.html``."""
    return atomic_write_text(Path(out) / "report.html", build_report(out))
