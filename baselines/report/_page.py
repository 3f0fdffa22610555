"""The page of ``report.html``: style, provenance, table of contents and one section per
job (:func:`build_report`), written atomically (:func:`write_report`)."""

from __future__ import annotations

import base64
import html
import json
import os
from pathlib import Path

from baselines.report._html import BUILDERS, MODELS_DOC
from motion_envs._io import atomic_write_text

__all__ = ["build_report", "write_report"]

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
        builder = BUILDERS.get(kind)
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
        body.append(f"<p>{html.escape(sec.reading)}</p>")
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
