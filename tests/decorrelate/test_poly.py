"""SPCA's 2-D polynomial models poly2-poly5: exact answers, SPCA's basis, binning, PSF widths."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
import pytest

import eclipsebench as eb
from eclipsebench.decorrelate.base import EpochData
from eclipsebench.decorrelate.poly import legendre_design, polynomial_terms
from eclipsebench.errors import InputError
from eclipsebench.fit.leastsq import fit_leastsq
from eclipsebench.fit.model import AstroModel

ORDERS = (2, 3, 4, 5)


@dataclass(frozen=True)
class WidthEpochData(EpochData):
    """EpochData plus the PSF widths (the columns ``psf_width`` reads), for these tests only."""

    width_x: np.ndarray | None = None
    width_y: np.ndarray | None = None


def _monomials(x, y, order):
    """SPCA's columns x^i y^j (i + j <= order) of the mean-centred centroids."""
    u, v = x - x.mean(), y - y.mean()
    return np.column_stack([u**i * v**j for i, j in polynomial_terms(order)])


def _poly_gain(x, y, order, seed):
    """A polynomial gain of total degree exactly ``order``, 1 +- a few 1e-3 on the cloud."""
    g = np.random.default_rng(seed)
    cols = _monomials(x, y, order)
    coef = g.normal(0.0, 1.0, cols.shape[1]) / np.max(np.abs(cols), axis=0)
    coef[0] = 0.0
    wiggle = cols @ coef
    return 1.0 + 3e-3 * wiggle / np.max(np.abs(wiggle))


def _exact_epoch(epoch, gain, **extra):
    flux = 1e5 * epoch.astro * gain
    cls = WidthEpochData if extra else EpochData
    return cls(time_bmjd=epoch.data.time_bmjd, flux=flux, flux_err=np.sqrt(flux),
               x=epoch.data.x, y=epoch.data.y, **extra)


def test_terms_follow_spca_order_and_count():
    assert polynomial_terms(3) == [(0, 0), (1, 0), (0, 1), (2, 0), (1, 1), (0, 2),
                                   (3, 0), (2, 1), (1, 2), (0, 3)]
    assert [len(polynomial_terms(n)) for n in ORDERS] == [6, 10, 15, 21]
    assert [eb.method_class(f"poly{n}").order for n in ORDERS] == list(ORDERS)


def test_legendre_columns_span_spca_monomials(epoch_small):
    """Same column space: monomials are reproduced exactly by the Legendre design."""
    x, y = epoch_small.data.x, epoch_small.data.y
    u = (x - x.mean()) / np.abs(x - x.mean()).max()
    v = (y - y.mean()) / np.abs(y - y.mean()).max()
    leg, mono = legendre_design(u, v, 5), _monomials(x, y, 5)
    coef = np.linalg.lstsq(leg, mono / np.abs(mono).max(axis=0), rcond=None)[0]
    np.testing.assert_allclose(leg @ coef, mono / np.abs(mono).max(axis=0), atol=1e-10)


@pytest.mark.parametrize("order", ORDERS)
def test_predict_is_spca_weighted_least_squares_on_monomials(order, epoch_small):
    """bin_frames=1: the model equals a weighted lstsq on SPCA's monomial basis."""
    data = epoch_small.data
    astro = epoch_small.astro
    model = eb.method_class(f"poly{order}").build(data, bin_frames=1)
    design = astro[:, None] * _monomials(data.x, data.y, order)
    c = np.linalg.lstsq(design / data.flux_err[:, None], data.flux / data.flux_err,
                        rcond=None)[0]
    np.testing.assert_allclose(model.predict(astro), design @ c, rtol=1e-10)
    assert model.n_effective_params() == len(polynomial_terms(order))


