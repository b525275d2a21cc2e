"""Helpers for the photometry tests: synthetic PRF frames and tiny BCD files."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from astropy.io import fits
from scipy.special import erf

GAIN, EXPTIME, FLUXCONV = 3.71, 1.92, 0.1447
E_PER_MJYSR = GAIN * EXPTIME / FLUXCONV


def integrated_gaussian(x0: float, y0: float, sigma: float, total: float = 1.0,
                        shape: tuple[int, int] = (32, 32)) -> np.ndarray:
    """A 2-D Gaussian integrated exactly over each pixel (centre of pixel (i, j) at (i, j))."""
    def edges(c, n):
        e = (np.arange(n + 1) - 0.5 - c) / (sigma * np.sqrt(2.0))
        return np.diff(0.5 * erf(e))
    return total * np.outer(edges(y0, shape[0]), edges(x0, shape[1]))


def bcd_header(*, aorkey=123456, expid=0, bmjd=57000.0, n_frames=64, **extra) -> fits.Header:
    h = fits.Header()
    h["NAXIS"] = 3
    h["CHNLNUM"] = 2
    h["BMJD_OBS"] = bmjd
    h["FRAMTIME"] = 2.0
    h["EXPTIME"] = EXPTIME
    h["SAMPTIME"] = 0.01
    h["AFOWLNUM"] = 8
    h["AWAITPER"] = 184
    h["GAIN"] = GAIN
    h["FLUXCONV"] = FLUXCONV
    h["RONOISE"] = 9.4
    h["BUNIT"] = "MJy/sr"
    h["READMODE"] = "SUB"
    h["AORKEY"] = aorkey
    h["EXPID"] = expid
    h["DCENUM"] = 0
    for k, v in extra.items():
        h[k] = v
    return h


def write_bcd(folder: Path, cube_e: np.ndarray, *, aorkey=123456, expid=0, bmjd=57000.0,
              **extra) -> Path:
    """Write a subarray BCD cube given in electrons (converted to MJy/sr)."""
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"SPITZER_I2_{aorkey}_{expid:04d}_0000_1_bcd.fits"
    header = bcd_header(aorkey=aorkey, expid=expid, bmjd=bmjd, n_frames=cube_e.shape[0], **extra)
    fits.PrimaryHDU((cube_e / E_PER_MJYSR).astype(np.float32), header=header).writeto(path)
    return path


def star_cube(n=64, *, x0=15.2, y0=14.9, sigma=0.6, total=70000.0, bg=5.0, seed=0,
              noise=True) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """n frames of a jittering integrated Gaussian star plus background, with photon noise."""
    rng = np.random.default_rng(seed)
    xs = x0 + 0.01 * rng.standard_normal(n)
    ys = y0 + 0.01 * rng.standard_normal(n)
    cube = np.stack([integrated_gaussian(x, y, sigma, total) for x, y in zip(xs, ys, strict=True)]) + bg
    if noise:
        cube = rng.poisson(cube).astype(float)
    return cube, xs, ys


@pytest.fixture
def make_bcd():
    return write_bcd


@pytest.fixture
def make_star_cube():
    return star_cube


@pytest.fixture
def gaussian_prf():
    return integrated_gaussian
