"""Wavelet pixel-ICA systematics (paper Appendix B.3; Morello et al. 2014-2016)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from eclipsebench.decorrelate.base import EpochData, MethodContext
from eclipsebench.decorrelate.ica import (
    IndependentComponents,
    fastica_isr,
    separate,
    wavelet_coefficients,
)
from eclipsebench.errors import InputError
from eclipsebench.seeding import rng


def test_wavelet_transform_is_orthogonal():
    g = rng(1, "tests", "ica", "dwt")
    x = g.standard_normal((1024, 3))
    c = wavelet_coefficients(x, "db4", 5)
    assert c.shape == (1024, 3)
    np.testing.assert_allclose(np.sum(c**2, axis=0), np.sum(x**2, axis=0), rtol=1e-10)


def _mixed_stamps(n=8192, seed=2):
    """Three independent sources mixed into nine pixels, plus white noise per pixel."""
    g = rng(seed, "tests", "ica", "sources")
    t = np.arange(n)
    sources = np.column_stack([
        g.laplace(size=n) * (g.random(n) < 0.05),                   # sparse jitter spikes
        np.cumsum(g.random(n) < 0.002) % 2 - 0.5,                   # random telegraph jumps
        np.convolve(g.exponential(size=n) * (g.random(n) < 0.01),   # decaying bursts
                    np.exp(-np.arange(60) / 15.0))[:n],
    ])
    sources = (sources - sources.mean(axis=0)) / sources.std(axis=0)
    stamp = np.array([1, 2, 1, 2, 6, 2, 1, 2, 1], float) * 1e4
    mixing = g.normal(0.0, 150.0, (9, 3))
    pixels = stamp + sources @ mixing.T + g.normal(0.0, 5.0, (n, 9))
    flux = pixels.sum(axis=1)
    data = EpochData(time_bmjd=56000.0 + t * 2.0 / 86400, flux=flux, flux_err=np.sqrt(flux),
                     x=np.zeros(n), y=np.zeros(n), pixels=pixels)
    return data, sources


def test_separates_injected_sources_and_reports_a_separation_error():
    """Each injected source is one component (|r| > 0.95); the separation error is > 0.

    The flux-free projection that stood in for ICA failed both: its components
    were projected away from the sources, and its separation error was 0.
    """
    data, sources = _mixed_stamps()
    m = IndependentComponents(data, n_components=3, context=MethodContext(seed=1, method="ica"))
    corr = np.abs(np.corrcoef(sources.T, m.all_components.T)[:3, 3:])
    assert np.all(corr.max(axis=1) > 0.95), corr
    assert sorted(corr.argmax(axis=1)) == [0, 1, 2]
    astro = np.ones(len(data))
    astro[3000:5000] = 1 - 2e-3
    var = m.extra_depth_variance(astro, (astro - 1.0) / 2e-3)
    assert var > 0
    assert m.diagnostics()["depth_err_separation_ppm"] == pytest.approx(np.sqrt(var) * 1e6)
    assert m.diagnostics()["depth_err_separation_ppm"] > 0


def test_asymptotic_isr_agrees_with_repeated_separations():
    """The FastICA ISR formula against the spread of separations on fresh samples."""
    n, k = 4000, 2
    g = rng(4, "tests", "ica", "isr")
    a = np.array([[1.0, 0.6], [0.4, 1.0]])
    gains = []
    for r in range(40):
        s = np.column_stack([g.laplace(size=n), g.uniform(-1, 1, n)])
        s = (s - s.mean(axis=0)) / s.std(axis=0)
        w, _, est, _ = separate(s @ a.T, k, r, max_iter=1000, tol=1e-8)
        gain = w @ a
        order = np.argmax(np.abs(gain), axis=1)
        gains.append(gain[:, [0, 1]][np.argsort(order)])
        if r == 0:
            isr_formula = fastica_isr(est)[np.ix_(np.argsort(order), np.argsort(order))]
    gains = np.array(gains)
    measured = np.mean((gains[:, 0, 1] / gains[:, 0, 0]) ** 2)
    assert 0.3 < isr_formula[0, 1] / measured < 3.0, (isr_formula, measured)


def _truth_box_amplitudes(components, epoch_sys, time_bmjd):
    """Each component's eclipse amplitude against the TRUE eclipse (tests only)."""
    astro = np.interp(time_bmjd, epoch_sys.data.time_bmjd, epoch_sys.astro)
    box = (astro.max() - astro) / (astro.max() - astro.min())
    tn = (time_bmjd - time_bmjd.mean()) / np.ptp(time_bmjd)
    design = np.column_stack([np.ones_like(tn), tn, tn**2, box])
    return np.linalg.lstsq(design, components, rcond=None)[0][-1]


