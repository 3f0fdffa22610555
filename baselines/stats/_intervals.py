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

Power (:func:`detectable_ratios`): the smallest effect the interval detects 80 % of the
time with this many groups, by the same resampling over groups. A study of the same
size drawn by resampling the groups has its estimate spread as the bootstrap replicates
are around the point, ``d = log(ratio*) - log(ratio)``, and its interval the same shape
(``l = log(low / ratio)``, ``u = log(high / ratio)``). With a true log-ratio ``t`` the
study says *better* when ``t + d + u < 0`` and *worse* when ``t + d + l > 0``; the
smallest ``|t|`` for which either happens with probability 0.8 is, below 1,
``t = -(u + q_0.8(d))`` and, above 1, ``t = -l - q_0.2(d)`` (for normal replicates with
a symmetric interval: ``(1.96 + 0.84)`` standard errors). A comparison whose interval
contains 1 and whose claimed effect ``|1 - ratio|`` is smaller than that in its
direction *cannot decide at this size*; a verdict of better or worse on such an effect
says so (a study of this size would often miss it).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from motion_envs._typing import FloatArray

__all__ = [
    "CONFIDENCE",
    "MIN_GROUPS",
    "N_RESAMPLES",
    "POWER",
    "Comparison",
    "compare_errors",
    "detectable_ratios",
    "from_readings",
    "group_bootstrap",
    "group_bootstrap_replicates",
    "group_wins",
    "intervals_document",
    "min_groups",
    "statistic_interval",
    "verdict",
    "verdict_sentence",
]

Statistic = Callable[[FloatArray], float]

#: Confidence level of every interval.
CONFIDENCE = 0.95
#: Bootstrap replicates of every interval.
N_RESAMPLES = 2000
#: The power at which the detectable effect is stated.
POWER = 0.8


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
    """``(point, low, high)`` of :func:`group_bootstrap_replicates`."""
    point, lo, hi, _ = group_bootstrap_replicates(statistic, groups, strata, n_resamples, seed)
    return point, lo, hi


