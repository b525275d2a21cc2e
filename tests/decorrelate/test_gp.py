"""Gaussian-process systematics (paper Appendix B.2; Evans et al. 2015)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.stats import multivariate_normal

from eclipsebench.decorrelate import get_method
from eclipsebench.decorrelate.base import EpochData
from eclipsebench.decorrelate.gp import OFFSET_NAMES, GaussianProcess, bin_epoch, kernel_matrix
from eclipsebench.errors import InputError
from eclipsebench.seeding import rng


def _small(n=80, seed=1):
    g = rng(seed, "tests", "gp", "small")
    t = 57000 + np.arange(n) * 30.0 / 86400
    x = 15.0 + 0.05 * np.sin(np.arange(n) / 7.0) + 0.01 * g.standard_normal(n)
    y = 15.0 + 0.04 * np.cos(np.arange(n) / 5.0) + 0.01 * g.standard_normal(n)
    flux = 1e5 * (1 + 0.003 * (x - 15) / 0.05 + 1e-3 * g.standard_normal(n))
    return EpochData(time_bmjd=t, flux=flux, flux_err=np.full(n, 100.0), x=x, y=y,
                     aorkey=np.ones(n, dtype=int))


def test_bin_epoch_is_an_inverse_variance_mean_within_each_aor():
    t = 57000 + np.array([0, 10, 20, 40, 50, 100, 110]) / 86400
    flux = np.array([1.0, 2.0, 4.0, 8.0, 16.0, 32.0, 64.0])
    err = np.array([1.0, 2.0, 1.0, 1.0, 1.0, 1.0, 1.0])
    aor = np.array([1, 1, 1, 1, 1, 2, 2])
    data = EpochData(time_bmjd=t, flux=flux, flux_err=err, x=flux, y=flux, aorkey=aor)
    b = bin_epoch(data, 30.0)
    # bins: AOR1 [0, 30) s -> frames 0,1,2; AOR1 [30, 60) -> 3,4; AOR2 [0, 30) -> 5,6
    w = 1.0 / err**2
    expect = {0: np.sum(w[:3] * flux[:3]) / np.sum(w[:3]), 1: 12.0, 2: 48.0}
    got = dict(zip(b.aorkey.tolist(), b.flux.tolist(), strict=False))
    assert len(b) == 3
    assert b.flux[np.argmin(b.time_bmjd)] == pytest.approx(expect[0])
    assert sorted(b.flux.tolist()) == pytest.approx(sorted(expect.values()))
    assert got[2] == pytest.approx(48.0)
    assert np.all(np.diff(b.time_bmjd) > 0)
    assert b.flux_err[np.argmin(b.time_bmjd)] == pytest.approx(1.0 / np.sqrt(np.sum(w[:3])))
    np.testing.assert_array_equal(np.sort(b.meta["n_per_bin"]), [2, 2, 3])


@pytest.mark.parametrize("kind", ["squared-exponential", "matern32"])
def test_kernel_matrix_formula_and_gradient(kind):
    g = rng(2, "tests", "gp", "kernel")
    z = g.standard_normal((6, 3))
    lengths = np.array([0.7, 1.3, 2.0])
    k, dk = kernel_matrix(z, lengths, kind, gradient=True)
    r = np.sqrt(np.sum(((z[:, None, :] - z[None, :, :]) / lengths) ** 2, axis=2))
    expect = np.exp(-0.5 * r**2) if kind == "squared-exponential" else \
        (1 + np.sqrt(3) * r) * np.exp(-np.sqrt(3) * r)
    np.testing.assert_allclose(k, expect, rtol=1e-12)
    h = 1e-6
    for d in range(3):
        up = lengths.copy()
        up[d] *= np.exp(h)
        num = (kernel_matrix(z, up, kind) - k) / h
        np.testing.assert_allclose(dk[d], num, rtol=1e-4, atol=1e-8)


@pytest.mark.parametrize("kind", ["squared-exponential", "matern32"])
def test_marginal_likelihood_gradient_matches_finite_differences(kind):
    m = GaussianProcess(_small(), bin_seconds=None, kernel=kind)
    y = m.flux_rel
    h0 = m.hyper + np.array([0.1, -0.2, 0.1, -0.5, 0.3])
    f0, grad = m._neg_log_ml(h0, y)
    num = np.empty(5)
    for i in range(5):
        e = np.zeros(5)
        e[i] = 1e-6
        num[i] = (m._neg_log_ml(h0 + e, y)[0] - m._neg_log_ml(h0 - e, y)[0]) / 2e-6
    np.testing.assert_allclose(grad, num, rtol=1e-4, atol=1e-4)


@pytest.mark.parametrize("kind", ["squared-exponential", "matern32"])
def test_compiled_likelihood_and_gradient_equal_dense_numpy(kind):
    # _neg_log_ml fills, factorises and inverts in place with compiled passes; the same
    # quantities from kernel_matrix's dense K and dK, numpy's inverse and full traces.
    m = GaussianProcess(_small(), bin_seconds=None, kernel=kind)
    y = m.flux_rel * (1.0 + 1e-3 * (np.arange(len(m.data)) > 40))
    h = m.hyper + np.array([0.3, -0.4, 0.2, -1.5, 0.5])
    nll, grad = m._neg_log_ml(h, y)
    amp2, white = np.exp(2 * h[0]), np.exp(2 * h[4]) * m.sigma_rel**2
    k, dk = kernel_matrix(m.inputs, np.exp(h[1:4]), kind, gradient=True)
    cov = amp2 * k + np.diag(white)
    cinv = np.linalg.inv(cov)
    ones = np.ones(len(y))
    r = y - (ones @ cinv @ y) / (ones @ cinv @ ones)
    alpha = cinv @ r
    expect_nll = 0.5 * r @ alpha + 0.5 * np.linalg.slogdet(cov)[1]
    dcov = [2 * amp2 * k] + [amp2 * d for d in dk] + [np.diag(2 * white)]
    expect = [-0.5 * (alpha @ d @ alpha - np.trace(cinv @ d)) for d in dcov]
    assert nll == pytest.approx(expect_nll, rel=1e-12)
    np.testing.assert_allclose(grad, expect, rtol=1e-9, atol=1e-9 * np.max(np.abs(expect)))


def test_log_likelihood_is_the_dense_gaussian_density():
    data = _small()
    h = np.log([2e-3, 0.05, 0.05, 0.01, 1.2])
    m = GaussianProcess(data, bin_seconds=None, hyperparameters=h)
    astro = 1.0 + 1e-3 * (np.arange(len(data)) > 40)
    norm = np.median(data.flux)
    yrel = data.flux / astro / norm
    z = np.column_stack([data.x, data.y, data.time_bmjd - data.time_bmjd[0]])
    r2 = np.sum(((z[:, None] - z[None]) / np.exp(h[1:4])) ** 2, axis=2)
    cov = np.exp(2 * h[0]) * np.exp(-0.5 * r2) + np.diag((np.exp(h[4]) * data.flux_err / norm) ** 2)
    ones = np.ones(len(data))
    f0 = ones @ np.linalg.solve(cov, yrel) / (ones @ np.linalg.solve(cov, ones))
    expect = multivariate_normal(mean=np.full(len(data), f0), cov=cov).logpdf(yrel) \
        - len(data) * np.log(norm)
    assert m.log_likelihood(astro) == pytest.approx(expect, rel=1e-10)
    w = m.residuals(astro)
    assert w @ w == pytest.approx((yrel - f0) @ np.linalg.solve(cov, yrel - f0), rel=1e-9)


def test_unbinned_epoch_is_binned_by_default_and_refused_unbinned(epoch_sys):
    data = epoch_sys.data
    assert len(data) == 15000
    with pytest.raises(InputError, match="bin") as info:
        GaussianProcess(data, bin_seconds=0)
    assert "\n" not in str(info.value) and "15000" in str(info.value)
    m = GaussianProcess(data)              # 30 s bins of 2 s frames
    assert len(m.data) == 1000
    assert m.unbinned_data is data
    pred = m.predict(epoch_sys.astro)      # per-frame astro: conditional mean at every frame
    assert pred.shape == (15000,)
    assert m.predict(np.ones(len(m.data))).shape == (1000,)


def test_depth_recovered_within_20_ppm_with_systematics(epoch_sys, synth):
    m = get_method("gp")(epoch_sys.data)
    depth, t_ecl = synth.fit_depth(m, m.data.time_bmjd,
                                   t_ecl_guess=epoch_sys.t_ecl_bmjd + 5.0 / 1440)
    assert abs(depth - epoch_sys.depth_ppm) <= 20.0, depth
    assert abs(t_ecl - epoch_sys.t_ecl_bmjd) * 86400 < 60.0
    assert m.ml_info["converged"]


def test_agrees_with_pld_within_5_ppm_without_systematics(epoch_flat, synth):
    depths = []
    for model in (GaussianProcess(epoch_flat.data), get_method("pld")(epoch_flat.data)):
        d, _ = synth.fit_depth(model, model.data.time_bmjd,
                               t_ecl_guess=epoch_flat.t_ecl_bmjd + 5.0 / 1440)
        depths.append(d)
    assert abs(depths[0] - depths[1]) <= 5.0, depths


def test_sample_kernel_samples_offsets_from_the_ml_kernel():
    data = _small()
    m = GaussianProcess(data, bin_seconds=None, sample_kernel=True)
    assert m.param_names == OFFSET_NAMES
    theta = m.initial_params()
    lo, hi = m.param_bounds()
    np.testing.assert_array_equal(theta, np.zeros(5))
    assert np.all(lo < 0) and np.all(hi > 0)
    astro = np.ones(len(m.data))
    base = m.log_likelihood(astro, theta)
    offset = np.array([0.3, 0.0, -0.2, 0.0, 0.5])
    # an offset is the same as fixing the shifted hyperparameters
    ref = GaussianProcess(data, bin_seconds=None, hyperparameters=m.hyper + offset)
    assert m.log_likelihood(astro, offset) == pytest.approx(ref.log_likelihood(astro), rel=1e-10)
    assert m.log_likelihood(astro, offset) != pytest.approx(base)
    assert m.log_likelihood(astro, theta) == pytest.approx(base, rel=1e-12)
    # least squares keeps the ML kernel whatever theta says
    np.testing.assert_array_equal(m.residuals(astro, offset), m.residuals(astro, theta))


def test_with_flux_keeps_the_kernel_and_bins():
    data = _small(n=200)
    m = GaussianProcess(data)
    new_flux = m.data.flux[::-1].copy()          # same median, so the same normalisation
    m2 = m.with_flux(new_flux)
    assert len(m2.data) == len(m.data)
    np.testing.assert_array_equal(m2.hyper, m.hyper)
    ref = GaussianProcess(dataclasses.replace(m.data, flux=new_flux), bin_seconds=None,
                          hyperparameters=m.hyper)
    astro = np.ones(len(m.data))
    np.testing.assert_allclose(m2.residuals(astro), ref.residuals(astro), rtol=1e-9)
    np.testing.assert_array_equal(m.data.flux, GaussianProcess(data).data.flux)


def test_bad_options_are_one_line_input_errors():
    data = _small()
    with pytest.raises(InputError, match="kernel"):
        GaussianProcess(data, kernel="rbf")
    with pytest.raises(InputError, match="hyperparameters"):
        GaussianProcess(data, hyperparameters=[1.0, 2.0])
