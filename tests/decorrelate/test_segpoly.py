"""SP(K2) segmented-polynomial detrending (paper Appendix B.6; Buzasi et al. 2015).

The K2 pipeline detrends blind to the eclipse (the default); the eclipse mask
and the division by the fitted astrophysical curve are named options, off by
default.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from eclipsebench.decorrelate import get_method
from eclipsebench.decorrelate.base import EpochData
from eclipsebench.decorrelate.segpoly import (
    SegmentedPolynomial,
    hf_scatter,
    iterative_poly_detrend,
    poly_design,
    segment_fractions_default,
    segment_slices,
    sp_k2_detrend,
)
from eclipsebench.errors import InputError
from eclipsebench.seeding import rng

MASKED = {"mask_eclipse": True, "divide_astro": True}


def test_hf_scatter_measures_white_noise_under_a_slow_trend():
    g = rng(3, "tests", "segpoly", "hf")
    n = 20000
    t = np.linspace(0, 1, n)
    flux = 1000.0 * (1.0 + 0.01 * np.sin(2 * np.pi * t) + 1e-3 * g.standard_normal(n))
    assert hf_scatter(flux) == pytest.approx(1e-3, rel=0.03)


def test_poly_design_has_all_monomials_of_standardised_coordinates():
    x = np.array([0.0, 1.0, 2.0, 3.0])
    y = np.array([1.0, 1.0, 3.0, 3.0])
    d = poly_design(x, y, 2)
    u = (x - 1.5) / np.std(x)
    v = (y - 2.0) / 1.0
    expected = np.column_stack([np.ones(4), u, v, u * u, u * v, v * v])
    np.testing.assert_allclose(d, expected)
    # a coordinate at rest (rounding noise only) contributes nothing
    d0 = poly_design(x, np.full(4, 15.0) + 1e-12 * np.arange(4), 1)
    np.testing.assert_array_equal(d0[:, 2], 0.0)


def test_ten_segment_lengths_between_0p04_and_0p125():
    f = np.asarray(segment_fractions_default)
    assert len(f) == 10 and f[0] == pytest.approx(0.04) and f[-1] == pytest.approx(0.125)


def test_stage_one_removes_a_cubic_gain_in_xy_exactly():
    g = rng(4, "tests", "segpoly", "cubic")
    n = 6000
    x = 15.0 + 0.1 * g.standard_normal(n)
    y = 15.0 + 0.1 * g.standard_normal(n)
    dx, dy = x - 15.0, y - 15.0
    gain = 1.0 - 0.5 * dx**2 + 0.3 * dx * dy + 0.2 * dy**3 + 0.05 * dx
    flux = 1e5 * gain
    data = EpochData(time_bmjd=57000 + np.arange(n) * 2 / 86400, flux=flux,
                     flux_err=np.sqrt(flux), x=x, y=y)
    m = SegmentedPolynomial(data)
    detrended = flux / m.trend
    assert np.std(detrended / np.mean(detrended)) < 1e-7
    np.testing.assert_allclose(m.predict(np.ones(n)), flux, rtol=1e-7)


def test_stopping_rule_discards_the_pass_that_gains_less_than_1_percent():
    """B.6: repeat "until there is < 1 % further reduction": that pass is not kept.

    A cubic gain times white noise: the first fit takes the gain, a second
    one gains nothing. The stand-in kept the useless second pass (2 passes).
    """
    g = rng(5, "tests", "segpoly", "stop")
    n = 5000
    x, y = g.normal(0, 0.1, n), g.normal(0, 0.1, n)
    gain = 1 + 0.3 * x - 0.5 * x * y + 0.2 * y**3
    flux = 1e4 * gain * (1 + 1e-3 * g.standard_normal(n))
    res = iterative_poly_detrend(flux, poly_design(x, y, 3), np.ones(n, bool),
                                 tolerance=0.01, max_iterations=20, clip_sigma=4.0)
    assert res.n_passes == 1
    # the first fit is removed even when it does not lower the scatter (B.6: "fit ... and removed")
    flat = 1e4 * (1 + 1e-3 * g.standard_normal(n))
    res = iterative_poly_detrend(flat, poly_design(x, y, 3), np.ones(n, bool),
                                 tolerance=0.01, max_iterations=20, clip_sigma=4.0)
    assert res.n_passes == 1 and not np.all(res.trend == 1.0)


@pytest.mark.parametrize("frac, expected", [(0.0494, 20), (0.0589, 17), (0.0683, 15),
                                            (0.1156, 9), (0.125, 8), (0.04, 25)])
def test_segments_are_never_shorter_than_half_their_length(frac, expected):
    """The stand-in kept a remainder down to 30 frames (1 min) as its own segment."""
    t = 56270.5 + np.arange(15000) * 2.0 / 86400
    span = t[-1] - t[0]
    slices = segment_slices(t, frac * span, min_points=30)
    assert len(slices) == expected
    assert slices[0].start == 0 and slices[-1].stop == len(t)
    assert all(a.stop == b.start for a, b in zip(slices[:-1], slices[1:], strict=True))
    durations = np.array([t[s.stop - 1] - t[s.start] for s in slices]) / (frac * span)
    assert durations.min() > 0.5 - 1e-3 and durations.max() < 1.5


def test_final_series_is_the_framewise_median_of_the_ten_detrendings(epoch_small):
    d = epoch_small.data
    res = sp_k2_detrend(d.time_bmjd, d.flux, d.x, d.y)
    assert res.stage2.shape == (10, len(d))
    final = d.flux / res.trend
    median = np.median(res.stage2, axis=0)
    np.testing.assert_allclose(final / np.mean(final), median / np.mean(median), rtol=1e-12)


def test_the_box_eclipse_is_the_paper_profile_s_not_the_controlled_one():
    """The team fitted a box (App. B.6); the controlled profile shares one shape."""
    from eclipsebench.fit.profiles import paper_profile
    from eclipsebench.fit.reduce import resolve_profile
    assert get_method("segpoly") is SegmentedPolynomial
    assert paper_profile("segpoly").eclipse_shape == "box"
    assert resolve_profile("segpoly", profile="paper")[0].eclipse_shape == "box"
    assert resolve_profile("segpoly", profile="controlled")[0].eclipse_shape == "physical"


def test_default_is_blind_and_the_options_say_so(epoch_small):
    m = SegmentedPolynomial.build(epoch_small.data)
    opts = m.options.to_dict()
    assert opts["mask_eclipse"] is False and opts["divide_astro"] is False
    assert m.diagnostics()["blind"] is True and m.diagnostics()["n_masked"] == 0
    trend = m.trend.copy()
    assert m.optimise_hyperparameters(epoch_small.astro) is None
    np.testing.assert_array_equal(m.trend, trend)


def test_detrended_light_curve_does_not_move_with_the_assumed_eclipse_time(epoch_sys, synth):
    """Acceptance (issue 13): the K2 detrend knows nothing of the eclipse.

    The stand-in masked the fitted eclipse window and divided by the fitted
    astro, so its detrended series followed the assumed eclipse time.
    """
    data, te = epoch_sys.data, epoch_sys.t_ecl_bmjd
    reference = SegmentedPolynomial(data).detrended
    for shift_d in (-0.03, 0.0, 0.03):
        m = SegmentedPolynomial(data)
        m.optimise_hyperparameters(synth.eclipse_curve(data.time_bmjd, te + shift_d, 1875.0))
        np.testing.assert_array_equal(m.detrended, reference)
        synth.fit_depth(m, data.time_bmjd, t_ecl_guess=te + shift_d)   # the fitter's own calls
        np.testing.assert_array_equal(m.detrended, reference)


def test_blind_detrend_recovers_the_depth_when_pointing_is_not_tied_to_time(epoch_sys, synth):
    """The pipeline itself is sound: epoch_sys with its pointing shuffled in time.

    The noiseless flux is ``F astro(t) S(x, y)``; the frames' gains S and
    centroids are permuted together, so the drift no longer follows the
    eclipse: measured -0.3 ppm (against -898 ppm with the track in time order).
    """
    d = epoch_sys.data
    perm = rng(1, "tests", "segpoly", "shuffle").permutation(len(d))
    gain = d.flux / epoch_sys.astro
    flux = gain[perm] * epoch_sys.astro
    data = dataclasses.replace(d, flux=flux, flux_err=np.sqrt(flux), x=d.x[perm], y=d.y[perm])
    m = SegmentedPolynomial(data)
    depth, _ = synth.fit_depth(m, d.time_bmjd, t_ecl_guess=epoch_sys.t_ecl_bmjd + 5.0 / 1440)
    assert abs(depth - epoch_sys.depth_ppm) <= 5.0, depth


def test_blind_detrend_takes_the_drift_correlated_part_of_the_eclipse(epoch_flat, synth):
    """Flat pixels, no systematics: all the loss is the (x, y) cubic fitting the eclipse.

    The pointing drifts with time (corr(y, t) = -0.93), so a cubic in (x, y)
    explains 45 % of the eclipse's variance. Measured: -899.5 ppm here,
    -898.1 ppm on epoch_sys (the contract case).
    """
    m = SegmentedPolynomial(epoch_flat.data)
    depth, _ = synth.fit_depth(m, m.data.time_bmjd, t_ecl_guess=epoch_flat.t_ecl_bmjd)
    assert -950.0 < depth - epoch_flat.depth_ppm < -850.0, depth


def test_mask_option_recovers_the_depth_with_systematics(epoch_sys, synth):
    """``mask_eclipse`` (not the K2 pipeline): the fitted eclipse left out of the fits."""
    m = SegmentedPolynomial(epoch_sys.data, **MASKED)
    depth, t_ecl = synth.fit_depth(m, m.data.time_bmjd,
                                   t_ecl_guess=epoch_sys.t_ecl_bmjd + 5.0 / 1440)
    assert abs(depth - epoch_sys.depth_ppm) <= 20.0, depth
    assert abs(t_ecl - epoch_sys.t_ecl_bmjd) * 86400 < 60.0
    lo, hi = m.mask_window_bmjd
    assert lo < epoch_sys.t_ecl_bmjd - 0.059 and hi > epoch_sys.t_ecl_bmjd + 0.059
    assert m.diagnostics()["blind"] is False


def test_mask_option_agrees_with_pld_within_5_ppm_without_systematics(epoch_flat, synth):
    depths = []
    for model in (SegmentedPolynomial(epoch_flat.data, **MASKED),
                  get_method("pld")(epoch_flat.data)):
        d, _ = synth.fit_depth(model, model.data.time_bmjd,
                               t_ecl_guess=epoch_flat.t_ecl_bmjd + 5.0 / 1440)
        depths.append(d)
    assert abs(depths[0] - depths[1]) <= 5.0, depths
    assert abs(depths[0] - epoch_flat.depth_ppm) <= 5.0, depths


def test_bad_options_are_one_line_input_errors(epoch_flat):
    data = epoch_flat.data
    t = data.time_bmjd
    with pytest.raises(InputError, match="mask_bmjd"):
        SegmentedPolynomial(data, mask_bmjd=(t[0] - 1, t[-1] + 1))
    with pytest.raises(InputError, match="order"):
        SegmentedPolynomial(data, order=2.5)
    with pytest.raises(InputError, match="segment_fractions"):
        SegmentedPolynomial(data, segment_fractions=[0.0, 0.1])
    with pytest.raises(InputError, match="positive"):
        SegmentedPolynomial(dataclasses.replace(data, flux=-data.flux))


def test_divide_astro_option_keeps_the_phase_curve_out_of_the_detrend(epoch_flat, synth):
    """A quadratic phase curve under a drifting pointing, eclipse masked (options).

    Flat pixels, so a steady 0.2 px drift in y changes no flux but makes every
    slow function of time a function of y for the polynomials.
    """
    d = epoch_flat.data
    t = d.time_bmjd
    te = epoch_flat.t_ecl_bmjd
    visible = synth.eclipse_curve(t, te, 1e6) - 1.0
    depth = epoch_flat.depth_ppm * 1e-6
    planet = depth + 2e-3 * (t - te) - 1.2e-2 * (t - te) ** 2
    flux = d.flux / epoch_flat.astro * (1.0 + visible * planet)
    data = dataclasses.replace(d, flux=flux, y=d.y + 0.2 * (t - t[0]) / (t[-1] - t[0]))
    got = {}
    for divide in (True, False):
        m = SegmentedPolynomial(data, mask_eclipse=True, divide_astro=divide)
        got[divide], _ = synth.fit_depth(m, t, t_ecl_guess=te + 5.0 / 1440, phase="quadratic")
    assert abs(got[True] - epoch_flat.depth_ppm) <= 20.0, got
    assert abs(got[False] - epoch_flat.depth_ppm) > 1.5 * abs(got[True] - epoch_flat.depth_ppm)


def test_mask_kept_when_the_fitted_curve_does_not_isolate_an_eclipse(epoch_flat):
    """A fitted phase swing larger than the eclipse must not mask the whole series.

    Simulated epoch 7 of the default challenge ran into this: its fitted quadratic
    phase curve spanned more than the eclipse depth, and the half-range window of
    the fitted curve covered nearly every frame.
    """
    data = epoch_flat.data
    t = data.time_bmjd
    m = SegmentedPolynomial(data, mask_eclipse=True)
    before = m.mask_window_bmjd
    swing = 1.0 + 5e-3 * ((t - t.mean()) / np.ptp(t)) ** 2  # U-shaped, no eclipse in it
    m.optimise_hyperparameters(swing)
    assert m.mask_window_bmjd == before
    outside = (t < before[0]) | (t > before[1])
    assert outside.sum() > len(t) // 3
