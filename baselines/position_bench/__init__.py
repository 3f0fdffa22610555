"""``motion-bench position``: the sine-series model on LASA (or the users' CSV) vs peers.

Leave one demonstration out per shape (task): every method is fitted on the other
demonstrations of the shape and predicts the held-out one from its start point, end
point and duration. All trajectories are resampled (linear interpolation) to
``--n-points`` samples of normalised time ``tau = t / T`` and every method works and is
scored on that grid, so the time normalisation is the same for all.

Methods:

* ``line``: the straight line from start to end;
* ``null``: the line plus the mean residual ``D(tau)`` of the training demonstrations;
* ``lippi``: :class:`~motion_envs.models.sine_regression.SineSeriesRegression` with
  conditions ``--conditions`` (start and end by default; columns constant over the
  training demonstrations, such as LASA's end point at the origin, are dropped) and ``N``
  chosen by leave-one-out cross-validation on the training demonstrations
  (``--n-sines auto``);
* ``dmp``, ``promp``: :mod:`baselines.peers` (``movement_primitives``), same start/goal;
* ``ridge``, ``mlp``: learned residuals (:mod:`baselines.learned.position`, docs/learned.md):
  ridge and a torch MLP of Lippi's residual on the conditions, hyper-parameters chosen
  on the training demonstrations only (``mlp`` is skipped without torch; both with
  ``--learned off``).

Criteria per held-out demonstration: max error (the papers' criterion), RMSE, DTW and
swept error area (:mod:`motion_envs.models.position_criteria`). Per shape we take the
median over its demonstrations; the printed table is the median across shapes. The
reading compares the learned columns with the analytic ones (ratios, a bootstrap over
shapes, per-shape counts; ``learned_ratio.png``).

:func:`run` computes (a pure function of a :class:`PositionConfig`), :func:`report` is
the printed text, :func:`write` writes ``results.json``, ``results.csv`` and
``shapes.png``; :func:`register` adds the sub-command to ``motion-bench``.

The package splits by concern: :mod:`~baselines.position_bench.config`,
:mod:`~baselines.position_bench.scoring` (:func:`run_benchmark`, the folds),
:mod:`~baselines.position_bench.runner` (:func:`run`), :mod:`~baselines.position_bench.text`
(report, CSV), :mod:`~baselines.position_bench.media` (:func:`write`, figure) and
:mod:`~baselines.position_bench.cli` (argparse).
"""

from __future__ import annotations

from baselines.position_bench.cli import (
    conditions_option,
    main,
    n_sines_option,
    position_data,
    register,
    warn_missing_peers,
)
from baselines.position_bench.config import CRITERION_TEXT, METHODS, PEER_METHODS, PositionConfig
from baselines.position_bench.media import plot_grid, write
from baselines.position_bench.runner import run
from baselines.position_bench.scoring import predict_folds, run_benchmark
from baselines.position_bench.text import format_table, format_validation, report, results_csv

__all__ = [
    "CRITERION_TEXT",
    "METHODS",
    "PEER_METHODS",
    "PositionConfig",
    "conditions_option",
    "format_table",
    "format_validation",
    "main",
    "n_sines_option",
    "plot_grid",
    "position_data",
    "predict_folds",
    "register",
    "report",
    "results_csv",
    "run",
    "run_benchmark",
    "warn_missing_peers",
    "write",
]
