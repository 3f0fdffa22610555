"""Ratios of two methods' criteria with a 95 % stratified bootstrap interval over groups.

A benchmark compares method A with method B by the ratio of their criteria,
``crit(A) / crit(B)``; every criterion of the project is an error (lower is better), so
a ratio below 1 means A is better. The trajectories of one group (a person, a LASA
shape, a training seed) are not independent of each other, the groups are: the
interval resamples *groups*, never trajectories.

Stratified bootstrap: a replicate draws, in every stratum, as many groups as the
stratum holds, with replacement, pools the rows of the drawn groups and recomputes the
ratio on the pool. Without strata there is one stratum (all groups); a stratum with a
single group keeps it in every replicate. The draws are
:func:`scipy.stats.bootstrap` (one sample of group indices per stratum, resampled
independently, ``method="percentile"``, ``n_resamples`` replicates, ``rng`` seeded).

The win count is the number of groups on which A's per-group statistic is below B's.
The verdict is in words: *better* when the whole interval is below 1, *worse* when it
is above 1, *no difference at 95 %* when it contains 1, and *cannot decide* with fewer
than :data:`MIN_GROUPS` groups, whatever the interval (:func:`min_groups`).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "CONFIDENCE",
    "MIN_GROUPS",
    "N_RESAMPLES",
    "Comparison",
    "compare_errors",
    "from_readings",
    "group_bootstrap",
    "group_wins",
    "intervals_document",
    "min_groups",
    "statistic_interval",
    "verdict",
]

FloatArray = NDArray[np.float64]
Statistic = Callable[[FloatArray], float]

#: Confidence level of every interval.
CONFIDENCE = 0.95
#: Bootstrap replicates of every interval.
N_RESAMPLES = 2000


def min_groups(confidence: float = CONFIDENCE) -> int:
    """The fewest groups on which a verdict in words can rest at ``confidence``.

    The smallest ``n`` that meets both:

    * the bootstrap over ``n`` groups has at most ``C(2n - 1, n)`` distinct replicates
      (the multisets of ``n`` groups drawn from ``n``: 3 for 2 groups, 10 for 3, 35 for
      4, 126 for 5); a percentile interval cuts ``(1 - confidence) / 2`` off each end,
      which needs at least ``2 / (1 - confidence)`` of them (40 at 95 %), else its ends
      are single extreme replicates (one group drawn ``n`` times);
    * A lower than B on all ``n`` groups, the strongest evidence ``n`` groups can give,
      has the two-sided sign-test p-value ``2^(1 - n)``, which must be below
      ``1 - confidence`` (at 95 %: ``n >= 6``, ``p = 0.031``; 5 groups give 0.0625).

    At 95 %: 6.
    """
    alpha = 1.0 - confidence
    n = 2
    while math.comb(2 * n - 1, n) < 2.0 / alpha or 2.0 ** (1 - n) >= alpha:
        n += 1
    return n


#: Fewest groups for a verdict at :data:`CONFIDENCE` (:func:`min_groups`): below it the
#: interval is still reported, the verdict is "cannot decide".
MIN_GROUPS = min_groups()


def _members(groups: ArrayLike) -> tuple[NDArray[np.str_], list[NDArray[np.int64]]]:
    labels = np.asarray(groups).astype(str)
    if labels.ndim != 1 or labels.size == 0:
        raise ValueError(f"groups must be a non-empty (n,) array; got shape {labels.shape}")
    levels = np.unique(labels)
    return levels, [np.flatnonzero(labels == g) for g in levels]


def _strata_of(
    levels: NDArray[np.str_], members: list[NDArray[np.int64]], strata: ArrayLike | None
) -> list[NDArray[np.int64]]:
    """Group indices of every stratum (strata given per row; a group must lie in one)."""
    if strata is None:
        return [np.arange(levels.size)]
    rows = np.asarray(strata).astype(str)
    of_group = []
    for g, idx in zip(levels, members, strict=True):
        s = np.unique(rows[idx])
        if s.size != 1:
            raise ValueError(f"group {g!r} lies in several strata {s.tolist()}")
        of_group.append(s[0])
    labels = np.asarray(of_group)
    return [np.flatnonzero(labels == s) for s in np.unique(labels)]


def group_bootstrap(
    statistic: Callable[[NDArray[np.int64]], float],
    groups: ArrayLike,
    strata: ArrayLike | None = None,
    n_resamples: int = N_RESAMPLES,
    seed: int = 0,
) -> tuple[float, float, float]:
    """``statistic(rows)`` on all rows and its 95 % stratified bootstrap interval.

    Parameters
    ----------
    statistic:
        Maps the (pooled) row indices of a replicate to a number.
    groups:
        ``(n,)`` group of every row (the resampled unit).
    strata:
        ``(n,)`` stratum of every row (None: one stratum); each group in one stratum.
    n_resamples, seed:
        Replicates and the seed of :func:`scipy.stats.bootstrap`'s generator.

    Returns
    -------
    (point, low, high)
        The statistic on all rows and the percentile interval.
    """
    from scipy.stats import bootstrap

    levels, members = _members(groups)
    strata_groups = _strata_of(levels, members, strata)
    fixed = [s for s in strata_groups if s.size < 2]  # one group: always drawn
    drawn = [s for s in strata_groups if s.size >= 2]
    order = np.concatenate(members)  # rows of group g: order[starts[g] : starts[g] + sizes[g]]
    sizes = np.array([m.size for m in members])
    starts = np.concatenate([[0], np.cumsum(sizes)[:-1]])
    fixed_groups = np.concatenate([*fixed, np.empty(0, np.int64)]).astype(np.int64)
    point = float(statistic(np.arange(order.size)))
    if not drawn:
        return point, point, point

    def replicate(*samples: NDArray[Any]) -> float:
        picked = np.concatenate([fixed_groups, *samples]).astype(np.int64)
        n = sizes[picked]
        offsets = np.arange(n.sum()) - np.repeat(np.cumsum(n) - n, n)
        return float(statistic(order[np.repeat(starts[picked], n) + offsets]))

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # scipy's DegenerateDataWarning for constant data
        res = bootstrap(
            tuple(s.astype(np.float64) for s in drawn),
            replicate,
            n_resamples=n_resamples,
            vectorized=False,
            paired=False,
            confidence_level=CONFIDENCE,
            method="percentile",
            rng=np.random.default_rng(seed),
        )
    return point, float(res.confidence_interval.low), float(res.confidence_interval.high)


def statistic_interval(
    values: ArrayLike,
    groups: ArrayLike,
    strata: ArrayLike | None = None,
    statistic: Statistic = np.median,
    n_resamples: int = N_RESAMPLES,
    seed: int = 0,
) -> tuple[float, float, float]:
    """``statistic(values)`` (default the median: the papers' criterion of per-trajectory
    max errors) and its 95 % interval resampling groups (:func:`group_bootstrap`)."""
    v = np.asarray(values, dtype=np.float64)
    return group_bootstrap(
        lambda rows: float(statistic(v[rows])), groups, strata, n_resamples, seed
    )


def group_wins(
    values_a: ArrayLike, values_b: ArrayLike, groups: ArrayLike, statistic: Statistic = np.median
) -> tuple[int, int]:
    """``(wins, n_groups)``: groups on which ``statistic`` of A's rows is below B's."""
    a = np.asarray(values_a, dtype=np.float64)
    b = np.asarray(values_b, dtype=np.float64)
    _, members = _members(groups)
    wins = sum(int(statistic(a[m]) < statistic(b[m])) for m in members)
    return wins, len(members)


def verdict(low: float, high: float, n_groups: int | None = None) -> str:
    """``"better"`` (interval below 1), ``"worse"`` (above 1) or ``"no difference"``;
    ``"cannot decide"`` when ``n_groups`` (None: not checked) is below :data:`MIN_GROUPS`."""
    if n_groups is not None and n_groups < MIN_GROUPS:
        return "cannot decide"
    if high < 1.0:
        return "better"
    if low > 1.0:
        return "worse"
    return "no difference"


@dataclass(frozen=True)
class Comparison:
    """One comparison ``a / b`` of two methods' criteria (lower is better).

    Attributes
    ----------
    a, b:
        Names of the methods (rows, columns, policies).
    ratio:
        ``crit(a) / crit(b)`` on all rows.
    ci95:
        95 % bootstrap interval of the ratio over ``group``.
    wins, n_groups:
        Groups on which ``a``'s per-group statistic is below ``b``'s, of ``n_groups``.
    group:
        What was resampled, plural (``"people"``, ``"shapes"``, ``"seeds"``).
    criterion, unit:
        What the criterion is and its unit (the ratio itself has none).
    """

    a: str
    b: str
    ratio: float
    ci95: tuple[float, float]
    wins: int
    n_groups: int
    group: str = "people"
    criterion: str = "median over trajectories of the max error over time"
    unit: str = "rad"

    @property
    def name(self) -> str:
        """``"a / b"``: the key of ``results.json``'s ``intervals``."""
        return f"{self.a} / {self.b}"

    @property
    def verdict(self) -> str:
        """``"better"``, ``"worse"`` or ``"no difference"`` (for ``a``, at 95 %);
        ``"cannot decide"`` with fewer than :data:`MIN_GROUPS` groups."""
        return verdict(*self.ci95, n_groups=self.n_groups)

    def sentence(self) -> str:
        """The verdict in words."""
        v = self.verdict
        if v == "cannot decide":
            return (
                f"cannot decide with {self.n_groups} {self.group} (a verdict at 95 % needs "
                f"at least {MIN_GROUPS}: docs/protocol.md)"
            )
        if v == "no difference":
            return "no difference at 95 % (the interval contains 1)"
        return f"{self.a} is {v.upper()} than {self.b} at 95 %"

    def line(self, width: int = 0) -> str:
        """One printed line: ratio, interval, wins, unit and direction, verdict."""
        lo, hi = self.ci95
        return (
            f"  {self.name:<{width}} = {self.ratio:.3f} (95% CI {lo:.3f}-{hi:.3f} over "
            f"{self.n_groups} {self.group}); lower on {self.wins}/{self.n_groups} {self.group}; "
            f"{self.sentence()}"
        )

    def to_dict(self) -> dict[str, Any]:
        """The ``results.json`` entry (``verdicts`` list)."""
        return {
            "a": self.a,
            "b": self.b,
            "ratio": self.ratio,
            "ci95": list(self.ci95),
            "wins": self.wins,
            "n_groups": self.n_groups,
            "group": self.group,
            "criterion": self.criterion,
            "unit": self.unit,
            "lower_is_better": True,
            "verdict": self.verdict,
        }


