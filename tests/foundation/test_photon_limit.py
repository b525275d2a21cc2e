"""Section 3.3 equations, checked against values computed here by hand."""

import math

import pytest

from eclipsebench.stats.photon_limit import (
    eclipse_depth_photon_noise,
    fowler_variance,
    frame_snr,
    photon_limit,
)


def gf_variance_by_hand(F, FN, WT, rn):
    # Garnett & Forrest as the paper writes it: sigma_int^2 [2 rn^2/(sigma_int^2 FN) + 1
    # - 2FN/(3 nmax) + 1/(6 FN nmax)], sigma_int^2 = F * t_int/t_exp
    nmax = 2 * FN + WT
    s2 = F * nmax / (FN + WT)
    return s2 * (2 * rn**2 / (s2 * FN) + 1 - 2 * FN / (3 * nmax) + 1 / (6 * FN * nmax))


@pytest.mark.parametrize("F,FN,WT,rn", [(70917, 8, 184, 9.4), (463, 8, 184, 9.4),
                                        (1000.0, 2, 6, 9.4), (5e4, 1, 10, 3.0)])
def test_fowler_variance_matches_equation(F, FN, WT, rn):
    assert fowler_variance(F, fowler=FN, wait=WT, read_noise_e=rn) == pytest.approx(
        gf_variance_by_hand(F, FN, WT, rn), rel=1e-12)


def test_zero_read_noise_is_pure_shot_noise():
    # FN=8, WT=184: nmax=200, t_int/t_exp = 200/192, bracket 1 - 16/600 + 1/9600
    expected = 1000 * (200 / 192) * (1 - 16 / 600 + 1 / 9600)
    assert fowler_variance(1000, fowler=8, wait=184, read_noise_e=0.0) == pytest.approx(expected)


def test_fowler_number_one():
    # FN=1, WT=0: nmax=2, t_int/t_exp=2, bracket 1 - 2/6 + 1/12 = 0.75, read term 2 rn^2
    assert fowler_variance(100, fowler=1, wait=0, read_noise_e=2.0) == pytest.approx(
        100 * 2 * 0.75 + 8.0)


def test_read_noise_per_pixel_scales_with_aperture_area():
    one = fowler_variance(0.0, read_noise_e=9.4)
    assert one == pytest.approx(2 * 9.4**2 / 8)
    assert fowler_variance(0.0, read_noise_e=9.4, n_pixels=16) == pytest.approx(16 * one)


def test_paper_single_frame_snr_real_and_simulated():
    _, snr_real = frame_snr(70858, 70917, 463)
    _, snr_sim = frame_snr(73246, 73358, 881)
    assert snr_real == pytest.approx(264, rel=0.01)
    assert snr_sim == pytest.approx(268, rel=0.01)


def test_photon_noise_equation_by_hand():
    N, snr, D, f = 14912, 264.0, 1520e-6, 1 / 3
    var = (1 + D) ** 2 / (N * snr**2) * (1 / ((1 - f) * (1 + D)) + 1 / f)
    assert eclipse_depth_photon_noise(N, snr, D, f) == pytest.approx(math.sqrt(var), rel=1e-12)
    # The paper quotes 53 ppm for these inputs, but its own equation gives ~66 ppm.
    assert 1e6 * math.sqrt(var) == pytest.approx(65.9, abs=0.1)


def test_photon_noise_zero_depth_half_in_eclipse():
    # D=0, f=1/2: sigma^2 = 4 / (N snr^2)
    assert eclipse_depth_photon_noise(100, 10.0, 0.0, 0.5) == pytest.approx(math.sqrt(4 / 1e4))


@pytest.mark.parametrize("f_in", [0.0, 1.0, -0.2, 1.5])
def test_f_in_outside_open_unit_interval_is_rejected(f_in):
    with pytest.raises(ValueError, match="f_in"):
        eclipse_depth_photon_noise(100, 10.0, 1e-3, f_in)


def test_fowler_number_zero_is_rejected():
    with pytest.raises(ValueError, match="fowler"):
        fowler_variance(100, fowler=0)


def test_photon_limit_bundle():
    result = photon_limit(70858, 70917, 463, frames=14912, depth_ppm=1520)
    assert result.t_int_s == pytest.approx(2.0)
    assert result.t_exp_s == pytest.approx(1.92)
    assert result.sigma_phot_ppm == pytest.approx(
        1e6 * eclipse_depth_photon_noise(14912, result.snr_single, 1520e-6))
