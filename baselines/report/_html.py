"""The building blocks of ``report.html``: the :class:`Section` of a benchmark, the
registry of section builders (:func:`register_section`) and the HTML table helpers the
sections share."""

from __future__ import annotations

import html
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

__all__ = [
    "BUILDERS",
    "LEARNED_RATIO_CAPTION",
    "MODELS_DOC",
    "VAL_KEYS",
    "Section",
    "SectionBuilder",
    "fmt",
    "html_table",
    "images",
    "learned_table",
    "register_section",
    "validation_table",
]

MODELS_DOC = "docs/models.md"


@dataclass
class Section:
    """One benchmark's part of the report: ``title``, ``command`` and ``reading`` are
    plain text (the page escapes them); ``tables`` are HTML fragments, already escaped."""

    title: str
    command: str
    reading: str
    tables: list[str] = field(default_factory=list)
    images: list[tuple[str, bytes]] = field(default_factory=list)  # (caption, PNG bytes)


SectionBuilder = Callable[[Path, dict[str, Any]], Section]
BUILDERS: dict[str, SectionBuilder] = {}


def register_section(kind: str, builder: SectionBuilder) -> None:
    """Use ``builder(folder, job)`` for jobs whose folder name starts with ``kind-``."""
    BUILDERS[kind] = builder


def fmt(value: Any, digits: int = 3) -> str:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "&ndash;"
    if isinstance(value, float):
        return f"{value:.{digits}f}" if abs(value) < 1000 else f"{value:.1f}"
    return html.escape(str(value))


def html_table(header: Sequence[str], rows: Sequence[Sequence[str]], caption: str) -> str:
    head = "".join(f"<th>{html.escape(h)}</th>" for h in header)
    body = "\n".join("<tr>" + "".join(f"<td>{c}</td>" for c in row) + "</tr>" for row in rows)
    return (
        f"<table>\n<caption>{html.escape(caption)}</caption>\n"
        f"<thead><tr>{head}</tr></thead>\n<tbody>\n{body}\n</tbody>\n</table>"
    )


def images(folder: Path, names: Sequence[tuple[str, str]]) -> list[tuple[str, bytes]]:
    return [(caption, (folder / n).read_bytes()) for n, caption in names if (folder / n).exists()]


def learned_table(doc: dict[str, Any], groups: str) -> list[str]:
    """The learned rows against the best analytic one: ratio, its 95 % bootstrap interval,
    the ratios it detects 80 % of the time at this many groups, the target and how many
    ``groups`` (subjects, shapes) the learned row is better on."""
    comparisons = (doc.get("learned") or {}).get("comparisons") or []
    if not comparisons:
        return []
    rows = []
    for c in comparisons:
        lo, hi = (c.get("ratio_ci95") or [None, None])[:2]
        below, above = (c.get("detectable_ratios") or [None, None])[:2]
        rows.append(
            [
                f"<code>{html.escape(str(c.get('learned')))}</code>",
                f"<code>{html.escape(str(c.get('best_analytic')))}</code>",
                fmt(c.get("ratio")),
                f"[{fmt(lo)}, {fmt(hi)}]",
                f"<= {fmt(below)} or >= {fmt(above)}" if below is not None else "-",
                fmt(c.get("target_ratio")),
                "yes" if c.get("met") else "no",
                f"{c.get('subjects_better')} of {c.get('n_subjects')}",
            ]
        )
    return [
        html_table(
            ["learned", "best analytic", "ratio", "95 % interval", "80 % power for",
             "target", "met", f"{groups} better"],
            rows,
            "Learned vs analytic, out of sample: ratio of the criteria (below 1: the learned "
            "row is better), bootstrap interval over " + groups,
        )
    ]  # fmt: skip


def validation_table(by_group: dict[str, Any], group: str, caption: str) -> list[str]:
    """The validation of the linear hypothesis (per group and coordinate): share of
    normal residuals, share of significant F-tests, relative CI and jackknife widths."""
    rows = [
        [html.escape(str(name)), "xyz"[int(r["coordinate"])] if int(r["coordinate"]) < 3 else "?"]
        + [fmt(r.get(k), 2) if k != "n_coefficients" else fmt(r.get(k)) for k in VAL_KEYS]
        for name, rs in by_group.items()
        for r in rs or []
    ]
    if not rows:
        return []
    header = [group, "coordinate", "coefficients", "normal residuals", "F-test significant",
              "CI width (rel.)", "jackknife width (rel.)"]  # fmt: skip
    return [html_table(header, rows, caption)]


VAL_KEYS = ("n_coefficients", "normal_frac", "ftest_frac", "ci_rel", "jack_rel")

LEARNED_RATIO_CAPTION = "Learned vs analytic criterion per group, out of sample"
