"""The single estimators: one definition each, shared with the full measurement set."""

from __future__ import annotations

import numpy as np
import pytest
from photutils.aperture import CircularAperture

from eclipsebench.config.photometry import PhotometrySection
from eclipsebench.photometry import estimators as E
from eclipsebench.photometry.measure import measure_noise_pixels, measure_stack


@pytest.fixture
def frames(gaussian_prf):
    rng = np.random.default_rng(3)
    xs, ys = rng.uniform(14.5, 15.5, 40), rng.uniform(14.5, 15.5, 40)
    stack = np.stack([gaussian_prf(x, y, 0.6, 4e4) for x, y in zip(xs, ys, strict=True)])
    return stack + 20.0 + rng.normal(0.0, 5.0, stack.shape)


def test_centroid_and_noise_pixels_on_hand_made_images():
    im = np.zeros((2, 32, 32))
    im[0, 15, 15] = 3.0
    im[0, 15, 16] = 1.0  # x = 15.25, y = 15
    im[1, 10:17, 20:27] = 2.0  # uniform 7x7 box centred on (23, 13): 49 noise pixels
    im[1, 13, 23] = 2.0 + 1e-9
    xs, ys = E.centroid_col(im)
    np.testing.assert_allclose(xs, [15.25, 23.0], atol=1e-8)
    np.testing.assert_allclose(ys, [15.0, 13.0], atol=1e-8)
    assert E.noise_pixels(im)[1] == pytest.approx(49.0)
    assert E.noise_pixels(im)[0] == pytest.approx(16.0 / 10.0)
    # a box that leaves the image gives NaN, as in the measurement set
    assert np.isnan(E.centroid_col(im[0], around=(1, 15))[0][0])


def test_brightest_pixel_skips_nan_and_reports_empty_boxes():
    im = np.zeros((2, 9, 9))
    im[0, 4, 4] = np.nan
    im[0, 2, 6] = 5.0
    im[1] = np.nan
    px, py = E.brightest_pixel(im)
    assert (px[0], py[0]) == (6, 2) and (px[1], py[1]) == (-1, -1)
    px, py = E.brightest_pixel(im[0], 4, 4, 1)  # (6, 2) lies outside the 3x3 search box
    assert (px[0], py[0]) == (3, 3)


@pytest.mark.parametrize("centroid", ["col", "lsq-asym"])
def test_single_estimators_are_the_measurement_set(frames, centroid):
    """Each estimator run alone gives the bytes measure_stack writes: one definition."""
    opt = PhotometrySection(centroid=centroid)
    m = measure_stack(frames, guess_x=15, guess_y=15, options=opt)
    px, py = E.brightest_pixel(frames, 15, 15, opt.search_px)
    assert np.array_equal(px, m["peak_x"]) and np.array_equal(py, m["peak_y"])
    bg0 = E.annulus_background(frames, px, py, opt.annulus_px)["mean_e"]
    x, y = E.centroid_col(frames, opt.box_px // 2, (px, py), background_e=bg0)
    assert np.array_equal(x, m["x_col"]) and np.array_equal(y, m["y_col"])
    beta = E.noise_pixels(frames, opt.box_px // 2, (px, py), background_e=bg0)
    assert np.array_equal(beta, m["noise_pixels"])
    g = E.centroid_gauss(frames, opt.box_px // 2, (px, py), background_e=bg0)
    for ours, theirs in (("x", "x_gauss"), ("y", "y_gauss"), ("width_x", "width_x"),
                         ("width_y", "width_y")):
        assert np.array_equal(g[ours], m[theirs])
    if centroid == "lsq-asym":
        xl, yl, ok = E.centroid_lsq_asym(frames, (px, py), background_e=bg0)
        assert np.array_equal(xl, m["x_lsq"]) and np.array_equal(yl, m["y_lsq"])
        assert ok.all()
    bg = E.annulus_background(frames, m["x"], m["y"], opt.annulus_px,
                              clip_sigma=opt.clip_sigma, clip_iters=opt.clip_iters)
    assert np.array_equal(bg["mean_e"], m["background_mean"])
    assert np.array_equal(bg["median_e"], m["background_median"])
    assert np.array_equal(bg["std_e"], m["background_sigma"])
    assert np.array_equal(bg["npix"], m["background_npix"])
    sums, areas = E.aperture_sums(frames, m["x"], m["y"], [opt.radius_px])
    assert np.array_equal(sums[:, 0], m["flux_raw"])
    assert np.array_equal(sums[:, 0] - m["background"] * areas[:, 0], m["flux"])


@pytest.mark.parametrize("options", [PhotometrySection(),
                                     PhotometrySection(box_px=5, search_px=2,
                                                       annulus_px=(2.5, 6.0))])
def test_noise_pixels_alone_are_the_measurement_sets(frames, options):
    """measure_noise_pixels (the twins' calibration) gives measure_stack's noise pixels, byte
    for byte, NaN included: a non-finite pixel in the box, none near the guess, a box
    leaving the image, a float32 stack."""
    stack = frames.copy()
    stack[1, 15, 15] = np.nan       # in the box: NaN
    stack[2, 8, 8] = np.nan         # in the annulus only: skipped there
    stack[3, 12:19, 12:19] = np.nan     # nothing finite near the guess
    stack[4] = np.roll(stack[4], (-14, -14), axis=(0, 1))    # the star at (1, 1): the box
    guess = np.full(len(stack), 15)                               # about it leaves the image
    guess[4] = 1
    for data in (stack, stack.astype(np.float32)):
        want = measure_stack(data, guess_x=guess, guess_y=guess, options=options)["noise_pixels"]
        got = measure_noise_pixels(data, guess_x=guess, guess_y=guess, options=options)
        assert np.isnan(want[[1, 3, 4]]).all() and np.isfinite(want[[0, 2, 5]]).all()
        assert got.tobytes() == want.tobytes()


def test_aperture_flux_matches_photutils_exact(frames):
    x = np.array([15.3, 14.71, 16.0])
    y = np.array([14.9, 15.44, 15.0])
    ours = E.aperture_flux(frames[:3], x, y, 2.25)
    ref = [CircularAperture((xi, yi), r=2.25).do_photometry(f, method="exact")[0][0]
           for f, xi, yi in zip(frames[:3], x, y, strict=True)]
    np.testing.assert_allclose(ours, ref, rtol=1e-12)
    with pytest.raises(ValueError, match="x_px"):
        E.aperture_flux(frames[:3], [1.0, 2.0], 15.0, 2.25)