def compare_errors(
    errors_a: ArrayLike,
    errors_b: ArrayLike,
    groups: ArrayLike,
    a: str,
    b: str,
    strata: ArrayLike | None = None,
    statistic: Statistic = np.median,
    group: str = "people",
    criterion: str = "median over trajectories of the max error over time",
    unit: str = "rad",
    n_resamples: int = N_RESAMPLES,
    seed: int = 0,
) -> Comparison:
    """Compare two methods scored on the same rows (see the module docstring).

    ``errors_a``, ``errors_b`` are ``(n,)`` per-row errors of A and B on the same rows
    (trajectories, or one value per group); the criterion is ``statistic`` of them
    (default the median).
    """
    ea = np.asarray(errors_a, dtype=np.float64)
    eb = np.asarray(errors_b, dtype=np.float64)
    if ea.shape != eb.shape or ea.ndim != 1:
        raise ValueError(f"errors_a and errors_b must be (n,) each; got {ea.shape}, {eb.shape}")
    point, lo, hi = group_bootstrap(
        lambda rows: float(statistic(ea[rows]) / statistic(eb[rows])),
        groups,
        strata,
        n_resamples,
        seed,
    )
    wins, n = group_wins(ea, eb, groups, statistic)
    return Comparison(a, b, point, (lo, hi), wins, n, group, criterion, unit)


