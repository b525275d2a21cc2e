"""SPCA's PLDAper: the aperture flux on normalised pixels; exact answers, SPCA's PCA basis."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import eclipsebench as eb
from eclipsebench.errors import InputError


def _phat(pixels, side):
    n = pixels.shape[0]
    m = int(round(np.sqrt(pixels.shape[1])))
    o = (m - side) // 2
    p = pixels.reshape(n, m, m)[:, o:o + side, o:o + side].reshape(n, side * side)
    return p / p.sum(axis=1, keepdims=True)


@pytest.mark.parametrize("stamp", [3, 5])
def test_exact_pixel_gain_is_fitted_exactly(stamp, epoch_sys, synth):
    """Aperture flux made exactly as astro * sum c_i P_hat_i: model and depth exact."""
    epoch = epoch_sys
    phat = _phat(epoch.data.pixels, stamp)
    c = 1e5 * (1 + 0.2 * np.random.default_rng(stamp).standard_normal(stamp * stamp))
    flux = epoch.astro * (phat @ c)
    data = dataclasses.replace(epoch.data, flux=flux, flux_err=np.sqrt(flux))
    model = eb.method_class("pld-aper").build(data, stamp=stamp)
    np.testing.assert_allclose(model.predict(epoch.astro), flux, rtol=1e-10)
    depth, t_ecl = synth.fit_depth(model, data.time_bmjd,
                                   t_ecl_guess=epoch.t_ecl_bmjd + 5.0 / 1440)
    assert abs(depth - epoch.depth_ppm) < 1e-3
    assert model.n_effective_params() == stamp * stamp


def test_the_fitted_flux_is_the_aperture_flux_not_the_stamp_sum(epoch_small):
    """PLDAper regresses the aperture flux: the stamp sum is not the target."""
    data, astro = epoch_small.data, epoch_small.astro
    phat = _phat(data.pixels, 3)
    model = eb.method_class("pld-aper").build(data, bin_frames=1)
    design = astro[:, None] * phat
    for target in (data.flux, 0.9 * data.flux + 0.1 * data.pixels.sum(axis=1)):
        got = model.with_flux(target).predict(astro)
        c = np.linalg.lstsq(design / data.flux_err[:, None], target / data.flux_err,
                            rcond=None)[0]
        np.testing.assert_allclose(got, design @ c, rtol=1e-10)


@pytest.mark.parametrize("stamp", [3, 5])
def test_spca_pca_basis_gives_the_same_model(stamp, epoch_small):
    """SPCA's [1, PCA(P_hat) with p-1 components] spans the normalised pixels: same fit.

    The synthetic 5x5 stamps have corner pixels of 1e-14 of the flux (condition
    number 4e9 even with unit columns), where lstsq itself is good to ~1e-8
    only: there the model must fit at least as well as the PCA-basis lstsq.
    """
    data, astro = epoch_small.data, epoch_small.astro
    p = stamp * stamp
    phat = _phat(data.pixels, stamp)
    centred = phat - phat.mean(axis=0)
    _, _, vt = np.linalg.svd(centred, full_matrices=False)
    pcs = np.column_stack([np.ones(len(data)), centred @ vt[:p - 1].T])
    design = astro[:, None] * pcs
    c = np.linalg.lstsq(design / data.flux_err[:, None], data.flux / data.flux_err,
                        rcond=None)[0]
    model = eb.method_class("pld-aper").build(data, stamp=stamp, bin_frames=1)
    got = model.predict(astro)
    if stamp == 3:
        np.testing.assert_allclose(got, design @ c, rtol=1e-9)
    else:
        np.testing.assert_allclose(got, design @ c, rtol=1e-7)
        chi2 = np.sum(((data.flux - got) / data.flux_err) ** 2)
        chi2_pca = np.sum(((data.flux - design @ c) / data.flux_err) ** 2)
        assert chi2 <= chi2_pca * (1 + 1e-9)


def test_options_and_refusals(epoch_small):
    data = epoch_small.data
    model = eb.method_class("pld-aper").build(data)
    assert model.diagnostics()["stamp"] == 3 and model.diagnostics()["bin_frames"] == 64
    with pytest.raises(InputError) as info:
        eb.method_class("pld-aper").build(data, psf_width=True)
    assert "pld-aper" in str(info.value) and "width_x" in str(info.value)
    with pytest.raises(InputError, match="stamp"):
        eb.method_class("pld-aper").build(data, stamp=4)
    no_pixels = dataclasses.replace(data, pixels=None)
    with pytest.raises(InputError, match="pixels"):
        eb.method_class("pld-aper").build(no_pixels)
    three = dataclasses.replace(data, pixels=_phat(data.pixels, 3))
    with pytest.raises(InputError, match="5x5"):
        eb.method_class("pld-aper").build(three, stamp=5)
