"""The statistics of repeated trials against textbook values, scipy and seeded simulation."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.stats import wilcoxon

from compliant_docking.results import stats


@pytest.mark.parametrize(
    "successes, trials, low, high",
    [  # Newcombe (1998), Stat. Med. 17:857, Table II, method 3 (Wilson score, no correction)
        (81, 263, 0.2553, 0.3662),
        (15, 148, 0.0624, 0.1605),
        (0, 20, 0.0, 0.1611),
        (1, 29, 0.0061, 0.1718),
    ],
)
def test_wilson_interval_matches_the_textbook(successes, trials, low, high):
    got = stats.wilson(successes, trials)
    # the table gives 4 decimals: half a unit of the last one
    assert got == pytest.approx((low, high), abs=5e-5)


def test_wilson_interval_edges():
    assert all(math.isnan(v) for v in stats.wilson(0, 0))  # no trials: no interval
    low, high = stats.wilson(10, 10)
    # all docked: still an interval, not [1, 1]: n/(n + z²) = 10/13.84 = 0.7225
    assert high == pytest.approx(1.0) and low == pytest.approx(10 / (10 + 1.959964**2), abs=1e-6)
    with pytest.raises(ValueError, match="within"):
        stats.wilson(3, 2)


def test_bootstrap_interval_covers_the_true_mean_and_median_about_95_percent_of_the_time():
    """1000 seeded samples of 30 normal values: the percentile bootstrap's 95 % interval of the
    mean behaves like x̄ ± 1.96·s/√n with s the plug-in deviation, whose coverage at n = 30
    is P(|t₂₉| ≤ 1.96·√(29/30)) = 0.936 (the known small-sample undercoverage). Accepted:
    within 0.012 of that plug-in interval's coverage on the same samples (the resampling's
    own noise, ~2000 resamples) and within ±0.025 (3 binomial standard errors of 1000
    repetitions) of 0.936. The median's interval jumps between order statistics and
    covers a little more: 0.91-0.99."""
    rng = np.random.default_rng(7)
    samples = rng.normal(0.0, 1.0, size=(1000, 30))
    summaries = [stats.bootstrap_ci(x, f"sample {i}") for i, x in enumerate(samples)]
    mean_cover = np.mean([s.mean_low <= 0.0 <= s.mean_high for s in summaries])
    median_cover = np.mean([s.median_low <= 0.0 <= s.median_high for s in summaries])
    plug_in = np.abs(samples.mean(axis=1)) <= 1.96 * samples.std(axis=1) / np.sqrt(30)
    assert abs(mean_cover - plug_in.mean()) <= 0.012, (mean_cover, plug_in.mean())
    assert abs(mean_cover - 0.936) <= 0.025, mean_cover
    assert 0.91 <= median_cover <= 0.99, median_cover


def test_bootstrap_is_seeded_by_name_not_by_order():
    x = np.arange(10.0) ** 2
    a = stats.bootstrap_ci(x, "fr3 · hqp|first_strike_force_N")
    stats.bootstrap_ci(x, "something else")  # another stream in between changes nothing
    b = stats.bootstrap_ci(x, "fr3 · hqp|first_strike_force_N")
    c = stats.bootstrap_ci(x, "fr3 · impedance|first_strike_force_N")
    assert a == b and a != c
    assert a.n == 10 and a.mean == pytest.approx(28.5) and a.median == pytest.approx(20.5)
    one = stats.bootstrap_ci([3.0, math.nan], "x")  # NaN dropped; one value: no spread known
    assert one.n == 1 and one.mean_low == one.mean_high == 3.0
    assert stats.bootstrap_ci([], "x").n == 0


def test_paired_test_is_scipys_wilcoxon_with_effect_sizes():
    rng = np.random.default_rng(3)
    a = rng.normal(20.0, 5.0, 15)
    b = a - 4.0 + rng.normal(0.0, 3.0, 15)
    result = stats.paired(a, b, "case")
    reference = wilcoxon(b - a)
    assert result.p_value == reference.pvalue and result.statistic == reference.statistic
    assert result.method == "exact" and result.n == 15
    assert result.median_difference == pytest.approx(np.median(b - a))
    assert result.difference_low <= result.median_difference <= result.difference_high
    assert result.relative_change == pytest.approx(np.median(b) / np.median(a) - 1)
    assert result.relative_low <= result.relative_change <= result.relative_high
    assert -1.0 <= result.rank_biserial < 0.0  # b mostly smaller


def test_paired_test_exact_values():
    # 8 pairs, all b > a: the exact two-sided p is 2/2^8, and r = +1
    result = stats.paired(np.zeros(8), np.arange(1.0, 9.0))
    assert result.p_value == pytest.approx(2 / 256, rel=1e-12) and result.rank_biserial == 1.0
    # r = (R+ − R−)/(R+ + R−): d = 1, −2, 3, 4 have ranks 1..4 → (1 + 3 + 4 − 2)/10
    assert stats.rank_biserial([1.0, -2.0, 3.0, 4.0]) == pytest.approx(0.6)
    # a NaN on either side drops its pair; every difference zero: nothing to test, p = 1
    nan_pair = stats.paired([1.0, 2.0, np.nan, 4.0], [1.0, 2.0, 3.0, 4.0])
    assert nan_pair.n == 3 and nan_pair.p_value == 1.0 and nan_pair.rank_biserial == 0.0
    # zeros among the differences: scipy's permutation test (≤ 13 pairs), p as scipy gives it
    d = np.array([0.0, 1.0, 2.0, 3.0, 4.0, 5.0, -0.5])
    tied = stats.paired(np.zeros(7), d)
    assert tied.method == "permutation" and tied.p_value == wilcoxon(d).pvalue
    with pytest.raises(ValueError, match="equal lengths"):
        stats.paired([1.0], [1.0, 2.0])


def test_mcnemar_counts_discordant_pairs():
    a = np.array([True] * 10)
    b = np.array([True] * 4 + [False] * 6)
    assert stats.mcnemar(a, b) == (6, 0, pytest.approx(2 * 0.5**6))
    assert stats.mcnemar(a, a) == (0, 0, 1.0)


def test_holm_on_a_known_example():
    # four tests at α = 0.05 (Holm 1979's step-down; e.g. Wikipedia's example): sorted
    # 0.005·4 = 0.02, 0.01·3 = 0.03, 0.03·2 = 0.06, 0.04·1 = 0.04 → monotone 0.06
    adjusted = stats.holm([0.01, 0.04, 0.03, 0.005])
    assert adjusted == pytest.approx([0.03, 0.06, 0.06, 0.02])
    assert list(adjusted <= 0.05) == [True, False, False, True]
    # NaN is no test: left out of the family (m = 2 here), and capped at 1
    assert np.allclose(stats.holm([0.6, np.nan, 0.01]), [0.6, np.nan, 0.02], equal_nan=True)
    assert stats.holm([0.9, 0.8])[0] == 1.0


def test_paired_test_without_pairs_is_empty_not_an_error():
    # no pair with both values (e.g. no draw docked on both sides for the docking time)
    empty = stats.paired([np.nan, 1.0], [2.0, np.nan])
    assert empty.n == 0 and math.isnan(empty.p_value) and empty.method == "none"