def group_bootstrap_replicates(
    statistic: Callable[[NDArray[np.int64]], float],
    groups: ArrayLike,
    strata: ArrayLike | None = None,
    n_resamples: int = N_RESAMPLES,
    seed: int = 0,
) -> tuple[float, float, float, FloatArray]:
    """``statistic(rows)`` on all rows, its 95 % stratified bootstrap interval and the
    replicates.

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
    (point, low, high, replicates)
        The statistic on all rows, the percentile interval and the ``(n_resamples,)``
        replicates (``(1,)`` holding the point when no stratum has two groups).
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
        return point, point, point, np.array([point])

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
    low, high = float(res.confidence_interval.low), float(res.confidence_interval.high)
    return point, low, high, np.asarray(res.bootstrap_distribution, dtype=np.float64)


def detectable_ratios(
    point: float, low: float, high: float, replicates: ArrayLike, power: float = POWER
) -> tuple[float, float]:
    """The true ratios, below and above 1, that the interval ``(low, high)`` around
    ``point`` detects with probability ``power`` at this many groups (module docstring);
    ``(nan, nan)`` for a ratio or replicate that is not positive and finite."""
    r = np.asarray(replicates, dtype=np.float64)
    values = np.array([point, low, high])
    if r.size == 0 or not (np.all(np.isfinite(r)) and np.all(r > 0)):
        return float("nan"), float("nan")
    if not (np.all(np.isfinite(values)) and np.all(values > 0)):
        return float("nan"), float("nan")
    d = np.log(r) - np.log(point)
    u, lo = np.log(high / point), np.log(low / point)
    below = float(np.exp(-(u + np.quantile(d, power))))
    above = float(np.exp(-lo - np.quantile(d, 1.0 - power)))
    return min(below, 1.0), max(above, 1.0)


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


def verdict_sentence(
    verdict: str,
    a: str,
    b: str,
    n_groups: int,
    group: str,
    decidable: bool | None,
    no_effect: str = "1",
) -> str:
    """A verdict in words (``no_effect``: the value an interval containing it cannot tell
    from no effect, 1 for a ratio, 0 for a difference), with "cannot decide at this size"
    where ``decidable`` is False (the claimed effect below the detectable one)."""
    if verdict == "cannot decide":
        return (
            f"cannot decide with {n_groups} {group} (a verdict at 95 % needs "
            f"at least {MIN_GROUPS}: docs/protocol.md)"
        )
    if verdict == "no difference":
        text = f"no difference at 95 % (the interval contains {no_effect})"
        return text + ("; cannot decide at this size" if decidable is False else "")
    text = f"{a} is {verdict.upper()} than {b} at 95 %"
    if decidable is False:
        text += " (an effect below the one this size detects 80 % of the time)"
    return text


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
    detectable:
        The true ratios below and above 1 that the interval detects with probability
        :data:`POWER` at ``n_groups`` groups (:func:`detectable_ratios`); None: unknown.
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
    detectable: tuple[float, float] | None = None

    @property
    def name(self) -> str:
        """``"a / b"``: the key of ``results.json``'s ``intervals``."""
        return f"{self.a} / {self.b}"

    @property
    def verdict(self) -> str:
        """``"better"``, ``"worse"`` or ``"no difference"`` (for ``a``, at 95 %);
        ``"cannot decide"`` with fewer than :data:`MIN_GROUPS` groups."""
        return verdict(*self.ci95, n_groups=self.n_groups)

    @property
    def decidable(self) -> bool | None:
        """Whether the claimed effect is at least the one detected with probability
        :data:`POWER` in its direction (None: power unknown)."""
        if self.detectable is None or not all(np.isfinite(self.detectable)):
            return None
        below, above = self.detectable
        return bool(self.ratio <= below) if self.ratio <= 1.0 else bool(self.ratio >= above)

    def sentence(self) -> str:
        """The verdict in words."""
        return verdict_sentence(
            self.verdict, self.a, self.b, self.n_groups, self.group, self.decidable, "1"
        )

    def power_text(self) -> str:
        """The power line: the effect detected 80 % of the time at this many groups and
        whether the claimed one reaches it."""
        if self.detectable is None or self.decidable is None:
            return f"power at {self.n_groups} {self.group}: unknown"
        below, above = self.detectable
        claimed = abs(1.0 - self.ratio)
        side = 1.0 - below if self.ratio <= 1.0 else above - 1.0
        return (
            f"{POWER:.0%} power at {self.n_groups} {self.group} for ratios <= {below:.3f} or "
            f">= {above:.3f}; the claimed {claimed:.1%} "
            + ("reaches" if self.decidable else "is below")
            + f" the detectable {side:.1%}"
        )

    def line(self, width: int = 0) -> str:
        """One printed line: ratio, interval, wins, unit and direction, verdict, power."""
        lo, hi = self.ci95
        return (
            f"  {self.name:<{width}} = {self.ratio:.3f} (95% CI {lo:.3f}-{hi:.3f} over "
            f"{self.n_groups} {self.group}); lower on {self.wins}/{self.n_groups} {self.group}; "
            f"{self.sentence()}; {self.power_text()}"
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
            "power": POWER,
            "detectable_ratios": None if self.detectable is None else list(self.detectable),
            "decidable": self.decidable,
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
    point, lo, hi, reps = group_bootstrap_replicates(
        lambda rows: float(statistic(ea[rows]) / statistic(eb[rows])),
        groups,
        strata,
        n_resamples,
        seed,
    )
    wins, n = group_wins(ea, eb, groups, statistic)
    detectable = detectable_ratios(point, lo, hi, reps)
    return Comparison(a, b, point, (lo, hi), wins, n, group, criterion, unit, detectable)


def intervals_document(comparisons: Sequence[Comparison]) -> dict[str, list[float]]:
    """``{"a / b": [low, high]}``: the ``intervals`` entry of ``results.json``."""
    return {c.name: [c.ci95[0], c.ci95[1]] for c in comparisons}


def _from_reading(
    entry: Mapping[str, Any], a_key: str, b_key: str, group: str, criterion: str, unit: str
) -> Comparison:
    """A :class:`Comparison` from an existing reading (``ratio``, ``ratio_ci95``, wins)."""
    lo, hi = entry["ratio_ci95"]
    detectable = entry.get("detectable_ratios")
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
        None if detectable is None else (float(detectable[0]), float(detectable[1])),
    )


def from_readings(
    readings: Sequence[Mapping[str, Any]],
    group: str,
    criterion: str = "median over trajectories of the max error over time",
    unit: str = "rad",
) -> list[Comparison]:
    """The learned-vs-analytic readings (``learned``, ``best_analytic``, ``ratio``,
    ``ratio_ci95``, ``subjects_better``, ``n_subjects``, ``detectable_ratios``) as
    comparisons, their interval unchanged."""
    return [_from_reading(r, "learned", "best_analytic", group, criterion, unit) for r in readings]
