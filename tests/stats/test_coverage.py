"""Coverage of the truth by the reported errors, with exact binomial intervals."""

from __future__ import annotations

import math

import numpy as np
import pytest
from astropy.table import Table
from scipy import stats as sps

from eclipsebench.errors import InputError
from eclipsebench.stats.ensemble import (
    GAUSS_1SIGMA,
    GAUSS_2SIGMA,
    binomial_interval,
    coverage,
    method_statistics,
    normalised_residuals,
)
from eclipsebench.stats.summary import summarize

TRUTH = 1875.0


def depths_with(n: int, k1: int, k2: int, sigma: float = 100.0) -> tuple[np.ndarray, np.ndarray]:
    """n epochs: exactly k1 within 1 sigma of the truth, k2 (>= k1) within 2 sigma."""
    z = np.concatenate([np.full(k1, 0.5), np.full(k2 - k1, 1.5), np.full(n - k2, 3.0)])
    z[1::2] *= -1  # both sides of the truth
    return TRUTH + z * sigma, np.full(n, sigma)


def test_gaussian_probabilities():
    assert GAUSS_1SIGMA == pytest.approx(sps.norm.cdf(1) - sps.norm.cdf(-1))
    assert GAUSS_2SIGMA == pytest.approx(sps.norm.cdf(2) - sps.norm.cdf(-2))
    assert round(GAUSS_1SIGMA, 4) == 0.6827 and round(GAUSS_2SIGMA, 4) == 0.9545


@pytest.mark.parametrize("n, k", [(10, 0), (10, 3), (10, 7), (10, 10), (100, 68), (100, 95),
                                  (100, 100), (1, 0), (1, 1), (37, 20)])
@pytest.mark.parametrize("level", [0.68, 0.95])
def test_interval_is_scipys_exact_interval(n, k, level):
    ci = sps.binomtest(k, n).proportion_ci(confidence_level=level, method="exact")
    lo, hi = binomial_interval(k, n, level)
    assert lo == pytest.approx(ci.low, abs=1e-12)
    assert hi == pytest.approx(ci.high, abs=1e-12)


@pytest.mark.parametrize("n", [1, 10, 100])
def test_interval_at_the_ends_is_analytic(n):
    # k = 0: P(0 successes) = (1 - p)^n = 0.16 at the upper bound; k = n mirrors it
    assert binomial_interval(0, n) == (0.0, pytest.approx(1 - 0.16 ** (1 / n)))
    assert binomial_interval(n, n) == (pytest.approx(0.16 ** (1 / n)), 1.0)


def test_interval_tails_are_16_percent():
    # the defining property: at the bounds, P(X >= k) and P(X <= k) are 16%
    lo, hi = binomial_interval(7, 10)
    assert sps.binom.sf(6, 10, lo) == pytest.approx(0.16)
    assert sps.binom.cdf(7, 10, hi) == pytest.approx(0.16)


def test_interval_rejects_impossible_counts():
    for k, n in ((11, 10), (-1, 10), (0, 0)):
        with pytest.raises(InputError, match="binomial interval"):
            binomial_interval(k, n)


def test_normalised_residuals_by_hand():
    z = normalised_residuals([1975.0, 1675.0, 1875.0], [100.0, 50.0, 10.0], TRUTH)
    assert z.tolist() == [1.0, -4.0, 0.0]


@pytest.mark.parametrize("n, k1, k2", [(10, 7, 10), (10, 0, 4), (100, 68, 95), (100, 100, 100)])
def test_exactly_k_of_n_within_sigma(n, k1, k2):
    d, e = depths_with(n, k1, k2)
    s = method_statistics(d, e, truth_ppm=TRUTH, n_bootstrap=0)
    assert s["coverage"] == k1 / n
    assert s["coverage_2sigma"] == k2 / n
    assert (s["coverage_lo"], s["coverage_hi"]) == binomial_interval(k1, n)
    assert (s["coverage_2sigma_lo"], s["coverage_2sigma_hi"]) == binomial_interval(k2, n)
    z = np.abs((d - TRUTH) / e)
    assert s["z_rms"] == pytest.approx(math.sqrt(np.mean(z**2)))


def test_an_epoch_exactly_at_one_sigma_counts_as_covered():
    f, _, _ = coverage([1975.0, 1775.0, 2075.0], [100.0] * 3, TRUTH)
    assert f == pytest.approx(2 / 3)
    f2, _, _ = coverage([1975.0, 1775.0, 2075.0], [100.0] * 3, TRUTH, n_sigma=2.0)
    assert f2 == 1.0


def test_honest_gaussian_errors_cover_68_and_95_percent():
    # 20,000 epochs with known unit-normal residuals: the coverages are the Gaussian
    # probabilities within their (narrow, +-0.003) intervals, and the RMS of z is 1
    rng = np.random.default_rng(11)
    e = rng.uniform(50.0, 150.0, 20_000)
    d = TRUTH + e * rng.standard_normal(e.size)
    f1, lo1, hi1 = coverage(d, e, TRUTH)
    f2, lo2, hi2 = coverage(d, e, TRUTH, n_sigma=2.0)
    assert lo1 - 0.01 < GAUSS_1SIGMA < hi1 + 0.01 and hi1 - lo1 < 0.01
    assert lo2 - 0.005 < GAUSS_2SIGMA < hi2 + 0.005 and hi2 - lo2 < 0.005
    z = normalised_residuals(d, e, TRUTH)
    assert math.sqrt(np.mean(z**2)) == pytest.approx(1.0, abs=0.02)


def test_without_truth_every_coverage_key_is_none():
    d, e = depths_with(10, 7, 10)
    s = method_statistics(d, e, n_bootstrap=0)
    for key in ("coverage", "coverage_lo", "coverage_hi", "coverage_2sigma", "coverage_2sigma_lo",
                "coverage_2sigma_hi", "z_rms"):
        assert s[key] is None


def test_summary_gives_coverage_per_method_and_its_average():
    rows = []
    for name, (k1, k2) in {"a": (7, 10), "b": (5, 9)}.items():
        d, e = depths_with(10, k1, k2)
        rows += [(name, i + 1, float(x), float(y)) for i, (x, y) in enumerate(zip(d, e, strict=True))]
    table = Table(rows=rows, names=["method", "epoch", "depth_ppm", "error_ppm"])
    s = summarize(table, truth_ppm=TRUTH, n_bootstrap=0)
    assert s["methods"]["a"]["coverage"] == 0.7 and s["methods"]["b"]["coverage_2sigma"] == 0.9
    lo, hi = binomial_interval(5, 10)
    assert s["methods"]["b"]["coverage_lo"] == lo and s["methods"]["b"]["coverage_hi"] == hi
    assert s["average"]["coverage"] == pytest.approx(0.6)
    assert s["average"]["coverage_2sigma"] == pytest.approx(0.95)
    assert s["methods"]["a"]["f_dis"] >= 1.0 and s["methods"]["a"]["N"] == 10
