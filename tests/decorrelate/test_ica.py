"""Wavelet pixel-ICA systematics (paper Appendix B.3; Morello et al. 2014-2016)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from eclipsebench.decorrelate import get_method
from eclipsebench.decorrelate.base import MethodContext
from eclipsebench.decorrelate.ica import IndependentComponents, separate, wavelet_coefficients
from eclipsebench.errors import InputError
from eclipsebench.seeding import rng


def test_wavelet_transform_is_orthogonal():
    g = rng(1, "tests", "ica", "dwt")
    x = g.standard_normal((1024, 3))
    c = wavelet_coefficients(x, "db4", 5)
    assert c.shape == (1024, 3)
    np.testing.assert_allclose(np.sum(c**2, axis=0), np.sum(x**2, axis=0), rtol=1e-10)


def test_fastica_recovers_two_non_gaussian_sources():
    """Sparse spikes and uniform noise mixed into four channels: unmixing x mixing ~ permutation."""
    n = 4096
    g = rng(2, "tests", "ica", "sources")
    s1 = g.laplace(size=n) * (g.random(n) < 0.05)
    s2 = g.uniform(-1.0, 1.0, n)
    a = np.array([[1.0, 0.5], [0.3, 1.0], [0.8, -0.6], [0.2, 0.9]])
    x = np.column_stack([s1, s2]) @ a.T
    xc = x - x.mean(axis=0)
    unmix, mixing, converged = separate(wavelet_coefficients(xc, "db4", 6), 2, 7,
                                        max_iter=2000, tol=1e-6)
    p = np.abs(unmix @ a)
    assert converged
    assert np.all(p.min(axis=1) < 0.02 * p.max(axis=1)), p
    assert mixing.shape == (4, 2)


def test_depth_recovered_within_20_ppm_with_systematics(epoch_sys, synth):
    m = get_method("ica")(epoch_sys.data, n_restarts=2)
    depth, t_ecl = synth.fit_depth(m, m.data.time_bmjd,
                                   t_ecl_guess=epoch_sys.t_ecl_bmjd + 5.0 / 1440)
    assert abs(depth - epoch_sys.depth_ppm) <= 20.0, depth
    assert abs(t_ecl - epoch_sys.t_ecl_bmjd) * 86400 < 60.0


def test_flux_free_components_carry_no_eclipse(epoch_sys):
    """A uniform flux change (the eclipse) leaves every projected regressor unchanged."""
    m = IndependentComponents(epoch_sys.data, n_restarts=0)
    pixels = epoch_sys.data.pixels
    scale = np.median(pixels.sum(axis=1))
    dimmed = (pixels * 0.998) / scale - (pixels / scale)
    mean_dir = (pixels / scale).mean(axis=0)
    mean_dir /= np.linalg.norm(mean_dir)
    unmix = m._unmix - np.outer(m._unmix @ mean_dir, mean_dir)
    change = dimmed @ unmix.T
    raw_change = dimmed @ m._unmix.T
    assert np.max(np.abs(change)) < 0.05 * np.max(np.abs(raw_change))


def test_agrees_with_pld_within_5_ppm_without_systematics(epoch_flat, synth):
    depths = []
    for model in (IndependentComponents(epoch_flat.data, n_restarts=0),
                  get_method("pld")(epoch_flat.data)):
        d, _ = synth.fit_depth(model, model.data.time_bmjd,
                               t_ecl_guess=epoch_flat.t_ecl_bmjd + 5.0 / 1440)
        depths.append(d)
    assert abs(depths[0] - depths[1]) <= 5.0, depths


CTX = MethodContext(seed=3, epoch=1, method="ica")


def test_separation_error_from_bootstrap_restarts(epoch_sys, synth):
    g = rng(9, "tests", "ica", "noise")
    d = epoch_sys.data.subset(np.arange(4000, 11000))
    pix = d.pixels + np.sqrt(np.clip(d.pixels, 1, None)) * g.standard_normal(d.pixels.shape)
    flux = d.flux + np.sqrt(d.flux) * g.standard_normal(len(d))
    noisy = dataclasses.replace(d, pixels=pix, flux=flux)
    m = IndependentComponents(noisy, n_restarts=3, max_iter=400, context=CTX)
    astro = synth.eclipse_curve(d.time_bmjd, epoch_sys.t_ecl_bmjd, epoch_sys.depth_ppm)
    dastro = (synth.eclipse_curve(d.time_bmjd, epoch_sys.t_ecl_bmjd, 1e6) - 1.0)
    var = m.extra_depth_variance(astro, dastro)
    assert np.isfinite(var) and 0 < np.sqrt(var) * 1e6 < 200.0
    assert IndependentComponents(noisy, n_restarts=0, max_iter=400).extra_depth_variance(
        astro, dastro) == 0.0
    # same seed, same components; the seed enters FastICA
    again = IndependentComponents(noisy, n_restarts=0, max_iter=400, context=CTX)
    np.testing.assert_array_equal(again.components, m.components)


def test_identify_astrophysical_picks_the_most_correlated_component(epoch_sys):
    m = IndependentComponents(epoch_sys.data, n_restarts=0)
    k = m.identify_astrophysical(epoch_sys.astro)
    corr = [abs(np.corrcoef(m._comps_raw[:, j], epoch_sys.astro)[0, 1])
            for j in range(m._comps_raw.shape[1])]
    assert k == int(np.argmax(corr))
    assert m.components.shape == (len(epoch_sys.data), m._comps_raw.shape[1] - 1)


def test_bad_options_are_one_line_input_errors(epoch_flat):
    data = epoch_flat.data
    with pytest.raises(InputError, match="n_components"):
        IndependentComponents(data, n_components=1)
    with pytest.raises(InputError, match="wavelet"):
        IndependentComponents(data, wavelet="no-such-wavelet")
    with pytest.raises(InputError, match="combine"):
        IndependentComponents(data, combine="both")
    with pytest.raises(InputError, match="stamp"):
        IndependentComponents(dataclasses.replace(data, pixels=data.pixels[:, :2]))
