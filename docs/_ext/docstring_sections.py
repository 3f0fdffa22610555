"""Sphinx extension: close a numpydoc field section before free text that follows it.

The project's docstrings write, after ``Parameters``, paragraphs such as ``Fitted
attributes: ``coef_`` ...`` or a custom header (``Fitted attributes`` underlined). Napoleon
reads every unindented line of a field section as a new parameter, so such text would
become bogus parameters. This hook runs before napoleon and puts that text under a
``Notes`` section (a custom header becomes its bold first words).
"""

from __future__ import annotations

import re
from typing import Any

#: Napoleon's sections whose unindented lines are field names.
FIELD_SECTIONS = {
    "Parameters",
    "Other Parameters",
    "Attributes",
    "Returns",
    "Yields",
    "Raises",
    "Warns",
    "Receives",
    "Methods",
    "Keyword Arguments",
}
#: Every header napoleon knows (numpy style).
KNOWN_SECTIONS = FIELD_SECTIONS | {
    "Notes",
    "Examples",
    "Example",
    "References",
    "See Also",
    "Warnings",
    "Warning",
    "Note",
    "Todo",
}
FIELD_LINE = re.compile(r"^\*{0,2}[A-Za-z_][\w.]*(\s*,\s*\*{0,2}[A-Za-z_][\w.]*)*\s*(:.*)?$")


def _is_underline(line: str) -> bool:
    text = line.strip()
    return len(text) >= 3 and set(text) == {"-"}


def close_field_sections(lines: list[str]) -> list[str]:
    """``lines`` with a ``Notes`` header before free text inside a field section."""
    out: list[str] = []
    in_fields = False
    i = 0
    while i < len(lines):
        line = lines[i]
        nxt = lines[i + 1] if i + 1 < len(lines) else ""
        if line.strip() and not line[0].isspace() and _is_underline(nxt):
            title = line.strip()
            if title in KNOWN_SECTIONS:
                in_fields = title in FIELD_SECTIONS
                out += [line, nxt]
            else:  # a custom header: a Notes paragraph that starts with it
                in_fields = False
                out += ["Notes", "-----", f"**{title}.**"]
            i += 2
            continue
        if in_fields and line.strip() and not line[0].isspace():
            is_field = FIELD_LINE.match(line.strip()) is not None
            if not is_field:
                in_fields = False
                if out and out[-1].strip():
                    out.append("")
                out += ["Notes", "-----"]
        out.append(line)
        i += 1
    return out


def process(app: Any, what: str, name: str, obj: Any, options: Any, lines: list[str]) -> None:
    lines[:] = close_field_sections(lines)


def setup(app: Any) -> dict[str, Any]:
    app.connect("autodoc-process-docstring", process, priority=100)
    return {"parallel_read_safe": True, "version": "1"}
