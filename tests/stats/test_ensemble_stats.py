"""Ensemble statistics against values computed by hand in the test."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats as sps

from eclipsebench.errors import InputError
from eclipsebench.stats.bootstrap import bootstrap_intervals
from eclipsebench.stats.ensemble import (
    accuracy_statistics,
    dispersion_factor,
    dispersion_interval,
    method_statistics,
    pairwise_differences,
    repeatability,
    weighted_mean,
)

# Ten hand-made depths (ppm) and errors; sum = 18575, mean = 1857.5.
DEPTHS = [1800.0, 1900.0, 1850.0, 1700.0, 2000.0, 1950.0, 1875.0, 1825.0, 1750.0, 1925.0]
ERRORS = [100.0, 100.0, 100.0, 100.0, 100.0, 100.0, 100.0, 100.0, 100.0, 100.0]


def hand_mean(xs):
    return sum(xs) / len(xs)


def hand_sd(xs):
    m = hand_mean(xs)
    return math.sqrt(sum((x - m) ** 2 for x in xs) / (len(xs) - 1))


def test_equal_errors_mean_sd_and_sigma_orig():
    s = method_statistics(DEPTHS, ERRORS, n_bootstrap=0)
    assert s["N"] == 10
    assert s["D_mean"] == pytest.approx(1857.5)
    assert s["mean_ppm"] == pytest.approx(1857.5)
    # deviations: -57.5 42.5 -7.5 -157.5 142.5 92.5 17.5 -32.5 -107.5 67.5; sum sq = 76312.5
    assert s["SD"] == pytest.approx(math.sqrt(76312.5 / 9))
    assert s["sigma_mean"] == pytest.approx(100.0)
    assert s["sigma_orig"] == pytest.approx(100.0 / math.sqrt(10))
    assert s["chi2"] == pytest.approx(76312.5 / 100.0**2)
    f_raw = math.sqrt(7.63125 / 9)
    assert s["f_dis_raw"] == pytest.approx(f_raw)
    assert f_raw < 1 and s["f_dis"] == 1.0  # floored as in the paper's tables
    assert s["sigma_tot"] == pytest.approx(100.0 / math.sqrt(10))


def test_weighted_mean_unequal_errors():
    d = [1000.0, 2000.0, 1600.0]
    e = [10.0, 20.0, 40.0]
    w = [1 / 100, 1 / 400, 1 / 1600]
    expected = (1000 / 100 + 2000 / 400 + 1600 / 1600) / sum(w)
    mean, sigma = weighted_mean(d, e)
    assert mean == pytest.approx(expected)
    assert sigma == pytest.approx(1 / math.sqrt(sum(w)))
    chi2 = sum((x - expected) ** 2 / s**2 for x, s in zip(d, e, strict=True))
    assert dispersion_factor(d, e) == pytest.approx(math.sqrt(chi2 / 2))
    s = method_statistics(d, e, n_bootstrap=0)
    assert s["f_dis"] == pytest.approx(math.sqrt(chi2 / 2))
    assert s["sigma_tot"] == pytest.approx(math.sqrt(chi2 / 2) / math.sqrt(sum(w)))


def test_repeatability_by_explicit_double_loop():
    diffs = [a - b for i, a in enumerate(DEPTHS) for j, b in enumerate(DEPTHS) if i != j]
    assert len(diffs) == 90
    assert sorted(pairwise_differences(DEPTHS)) == pytest.approx(sorted(diffs))
    assert repeatability(DEPTHS) == pytest.approx(hand_sd(diffs))


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_repeatability_over_sd_for_ten_epochs(seed):
    d = np.random.default_rng(seed).normal(1875, 150, 10)
    s = method_statistics(d, np.full(10, 120.0), n_bootstrap=0)
    assert s["R"] / s["SD"] == pytest.approx(math.sqrt(2 * 90 / 89), rel=1e-12)


def test_paper_bliss_row_is_consistent():
    # Table 3: BLISS SD = 133 ppm gives R = 189 ppm; r = 53/133 = 0.40.
    assert 133 * math.sqrt(2 * 90 / 89) == pytest.approx(189, abs=0.5)


def _with_f_dis(f_target, n=10):
    d = np.array(DEPTHS[:n])
    e = np.full(n, 100.0)
    f0 = math.sqrt(sum((x - hand_mean(list(d))) ** 2 for x in d) / 100.0**2 / (n - 1))
    return d, e * f0 / f_target


@pytest.mark.parametrize("f_dis, plus, minus", [
    (1.5, 0.5, 0.3),   # Table 3, BLISS (real)
    (2.8, 1.0, 0.5),   # Table 3, SP(K2) (real)
    (1.2, 0.4, 0.2),   # Table 4, GP (simulated)
    (1.6, 0.6, 0.3),   # Table 4, KR/Data
    (4.6, 1.6, 0.8),   # Table 4, SP(K2)
])
def test_f_dis_interval_reproduces_the_paper(f_dis, plus, minus):
    d, e = _with_f_dis(f_dis)
    s = method_statistics(d, e, n_bootstrap=0)
    assert s["f_dis"] == pytest.approx(f_dis)
    assert round(s["f_dis_hi"] - s["f_dis"], 1) == plus
    assert round(s["f_dis"] - s["f_dis_lo"], 1) == minus
    # independently: chi2 = 9 f^2 / f_true^2 at the 84% and 16% quantiles
    assert s["f_dis_lo"] == pytest.approx(f_dis * math.sqrt(9 / sps.chi2.ppf(0.84, 9)))
    assert s["f_dis_hi"] == pytest.approx(f_dis * math.sqrt(9 / sps.chi2.ppf(0.16, 9)))


def test_dispersion_interval_n10_f15_numbers():
    lo, hi = dispersion_interval(1.5, 10)
    assert lo == pytest.approx(1.2453, abs=1e-3)
    assert hi == pytest.approx(2.0258, abs=1e-3)


def test_truth_statistics_by_hand():
    truth = 1875.0
    s = method_statistics(DEPTHS, ERRORS, sigma_phot_ppm=53.0, truth_ppm=truth, n_bootstrap=0)
    mse = sum((x - truth) ** 2 for x in DEPTHS) / 10
    assert s["RMSE"] == pytest.approx(math.sqrt(mse))
    assert s["bias"] == pytest.approx(1857.5 - truth)
    assert s["r"] == pytest.approx(53.0 / hand_sd(DEPTHS))
    assert s["a"] == pytest.approx(53.0 / math.sqrt(mse))
    inside = sum(abs(x - truth) <= 100.0 for x in DEPTHS)  # 7 of 10
    assert inside == 7
    assert s["coverage"] == pytest.approx(0.7)


def test_missing_inputs_give_none():
    s = method_statistics(DEPTHS, ERRORS, n_bootstrap=0)
    for key in ("r", "RMSE", "bias", "a", "coverage", "R_lo", "r_lo", "a_hi"):
        assert s[key] is None


@pytest.mark.parametrize("d, e, match", [
    ([1800.0], [100.0], "at least 2"),
    ([1800.0, float("nan")], [100.0, 100.0], "NaN"),
    ([1800.0, 1900.0], [100.0, 0.0], "positive"),
    ([1800.0, 1900.0], [100.0], "as many"),
])
def test_bad_inputs(d, e, match):
    with pytest.raises(InputError, match=match):
        method_statistics(d, e)


def test_bootstrap_seeded_and_calibrated():
    d = np.random.default_rng(11).normal(0.0, 100.0, 400)
    a = bootstrap_intervals(d, sigma_phot_ppm=50.0, truth_ppm=0.0, seed=5, n_resamples=3000)
    b = bootstrap_intervals(d, sigma_phot_ppm=50.0, truth_ppm=0.0, seed=5, n_resamples=3000)
    c = bootstrap_intervals(d, sigma_phot_ppm=50.0, truth_ppm=0.0, seed=6, n_resamples=3000)
    assert a == b and a != c
    sd = hand_sd(list(d))
    r_point = sd * math.sqrt(2 * 400 * 399 / (400 * 399 - 1))
    lo, hi = a["R"]
    assert lo < r_point < hi
    # SE of an SD is about SD / sqrt(2N); the 68% interval spans about two of them
    width_expected = 2 * math.sqrt(2) * sd / math.sqrt(2 * 400)
    assert 0.75 * width_expected < hi - lo < 1.25 * width_expected
    assert a["r"][0] < 50.0 / sd < a["r"][1]
    assert a["a"][0] < a["r"][1]


def test_method_statistics_bootstrap_keys():
    s = method_statistics(DEPTHS, ERRORS, sigma_phot_ppm=53.0, truth_ppm=1875.0, seed=3)
    for name in ("R", "r", "a"):
        assert s[f"{name}_lo"] < s[f"{name}_hi"]


def test_bias_is_the_plain_mean_in_run_s_table_and_in_trust_s_scores():
    """Issue 38: one definition of the accuracy statistics. With unequal errors the plain
    mean of D_i - D_t (the paper's mean bias) differs from the weighted mean's; run's
    Table 4 and trust's twin scores both give the plain one, to the bit."""
    from eclipsebench.trust.score import method_score

    depths, errors, truth = [1900.0, 1800.0, 1950.0, 1700.0], [20.0, 80.0, 40.0, 160.0], 1875.0
    plain = sum(d - truth for d in depths) / len(depths)
    weighted, _ = weighted_mean(depths, errors)
    assert abs((weighted - truth) - plain) > 10.0      # the two definitions differ here
    table4 = method_statistics(depths, errors, truth_ppm=truth, n_bootstrap=0)
    twins = method_score(depths, errors, truth)
    acc = accuracy_statistics(depths, errors, truth)
    assert acc["bias"] == pytest.approx(plain)
    assert table4["bias"] == twins["bias_ppm"] == acc["bias"]
    assert table4["RMSE"] == twins["rmse_ppm"] == acc["RMSE"]
    assert table4["z_rms"] == twins["z_rms"] == acc["z_rms"]
    assert [table4["coverage"], table4["coverage_lo"], table4["coverage_hi"]] == \
        [twins["coverage_1sigma"], *twins["coverage_1sigma_interval"]]
    assert twins["sd_ppm"] == pytest.approx(table4["SD"]) and twins["sd_ppm"] == acc["SD"]
