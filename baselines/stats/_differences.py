"""Paired differences ``a - b`` of two methods' statistics, with their power line.

Some comparisons are differences, not ratios: the cascade's median catches before the
first drop and its catch rate, agent minus juggler on the same seeds (higher is better).
Their 95 % interval resamples the groups (episodes: one seed each, both methods'
episodes of a seed together, so the difference is paired) by
:func:`~baselines.stats.group_bootstrap_replicates`.

Power: the smallest difference, below and above 0, that the interval detects 80 % of
the time at this many groups, by the same argument as the ratios'
(:func:`~baselines.stats.detectable_ratios`, module docstring of ``_intervals``) on the
additive scale. :func:`detectable_differences` computes it WITH that function:
``detectable_ratios`` works on the logs of the ratio, its interval and its replicates;
given ``exp(x / s)`` for each difference ``x`` (``s`` the largest ``|x|``, so that the
exponentials stay near 1), its logs are ``x / s``, and ``s log`` of its answer is the
additive threshold. A comparison whose interval contains 0 and whose claimed difference
is smaller than the detectable one in its direction (a difference of 0: the side below
0, as a ratio of 1) *cannot decide at this size*.

The argument shifts the replicates continuously. A median of integer counts has
discrete replicates: when an interval end coincides with the point, the threshold on
that side comes out at (or near) 0, a lower bound of the real one (a median moves by
whole catches); the power line says so.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from baselines.stats._intervals import (
    MIN_GROUPS,
    N_RESAMPLES,
    POWER,
    detectable_ratios,
    group_bootstrap_replicates,
    verdict_sentence,
)

__all__ = [
    "Difference",
    "compare_difference",
    "detectable_differences",
    "paired_mean_difference",
]


def detectable_differences(
    point: float, low: float, high: float, replicates: ArrayLike, power: float = POWER
) -> tuple[float, float]:
    """``(below, above)``: the true differences, ``<= 0`` and ``>= 0``, that the interval
    ``(low, high)`` around ``point`` detects with probability ``power`` at this many
    groups (module docstring); ``(nan, nan)`` for a value that is not finite."""
    r = np.asarray(replicates, dtype=np.float64).ravel()
    values = np.concatenate([[point, low, high], r])
    if r.size == 0 or not np.all(np.isfinite(values)):
        return float("nan"), float("nan")
    s = float(np.max(np.abs(values))) or 1.0
    below, above = detectable_ratios(
        float(np.exp(point / s)), float(np.exp(low / s)), float(np.exp(high / s)),
        np.exp(r / s), power,
    )  # fmt: skip
    return s * float(np.log(below)), s * float(np.log(above))


@dataclass(frozen=True)
class Difference:
    """One paired difference ``a - b`` with its 95 % interval over ``n_groups`` groups
    and its power (``detectable``: :func:`detectable_differences`; None: unknown)."""

    a: str
    b: str
    difference: float
    ci95: tuple[float, float]
    n_groups: int
    group: str = "episodes"
    quantity: str = "median catches before the first drop"
    higher_is_better: bool = True
    detectable: tuple[float, float] | None = None

    @property
    def verdict(self) -> str:
        """``"better"`` or ``"worse"`` (for ``a``, the interval off 0 in the direction
        that is better or worse), ``"no difference"``, or ``"cannot decide"`` with fewer
        than :data:`~baselines.stats.MIN_GROUPS` groups."""
        lo, hi = self.ci95
        if self.n_groups < MIN_GROUPS:
            return "cannot decide"
        if lo > 0 or hi < 0:
            return "better" if (lo > 0) == self.higher_is_better else "worse"
        return "no difference"

    @property
    def decidable(self) -> bool | None:
        """Whether the claimed difference is at least the one detected with probability
        :data:`~baselines.stats.POWER` in its direction (None: power unknown)."""
        if self.detectable is None or not all(np.isfinite(self.detectable)):
            return None
        below, above = self.detectable
        if self.difference <= 0:  # as the ratios': no difference is judged on the low side
            return bool(self.difference <= below)
        return bool(self.difference >= above)

    def sentence(self) -> str:
        """The verdict in words, with "cannot decide at this size" where the claimed
        difference is below the detectable one."""
        return verdict_sentence(
            self.verdict, self.a, self.b, self.n_groups, self.group, self.decidable, "0"
        )

    def power_text(self) -> str:
        """The power line: the differences detected 80 % of the time at this many groups
        and whether the claimed one reaches the one in its direction."""
        if self.detectable is None or self.decidable is None:
            return f"power at {self.n_groups} {self.group}: unknown"
        below, above = self.detectable
        side = below if self.difference <= 0 else above
        text = (
            f"{POWER:.0%} power at {self.n_groups} {self.group} for differences <= "
            f"{below:+.3g} or >= {above:+.3g}; the claimed {self.difference:+.3g} "
            + ("reaches" if self.decidable else "is below")
            + f" the detectable {side:+.3g}"
        )
        lo, hi = self.ci95
        if lo < hi and self.difference in (lo, hi):
            text += (
                " (discrete replicates: an interval end at the point, the threshold on "
                "that side is a lower bound)"
            )
        return text

    def power_cell(self) -> str:
        """The power line in a table cell: ``<= below or >= above``, and ``cannot decide
        at this size`` or ``below it`` where the claimed difference is below it."""
        if self.detectable is None or self.decidable is None:
            return "unknown"
        below, above = self.detectable
        text = f"<= {below:+.3g} or >= {above:+.3g}"
        if self.decidable:
            return text
        return text + ("; cannot decide at this size" if self.verdict == "no difference" else
                       "; the claimed is below it")  # fmt: skip

    def line(self) -> str:
        """One printed line: difference, interval, direction, verdict, power."""
        lo, hi = self.ci95
        better = "higher" if self.higher_is_better else "lower"
        return (
            f"{self.quantity} {self.a} - {self.b} = {self.difference:+.4g} (95% CI "
            f"{lo:+.4g} to {hi:+.4g}, paired over {self.n_groups} {self.group}; {better} is "
            f"better): {self.sentence()}; {self.power_text()}"
        )

    def to_dict(self) -> dict[str, Any]:
        """The ``results.json`` entry."""
        return {
            "a": self.a,
            "b": self.b,
            "quantity": self.quantity,
            "difference": self.difference,
            "ci95": list(self.ci95),
            "n_groups": self.n_groups,
            "group": self.group,
            "higher_is_better": self.higher_is_better,
            "verdict": self.verdict,
            "power": POWER,
            "detectable_differences": None if self.detectable is None else list(self.detectable),
            "decidable": self.decidable,
            "sentence": self.sentence(),
            "power_line": self.power_text(),
        }


def compare_difference(
    statistic: Callable[[NDArray[np.int64]], float],
    groups: ArrayLike,
    a: str,
    b: str,
    quantity: str,
    group: str = "episodes",
    higher_is_better: bool = True,
    n_resamples: int = N_RESAMPLES,
    seed: int = 0,
) -> Difference:
    """``statistic(rows)`` (a's statistic minus b's on those rows: both methods' rows of
    a group are resampled together) with its 95 % interval over ``groups`` and power."""
    point, lo, hi, reps = group_bootstrap_replicates(statistic, groups, None, n_resamples, seed)
    n = int(np.unique(np.asarray(groups).astype(str)).size)
    detectable = detectable_differences(point, lo, hi, reps)
    return Difference(a, b, point, (lo, hi), n, group, quantity, higher_is_better, detectable)


def paired_mean_difference(
    values_a: ArrayLike,
    values_b: ArrayLike,
    a: str,
    b: str,
    quantity: str = "mean catches before the first drop",
    group: str = "episodes",
    higher_is_better: bool = True,
    seed: int = 0,
) -> Difference:
    """The mean of ``values_a - values_b`` (one pair per group: the same seed played by
    both) with its 95 % paired bootstrap interval and power (:func:`compare_difference`)."""
    d = np.asarray(values_a, dtype=np.float64) - np.asarray(values_b, dtype=np.float64)
    if d.ndim != 1 or d.size == 0:
        raise ValueError(f"values_a and values_b must be (n,) each, n >= 1; got {d.shape}")
    return compare_difference(
        lambda rows: float(d[rows].mean()), np.arange(d.size), a, b, quantity, group,
        higher_is_better, seed=seed,
    )  # fmt: skip
