"""Statistics of the benchmarks' comparisons (docs/protocol.md).

* :mod:`._intervals`: ratio of two methods' criteria with a 95 % stratified bootstrap
  interval over groups (people, shapes, seeds; :func:`scipy.stats.bootstrap`), the
  per-group win count, the verdict in words and the power: the effect the interval
  detects 80 % of the time at this many groups (:class:`Comparison`);
* :mod:`._differences`: paired differences ``a - b`` (the cascade's catches) with their
  interval over groups and the same power line, on the additive scale (:class:`Difference`);
* :mod:`._seeds`: across seeds and sweeps, the interquartile mean with its stratified
  bootstrap interval and the probability of improvement (scipy).
"""

from baselines.stats._differences import Difference, compare_difference, detectable_differences
from baselines.stats._intervals import (
    CONFIDENCE,
    MIN_GROUPS,
    N_RESAMPLES,
    POWER,
    Comparison,
    compare_errors,
    detectable_ratios,
    from_readings,
    group_bootstrap,
    group_bootstrap_replicates,
    group_wins,
    intervals_document,
    min_groups,
    statistic_interval,
    verdict,
)
from baselines.stats._seeds import iqm, iqm_intervals, probability_of_improvement

__all__ = [
    "CONFIDENCE",
    "MIN_GROUPS",
    "N_RESAMPLES",
    "POWER",
    "Comparison",
    "Difference",
    "compare_difference",
    "compare_errors",
    "detectable_differences",
    "detectable_ratios",
    "from_readings",
    "group_bootstrap",
    "group_bootstrap_replicates",
    "group_wins",
    "intervals_document",
    "iqm",
    "iqm_intervals",
    "min_groups",
    "probability_of_improvement",
    "statistic_interval",
    "verdict",
]
