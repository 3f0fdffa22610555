"""baselines.stats: the group bootstrap against closed forms, its exact invariances, win
counts against a pandas oracle, verdicts, and the rliable wrappers."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from scipy import stats as sps

from baselines.stats import (
    Comparison,
    compare_errors,
    group_bootstrap,
    group_wins,
    intervals_document,
    iqm_intervals,
    probability_of_improvement,
    statistic_interval,
    verdict,
)


def test_mean_of_normal_data_matches_the_closed_form_interval():
    rng = np.random.default_rng(7)
    x = rng.normal(2.0, 3.0, 3000)
    point, lo, hi = statistic_interval(x, np.arange(x.size), statistic=np.mean, seed=1)
    half = 1.96 * x.std(ddof=1) / np.sqrt(x.size)
    assert point == x.mean()
    assert lo == pytest.approx(x.mean() - half, abs=0.08 * half)
    assert hi == pytest.approx(x.mean() + half, abs=0.08 * half)


def test_stratified_mean_matches_the_stratified_variance():
    """Two strata of unequal size and spread: the half-width of the pooled mean is
    1.96 sqrt(sum_h (n_h / N)^2 s_h^2 / n_h), the stratified sampling variance."""
    rng = np.random.default_rng(3)
    a, b = rng.normal(0.0, 1.0, 2000), rng.normal(5.0, 4.0, 1000)
    x = np.concatenate([a, b])
    strata = np.repeat(["a", "b"], [a.size, b.size])
    _, lo, hi = statistic_interval(x, np.arange(x.size), strata, statistic=np.mean, seed=2)
    N = x.size
    var = sum((s.size / N) ** 2 * s.var(ddof=1) / s.size for s in (a, b))
    assert (hi - lo) / 2 == pytest.approx(1.96 * np.sqrt(var), rel=0.08)
    # unstratified, the between-strata spread inflates the interval
    _, lo_u, hi_u = statistic_interval(x, np.arange(x.size), statistic=np.mean, seed=2)
    assert hi_u - lo_u > 1.2 * (hi - lo)


def test_groups_not_rows_are_resampled():
    """Rows repeated within a group carry no extra information: the interval is that of
    one row per group, not sqrt(rows per group) narrower."""
    rng = np.random.default_rng(0)
    per_group = rng.normal(1.0, 1.0, 40)
    rows = np.repeat(per_group, 25)
    groups = np.repeat(np.arange(40), 25)
    _, lo, hi = statistic_interval(rows, groups, statistic=np.mean, seed=4)
    _, lo1, hi1 = statistic_interval(per_group, np.arange(40), statistic=np.mean, seed=4)
    assert lo == pytest.approx(lo1, rel=1e-12) and hi == pytest.approx(hi1, rel=1e-12)
    _, lo_r, hi_r = statistic_interval(rows, np.arange(rows.size), statistic=np.mean, seed=4)
    assert (hi - lo) > 3 * (hi_r - lo_r)


def _data(seed=0, n_groups=9, per=12):
    rng = np.random.default_rng(seed)
    groups = np.repeat([f"p{i}" for i in range(n_groups)], per)
    a = rng.gamma(3.0, 0.05, groups.size) * np.repeat(rng.uniform(0.8, 1.2, n_groups), per)
    b = a * rng.uniform(0.9, 1.3, groups.size)
    return a, b, groups


def test_ratio_interval_exact_invariances():
    a, b, g = _data()
    base = compare_errors(a, b, g, "A", "B")
    assert base.ratio == np.median(a) / np.median(b)
    assert base.ci95[0] <= base.ratio <= base.ci95[1]
    # same seed: the same interval; another seed: another
    assert compare_errors(a, b, g, "A", "B").ci95 == base.ci95
    assert compare_errors(a, b, g, "A", "B", seed=1).ci95 != base.ci95
    # a common unit (radians -> degrees) cancels; scaling A scales the ratio
    scaled = compare_errors(a * 57.3, b * 57.3, g, "A", "B")
    np.testing.assert_allclose(scaled.ci95, base.ci95, rtol=1e-12)
    doubled = compare_errors(2 * a, b, g, "A", "B")
    np.testing.assert_allclose(doubled.ci95, 2 * np.array(base.ci95), rtol=1e-12)
    # the order of the rows does not matter
    perm = np.random.default_rng(5).permutation(a.size)
    shuffled = compare_errors(a[perm], b[perm], g[perm], "A", "B")
    assert shuffled.ci95 == base.ci95 and shuffled.wins == base.wins
    # a method against itself: exactly 1, no difference
    same = compare_errors(a, a, g, "A", "A")
    assert same.ci95 == (1.0, 1.0) and same.verdict == "no difference" and same.wins == 0


def test_win_count_matches_a_pandas_oracle():
    a, b, g = _data(seed=2)
    frame = pd.DataFrame({"g": g, "a": a, "b": b}).groupby("g").median()
    assert group_wins(a, b, g) == (int((frame.a < frame.b).sum()), len(frame))
    c = compare_errors(a, b, g, "A", "B")
    assert (c.wins, c.n_groups) == group_wins(a, b, g)


def test_verdicts_in_words():
    assert verdict(0.8, 0.95) == "better"
    assert verdict(1.01, 1.2) == "worse"
    assert verdict(0.9, 1.1) == "no difference"
    c = Comparison("mlp", "null", 0.9, (0.8, 0.95), 7, 8)
    line = c.line()
    assert "mlp / null = 0.900" in line and "95% CI 0.800-0.950 over 8 people" in line
    assert "lower on 7/8 people" in line and "mlp is BETTER than null at 95 %" in line
    assert c.to_dict()["lower_is_better"] is True and c.to_dict()["unit"] == "rad"
    assert intervals_document([c]) == {"mlp / null": [0.8, 0.95]}
    worse = Comparison("a", "b", 1.2, (1.1, 1.3), 0, 8).sentence()
    assert worse == "a is WORSE than b at 95 %"


def test_strata_rules():
    a, _, g = _data()
    strata = np.where(np.isin(g, ["p0", "p1", "p2"]), "s1", "s2")
    strata[0] = "s2"  # p0 now lies in two strata
    with pytest.raises(ValueError, match="several strata"):
        group_bootstrap(lambda rows: float(a[rows].mean()), g, strata)
    # a stratum with a single group keeps it in every replicate
    one = np.where(g == "p0", "alone", "rest")
    point, lo, hi = group_bootstrap(lambda rows: float(np.sum(rows < 12)), g, one)
    assert point == lo == hi == 12.0  # p0's 12 rows are always drawn once


def test_rliable_iqm_and_probability_of_improvement():
    pytest.importorskip("rliable")
    rng = np.random.default_rng(0)
    scores = rng.normal(1.0, 0.3, (6, 4))
    got = iqm_intervals({"m": scores}, reps=500)["m"]
    assert got["iqm"] == pytest.approx(sps.trim_mean(scores.ravel(), 0.25), rel=1e-12)
    assert got["ci95"][0] < got["iqm"] < got["ci95"][1]
    low, high = scores, scores + 1.0
    assert probability_of_improvement(low, high) == 1.0  # errors: lower is better
    assert probability_of_improvement(low, high, lower_is_better=False) == 0.0
    assert probability_of_improvement(low, low) == 0.5
