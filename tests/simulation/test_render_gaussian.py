"""The twins' Gaussian photon noise (``FrameModel.gaussian_skew``, issue 40): the physical
model's mean and variance per pixel with one draw, exact draws kept where the skewness lost
would be large."""

from __future__ import annotations

import numpy as np
import pytest

from eclipsebench.detector.constants import ReadoutMode
from eclipsebench.detector.fowler import fowler_weights
from eclipsebench.errors import InputError
from eclipsebench.simulation.render import FrameModel, render_frames, tick_moments

SUB2 = ReadoutMode("sub_2s", 8, 184, 0.01, 2.0, True)


def _render(skew: float, read_noise_e: float, nf: int, seed: int = 1):
    """A star in the 5 x 5 stamp (0.02 to 3,600 e per exposure) on 35 e of sky, 8 x 8 pixels."""
    model = FrameModel(mode=SUB2, read_noise_e=read_noise_e, stamp_px=5, shape=(8, 8),
                       gaussian_skew=skew)
    zero = np.zeros((nf, model.grid_samples_per_frame))
    _, _, moments = tick_moments(zero, zero, model)
    basis = np.zeros((nf, 6, 25))
    basis[:, 0] = np.geomspace(1e-4, 20.0, 25)[None, :]       # PRF units per stamp pixel
    photon, read = np.random.default_rng(seed), np.random.default_rng(seed + 100)
    wings = np.zeros((8, 8))
    wings[0, :] = 0.01
    frames, expected = render_frames(
        model=model, moments=moments, basis=basis, stamp_x0=2, stamp_y0=2, wings=wings,
        star_e_per_tick=np.ones(nf), background_e_per_tick=np.full(nf, 35.0 / 192.0),
        rng_photon=photon, rng_read=read)
    return frames.reshape(nf, -1), expected.reshape(nf, -1), photon


def _physical_variance(expected: np.ndarray, read_noise_e: float) -> np.ndarray:
    """Without motion each tick holds the same charge: the frame's photon variance is
    ``sum_k w_k^2 q / FN^2`` with ``q = expected FN / sum_k w_k``, plus the read noise."""
    w = fowler_weights(SUB2).astype(float)
    return expected * (w**2).sum() / (SUB2.fowler * w.sum()) + 2 * read_noise_e**2 / SUB2.fowler


def test_gaussian_photon_noise_has_the_physical_mean_and_variance_in_one_draw():
    nf = 6000
    frames, expected, photon = _render(0.1, 9.4, nf)
    exact, exact_expected, _ = _render(0.0, 9.4, nf, seed=2)
    np.testing.assert_array_equal(expected, exact_expected)
    # with 9.4 e of read noise no pixel keeps exact draws: the photon stream is never read
    assert photon.bit_generator.state == np.random.default_rng(1).bit_generator.state
    var = _physical_variance(expected[0], 9.4)
    for sample in (frames, exact):
        mean_z = (sample.mean(axis=0) - expected[0]) / np.sqrt(var / nf)
        assert np.max(np.abs(mean_z)) < 4.5
        # the sample variance's relative SE is sqrt(2 / nf) = 1.8 % (the Gaussian's)
        np.testing.assert_allclose(sample.var(axis=0, ddof=1) / var, 1.0, atol=0.08)
    # the aperture sum's variance too (the 9 brightest pixels; covariances are zero)
    bright = np.argsort(expected[0])[-9:]
    total = var[bright].sum()
    for sample in (frames, exact):
        assert sample[:, bright].sum(axis=1).var(ddof=1) / total == pytest.approx(1.0, abs=0.06)


def test_pixels_whose_skewness_would_be_lost_keep_their_exact_draws():
    """Without read noise the bound is 1 / sqrt(photon variance): pixels under 100 e^2 stay
    Poisson (their FN-fold values whole electrons), the brighter ones are Gaussian."""
    nf = 3000
    frames, expected, photon = _render(0.1, 0.0, nf)
    var = _physical_variance(expected[0], 0.0)
    whole = np.all(np.abs(frames * SUB2.fowler - np.rint(frames * SUB2.fowler)) < 1e-9, axis=0)
    assert np.array_equal(whole, var < 100.0)
    assert 0 < whole.sum() < whole.size
    assert photon.bit_generator.state != np.random.default_rng(1).bit_generator.state
    mean_z = (frames.mean(axis=0) - expected[0]) / np.sqrt(var / nf)
    assert np.max(np.abs(mean_z)) < 4.5
    np.testing.assert_allclose(frames.var(axis=0, ddof=1) / var, 1.0, atol=0.12)


@pytest.mark.parametrize("noise_model, skew", [("iracsim2015", 0.1), ("none", 0.1),
                                               ("physical", -0.1)])
def test_gaussian_skew_is_refused_outside_the_physical_model(noise_model, skew):
    with pytest.raises(InputError, match="gaussian_skew"):
        FrameModel(mode=SUB2, noise_model=noise_model, gaussian_skew=skew)
