"""PRFs: normalisation, flux conservation, centring, derivatives, flux scaling."""

from __future__ import annotations

import numpy as np
import pytest
from photutils.aperture import CircularAperture

from eclipsebench.errors import InputError
from eclipsebench.instrument import prf as P


@pytest.fixture(scope="module")
def flat():
    return P.BuiltinPRF(gain=False)


@pytest.fixture(scope="module")
def builtin():
    return P.BuiltinPRF()


def col(image, i=15, j=15, half=3):
    box = image[j - half:j + half + 1, i - half:i + half + 1]
    ys, xs = np.mgrid[j - half:j + half + 1, i - half:i + half + 1]
    return (box * xs).sum() / box.sum(), (box * ys).sum() / box.sum()


def test_unit_flux_at_pixel_centre_and_conserved_under_subpixel_shifts(flat, builtin):
    assert builtin.render([15.0], [15.0]).sum() == pytest.approx(1.0, abs=1e-12)
    g = np.linspace(-0.5, 0.5, 9)
    xs, ys = np.meshgrid(15.0 + g, 14.7 + 0.6 * g)
    tot = flat.render(xs.ravel(), ys.ravel()).sum(axis=(1, 2))
    assert np.max(np.abs(tot - 1.0)) < 1e-4
    # another pixel gives the same image, shifted
    a = flat.render([10.3], [20.6])[0]
    b = flat.render([11.3], [19.6])[0]
    np.testing.assert_allclose(b[:-1, 1:], a[1:, :-1], atol=1e-12)  # b[j, i] = a[j+1, i-1]


def test_centre_of_light_at_pixel_centre_equals_input(builtin):
    for x, y in ((15.0, 15.0), (12.0, 18.0)):
        xc, yc = col(builtin.render([x], [y])[0], int(x), int(y))
        assert xc == pytest.approx(x, abs=1e-6)
        assert yc == pytest.approx(y, abs=1e-6)


def test_gain_is_the_committed_polynomial(flat, builtin):
    coeff = P.load_gainmap_coefficients()["builtin"]["gain"]
    x, y = np.array([15.2, 14.8, 15.45]), np.array([15.1, 15.3, 14.6])
    u, v = x - 15.0, y - 15.0
    g = sum(c * u**m * v**n for (m, n), c in zip(coeff["powers"], coeff["coeffs"], strict=True))
    g0 = sum(c for (m, n), c in zip(coeff["powers"], coeff["coeffs"], strict=True)
             if m == 0 and n == 0)
    ratio = builtin.render(x, y).sum(axis=(1, 2)) / flat.render(x, y).sum(axis=(1, 2))
    np.testing.assert_allclose(ratio, g / g0, rtol=1e-9)


def test_taylor_stamps_match_finite_differences_and_subsample_averages(builtin):
    x, y = np.array([15.13, 14.71]), np.array([15.22, 15.4])
    ts = builtin.render_taylor(x, y, half=6)
    h = 1e-4

    def st(dx, dy):
        return builtin.render_stamp(x + dx, y + dy, half=6)[0]

    np.testing.assert_allclose(ts.value, st(0, 0), atol=1e-15)
    np.testing.assert_allclose(ts.dx, (st(h, 0) - st(-h, 0)) / (2 * h), atol=1e-7)
    np.testing.assert_allclose(ts.dy, (st(0, h) - st(0, -h)) / (2 * h), atol=1e-7)
    np.testing.assert_allclose(ts.dxx, (st(h, 0) - 2 * st(0, 0) + st(-h, 0)) / h**2, atol=2e-4)
    np.testing.assert_allclose(ts.dxy, (st(h, h) - st(h, -h) - st(-h, h) + st(-h, -h))
                               / (4 * h * h), atol=2e-4)
    # the stamp sits at the nearest pixel and matches the full-frame render
    full = builtin.render(x, y)
    a = full[0, ts.y0[0]:ts.y0[0] + 13, ts.x0[0]:ts.x0[0] + 13]
    np.testing.assert_allclose(ts.value[0], a, atol=1e-15)
    # second-order expansion of a 0.05 px jitter cloud
    rng = np.random.default_rng(0)
    u, v = rng.normal(0, 0.05, 500), rng.normal(0, 0.05, 500)
    mean = builtin.render_stamp(x[0] + u, y[0] + v, half=6)[0].mean(axis=0)
    approx = (ts.value[0] + u.mean() * ts.dx[0] + v.mean() * ts.dy[0]
              + 0.5 * ((u**2).mean() * ts.dxx[0] + 2 * (u * v).mean() * ts.dxy[0]
                       + (v**2).mean() * ts.dyy[0]))
    assert np.max(np.abs(mean - approx)) < 1e-4 * ts.value[0].max()  # measured 5e-5


def test_flux_scale_in_electrons_and_jansky(builtin):
    k = P.electrons_per_second_scale(builtin, 73246.0, 2.25, t_exp_s=1.92)
    im = builtin.render([15.0], [15.0])[0] * k * 1.92
    ap = CircularAperture((15.0, 15.0), r=2.25).do_photometry(im, method="exact")[0][0]
    assert ap == pytest.approx(73246.0, rel=1e-9)
    omega = 1.21641835430637 * 1.21585676679388 / 206264.80624709636**2
    assert P.jy_to_electrons_per_second(1.0) == pytest.approx(3.71 / (1e6 * omega * 0.1469))
    with pytest.raises(InputError, match="flux_aperture_e"):
        P.electrons_per_second_scale(builtin, -1.0, t_exp_s=1.92)
    with pytest.raises(InputError, match="finite"):
        builtin.render([np.nan], [15.0])


def test_psf_fine_makes_the_airy_patterns_once_per_optics(monkeypatch):
    """The blurs share one polychromatic Airy sum (issue 40: the twins' calibration tries nine
    blurs), with the bytes of the sum made anew; the blur-free PSF is the caller's own."""
    optics = {"obscuration": 0.3, "n_wavelengths": 3}
    first = P.psf_fine(4, 3.0, blur_px=0.2, **optics)
    j1 = P.special.j1
    calls = []

    def counted(v):
        calls.append(v.shape)
        return j1(v)

    monkeypatch.setattr(P.special, "j1", counted)
    again = [P.psf_fine(4, 3.0, blur_px=b, **optics) for b in (0.2, 0.0, 0.35)]
    assert calls == [] and again[0].tobytes() == first.tobytes()
    again[1][0, 0] = -1.0          # a caller may change the blur-free PSF it was given
    P._airy_band.cache_clear()     # made anew, with the calls counted
    fresh = [P.psf_fine(4, 3.0, blur_px=b, **optics) for b in (0.2, 0.0, 0.35)]
    assert len(calls) == 2 * optics["n_wavelengths"]
    assert fresh[1][0, 0] != -1.0
    assert all(a.tobytes() == b.tobytes() for a, b in zip(again[::2], fresh[::2], strict=True))
