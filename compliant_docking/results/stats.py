"""Statistics of repeated trials: intervals, paired tests and multiple-comparison correction.

Plain functions on numpy arrays (no pandas, no run directories); the frame-level tables that
use them are in :mod:`compliant_docking.results.compare`.

- :func:`wilson`: the Wilson score interval of a success rate (Wilson 1927; Newcombe 1998,
  method 3, no continuity correction);
- :func:`bootstrap_ci`: the seeded percentile bootstrap interval of the mean and the median;
- :func:`paired`: the paired comparison of two matched samples: Wilcoxon's signed-rank test
  (scipy), the matched-pairs rank-biserial correlation, the median of the differences with
  its bootstrap interval and the relative change of the medians with its bootstrap interval;
- :func:`mcnemar`: McNemar's exact test of two paired success indicators;
- :func:`holm`: Holm's step-down adjustment of a family of p-values.

Every bootstrap is seeded (``numpy.random.SeedSequence([seed, crc32(name)])``): the same
data, seed and name give the same interval on any machine, whatever else was computed.
"""

from __future__ import annotations

import math
import zlib
from dataclasses import dataclass
from statistics import NormalDist

import numpy as np

#: confidence level of every interval
LEVEL = 0.95
#: bootstrap resamples and the default seed
RESAMPLES = 2000
SEED = 20260611


def _rng(seed: int, name: str) -> np.random.Generator:
    return np.random.default_rng(np.random.SeedSequence([int(seed), zlib.crc32(name.encode())]))


def _z(level: float) -> float:
    """The two-sided normal quantile: the standard library's, since importing scipy.stats
    for it cost the end of every sweep about 0.5 s (Wilcoxon imports it when pairs exist)."""
    return NormalDist().inv_cdf(0.5 + level / 2)


def wilson(successes: int, trials: int, level: float = LEVEL) -> tuple[float, float]:
    """Wilson score interval of ``successes``/``trials``; (nan, nan) for no trials.

    (p̂ + z²/2n ± z·√(p̂(1−p̂)/n + z²/4n²)) / (1 + z²/n), z the normal quantile. Unlike the
    Wald interval it stays inside [0, 1] and does not collapse at 0 or n successes.
    """
    if trials <= 0:
        return math.nan, math.nan
    if not 0 <= successes <= trials:
        raise ValueError(f"successes must be within [0, trials], got {successes} of {trials}")
    z = _z(level)
    p = successes / trials
    denominator = 1 + z * z / trials
    centre = (p + z * z / (2 * trials)) / denominator
    half = z * math.sqrt(p * (1 - p) / trials + z * z / (4 * trials * trials)) / denominator
    return max(0.0, centre - half), min(1.0, centre + half)


def _percentile(samples: np.ndarray, level: float) -> tuple[float, float]:
    low, high = np.quantile(samples, [(1 - level) / 2, (1 + level) / 2])
    return float(low), float(high)


def resample_indices(n: int, name: str, seed: int = SEED, resamples: int = RESAMPLES) -> np.ndarray:
    """``resamples`` × ``n`` indices drawn with replacement (the seeded bootstrap draws)."""
    return _rng(seed, name).integers(0, n, size=(resamples, n))


@dataclass(frozen=True)
class Summary:
    """Location of one sample with its bootstrap intervals (NaN where undefined)."""

    n: int
    mean: float
    mean_low: float
    mean_high: float
    median: float
    median_low: float
    median_high: float
    minimum: float
    maximum: float


def bootstrap_ci(
    values,
    name: str = "",
    *,
    seed: int = SEED,
    resamples: int = RESAMPLES,
    level: float = LEVEL,
    median: bool = True,
) -> Summary:
    """Mean and median of the finite ``values`` with seeded percentile-bootstrap intervals.

    ``name`` picks the random stream (e.g. configuration and metric), so intervals do not
    depend on the order in which they are computed. One value gives its value as both
    bounds (no spread is known); none gives NaN. ``median=False`` skips the median's
    interval (NaN; sorting every resample is most of the cost).
    """
    x = np.asarray(values, dtype=float)
    x = x[np.isfinite(x)]
    n = len(x)
    if n == 0:
        return Summary(0, *([math.nan] * 8))
    mean, middle = float(x.mean()), float(np.median(x))
    if n == 1:
        return Summary(1, mean, mean, mean, middle, middle, middle, mean, mean)
    draws = x[resample_indices(n, name, seed, resamples)]
    mean_ci = _percentile(draws.mean(axis=1), level)
    median_ci = _percentile(np.median(draws, axis=1), level) if median else (math.nan, math.nan)
    return Summary(n, mean, *mean_ci, middle, *median_ci, float(x.min()), float(x.max()))


