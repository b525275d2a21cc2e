"""Fowler sampling kernels: weights, the two noise models, conversions."""

from __future__ import annotations

import numpy as np
import pytest

from eclipsebench.detector import fowler as F
from eclipsebench.detector.constants import SUB_0P1S, SUB_2S, ReadoutMode
from eclipsebench.detector.fowler import fowler_variance
from eclipsebench.errors import InputError

N_PIX = 200_000


def test_weights_by_hand_for_the_paper_figure_mode():
    # FN=4, WT=5 (the paper's schematic): S_i - P_i spans ticks i+1 .. i+9
    mode = ReadoutMode("fig", 4, 5, 0.2, 2.6)
    expected = np.zeros(13, int)
    for i in range(1, 5):
        expected[i:i + 9] += 1  # ticks i+1 .. i+9 are array indices i .. i+8
    np.testing.assert_array_equal(F.fowler_weights(mode), expected)
    assert F.fowler_weights(SUB_2S).sum() == 8 * 192


def test_grouped_charges_preserve_the_weighted_total():
    rng = np.random.default_rng(0)
    q = rng.uniform(0, 5, size=(SUB_2S.n_max, 3))
    g = F.group_charges(q, SUB_2S)
    w = F.fowler_weights(SUB_2S)
    np.testing.assert_allclose((np.arange(1, 9)[:, None] * g).sum(0), (w[:, None] * q).sum(0))


def test_noiseless_frame_is_the_charge_per_exposure_time():
    # relative photon noise 1e-6 at this level
    q_big = np.full((SUB_2S.n_max, 4), 1e12)
    e = F.fowler_sample(q_big, SUB_2S, np.random.default_rng(1), 0.0)
    np.testing.assert_allclose(e, 1e12 * 192, rtol=1e-5)


@pytest.mark.parametrize("mode", [SUB_2S, SUB_0P1S])
def test_physical_uniform_illumination_variance(mode):
    """Acceptance: the physical model's per-pixel variance.

    Exact Fowler variance, derived here independently of the package:
    q [n - 4 FN/3 + 1/(3 FN)] + 2 rn^2 / FN. The calculator's
    ``shot_noise="poisson"`` must give that, and the simulator must match it
    within 2%. The paper's Eq. gar_for_var as printed (``shot_noise="paper"``)
    gives q [n - 2 FN/3 + 1/(6 FN)] + ..., 2.7% higher for FN=8, WT=184, which
    we assert too (README, "Where the paper is inconsistent").
    """
    q_tick, rn = 20.0, 9.4
    fn, n = mode.fowler, mode.n_max
    mean_e = q_tick * (fn + mode.wait)
    exact = q_tick * (n - 4 * fn / 3 + 1 / (3 * fn)) + 2 * rn**2 / fn
    assert fowler_variance(mean_e, fowler=fn, wait=mode.wait, read_noise_e=rn,
                           shot_noise="poisson") == pytest.approx(exact, rel=1e-12)
    groups = F.group_charges(np.full((n, 1), q_tick), mode)  # deterministic, tested above
    e = F.fowler_sample(np.repeat(groups, N_PIX, axis=1), mode, np.random.default_rng(2), rn,
                        grouped=True)
    assert e.mean() == pytest.approx(mean_e, rel=2e-3)
    var = e.var(ddof=1)
    assert abs(var / exact - 1) < 0.02  # the acceptance point (sampling error 0.3%)
    assert var == pytest.approx(exact, rel=0.012)  # 4 sigma of a 200k-sample variance
    printed = fowler_variance(mean_e, fowler=fn, wait=mode.wait, read_noise_e=rn)
    assert var / printed == pytest.approx(exact / printed, rel=0.012)
    if mode is SUB_2S:
        assert exact / printed == pytest.approx(0.9727, abs=5e-4)


def test_printed_fowler_equation_exceeds_the_mean_signal():
    """Why the paper's Eq. gar_for_var cannot describe Poisson increments.

    A correlated double sample (FN = 1, WT = 0) of a Poisson process has
    variance equal to its mean q; the printed equation gives 1.5 q.
    """
    q = 1000.0
    assert fowler_variance(q, fowler=1, wait=0, read_noise_e=0.0) == pytest.approx(1.5 * q)
    assert fowler_variance(q, fowler=1, wait=0, read_noise_e=0.0,
                           shot_noise="poisson") == pytest.approx(q)
    with pytest.raises(ValueError, match="shot_noise"):
        fowler_variance(q, shot_noise="gaussian")


