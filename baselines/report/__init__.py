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

from baselines.report._html import Section, register_section
from baselines.report._juggling import juggling_levels_section, juggling_section
from baselines.report._page import build_report, write_report
from baselines.report._reaching import orientation_section, position_section

__all__ = ["Section", "build_report", "register_section", "write_report"]


register_section("orientation", orientation_section)
register_section("position", position_section)
register_section("juggling", juggling_section)
register_section("juggling_v1", juggling_levels_section)
