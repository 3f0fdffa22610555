"""``motion-bench orientation``: Faraway & Choe's Table 1 on real or the users' data.

:func:`run` computes (a pure function of an :class:`OrientationConfig`); :func:`report`
is the printed table, every criterion beside the paper's value; :func:`write` writes
``results.json``, ``results.csv`` and a residual plot in the style of the paper's
Figure 5. With at least 3 subjects, ``run`` adds the path-frame, predicted-timing and
learned leave-one-subject-out rows of :mod:`baselines.learned.rows` (``--learned``,
docs/learned.md); ``report`` prints a reading of learned against analytic and ``write``
adds ``learned_ratio.png``. :func:`register` adds the sub-command to ``motion-bench``.

The package splits by concern: :mod:`~baselines.orientation_bench.config`,
:mod:`~baselines.orientation_bench.runner` (:func:`run`), :mod:`~baselines.orientation_bench.text`
(Table 1, report, CSV), :mod:`~baselines.orientation_bench.media` (:func:`write`, figure) and
:mod:`~baselines.orientation_bench.cli` (argparse).
"""

from __future__ import annotations

from baselines.orientation_bench.cli import main, orientation_data, register, up_option
from baselines.orientation_bench.config import SPLITS, OrientationConfig, OrientationResults
from baselines.orientation_bench.media import plot_residuals, write
from baselines.orientation_bench.runner import run
from baselines.orientation_bench.text import (
    document,
    format_table1,
    report,
    results_csv,
    results_document,
)

__all__ = [
    "SPLITS",
    "OrientationConfig",
    "OrientationResults",
    "document",
    "format_table1",
    "main",
    "orientation_data",
    "plot_residuals",
    "register",
    "report",
    "results_csv",
    "results_document",
    "run",
    "up_option",
    "write",
]