def intervals_document(comparisons: Sequence[Comparison]) -> dict[str, list[float]]:
    """``{"a / b": [low, high]}``: the ``intervals`` entry of ``results.json``."""
    return {c.name: [c.ci95[0], c.ci95[1]] for c in comparisons}


def _from_reading(
    entry: Mapping[str, Any], a_key: str, b_key: str, group: str, criterion: str, unit: str
) -> Comparison:
    """A :class:`Comparison` from an existing reading (``ratio``, ``ratio_ci95``, wins)."""
    lo, hi = entry["ratio_ci95"]
    return Comparison(
        entry[a_key],
        entry[b_key],
        float(entry["ratio"]),
        (float(lo), float(hi)),
        int(entry["subjects_better"]),
        int(entry["n_subjects"]),
        group,
        criterion,
        unit,
    )


def from_readings(
    readings: Sequence[Mapping[str, Any]],
    group: str,
    criterion: str = "median over trajectories of the max error over time",
    unit: str = "rad",
) -> list[Comparison]:
    """The learned-vs-analytic readings (``learned``, ``best_analytic``, ``ratio``,
    ``ratio_ci95``, ``subjects_better``, ``n_subjects``) as comparisons, their interval
    unchanged."""
    return [_from_reading(r, "learned", "best_analytic", group, criterion, unit) for r in readings]
