"""Centroids, noise pixels and apertures on noiseless frames of known PRFs at known positions."""

from __future__ import annotations

import numpy as np
import pytest
from photutils.aperture import CircularAperture, aperture_photometry
from scipy.special import j1

from eclipsebench.config.photometry import PhotometrySection
from eclipsebench.photometry.measure import measure_stack


def _positions(n=60, seed=11):
    rng = np.random.default_rng(seed)
    return rng.uniform(14.5, 15.5, n), rng.uniform(14.5, 15.5, n)


def _expected_col(img, px, py, h=3, r_in=3.0, r_out=7.0):
    """Paper Eqs. x_centroid, y_centroid written out independently: annulus mean about the
    brightest pixel (pixel centres in [r_in, r_out]), then the 7x7 center of light."""
    jj, ii = np.mgrid[: img.shape[0], : img.shape[1]]
    d2 = (ii - px) ** 2 + (jj - py) ** 2
    bg = img[(d2 >= r_in**2) & (d2 <= r_out**2)].mean()
    box = img[py - h: py + h + 1, px - h: px + h + 1] - bg
    xs = np.arange(px - h, px + h + 1)
    ys = np.arange(py - h, py + h + 1)
    s = box.sum()
    return (box.sum(axis=0) @ xs) / s, (box.sum(axis=1) @ ys) / s, s**2 / (box**2).sum()


@pytest.mark.parametrize("sigma", [0.45, 0.6, 0.9])
def test_gaussian_centroid_recovers_integrated_gaussian_positions(gaussian_prf, sigma):
    xs, ys = _positions()
    frames = np.stack([gaussian_prf(x, y, sigma, 5e4) for x, y in zip(xs, ys, strict=True)]) + 3.0
    m = measure_stack(frames, guess_x=15, guess_y=15,
                      options=PhotometrySection(centroid="gauss"))
    assert np.max(np.abs(m["x_gauss"] - xs)) < 0.01
    assert np.max(np.abs(m["y_gauss"] - ys)) < 0.01
    assert np.max(np.abs(m["width_x"] - sigma)) < 0.01
    assert np.array_equal(m["x"], m["x_gauss"])  # the chosen centroid places the apertures


def test_fixed_width_gaussian_centroid(gaussian_prf):
    xs, ys = _positions(seed=5)
    frames = np.stack([gaussian_prf(x, y, 0.55, 5e4) for x, y in zip(xs, ys, strict=True)])
    m = measure_stack(frames, guess_x=15, guess_y=15,
                      options=PhotometrySection(centroid="gauss-fixed"))
    assert np.allclose(m["gauss_fixed_width"], 0.55, atol=1e-3)  # median free-fit width
    assert np.max(np.abs(m["x_gfix"] - xs)) < 0.01
    assert np.max(np.abs(m["y_gfix"] - ys)) < 0.01


def test_center_of_light_bias_is_what_the_gaussian_prf_implies(gaussian_prf):
    xs, ys = _positions(seed=2)
    frames = np.stack([gaussian_prf(x, y, 0.6, 5e4) for x, y in zip(xs, ys, strict=True)]) + 2.0
    m = measure_stack(frames, guess_x=15, guess_y=15, options=PhotometrySection())
    for k, img in enumerate(frames):
        j, i = np.unravel_index(np.argmax(img), img.shape)
        ex, ey, beta = _expected_col(img, i, j)
        assert m["x_col"][k] == pytest.approx(ex, abs=1e-9)
        assert m["y_col"][k] == pytest.approx(ey, abs=1e-9)
        assert m["noise_pixels"][k] == pytest.approx(beta, rel=1e-9)
    # a compact Gaussian loses almost no light outside 7x7: the bias is tiny
    assert np.max(np.abs(m["x_col"] - xs)) < 2e-3


def _airy_frame(x0, y0, total, shape=(32, 32), lam_over_d_px=1.2, oversample=9):
    """An Airy PRF integrated over pixels by oversampling (a broad-winged PRF)."""
    n = shape[0] * oversample
    c = (np.arange(n) + 0.5) / oversample - 0.5
    xx, yy = np.meshgrid(c, c)
    r = np.hypot(xx - x0, yy - y0) * np.pi / lam_over_d_px
    with np.errstate(invalid="ignore", divide="ignore"):
        psf = np.where(r > 0, (2 * j1(r) / r) ** 2, 1.0)
    img = psf.reshape(shape[0], oversample, shape[1], oversample).sum(axis=(1, 3))
    return total * img / img.sum()


