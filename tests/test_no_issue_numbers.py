"""Users' text never speaks of the project's internal issue numbers ("issue 9"): README,
docs, shipped configs, the CLI's printed text and help (all in these sources)."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PATTERN = re.compile(r"\bissues? #?[0-9]+", re.IGNORECASE)


def test_no_internal_issue_numbers():
    files = [ROOT / "README.md"]
    for folder, globs in (
        ("docs", ("*.md", "*.rst", "*.py")),
        ("baselines", ("*.py", "*.yaml")),
        ("motion_envs", ("*.py", "*.yaml")),
        ("configs", ("*.yaml", "*.yml")),
    ):
        for glob in globs:
            files += [p for p in (ROOT / folder).rglob(glob) if "_build" not in p.parts]
    hits = [
        f"{p.relative_to(ROOT)}:{i}: {line.strip()}"
        for p in files
        for i, line in enumerate(p.read_text(encoding="utf-8").splitlines(), 1)
        if PATTERN.search(line)
    ]
    assert not hits, "\n".join(hits)