def test_binned_fit_uses_means_of_consecutive_frames(epoch_small):
    data, astro = epoch_small.data, epoch_small.astro
    model = eb.method_class("poly2").build(data)          # default: 64 frames per bin
    assert model.diagnostics()["n_fit_points"] == -(-len(data) // 64)
    starts = np.arange(0, len(data), 64)
    counts = np.diff(np.append(starts, len(data)))
    design = astro[:, None] * _monomials(data.x, data.y, 2)
    b_design = np.add.reduceat(design, starts, axis=0) / counts[:, None]
    b_flux = np.add.reduceat(data.flux, starts) / counts
    b_err = np.sqrt(np.add.reduceat(data.flux_err**2, starts)) / counts
    c = np.linalg.lstsq(b_design / b_err[:, None], b_flux / b_err, rcond=None)[0]
    np.testing.assert_allclose(model.predict(astro), design @ c, rtol=1e-10)


def _binned_chi2(data, astro, design, size=64):
    """SPCA's objective written out: weighted least squares on 64-frame means."""
    starts = np.arange(0, len(data), size)
    counts = np.diff(np.append(starts, len(data)))
    b_design = np.add.reduceat(astro[:, None] * design, starts, axis=0) / counts[:, None]
    b_flux = np.add.reduceat(data.flux, starts) / counts
    b_err = np.sqrt(np.add.reduceat(data.flux_err**2, starts)) / counts
    a, b = b_design / b_err[:, None], b_flux / b_err
    return float(np.sum((b - a @ np.linalg.lstsq(a, b, rcond=None)[0]) ** 2))


@pytest.mark.parametrize("order", (2, 4))
def test_the_fitted_depth_minimises_the_chi2_of_the_bins(order, epoch_sys, synth):
    """The whole fit is made on the bins: the depth is the minimum of the binned chi^2
    (a per-frame chi^2 with coefficients from the bins, the earlier code, put the
    simulator's noise-free epoch 112-439 ppm off for poly2-poly5)."""
    data = epoch_sys.data
    model = eb.method_class(f"poly{order}").build(data)
    assert len(model.residuals(epoch_sys.astro)) == -(-len(data) // 64)
    depth, t_ecl = synth.fit_depth(model, data.time_bmjd,
                                   t_ecl_guess=epoch_sys.t_ecl_bmjd + 5.0 / 1440)
    design = _monomials(data.x, data.y, order)
    grid = depth + np.arange(-10.0, 10.25, 0.25)
    chi2 = [_binned_chi2(data, synth.eclipse_curve(data.time_bmjd, t_ecl, d), design)
            for d in grid]
    assert abs(grid[int(np.argmin(chi2))] - depth) <= 0.25


@pytest.mark.parametrize("order", ORDERS)
def test_exact_polynomial_gain_is_fitted_exactly_by_its_order(order, epoch_sys, synth):
    """Data made from a degree-N gain: polyN recovers model and depth; poly(N-1) cannot."""
    epoch = epoch_sys
    data = _exact_epoch(epoch, _poly_gain(epoch.data.x, epoch.data.y, order, seed=order))
    model = eb.method_class(f"poly{order}").build(data)
    np.testing.assert_allclose(model.predict(epoch.astro), data.flux, rtol=1e-10)
    depth, t_ecl = synth.fit_depth(model, data.time_bmjd,
                                   t_ecl_guess=epoch.t_ecl_bmjd + 5.0 / 1440)
    assert abs(depth - epoch.depth_ppm) < 1e-3
    assert abs(t_ecl - epoch.t_ecl_bmjd) * 86400 < 1e-2
    if order > 2:
        lower = eb.method_class(f"poly{order - 1}").build(data)
        rel = data.flux / lower.predict(epoch.astro) - 1
        assert np.sqrt(np.mean(rel**2)) > 1e-7


def test_psf_width_needs_the_widths(epoch_small):
    with pytest.raises(InputError) as info:
        eb.method_class("poly3").build(epoch_small.data, psf_width=True)
    msg = str(info.value)
    assert "\n" not in msg and "poly3" in msg and "psf_width" in msg and "width_x" in msg
    model = eb.method_class("poly3").build(epoch_small.data)
    assert model.param_names == () and len(model.initial_params()) == 0


def _width_epoch(epoch, d_per_px, order=3):
    g = np.random.default_rng(7)
    n = len(epoch.data)
    t = np.arange(n) / n
    wx = 0.60 + 0.004 * np.sin(2 * np.pi * 3 * t) + 0.001 * g.standard_normal(n)
    wy = 0.64 + 0.003 * np.cos(2 * np.pi * 5 * t) + 0.001 * g.standard_normal(n)
    psfw = 1 + d_per_px[0] * (wx - wx.mean()) + d_per_px[1] * (wy - wy.mean())
    gain = _poly_gain(epoch.data.x, epoch.data.y, order, seed=11) * psfw
    return _exact_epoch(epoch, gain, width_x=wx, width_y=wy)


class _Trapezoid:
    """The test eclipse geometry in the astro API (as conftest's ``fit_depth`` uses)."""

    def __init__(self, time_bmjd, synth):
        self.time_bmjd, self.synth = time_bmjd, synth

    def visible_fraction(self, t_ecl_bmjd):
        return self.synth.eclipse_curve(self.time_bmjd, t_ecl_bmjd, 1e6) - 1.0


def test_psf_width_term_multiplies_the_polynomial_exactly(epoch_sys, synth):
    """SPCA's poly x (1 + d_x wx + d_y wy): slopes and depth recovered exactly."""
    d_true = (0.35, -0.25)     # relative flux per pixel of width
    data = _width_epoch(epoch_sys, d_true)
    model = eb.method_class("poly3").build(data, psf_width=True)
    assert model.param_names == ("psfw_x_per_px", "psfw_y_per_px")
    assert model.n_effective_params() == 10 + 2
    np.testing.assert_allclose(model.predict(epoch_sys.astro, np.array(d_true)), data.flux,
                               rtol=1e-10)
    astro = AstroModel(data.time_bmjd, None, phase="flat", shape=_Trapezoid(data.time_bmjd, synth))
    fit = fit_leastsq(model, astro, astro.initial(depth=1.5e-3,
                                                  t_event_bmjd=epoch_sys.t_ecl_bmjd + 0.003))
    assert abs(fit.value("depth") * 1e6 - epoch_sys.depth_ppm) < 1e-3
    np.testing.assert_allclose([fit.value("sys_psfw_x_per_px"), fit.value("sys_psfw_y_per_px")],
                               d_true, rtol=1e-6)
    without = eb.method_class("poly3").build(data)
    rel = data.flux / without.predict(epoch_sys.astro) - 1
    assert np.sqrt(np.mean(rel**2)) > 1e-5


def test_psf_width_refit_equals_fresh_build(epoch_sys):
    data = _width_epoch(epoch_sys, (0.2, 0.1))
    model = eb.method_class("poly4").build(data, psf_width=True)
    flux = data.flux * (1 + 1e-4 * np.random.default_rng(1).standard_normal(len(data)))
    refit = model.with_flux(flux)
    fresh = type(model)(dataclasses.replace(data, flux=flux), model.options)
    theta = np.array([0.1, -0.2])
    np.testing.assert_allclose(refit.predict(epoch_sys.astro, theta),
                               fresh.predict(epoch_sys.astro, theta), rtol=1e-10)


def test_too_few_binned_points_is_one_line(epoch_small):
    with pytest.raises(InputError, match="poly5.*bin_frames"):
        eb.method_class("poly5").build(epoch_small.data.subset(np.arange(640)))
