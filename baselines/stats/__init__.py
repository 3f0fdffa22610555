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

from baselines.stats import _differences, _intervals, _seeds
from baselines.stats._differences import *  # noqa: F403  (its __all__)
from baselines.stats._intervals import *  # noqa: F403  (its __all__)
from baselines.stats._seeds import *  # noqa: F403  (its __all__)

__all__ = [*_intervals.__all__, *_differences.__all__, *_seeds.__all__]
