"""Synthetic IRAC-like epochs with known truth, for the systematics-method tests.

Everything is computed analytically and independently of the code under test:

* an eclipse of known depth (a trapezoid: linear ingress and egress);
* a pointing track with the components of the paper's Appendix A.1
  (long-term drift, decaying short-term drift, a skewed 40-minute wobble,
  a 60-second jitter sinusoid and a seeded random-walk jitter);
* an intra-pixel sensitivity ``S(u, v) = 1 - a u^2 - b v^2 + c u`` (u, v from
  the pixel centre), the same for every pixel;
* pixel values = flux x the integral over each pixel of a Gaussian PSF times
  S, in closed form (Gaussian moments over an interval), on a 7x7 stamp;
* aperture flux = sum of the 7x7 stamp; centre-of-light centroids and noise
  pixels (paper Eqs. ``x_centroid``, ``noise_pixels``) over the same stamp.

The data are noiseless; ``flux_err`` is the photon noise of the flux.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from scipy.special import erf

from eclipsebench.decorrelate.base import EpochData
from eclipsebench.seeding import rng

CADENCE_S = 2.0
T_START_BMJD = 56270.5
DURATION_D = 0.118       # XO-3b-like total eclipse duration, ~2.8 h
INGRESS_D = 0.012        # ~17 min
PSF_SIGMA_PX = (0.30, 0.32)   # a sharp core: the pixel-phase effect of an undersampled PRF
SENSITIVITY = (0.8, 0.6, 0.05)     # a, b, c of S(u, v)
FLUX_E = 1.0e5
STAMP = 7
CENTER_PIX = 15


def eclipse_curve(time_bmjd, t_ecl_bmjd, depth_ppm):
    """``1 + D * visible(t)``: 1 = the star alone, trapezoidal visibility of the planet."""
    half = DURATION_D / 2
    dt = np.abs(np.asarray(time_bmjd) - t_ecl_bmjd)
    visible = np.clip((dt - (half - INGRESS_D)) / INGRESS_D, 0.0, 1.0)
    return 1.0 + depth_ppm * 1e-6 * visible


def pointing_track(t_s, seed):
    """(x, y) of the star (0-based px) at times ``t_s`` seconds after the AOR start."""
    g = rng(seed, "tests", "decorrelate", "pointing")

    def axis(theta_deg):
        th = np.deg2rad(theta_deg)
        return np.cos(th), np.sin(th)

    ld = 0.015 * t_s / 3600.0                      # long-term drift, px
    sd = 0.06 * np.exp(-t_s / 1800.0)              # short-term drift, px
    q = (t_s / 2400.0) % 1.0                       # skewed wobble, period 40 min
    wob = 0.025 * np.sin(2 * np.pi * q + 0.35 * np.sin(2 * np.pi * q))
    jit = 0.01 * np.sin(2 * np.pi * t_s / 60.0 + 1.0)
    walk = np.cumsum(g.normal(0.0, 1.0, (2, len(t_s))), axis=1)
    walk = 0.004 * walk / np.max(np.abs(walk), axis=1, keepdims=True)
    x = 15.12 + ld * axis(-75)[0] + sd * axis(100)[0] + wob * axis(-60)[0] + jit * axis(-45)[0]
    y = 15.02 + ld * axis(-75)[1] + sd * axis(100)[1] + wob * axis(-60)[1] + jit * axis(-45)[1]
    return x + walk[0], y + walk[1]


def _interval_moments(lo, hi, sigma):
    """Integrals of z^m N(z; 0, sigma) over [lo, hi] for m = 0, 1, 2."""
    def pdf(z):
        return np.exp(-0.5 * (z / sigma) ** 2) / (sigma * np.sqrt(2 * np.pi))
    m0 = 0.5 * (erf(hi / (sigma * np.sqrt(2))) - erf(lo / (sigma * np.sqrt(2))))
    m1 = sigma**2 * (pdf(lo) - pdf(hi))
    m2 = sigma**2 * m0 + sigma**2 * (lo * pdf(lo) - hi * pdf(hi))
    return m0, m1, m2


def _axis_integrals(centre, sigma, pixel_index):
    """I_m = int over the pixel of (u - i)^m PSF(u - centre) du, shapes (n, npix)."""
    d = centre[:, None] - pixel_index[None, :]        # pixel centre offset of the star
    lo = pixel_index[None, :] - 0.5 - centre[:, None]
    hi = lo + 1.0
    m0, m1, m2 = _interval_moments(lo, hi, sigma)
    return m0, m1 + d * m0, m2 + 2 * d * m1 + d * d * m0


def render_stamps(x, y, total_flux, sensitivity=SENSITIVITY):
    """Pixel values (n, 7, 7) of a Gaussian PSF through the intra-pixel sensitivity."""
    a, b, c = sensitivity
    idx = CENTER_PIX + np.arange(STAMP) - STAMP // 2
    ix0, ix1, ix2 = _axis_integrals(np.asarray(x, float), PSF_SIGMA_PX[0], idx.astype(float))
    iy0, _, iy2 = _axis_integrals(np.asarray(y, float), PSF_SIGMA_PX[1], idx.astype(float))
    # image[y, x] = Iy0 (Ix0 - a Ix2 + c Ix1) - b Iy2 Ix0
    img = (np.einsum("nj,ni->nji", iy0, ix0 - a * ix2 + c * ix1)
           - b * np.einsum("nj,ni->nji", iy2, ix0))
    return img * np.asarray(total_flux, float)[:, None, None]


def stamp_measurements(stamps):
    """Aperture flux, centre-of-light centroid and noise pixels of (n, 7, 7) stamps."""
    idx = CENTER_PIX + np.arange(STAMP) - STAMP // 2
    tot = stamps.sum(axis=(1, 2))
    xc = np.einsum("nji,i->n", stamps, idx) / tot
    yc = np.einsum("nji,j->n", stamps, idx) / tot
    beta = tot**2 / np.sum(stamps**2, axis=(1, 2))
    return tot, xc, yc, beta


@dataclass
class SyntheticEpoch:
    data: EpochData
    astro: np.ndarray
    depth_ppm: float
    t_ecl_bmjd: float
    sensitivity: tuple


def make_epoch(*, n_frames=15000, depth_ppm=1875.0, systematics=True, seed=2015,
               meta=None) -> SyntheticEpoch:
    t_s = np.arange(n_frames) * CADENCE_S
    time = T_START_BMJD + t_s / 86400.0
    t_ecl = T_START_BMJD + 0.52 * t_s[-1] / 86400.0
    astro = eclipse_curve(time, t_ecl, depth_ppm)
    x_true, y_true = pointing_track(t_s, seed)
    sens = SENSITIVITY if systematics else (0.0, 0.0, 0.0)
    stamps = render_stamps(x_true, y_true, FLUX_E * astro, sens)
    flux, xc, yc, beta = stamp_measurements(stamps)
    data = EpochData(time_bmjd=time, flux=flux, flux_err=np.sqrt(flux), x=xc, y=yc,
                     noise_pixels=beta, pixels=stamps[:, 1:6, 1:6].reshape(n_frames, 25),
                     aorkey=np.full(n_frames, 46469632), meta=dict(meta or {}))
    return SyntheticEpoch(data=data, astro=astro, depth_ppm=depth_ppm, t_ecl_bmjd=t_ecl,
                          sensitivity=sens)


def write_calibration_table(path: Path, *, n_points=200000, seed=2015, systematics=True):
    """A noiseless calibration-star table over the sweet spot (the simulator's columns)."""
    from astropy.io import fits

    g = rng(seed, "tests", "decorrelate", "calibration")
    x = g.uniform(14.80, 15.45, n_points)
    y = g.uniform(14.70, 15.35, n_points)
    sens = SENSITIVITY if systematics else (0.0, 0.0, 0.0)
    stamps = render_stamps(x, y, np.full(n_points, 3.0e5), sens)
    flux, xc, yc, beta = stamp_measurements(stamps)
    cols = [fits.Column(name=n, format="D", array=v) for n, v in
            (("x", xc), ("y", yc), ("noise_pixels", beta), ("flux", flux),
             ("flux_err", np.sqrt(flux)))]
    path.parent.mkdir(parents=True, exist_ok=True)
    fits.BinTableHDU.from_columns(cols).writeto(path, overwrite=True)
    return path


class TrapezoidShape:
    """The test eclipse geometry in the astro API (``visible_fraction(t_ecl)``)."""

    def __init__(self, time_bmjd):
        self.time_bmjd = np.asarray(time_bmjd, float)

    def visible_fraction(self, t_ecl_bmjd):
        return (eclipse_curve(self.time_bmjd, t_ecl_bmjd, 1e6) - 1.0)


def fit_depth(model, time, *, t_ecl_guess, depth_guess=1500.0, phase="flat"):
    """Joint least squares of depth and t_ecl with the framework (``eclipsebench.fit``).

    Returns (depth_ppm, t_ecl_bmjd).
    """
    from eclipsebench.fit.leastsq import fit_leastsq
    from eclipsebench.fit.model import AstroModel

    astro = AstroModel(time, None, phase=phase, shape=TrapezoidShape(time))
    fit = fit_leastsq(model, astro, astro.initial(depth=depth_guess * 1e-6,
                                                  t_event_bmjd=t_ecl_guess))
    return fit.value("depth") * 1e6, fit.value("t_ecl_bmjd")


def kept_frames(model, epoch: SyntheticEpoch):
    """(flux, astro) of the frames ``model`` fits: all of them, or the subset it kept.

    A method that drops frames (BLISS's sparse knots, KR/Pmap's low occupancy)
    holds the kept frames in ``model.data``; ``astro`` is the epoch's curve there.
    """
    if not model.dropped_frames():
        return epoch.data.flux, epoch.astro
    keep = np.searchsorted(epoch.data.time_bmjd, model.data.time_bmjd)
    return epoch.data.flux[keep], epoch.astro[keep]


@pytest.fixture(scope="session")
def synth():
    """The generator functions, for tests that need their own variants."""
    return SimpleNamespace(make_epoch=make_epoch, eclipse_curve=eclipse_curve, kept_frames=kept_frames,
                           fit_depth=fit_depth, write_calibration_table=write_calibration_table,
                           render_stamps=render_stamps, stamp_measurements=stamp_measurements)


@pytest.fixture(scope="session")
def simdir(tmp_path_factory) -> Path:
    """A simulation folder holding only ``calibration/pmap_calibration.fits``."""
    d = tmp_path_factory.mktemp("simdir")
    write_calibration_table(d / "calibration" / "pmap_calibration.fits")
    return d


@pytest.fixture(scope="session")
def epoch_sys(simdir) -> SyntheticEpoch:
    """15,000 noiseless frames with pointing systematics; SIMDIR points to a calibration set."""
    return make_epoch(meta={"SIMDIR": str(simdir)})


@pytest.fixture(scope="session")
def epoch_small(simdir) -> SyntheticEpoch:
    """The first 4,000 frames' worth of the same set-up (interface tests of every method)."""
    return make_epoch(n_frames=4000, meta={"SIMDIR": str(simdir)})


@pytest.fixture(scope="session")
def epoch_flat(tmp_path_factory) -> SyntheticEpoch:
    """The same pointing with the intra-pixel sensitivity switched off (flat pixels)."""
    d = tmp_path_factory.mktemp("simdir_flat")
    write_calibration_table(d / "calibration" / "pmap_calibration.fits", systematics=False)
    return make_epoch(systematics=False, meta={"SIMDIR": str(d)})