def test_eclipse_component_and_depth_with_photon_noise(epoch_sys, synth):
    """3x3 stamps with photon noise (10,000 frames): the eclipse component is the one a
    common-mode change enters most, every other component is kept (App. B.3), and the
    depth is recovered to -207 ppm (photon error about 70 ppm; purity 0.76: a kept
    component follows the eclipse window without taking a common-mode change)."""
    m = IndependentComponents(_noisy_epoch(epoch_sys, predicted=False),
                              context=MethodContext(seed=3, epoch=1, method="ica"))
    diag = m.diagnostics()
    assert diag["eclipse_rule"] == "common_mode_gain"
    assert m.eclipse_index == int(np.argmax(np.abs(diag["common_mode_gain"])))
    assert 0.0 < diag["eclipse_purity"] <= 1.0
    assert m.selected == [j for j in range(9) if j != m.eclipse_index] and m.n_effective_params() == 9
    depth, _ = synth.fit_depth(m, m.data.time_bmjd,
                               t_ecl_guess=epoch_sys.t_ecl_bmjd + 5.0 / 1440)
    assert abs(depth - epoch_sys.depth_ppm) < 250.0, depth


def test_common_mode_gain_finds_the_eclipse_where_the_mixing_column_does_not(epoch_sys, synth):
    """Low noise (0.3 x photon noise, 3x3): the estimated mixing column of the eclipse
    component takes the signature of the strong pointing signals, so the component
    most parallel to the mean stamp is a pointing one; the common-mode gain picks
    the component that carries the (true) eclipse, and the depth follows."""
    g = rng(9, "tests", "ica", "low-noise")
    d = epoch_sys.data
    pix = d.pixels.reshape(-1, 5, 5)[:, 1:4, 1:4].reshape(-1, 9)
    pix = pix + 0.3 * np.sqrt(pix) * g.standard_normal(pix.shape)
    data = dataclasses.replace(d, pixels=pix, flux=pix.sum(axis=1), flux_err=np.sqrt(pix.sum(axis=1)))
    m = IndependentComponents(data, context=MethodContext(seed=3, epoch=1, method="ica"))
    diag = m.diagnostics()
    amp = np.abs(_truth_box_amplitudes(m.all_components, epoch_sys, data.time_bmjd))
    assert m.eclipse_index == int(np.argmax(amp)), (amp, diag["common_mode_gain"])
    assert amp[diag["mean_stamp_index"]] < 0.2 * amp.max()
    depth, _ = synth.fit_depth(m, data.time_bmjd, t_ecl_guess=epoch_sys.t_ecl_bmjd + 5.0 / 1440)
    assert abs(depth - epoch_sys.depth_ppm) < 100.0, depth


def test_noiseless_stress_epoch_spreads_the_eclipse_and_the_purity_says_so(epoch_sys):
    """Noiseless pixel series that are a non-linear function of the pointing (rank about
    10 for the 5x5 stamp, pointing terms as small as the eclipse) are not a linear
    mixture of independent sources: the eclipse lands in several components. The
    common-mode gains predict each component's (true) eclipse content and the
    purity flags the failure; the ISR does not (docs/methods.md, ICA)."""
    m = IndependentComponents(epoch_sys.data, context=MethodContext(seed=0, method="ica"))
    diag = m.diagnostics()
    gain = np.asarray(diag["common_mode_gain"]) * epoch_sys.depth_ppm * 1e-6
    amp = _truth_box_amplitudes(m.all_components, epoch_sys, epoch_sys.data.time_bmjd)
    assert abs(np.corrcoef(gain, amp)[0, 1]) > 0.9, (gain, amp)
    assert diag["eclipse_purity"] < 0.7
    assert np.sum(np.abs(amp) > 0.3 * np.abs(amp).max()) >= 3
    assert diag["isr_max"] < 0.05


def test_seed_enters_fastica_and_bootstrap_restarts(epoch_small):
    data = epoch_small.data
    ctx = MethodContext(seed=3, epoch=1, method="ica")
    a = IndependentComponents(data, n_restarts=2, max_iter=400, context=ctx)
    b = IndependentComponents(data, n_restarts=2, max_iter=400, context=ctx)
    np.testing.assert_array_equal(a.all_components, b.all_components)
    np.testing.assert_array_equal(a.isr, b.isr)
    assert a.diagnostics()["isr_method"] == "bootstrap"
    c = IndependentComponents(data, n_restarts=2, max_iter=400,
                              context=MethodContext(seed=4, epoch=1, method="ica"))
    assert not np.array_equal(a.isr, c.isr)


