"""The README's two commands stay runnable and CI runs the README's test command."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def readme_commands() -> list[str]:
    text = (ROOT / "README.md").read_text()
    quickstart = text.split("## Quickstart", 1)[1].split("\n## ", 1)[0]
    return re.findall(r"```bash\n(.*?)\n```", quickstart, flags=re.S)


def test_quickstart_has_exactly_two_commands():
    cmds = readme_commands()
    assert len(cmds) == 2
    assert all("\n" not in c for c in cmds)
    assert "motion-bench" in cmds[0]
    assert "pytest" in cmds[1]


def test_ci_runs_the_readme_test_command():
    test_cmd = readme_commands()[1]
    # CI creates its own venv; everything after the activation must be identical.
    tail = test_cmd.split(". .venv/bin/activate && ", 1)[1]
    assert tail in (ROOT / ".ci" / "run").read_text()


PAGES = [
    page
    for page in [
        "README.md",
        *sorted(p.relative_to(ROOT).as_posix() for p in (ROOT / "docs").glob("*.md")),
    ]
    if "```python" in (ROOT / page).read_text()
]


@pytest.mark.parametrize("page", PAGES)
def test_python_examples_run(tmp_path, monkeypatch, page):
    """Every ```python block of the README and of each docs page runs as shown."""
    text = (ROOT / page).read_text()
    # a block after "<!-- not run by the tests: ... -->" needs the reader's own files
    text = re.sub(r"<!-- not run by the tests[^>]*-->\n```python\n.*?\n```", "", text, flags=re.S)
    blocks = re.findall(r"```python\n(.*?)\n```", text, flags=re.S)
    monkeypatch.chdir(tmp_path)
    namespace = {"__name__": "docs_example"}
    for block in blocks:
        exec(compile(block, page, "exec"), namespace)
    if page == "docs/results.md":
        assert (tmp_path / "task_d2.json").exists()