def test_center_of_light_bias_of_a_broad_airy_prf_pulls_toward_the_box_centre():
    xs = np.array([14.6, 14.8, 15.0, 15.2, 15.4])
    ys = np.full(xs.size, 15.0)
    frames = np.stack([_airy_frame(x, y, 5e4) for x, y in zip(xs, ys, strict=True)])
    m = measure_stack(frames, guess_x=15, guess_y=15, options=PhotometrySection())
    for k, img in enumerate(frames):
        j, i = np.unravel_index(np.argmax(img), img.shape)
        ex, ey, _ = _expected_col(img, i, j)
        assert m["x_col"][k] == pytest.approx(ex, abs=1e-9)
    bias = m["x_col"] - xs
    # truncated wings + background from the wings: col is pulled toward pixel 15
    assert bias[0] > 0.005 and bias[-1] < -0.005
    assert abs(bias[2]) < 1e-6
    # a Gaussian model of an Airy PRF is biased too (away from the pixel centre, ~0.01 px)
    assert np.max(np.abs(m["x_gauss"] - xs)) < 0.02


def test_least_asymmetry_centroid_is_within_its_documented_accuracy(gaussian_prf):
    xs, ys = _positions(seed=9)
    frames = np.stack([gaussian_prf(x, y, 0.6, 5e4) for x, y in zip(xs, ys, strict=True)])
    m = measure_stack(frames, guess_x=15, guess_y=15,
                      options=PhotometrySection(centroid="lsq-asym"))
    assert np.max(np.abs(m["x_lsq"] - xs)) < 0.15
    assert np.max(np.abs(m["y_lsq"] - ys)) < 0.15


def test_apertures_match_photutils_and_analytic_background(gaussian_prf):
    xs, ys = _positions(n=20, seed=4)
    bg = 7.5
    frames = np.stack([gaussian_prf(x, y, 0.6, 5e4) for x, y in zip(xs, ys, strict=True)]) + bg
    opt = PhotometrySection(centroid="gauss")
    m = measure_stack(frames, guess_x=15, guess_y=15, options=opt)
    for k in range(len(frames)):
        for r in opt.radii_px:
            ap = CircularAperture((m["x"][k], m["y"][k]), r)
            ref = aperture_photometry(frames[k] - m["background"][k], ap,
                                      method="exact")["aperture_sum"][0]
            assert m[f"flux_r{r:.2f}".replace(".", "p")][k] == pytest.approx(ref, rel=1e-9)
    # with a 0.6 px Gaussian the 3-7 px annulus holds background and < 0.02 e of wings
    assert np.allclose(m["background_mean"], bg, atol=0.02)
    assert np.allclose(m["background_median"], bg, atol=0.02)
    assert np.allclose(m["flux_r4p00"], 5e4, rtol=1e-3)
    # variable aperture r = sqrt(beta)
    assert np.allclose(m["radius_va1p00b0p00"], np.sqrt(m["noise_pixels"]))


def test_stamps_are_background_subtracted_pixels(gaussian_prf):
    frames = np.stack([gaussian_prf(15.1, 14.9, 0.6, 5e4) + 4.0])
    m = measure_stack(frames, guess_x=15, guess_y=15, stamp_x=15, stamp_y=15,
                      options=PhotometrySection())
    bg = m["background"][0]
    assert np.allclose(m["stamp3"][0], frames[0, 14:17, 14:17] - bg)
    assert np.allclose(m["stamp5"][0], frames[0, 13:18, 13:18] - bg)


def test_annulus_clipped_median_matches_astropy_sigma_clipped_stats():
    from astropy.stats import sigma_clipped_stats

    rng = np.random.default_rng(21)
    frames = rng.normal(50.0, 4.0, (40, 32, 32))
    hot = rng.random(frames.shape) < 0.03
    frames[hot] += rng.uniform(30, 300, hot.sum())     # outliers the clipping must remove
    frames[:, 15, 15] = 1e5                             # a "star" pixel so the peak is (15, 15)
    opt = PhotometrySection(clip_sigma=3.0, clip_iters=5)
    m = measure_stack(frames, guess_x=15, guess_y=15, options=opt)
    jj, ii = np.mgrid[:32, :32]
    for k in range(len(frames)):
        d2 = (ii - m["x"][k]) ** 2 + (jj - m["y"][k]) ** 2
        vals = frames[k][(d2 >= 9.0) & (d2 <= 49.0)]
        mean, med, std = sigma_clipped_stats(vals, sigma=3.0, maxiters=5)
        assert m["background_median"][k] == pytest.approx(med, rel=1e-12)
        assert m["background_sigma"][k] == pytest.approx(std, rel=1e-9)
        assert m["background_mean"][k] == pytest.approx(vals.mean(), rel=1e-12)
        assert m["background_npix"][k] == vals.size