def test_refit_keeps_the_separation_and_redoes_the_selection(epoch_small):
    m = IndependentComponents(epoch_small.data, max_iter=400, selection="bic")
    flux = m.data.flux + 30.0 * m.all_components[:, m.eclipse_index - 1]
    refit = m.with_flux(flux)
    fresh = IndependentComponents(dataclasses.replace(m.data, flux=flux), m.options,
                                  context=m.context)
    assert refit.selected == fresh.selected
    assert refit.diagnostics()["selection_bic"] == fresh.diagnostics()["selection_bic"]
    np.testing.assert_array_equal(refit.all_components, m.all_components)


def test_bad_options_are_one_line_input_errors(epoch_flat):
    data = epoch_flat.data
    with pytest.raises(InputError, match="n_components"):
        IndependentComponents(data, n_components=1)
    with pytest.raises(InputError, match="wavelet"):
        IndependentComponents(data, wavelet="no-such-wavelet")
    with pytest.raises(InputError, match="combine"):
        IndependentComponents(data, combine="both")
    with pytest.raises(InputError, match="selection"):
        IndependentComponents(data, selection="some")
    with pytest.raises(InputError, match="n_restarts"):
        IndependentComponents(data, n_restarts=1)
    with pytest.raises(InputError, match="flux_free"):
        IndependentComponents(data, flux_free=True)
    with pytest.raises(InputError, match="stamp"):
        IndependentComponents(dataclasses.replace(data, pixels=data.pixels[:, :2]))


def _noisy_epoch(epoch_sys, *, predicted=True):
    """The tests' synthetic epoch, central 3x3 pixels with photon noise, and (as the
    reducer passes it) the eclipse time predicted by the ephemeris."""
    g = rng(9, "tests", "ica", "noise")
    d = epoch_sys.data.subset(np.arange(2000, 12000))
    pix = d.pixels.reshape(-1, 5, 5)[:, 1:4, 1:4].reshape(-1, 9)
    pix = pix + np.sqrt(pix) * g.standard_normal(pix.shape)
    meta = {**d.meta, "t_ecl_predicted_bmjd": epoch_sys.t_ecl_bmjd} if predicted else d.meta
    return dataclasses.replace(d, pixels=pix, flux=pix.sum(axis=1),
                               flux_err=np.sqrt(pix.sum(axis=1)), meta=meta)


def test_eclipse_shape_at_the_predicted_time_is_scored_not_used(epoch_sys):
    """With the predicted eclipse time each component gets an eclipse-shape score (box
    at that time) in the diagnostics; the component used is the common-mode one (the
    box score is fooled by red-noise components: docs/methods.md). Without the time
    there is no score and the same component."""
    data = _noisy_epoch(epoch_sys)
    ctx = MethodContext(seed=3, epoch=1, method="ica")
    m = IndependentComponents(data, context=ctx)
    diag = m.diagnostics()
    assert diag["eclipse_rule"] == "common_mode_gain"
    assert m.eclipse_index == int(np.argmax(np.abs(diag["common_mode_gain"])))
    assert len(diag["eclipse_shape_score"]) == m.all_components.shape[1]
    assert diag["eclipse_box_duration_d"] > 0
    blind = IndependentComponents(_noisy_epoch(epoch_sys, predicted=False), context=ctx)
    assert "eclipse_shape_score" not in blind.diagnostics()
    assert blind.eclipse_index == m.eclipse_index


def test_eclipse_left_in_kept_components_enters_the_separation_error(epoch_sys):
    """A kept component that carries part of the eclipse (an imperfect separation)
    pulls the fitted depth; the separation error includes that depth (the ISR alone,
    a few ppm, did not)."""
    data = _noisy_epoch(epoch_sys)
    m = IndependentComponents(data, context=MethodContext(seed=3, epoch=1, method="ica"))
    t = m.data.time_bmjd
    box = (np.abs(t - epoch_sys.t_ecl_bmjd) < 0.05).astype(float)
    astro = 1.0 - 1.875e-3 * box
    clean = m.extra_depth_variance(astro, -box)
    leak_clean = m.diagnostics()["eclipse_leak_ppm"]
    j = m.selected[0]
    m.all_components[:, j] -= 0.5 * box          # eclipse signal left in a kept component
    m._select()
    var = m.extra_depth_variance(astro, -box)
    diag = m.diagnostics()
    assert j in m.selected
    assert abs(diag["eclipse_leak_ppm"] - leak_clean) > 100.0, (diag, leak_clean)
    assert np.sqrt(var) * 1e6 >= abs(diag["eclipse_leak_ppm"])
    assert np.sqrt(clean) * 1e6 >= abs(leak_clean)
    assert diag["depth_err_isr_ppm"] < 0.2 * abs(diag["eclipse_leak_ppm"])
