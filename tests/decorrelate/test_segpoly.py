"""SP(K2) segmented-polynomial detrending (paper Appendix B.6; Buzasi et al. 2015)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from eclipsebench.decorrelate import get_method
from eclipsebench.decorrelate.base import EpochData
from eclipsebench.decorrelate.segpoly import (
    SegmentedPolynomial,
    hf_scatter,
    poly_design,
    segment_fractions_default,
)
from eclipsebench.errors import InputError
from eclipsebench.seeding import rng


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
    m = SegmentedPolynomial(data, mask_eclipse=False)
    detrended = flux / m.trend
    assert np.std(detrended / np.mean(detrended)) < 1e-7
    np.testing.assert_allclose(m.predict(np.ones(n)), flux, rtol=1e-7)


def test_box_eclipse_is_the_faithful_default():
    assert SegmentedPolynomial.default_eclipse_shape == "box"
    assert get_method("segpoly") is SegmentedPolynomial


def test_depth_recovered_within_20_ppm_with_systematics(epoch_sys, synth):
    """Shared eclipse shape (option): the fitted eclipse is masked from the polynomial fits."""
    m = SegmentedPolynomial(epoch_sys.data)
    depth, t_ecl = synth.fit_depth(m, m.data.time_bmjd,
                                   t_ecl_guess=epoch_sys.t_ecl_bmjd + 5.0 / 1440)
    assert abs(depth - epoch_sys.depth_ppm) <= 20.0, depth
    assert abs(t_ecl - epoch_sys.t_ecl_bmjd) * 86400 < 60.0
    lo, hi = m.mask_window_bmjd
    assert lo < epoch_sys.t_ecl_bmjd - 0.059 and hi > epoch_sys.t_ecl_bmjd + 0.059


def test_unmasked_detrend_eats_the_eclipse(epoch_flat, synth):
    """The K2 pipeline without a mask: the (x, y) polynomial absorbs the drift-correlated eclipse."""
    m = SegmentedPolynomial(epoch_flat.data, mask_eclipse=False, divide_astro=False)
    depth, _ = synth.fit_depth(m, m.data.time_bmjd, t_ecl_guess=epoch_flat.t_ecl_bmjd)
    assert depth < epoch_flat.depth_ppm - 300.0


def test_agrees_with_pld_within_5_ppm_without_systematics(epoch_flat, synth):
    depths = []
    for model in (SegmentedPolynomial(epoch_flat.data), get_method("pld")(epoch_flat.data)):
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


def test_phase_curve_is_not_taken_by_the_detrend(epoch_flat, synth):
    """A quadratic phase curve under a drifting pointing: the fitted astro is divided out.

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
        m = SegmentedPolynomial(data, divide_astro=divide)
        got[divide], _ = synth.fit_depth(m, t, t_ecl_guess=te + 5.0 / 1440, phase="quadratic")
    # measured: +16.5 ppm dividing the fitted astro out, +31.4 ppm detrending the raw flux
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
    m = SegmentedPolynomial(data)
    before = m.mask_window_bmjd
    swing = 1.0 + 5e-3 * ((t - t.mean()) / np.ptp(t)) ** 2  # U-shaped, no eclipse in it
    m.optimise_hyperparameters(swing)
    assert m.mask_window_bmjd == before
    outside = (t < before[0]) | (t > before[1])
    assert outside.sum() > len(t) // 3
