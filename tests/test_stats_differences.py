"""Paired differences with the power line (baselines.stats.Difference): the detectable
differences are the ratio helper's on the additive scale (closed form for normal
replicates, and detected about 80 % of the time by simulated studies), the words say
"cannot decide at this size" where the claimed difference is below them."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import norm

from baselines.stats import Difference, compare_difference, detectable_differences


def test_detectable_differences_closed_form_for_normal_replicates():
    """Normal replicates with standard error se and the interval +-1.96 se: the
    difference detected 80 % of the time is (1.96 + 0.84) se on either side, whatever the
    point and the scale (the oracle: the normal quantiles, not the helper)."""
    z = norm.ppf(0.975)
    for point, se in ((0.3, 0.05), (-4.0, 2.5), (120.0, 30.0)):
        d = norm.ppf((np.arange(200_000) + 0.5) / 200_000) * se
        below, above = detectable_differences(point, point - z * se, point + z * se, point + d)
        k = (z + norm.ppf(0.8)) * se
        assert below == pytest.approx(-k, rel=1e-4)
        assert above == pytest.approx(k, rel=1e-4)
    # a point interval detects every difference; a non-finite one is unknown
    assert detectable_differences(1.0, 1.0, 1.0, [1.0, 1.0]) == (0.0, 0.0)
    assert detectable_differences(0.0, 0.0, 0.0, [0.0]) == (0.0, 0.0)
    assert all(np.isnan(detectable_differences(1.0, 0.0, np.inf, [1.0, 2.0])))
    assert all(np.isnan(detectable_differences(1.0, 0.0, 2.0, [])))


def test_detectable_difference_is_detected_80_percent_of_the_time():
    """Studies of 30 paired groups whose true difference is the detectable one (estimated
    on pilot studies of the same size at no difference) say BETTER in about 80 % of them;
    half of it far less often."""
    rng = np.random.default_rng(5)
    n, reps = 30, 400

    def study(theta: float) -> Difference:
        b = rng.normal(5.0, 2.0, n)
        a = b + theta + rng.normal(0.0, 1.0, n)
        return compare_difference(
            lambda rows: float(np.mean(a[rows]) - np.mean(b[rows])), np.arange(n), "a", "b",
            "mean", n_resamples=reps,
        )  # fmt: skip

    pilot = [study(0.0).detectable for _ in range(30)]
    theta = float(np.mean([p[1] for p in pilot]))
    assert 0.3 < theta < 0.8  # about 2.8 / sqrt(30) = 0.51
    hits = [study(theta).verdict == "better" for _ in range(150)]
    assert 0.68 <= np.mean(hits) <= 0.92
    half = [study(theta / 2).verdict == "better" for _ in range(60)]
    assert np.mean(half) < 0.5


def test_difference_words_and_power_line():
    small = Difference("agent", "juggler", 0.5, (-1.0, 2.0), 40, detectable=(-1.8, 1.9))
    assert small.decidable is False and small.verdict == "no difference"
    assert small.sentence() == (
        "no difference at 95 % (the interval contains 0); cannot decide at this size"
    )
    line = small.line()
    assert "80% power at 40 episodes for differences <= -1.8 or >= +1.9" in line
    assert "the claimed +0.5 is below the detectable +1.9" in line
    big = Difference("agent", "juggler", 3.0, (1.5, 4.0), 40, detectable=(-1.8, 1.9))
    assert big.decidable and big.sentence() == "agent is BETTER than juggler at 95 %"
    assert "the claimed +3 reaches the detectable +1.9" in big.power_text()
    # lower is better: a negative difference off 0 is better; a small one is flagged
    lower = Difference("a", "b", -0.2, (-0.3, -0.1), 40, higher_is_better=False,
                       detectable=(-0.25, 0.25))  # fmt: skip
    assert lower.verdict == "better" and "below the one this size detects" in lower.sentence()
    worse = Difference("a", "b", -3.0, (-4.0, -2.0), 40, detectable=(-1.8, 1.9))
    assert worse.verdict == "worse" and worse.decidable
    assert Difference("a", "b", 1.0, (0.0, 2.0), 3).verdict == "cannot decide"
    assert "power at 40 episodes: unknown" in Difference("a", "b", 1.0, (0.0, 2.0), 40).line()
    # no difference is judged on the low side (as a ratio of 1); a point at an interval
    # end (discrete replicates) is flagged
    zero = Difference("a", "b", 0.0, (0.0, 1.0), 40, detectable=(-1.5, 0.0))
    assert zero.decidable is False and zero.sentence().endswith("cannot decide at this size")
    assert "the claimed +0 is below the detectable -1.5 (discrete replicates" in zero.line()
    assert "discrete" not in small.line()
    doc = small.to_dict()
    assert doc["detectable_differences"] == [-1.8, 1.9] and doc["decidable"] is False
    assert doc["power_line"] == small.power_text() and doc["sentence"] == small.sentence()


def test_compare_difference_is_the_paired_bootstrap():
    """The interval and replicates are group_bootstrap_replicates' on the same rows, and
    the power is detectable_differences of them (the same seed gives the same numbers)."""
    from baselines.stats import group_bootstrap_replicates

    rng = np.random.default_rng(2)
    a, b = rng.integers(0, 30, 50).astype(float), rng.integers(0, 30, 50).astype(float)

    def stat(rows):
        return float(np.median(a[rows]) - np.median(b[rows]))

    c = compare_difference(stat, np.arange(50), "a", "b", "median", seed=4)
    point, lo, hi, reps = group_bootstrap_replicates(stat, np.arange(50), seed=4)
    assert (c.difference, c.ci95, c.n_groups) == (point, (lo, hi), 50)
    assert c.detectable == detectable_differences(point, lo, hi, reps)


def test_paired_mean_difference_and_its_table_cell():
    """The mean of the per-seed differences with the paired interval (the mean of
    normal differences: mean +- 1.96 sd / sqrt(n), closely); a constant gain has a point
    interval; the table cell says where the claimed difference is below the detectable."""
    from baselines.stats import paired_mean_difference

    rng = np.random.default_rng(9)
    before = rng.integers(0, 30, 400).astype(float)
    after = before + rng.normal(0.2, 3.0, 400)
    d = paired_mean_difference(after, before, "after", "before")
    half = 1.96 * np.std(after - before, ddof=1) / np.sqrt(400)
    assert d.difference == pytest.approx(np.mean(after - before))
    assert d.ci95 == pytest.approx((d.difference - half, d.difference + half), abs=0.06)
    assert d.power_cell().endswith("; cannot decide at this size")  # 0.2 against ~0.42
    assert d.power_cell().startswith("<= -0.")
    sure = paired_mean_difference(before + 1, before, "after", "before")
    assert sure.ci95 == (1.0, 1.0) and sure.power_cell() == "<= +0 or >= +0"
    with pytest.raises(ValueError, match="values_a and values_b"):
        paired_mean_difference([], [], "a", "b")
