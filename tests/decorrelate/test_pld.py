"""PLD: normalised pixels, weighted linear least squares, time terms, binning."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from astropy.table import Table

from eclipsebench.astro.catalogue import get_system
from eclipsebench.astro.eclipse import EclipseShape
from eclipsebench.astro.orbit import eclipse_time_bmjd
from eclipsebench.config.reduce import ReduceSection
from eclipsebench.config.system import SystemSection
from eclipsebench.decorrelate import get_method
from eclipsebench.decorrelate.base import EpochData
from eclipsebench.decorrelate.linear import LinearDesign, fit_residuals, solve_coefficients
from eclipsebench.decorrelate.pld import time_averaging_error
from eclipsebench.errors import InputError
from eclipsebench.fit.reduce import reduce_epoch


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


def test_binned_residuals_bin_the_design_once(monkeypatch):
    """A binned fit's residuals bin ``astro D`` once per evaluation, for the solve and the
    residuals both (issue 40: half the prayer bead's time), with the bytes of the two taken
    apart; frames already in time order are binned without being reordered."""
    data = _pixel_epoch(n=605)
    astro = 1 + 1e-3 * np.cos(np.arange(len(data)) / 30.0)
    model = get_method("pld")(data, bin_frames=10)
    design = model.design
    assert design.order is None
    want = fit_residuals(design, astro, solve_coefficients(design, astro))
    binned = LinearDesign._binned
    calls = []

    def counted(self, a):
        calls.append(a.shape)
        return binned(self, a)

    monkeypatch.setattr(LinearDesign, "_binned", counted)
    got = model.residuals(astro)
    assert calls == [(605, 9)] and got.tobytes() == want.tobytes()


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


# --------------------------------------------------------------------------- binned fit, bin choice
def _noisy(epoch, sigma=3e-4, seed=5):
    g = np.random.default_rng(seed)
    d = epoch.data
    return dataclasses.replace(d, flux=d.flux * (1 + sigma * g.standard_normal(len(d))))


def test_the_fit_is_made_on_the_bins():
    data = _pixel_epoch(n=605)
    astro = 1 + 1e-3 * np.cos(np.arange(len(data)) / 30.0)
    model = get_method("pld")(data, bin_frames=10)
    starts = np.arange(0, 605, 10)
    phat = _phat(data.pixels, 3)
    design = np.array([(astro[s:s + 10, None] * phat[s:s + 10]).mean(axis=0) for s in starts])
    flux = np.array([data.flux[s:s + 10].mean() for s in starts])
    sigma = np.array([np.sqrt(np.sum(data.flux_err[s:s + 10] ** 2)) / len(data.flux_err[s:s + 10])
                      for s in starts])
    c = _wls(design, flux, sigma)
    resid = model.residuals(astro)
    assert len(resid) == 61          # one per bin: the fitter minimises the binned chi^2
    np.testing.assert_allclose(resid, (flux - design @ c) / sigma, rtol=1e-6, atol=1e-9)


def _independent_slope(rel):
    """Weighted log-log slope of the rms of 2^k-frame means (>= 10 bins), by numpy.polyfit."""
    sizes, logs, w = [], [], []
    k = 1
    while len(rel) // k >= 10:
        m = len(rel) // k
        means = rel[:m * k].reshape(m, k).mean(axis=1)
        sizes.append(np.log(k))
        logs.append(np.log(np.std(means, ddof=1)))
        w.append(np.sqrt(m - 1.0))
        k *= 2
    slope, intercept = np.polyfit(sizes, logs, 1, w=w)
    return slope, intercept


def test_bin_size_is_chosen_by_the_slope_criterion(epoch_small):
    data = _noisy(epoch_small)
    astro = epoch_small.astro
    model = get_method("pld")(data, bin_candidates=[1, 4, 16, 64])
    assert model.bin_frames == 1     # before any fit
    model.optimise_hyperparameters(astro)
    slopes = {}
    for b in (1, 4, 16, 64):
        fixed = get_method("pld")(data, bin_frames=b)
        slopes[b] = _independent_slope(data.flux / fixed.predict(astro) - 1.0)[0]
    best = min(slopes, key=lambda b: abs(slopes[b] + 0.5))
    assert model.bin_frames == best
    for b, s in slopes.items():
        assert model.diagnostics()["scatter_slope_by_bin"][str(b)] == pytest.approx(s, rel=1e-9)
    # A fixed bin size is never changed.
    fixed = get_method("pld")(data, bin_frames=16)
    assert fixed.optimise_hyperparameters(astro) is None and fixed.bin_frames == 16


def test_time_averaging_error_of_white_noise_and_its_baseline_term():
    rel = 1e-3 * np.random.default_rng(3).standard_normal(2**14)
    slope, intercept = _independent_slope(rel)
    err = time_averaging_error(rel, 4000)
    assert err == pytest.approx(np.exp(intercept) * 4000**slope, rel=1e-9)
    assert err == pytest.approx(1e-3 / np.sqrt(4000), rel=0.15)
    both = time_averaging_error(rel, 4000, n_baseline=12000)
    assert both == pytest.approx(np.hypot(err, np.exp(intercept) * 12000**slope), rel=1e-9)


def _xo3_pld_table(synth, n_frames=3000, noise=3e-4, seed=7):
    """A photometry table around XO-3b's predicted eclipse with rendered 5x5 stamps."""
    system = get_system(SystemSection().name)  # the default planet, which reduce_epoch assumes
    t_ecl = eclipse_time_bmjd(system, 57000.0)
    time = t_ecl + np.linspace(-0.2, 0.17, n_frames)
    astro = 1 + 1875e-6 * EclipseShape(time, system).visible_fraction(t_ecl)
    g = np.random.default_rng(seed)
    t_h = (time - time[0]) * 24.0
    x = 15.1 + 0.02 * t_h + 0.02 * np.sin(2 * np.pi * t_h / 0.67) + 0.005 * g.standard_normal(n_frames)
    y = 15.0 - 0.01 * t_h + 0.015 * np.cos(2 * np.pi * t_h / 0.67) + 0.005 * g.standard_normal(n_frames)
    stamps = synth.render_stamps(x, y, 1e5 * astro)
    stamps = stamps * (1 + noise * g.standard_normal(len(time)))[:, None, None]
    flux, xc, yc, beta = synth.stamp_measurements(stamps)
    n = len(time)
    table = Table({"time_bmjd": time, "aorkey": np.full(n, 20150001), "x": xc, "y": yc,
                   "noise_pixels": beta, "flux": flux, "flux_err": np.full(n, 1e5 * noise),
                   "flag": np.zeros(n, dtype=np.int32), "stamp3": stamps[:, 2:5, 2:5],
                   "stamp5": stamps[:, 1:6, 1:6]})
    table.meta["EPOCH"] = 1
    table.meta["SYSTEM"] = "XO-3b (2015 challenge)"
    return table


def test_reported_error_is_the_time_averaging_extrapolation(synth):
    table = _xo3_pld_table(synth)
    res = reduce_epoch(table, "pld", options=ReduceSection(error_rule="method",
                                                           prayer_bead_shifts=0))
    own = res.depth_err_own_ppm["time_averaging"]
    assert res.depth_err_method == "time_averaging"
    assert res.depth_err_ppm == own
    # Independently: the relative residuals' rms against bin size, extrapolated
    # to the frames of the eclipse (planet below half its light).
    lc = res.lightcurve
    rel = lc["residual"] / lc["astro_model"]
    slope, intercept = _independent_slope(rel[np.argsort(lc["time_bmjd"])])
    visible = EclipseShape(lc["time_bmjd"], get_system(SystemSection().name)).visible_fraction(
        res.t_ecl_bmjd)
    n_ecl = int(np.count_nonzero(visible < 0.5))
    # The method counts the frames from d astro / d depth, which also carries the
    # phase curve's few-percent variation: a frame or two of ~1,000 either way.
    assert own == pytest.approx(np.exp(intercept) * n_ecl**slope * 1e6, rel=2e-3)
    # The default rule ("largest") reports the largest of the shared estimates instead.
    shared = reduce_epoch(table, "pld", options=ReduceSection(prayer_bead_shifts=0))
    assert shared.depth_err_method != "time_averaging"
    assert shared.depth_err_own_ppm["time_averaging"] == pytest.approx(own, rel=1e-6)
