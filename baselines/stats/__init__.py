"""Statistics of the benchmarks' comparisons (docs/protocol.md).

* :mod:`._intervals`: ratio of two methods' criteria with a 95 % stratified bootstrap
  interval over groups (people, shapes, seeds; :func:`scipy.stats.bootstrap`), the
  per-group win count and the verdict in words (:class:`Comparison`);
* :mod:`._seeds`: across seeds and sweeps, ``rliable``'s interquartile mean with its
  interval and the probability of improvement (extra ``stats``).
"""

from baselines.stats._intervals import (
    CONFIDENCE,
    N_RESAMPLES,
    Comparison,
    compare_errors,
    from_readings,
    group_bootstrap,
    group_wins,
    intervals_document,
    statistic_interval,
    verdict,
)
from baselines.stats._seeds import iqm_intervals, probability_of_improvement

__all__ = [
    "CONFIDENCE",
    "N_RESAMPLES",
    "Comparison",
    "compare_errors",
    "from_readings",
    "group_bootstrap",
    "group_wins",
    "intervals_document",
    "iqm_intervals",
    "probability_of_improvement",
    "statistic_interval",
    "verdict",
]