def test_grouped_and_per_tick_physical_models_agree_in_distribution():
    rng = np.random.default_rng(3)
    q = np.abs(np.sin(np.arange(SUB_2S.n_max) / 7.0))[:, None] * np.full((1, 40_000), 4.0)
    a = F.fowler_sample_ticks(q, SUB_2S, rng, 9.4)
    b = F.fowler_sample(q, SUB_2S, rng, 9.4)
    expected_var = F.fowler_variance_exact(q[:, :1], SUB_2S, 9.4)[0]
    w = F.fowler_weights(SUB_2S)
    expected_mean = (w * q[:, 0]).sum() / 8
    for x in (a, b):
        assert x.mean() == pytest.approx(expected_mean, rel=3e-3)
        assert x.var(ddof=1) == pytest.approx(expected_var, rel=0.03)  # 4 sigma


def test_iracsim2015_noise_compounds():
    """Acceptance: variance about 3.2 x the signal (FN=8), computed here independently.

    Reads r = 1..2FN at ticks k_r; the deviate added at read r has variance
    c_r (mean cumulative charge, 11/10 of the true one) and enters
    sum_i (S_i - P_i) with weight u_r = #{i : i < r <= i + FN}.
    """
    q_tick, rn = 20.0, 16.8
    fn, wt = 8, 184
    ticks = np.r_[np.arange(1, fn + 1), fn + wt + np.arange(1, fn + 1)]
    c = q_tick * ticks
    r = np.arange(1, 2 * fn + 1)
    u = np.array([np.sum((np.arange(1, fn + 1) < rr) & (rr <= np.arange(1, fn + 1) + fn))
                  for rr in r])
    shot = (u**2 * c).sum() / fn**2
    signal = q_tick * (fn + wt)
    reads = F.read_charges(np.full((SUB_2S.n_max, 1), q_tick), SUB_2S)
    np.testing.assert_allclose(reads[:, 0], c)
    e = F.fowler_sample_iracsim2015(np.repeat(reads, N_PIX, axis=1), SUB_2S,
                                    np.random.default_rng(4), rn)
    assert e.mean() == pytest.approx(signal, rel=2e-3)
    ratio = (e.var(ddof=1) - 2 * rn**2 / fn) / e.mean()
    assert ratio == pytest.approx(shot / signal, rel=0.015)
    assert 3.0 < ratio < 3.5
    # the leading-order value quoted in the issue
    assert (fn + 1) * (2 * fn + 1) / (6 * fn) == pytest.approx(3.19, abs=0.01)


def test_same_seed_same_bytes_and_bad_inputs():
    q = np.full((SUB_2S.n_max, 8, 8), 2.0)
    for model in F.NOISE_MODELS:
        a = F.fowler_sample(q, SUB_2S, np.random.default_rng(9), 9.4, noise_model=model)
        b = F.fowler_sample(q, SUB_2S, np.random.default_rng(9), 9.4, noise_model=model)
        assert a.tobytes() == b.tobytes()
    with pytest.raises(InputError, match="noise_model"):
        F.fowler_sample(q, SUB_2S, np.random.default_rng(9), 9.4, noise_model="x")
    with pytest.raises(InputError, match="n_max"):
        F.fowler_sample(q[:10], SUB_2S, np.random.default_rng(9), 9.4)
    with pytest.raises(InputError, match="fowler"):
        ReadoutMode("bad", 0, 184, 0.01, 2.0)


def test_unit_conversions_round_trip_and_bunc():
    e = np.array([0.0, 100.0, 73246.0])
    bcd = F.electrons_to_mjysr(e, fluxconv=0.1469, gain=3.71, t_exp_s=1.92)
    np.testing.assert_allclose(bcd, 0.1469 * e / (3.71 * 1.92))
    np.testing.assert_allclose(F.mjysr_to_electrons(bcd, fluxconv=0.1469, gain=3.71, t_exp_s=1.92),
                               e)
    np.testing.assert_allclose(F.dn_to_electrons(F.electrons_to_dn(e, 3.71), 3.71), e)
    bunc = F.bunc_mjysr(e, SUB_2S, read_noise_e=9.4, fluxconv=0.1469, gain=3.71)
    # zero signal: read noise only, sqrt(2 * 9.4^2 / 8) electrons
    assert bunc[0] == pytest.approx(0.1469 * np.sqrt(2 * 9.4**2 / 8) / (3.71 * 1.92))
    assert np.all(np.diff(bunc) > 0)
