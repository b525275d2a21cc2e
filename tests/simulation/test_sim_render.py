"""Rendering kernels: Fowler grouping, the uniform-rate sampler, the Taylor expansion."""

from __future__ import annotations

import numpy as np
import pytest

from eclipsebench.detector.constants import ReadoutMode
from eclipsebench.instrument.prf import TaylorStamps
from eclipsebench.simulation.render import (
    FrameModel,
    fowler_uniform,
    read_intervals,
    render_frames,
    star_group_charges,
    tick_means,
    tick_moments,
    weight_groups,
)
from eclipsebench.simulation.star import StarImager

SUB2 = ReadoutMode("sub_2s", 8, 184, 0.01, 2.0, True)
SMALL = ReadoutMode("small", 4, 5, 0.01, 0.13, True)


class GaussPRF:
    """Test double: a circular Gaussian star (sigma 0.6 px), analytic derivatives."""

    sigma = 0.6

    def _grid(self, x, y, half):
        x = np.atleast_1d(np.asarray(x, float))
        y = np.atleast_1d(np.asarray(y, float))
        x0 = np.rint(x).astype(int) - half
        y0 = np.rint(y).astype(int) - half
        k = np.arange(2 * half + 1)
        px = x0[:, None, None] + k[None, None, :]
        py = y0[:, None, None] + k[None, :, None]
        return x, y, x0, y0, px - x[:, None, None], py - y[:, None, None]

    def value(self, u, v):
        return np.exp(-(u * u + v * v) / (2 * self.sigma**2)) / (2 * np.pi * self.sigma**2)

    def render(self, x, y, shape=(32, 32)):
        x = np.atleast_1d(np.asarray(x, float))
        y = np.atleast_1d(np.asarray(y, float))
        py, px = np.mgrid[0:shape[0], 0:shape[1]]
        return self.value(px[None] - x[:, None, None], py[None] - y[:, None, None])

    def render_stamp(self, x, y, half=6):
        x, y, x0, y0, u, v = self._grid(x, y, half)
        return self.value(u, v), x0, y0

    def render_taylor(self, x, y, half=6):
        x, y, x0, y0, u, v = self._grid(x, y, half)
        s2 = self.sigma**2
        f = self.value(u, v)
        # derivatives with respect to the star position (x, y): d/dx = -d/du
        return TaylorStamps(f, f * u / s2, f * v / s2, f * (u * u / s2 - 1) / s2,
                            f * u * v / s2**2, f * (v * v / s2 - 1) / s2, x0, y0)


def test_weight_groups_and_read_intervals_partition_the_ticks():
    g = weight_groups(SUB2)
    assert g.shape == (200, 8) and g[0].sum() == 0 and np.all(g[1:].sum(axis=1) == 1)
    assert g[:, 7].sum() == 185 and np.all(g[:, :7].sum(axis=0) == 2)
    r = read_intervals(SMALL)   # reads after ticks 1,2,3,4 and 10,11,12,13
    assert r.shape == (13, 8)
    np.testing.assert_array_equal(r.sum(axis=0), [1, 1, 1, 1, 6, 1, 1, 1])
    assert r[4:10, 4].sum() == 6


@pytest.mark.parametrize("mode", [SUB2, SMALL, ReadoutMode("f2", 2, 6, 0.01, 0.1, True)])
@pytest.mark.parametrize("rate", [0.02, 1.5, 40.0])
def test_uniform_sampler_has_the_exact_fowler_mean_and_variance(mode, rate):
    n = 200_000
    frames = fowler_uniform(np.full(n, rate), mode, np.random.default_rng(3))
    w = np.clip(np.minimum(np.minimum(np.arange(mode.n_max), mode.fowler),
                           mode.n_max - np.arange(mode.n_max)), 0, None).astype(float)
    mean = rate * w.sum() / mode.fowler
    var = rate * (w**2).sum() / mode.fowler**2
    assert mean == pytest.approx(rate * (mode.fowler + mode.wait))
    assert frames.mean() == pytest.approx(mean, rel=4 * np.sqrt(var / n) / mean + 1e-12)
    assert frames.var() == pytest.approx(var, rel=0.02)


def test_taylor_group_charges_match_brute_force_subsampling():
    model = FrameModel(mode=SUB2, subsamples=10, stamp_px=13)
    rng = np.random.default_rng(5)
    n_grid = model.grid_samples_per_frame
    t = np.arange(n_grid) * 1e-3
    # a drift, a 60 s sine and a 0.09 px rms jitter, like the pointing model
    dx = (0.02 * t + 0.04 * np.sin(2 * np.pi * t / 60.0) + rng.normal(0, 0.09, n_grid))[None]
    dy = (-0.01 * t + rng.normal(0, 0.09, n_grid))[None]
    x_off, y_off, moments = tick_moments(dx, dy, model)
    prf = GaussPRF()
    star = StarImager(prf, x_ref_px=15.0, y_ref_px=15.0, radius_px=2.25)
    x0, y0 = 15.13, 15.21
    xf, yf = x0 + x_off, y0 + y_off
    basis = star.taylor_basis(xf, yf, 9, 9, 13)
    groups = star_group_charges(basis, np.einsum("ftm,tg->fgm", moments, weight_groups(SUB2)),
                                np.ones(1))
    # brute force: the PRF at every sub-sample, summed per tick group
    sub = (np.arange(200)[:, None] * 10 + np.arange(10)[None, :])
    py, px = np.mgrid[9:22, 9:22]
    img = prf.value(px[None] - (x0 + dx[0, sub.ravel()])[:, None, None],
                    py[None] - (y0 + dy[0, sub.ravel()])[:, None, None]).reshape(200, 10, -1)
    tick = img.sum(axis=1) / 10.0
    brute = weight_groups(SUB2).T @ tick          # (FN, 169)
    peak = brute.max()
    assert np.abs(groups[:, 0, :] - brute).max() < 2e-3 * peak
    # the Fowler-weighted mean position is what XYMEAN reports
    w = weight_groups(SUB2) @ np.arange(1, 9)
    assert x_off[0] == pytest.approx((w @ dx[0, sub].mean(axis=1)) / w.sum())


