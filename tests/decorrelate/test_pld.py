"""PLD: normalised pixels, weighted linear least squares, time terms, binning."""

from __future__ import annotations

import numpy as np
import pytest

from eclipsebench.decorrelate import get_method
from eclipsebench.decorrelate.base import EpochData
from eclipsebench.errors import InputError


def _pixel_epoch(n=600, side=5, seed=11):
    g = np.random.default_rng(seed)
    pix = g.uniform(50.0, 5000.0, (n, side * side))
    time = 56000.0 + np.arange(n) * 2.0 / 86400
    flux = pix.sum(axis=1) * (1 + 1e-3 * g.standard_normal(n))
    err = np.sqrt(flux) * g.uniform(0.8, 1.2, n)
    return EpochData(time_bmjd=time, flux=flux, flux_err=err, x=np.zeros(n), y=np.zeros(n),
                     pixels=pix)


def _phat(pixels, side):
    n = pixels.shape[0]
    m = int(np.sqrt(pixels.shape[1]))
    o = (m - side) // 2
    p = pixels.reshape(n, m, m)[:, o:o + side, o:o + side].reshape(n, side * side)
    return p / p.sum(axis=1, keepdims=True)


def _wls(design, target, sigma):
    return np.linalg.lstsq(design / sigma[:, None], target / sigma, rcond=None)[0]


def test_exact_pixel_model_is_recovered():
    data = _pixel_epoch()
    phat = _phat(data.pixels, 3)
    c_true = np.linspace(0.9e5, 1.1e5, 9)
    astro = 1 + 2e-3 * np.sin(np.arange(len(data)) / 40.0)
    exact = EpochData(time_bmjd=data.time_bmjd, flux=astro * (phat @ c_true),
                      flux_err=data.flux_err, x=data.x, y=data.y, pixels=data.pixels)
    model = get_method("pld")(exact)
    np.testing.assert_allclose(model.coefficients(astro), c_true, rtol=1e-8)
    np.testing.assert_allclose(model.predict(astro), exact.flux, rtol=1e-10)


@pytest.mark.parametrize("stamp", [3, 5])
def test_weighted_least_squares_matches_lstsq(stamp):
    data = _pixel_epoch()
    astro = 1 + 1e-3 * np.cos(np.arange(len(data)) / 30.0)
    model = get_method("pld")(data, stamp=stamp)
    phat = _phat(data.pixels, stamp)
    c = _wls(astro[:, None] * phat, data.flux, data.flux_err)
    np.testing.assert_allclose(model.coefficients(astro), c, rtol=1e-7)
    np.testing.assert_allclose(model.predict(astro), astro * (phat @ c), rtol=1e-10)
    assert model.n_effective_params() == stamp * stamp


def test_time_polynomial_terms():
    data = _pixel_epoch()
    astro = np.ones(len(data))
    model = get_method("pld")(data, time_poly_degree=2)
    t = data.time_bmjd
    tau = 2 * (t - t.min()) / (t.max() - t.min()) - 1
    design = np.column_stack([_phat(data.pixels, 3), tau, tau**2])
    c = _wls(design, data.flux, data.flux_err)
    np.testing.assert_allclose(model.coefficients(astro), c, rtol=1e-7)
    assert model.n_effective_params() == 11


def test_binned_coefficients_as_deming_et_al():
    data = _pixel_epoch(n=605)
    astro = 1 + 1e-3 * np.cos(np.arange(len(data)) / 30.0)
    model = get_method("pld")(data, bin_frames=10)
    phat = _phat(data.pixels, 3)
    starts = np.arange(0, 605, 10)
    design = np.array([(astro[s:s + 10, None] * phat[s:s + 10]).mean(axis=0) for s in starts])
    flux = np.array([data.flux[s:s + 10].mean() for s in starts])
    sigma = np.array([np.sqrt(np.sum(data.flux_err[s:s + 10] ** 2)) / len(data.flux_err[s:s + 10])
                      for s in starts])
    c = _wls(design, flux, sigma)
    np.testing.assert_allclose(model.coefficients(astro), c, rtol=1e-7)
    # Applied to the unbinned frames.
    np.testing.assert_allclose(model.predict(astro), astro * (phat @ c), rtol=1e-10)


def test_binning_follows_time_order():
    data = _pixel_epoch(n=200)
    perm = np.random.default_rng(0).permutation(200)
    shuffled = EpochData(time_bmjd=data.time_bmjd[perm], flux=data.flux[perm],
                         flux_err=data.flux_err[perm], x=data.x, y=data.y,
                         pixels=data.pixels[perm])
    astro = np.ones(200)
    a = get_method("pld")(data, bin_frames=8).coefficients(astro)
    b = get_method("pld")(shuffled, bin_frames=8).coefficients(astro)
    np.testing.assert_allclose(a, b, rtol=1e-10)


def test_options_and_bad_stamps():
    data = _pixel_epoch(side=3)
    with pytest.raises(InputError, match="5x5"):
        get_method("pld")(data, stamp=5)
    with pytest.raises(InputError, match="stamp"):
        get_method("pld")(data, stamp=4)
    with pytest.raises(InputError, match="bin_frames"):
        get_method("pld")(data, bin_frames=0)
    with pytest.raises(InputError, match="fewer bin_frames"):
        get_method("pld")(data, bin_frames=100)
    with pytest.raises(InputError, match="unknown option"):
        get_method("pld")(data, order=2)
    bad = EpochData(time_bmjd=data.time_bmjd, flux=data.flux, flux_err=data.flux_err,
                    x=data.x, y=data.y, pixels=-data.pixels)
    with pytest.raises(InputError, match="positive sum"):
        get_method("pld")(bad)


def test_with_flux_keeps_the_design(epoch_sys):
    model = get_method("pld")(epoch_sys.data, bin_frames=4)
    other = model.with_flux(2.0 * epoch_sys.data.flux)
    np.testing.assert_allclose(other.predict(epoch_sys.astro), 2.0 * model.predict(epoch_sys.astro),
                               rtol=1e-10)
    np.testing.assert_array_equal(model.data.flux, epoch_sys.data.flux)