@dataclass(frozen=True)
class Paired:
    """Paired comparison of b against a on the same draws (differences b − a)."""

    n: int  # pairs with both values finite
    median_a: float
    median_b: float
    median_difference: float  # median of b − a
    difference_low: float
    difference_high: float
    relative_change: float  # median(b) / median(a) − 1
    relative_low: float
    relative_high: float
    rank_biserial: float  # matched-pairs rank-biserial correlation, in [−1, 1] (+: b larger)
    statistic: float  # Wilcoxon's T (scipy: the smaller of the signed-rank sums)
    p_value: float  # two-sided, Wilcoxon signed-rank (scipy.stats.wilcoxon)
    method: str  # scipy's choice: exact, permutation (zeros or ties, ≤ 13 pairs), normal approximation


def rank_biserial(differences) -> float:
    """Matched-pairs rank-biserial correlation (Kerby 2014): (R₊ − R₋)/(R₊ + R₋), the signed
    ranks of |d| over the non-zero differences; 0 when every difference is zero."""
    from scipy.stats import rankdata

    d = np.asarray(differences, dtype=float)
    d = d[d != 0]
    if not len(d):
        return 0.0
    ranks = rankdata(np.abs(d))
    return float((ranks[d > 0].sum() - ranks[d < 0].sum()) / ranks.sum())


def paired(
    a, b, name: str = "", *, seed: int = SEED, resamples: int = RESAMPLES, level: float = LEVEL
) -> Paired:
    """Compare ``b`` with ``a`` pair by pair (equal lengths; pairs with a NaN are left out).

    Wilcoxon's signed-rank test, two-sided, as ``scipy.stats.wilcoxon(b − a)`` computes it
    (zero differences dropped, ``zero_method="wilcox"``; ``method="auto"``: the exact null
    distribution for up to 50 pairs without zeros or ties, an exhaustive permutation test
    for up to 13 pairs with them, else the normal approximation); p = 1 when every
    difference is zero. Effect sizes: the rank-biserial correlation, the median of the
    differences and the relative change of the medians, with seeded percentile-bootstrap
    intervals over the pairs.
    """
    from scipy.stats import wilcoxon

    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if a.shape != b.shape:
        raise ValueError(f"paired samples must have equal lengths, got {len(a)} and {len(b)}")
    keep = np.isfinite(a) & np.isfinite(b)
    a, b = a[keep], b[keep]
    n = len(a)
    nan = math.nan
    if n == 0:
        return Paired(0, nan, nan, nan, nan, nan, nan, nan, nan, nan, nan, nan, "none")
    d = b - a
    med_a, med_b = float(np.median(a)), float(np.median(b))
    relative = med_b / med_a - 1 if med_a != 0 else nan
    if n == 1:
        return Paired(1, med_a, med_b, float(d[0]), nan, nan, relative, nan, nan, nan, nan, nan, "none")
    idx = resample_indices(n, name, seed, resamples)
    diff_ci = _percentile(np.median(d[idx], axis=1), level)
    boot_a = np.median(a[idx], axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratios = np.median(b[idx], axis=1) / boot_a - 1
    ratios = ratios[np.isfinite(ratios)]
    rel_ci = _percentile(ratios, level) if len(ratios) else (nan, nan)
    if np.all(d == 0):
        statistic, p, method = 0.0, 1.0, "all equal"
    else:
        clean = np.all(d != 0) and len(np.unique(np.abs(d))) == n  # no zeros, no ties
        method = "exact" if clean and n <= 50 else ("permutation" if n <= 13 else "normal approximation")
        result = wilcoxon(d, zero_method="wilcox", alternative="two-sided", method="auto")
        statistic, p = float(result.statistic), float(result.pvalue)
    return Paired(
        n,
        med_a,
        med_b,
        float(np.median(d)),
        *diff_ci,
        relative,
        *rel_ci,
        rank_biserial(d),
        statistic,
        p,
        method,
    )


def mcnemar(a, b) -> tuple[int, int, float]:
    """McNemar's exact test of paired success indicators (True/False per draw).

    Returns (a only, b only, two-sided p): the draws where only ``a`` succeeded, only ``b``
    did, and the binomial test of those discordant pairs against 1/2 (p = 1 without any).
    """
    from scipy.stats import binomtest

    a, b = np.asarray(a, dtype=bool), np.asarray(b, dtype=bool)
    only_a, only_b = int(np.sum(a & ~b)), int(np.sum(b & ~a))
    if only_a + only_b == 0:
        return 0, 0, 1.0
    return only_a, only_b, float(binomtest(only_b, only_a + only_b, 0.5).pvalue)


def holm(p_values) -> np.ndarray:
    """Holm's step-down adjusted p-values (same order as given; NaN stays NaN and is not
    counted in the family): sorted ascending, p₍ᵢ₎·(m − i + 1), made monotone, capped at 1.
    A hypothesis is rejected at level α when its adjusted p-value is ≤ α."""
    p = np.asarray(p_values, dtype=float)
    out = np.full(p.shape, math.nan)
    valid = np.flatnonzero(np.isfinite(p))
    m = len(valid)
    if not m:
        return out
    order = valid[np.argsort(p[valid], kind="stable")]
    adjusted = np.maximum.accumulate(p[order] * (m - np.arange(m)))
    out[order] = np.minimum(adjusted, 1.0)
    return out