def test_common_stamp_crops_each_frame_consistently():
    star = StarImager(GaussPRF(), x_ref_px=15.0, y_ref_px=15.0, radius_px=2.25)
    x = np.array([14.6, 15.4, 16.2])
    y = np.array([15.0, 14.4, 15.6])
    vals = star.stamps(x, y, 9, 9, 13)
    py, px = np.mgrid[9:22, 9:22]
    expect = GaussPRF().value(px[None] - x[:, None, None], py[None] - y[:, None, None])
    np.testing.assert_allclose(vals, expect, rtol=1e-12)
    basis = star.taylor_basis(x, y, 9, 9, 13)
    np.testing.assert_allclose(basis[:, 0].reshape(3, 13, 13), expect, rtol=1e-12)


@pytest.mark.parametrize("noise_model, ratio", [("physical", (189.375 / 192)),
                                                ("iracsim2015", 3.31), ("none", 0.0)])
def test_render_frames_noise_of_a_flat_illumination(noise_model, ratio):
    """Uniform illumination: variance/mean per pixel, physical, IRACSIM's compounding, none.

    IRACSIM's n + 1 sub-samples per tick add no light: the frames show the
    configured 200 e (the 2015 frames show the flux the paper measured)."""
    model = FrameModel(mode=SUB2, noise_model=noise_model, read_noise_e=0.0, subsamples=10,
                       stamp_px=5, shape=(8, 8))
    nf = 3000
    dx = np.zeros((nf, model.grid_samples_per_frame))
    _, _, moments = tick_moments(dx, dx, model)
    basis = np.zeros((nf, 6, 25))
    q = 200.0 / 192.0                                        # 200 e per exposure
    frames, expected = render_frames(
        model=model, moments=moments, basis=basis, stamp_x0=1, stamp_y0=1,
        wings=np.zeros((8, 8)), star_e_per_tick=np.ones(nf), background_e_per_tick=np.full(nf, q),
        rng_photon=np.random.default_rng(1), rng_read=np.random.default_rng(2))
    np.testing.assert_allclose(expected, 200.0, rtol=1e-9)
    var = frames.reshape(nf, -1).var(axis=0)
    # both the stamp (per-group sampler) and the outside (uniform sampler) pixels
    stamp = np.zeros((8, 8), bool)
    stamp[1:6, 1:6] = True
    target = ratio * 200.0
    assert np.mean(var[stamp.ravel()]) == pytest.approx(target, rel=0.03, abs=1e-12)
    assert np.mean(var[~stamp.ravel()]) == pytest.approx(target, rel=0.03, abs=1e-12)
    if noise_model == "none":
        np.testing.assert_array_equal(frames, expected)


def test_read_noise_stream_is_independent_of_the_pointing():
    """Without light, frames are read noise only: identical whatever the pointing did."""
    model = FrameModel(mode=SMALL, read_noise_e=10.0, stamp_px=5, shape=(8, 8))
    nf = 400
    out = []
    for amp in (0.0, 0.3):
        dx = amp * np.random.default_rng(7).normal(size=(nf, model.grid_samples_per_frame))
        _, _, moments = tick_moments(dx, dx, model)
        frames, _ = render_frames(
            model=model, moments=moments, basis=np.zeros((nf, 6, 25)), stamp_x0=1, stamp_y0=1,
            wings=np.zeros((8, 8)), star_e_per_tick=np.ones(nf),
            background_e_per_tick=np.zeros(nf),
            rng_photon=np.random.default_rng(1), rng_read=np.random.default_rng(2))
        out.append(frames)
    np.testing.assert_array_equal(out[0], out[1])
    assert out[0].std() == pytest.approx(10.0 * np.sqrt(2 / 4), rel=0.02)


@pytest.mark.parametrize("noise_model", ["physical", "iracsim2015"])
def test_tick_means_are_the_means_of_tick_moments(noise_model):
    """The twins remove each exposure's mean offset with :func:`tick_means` (issue 40): the
    same bytes as :func:`tick_moments`' means, without its moments."""
    model = FrameModel(mode=SMALL, noise_model=noise_model, read_noise_e=10.0, subsamples=3)
    rng = np.random.default_rng(8)
    dx = rng.normal(0.0, 0.1, (6, model.grid_samples_per_frame))
    dy = rng.normal(0.0, 0.1, (6, model.grid_samples_per_frame))
    mx, my, _ = tick_moments(dx, dy, model)
    tx, ty = tick_means(dx, dy, model)
    assert np.array_equal(tx, mx) and np.array_equal(ty, my)
    assert np.ptp(tx) > 0
