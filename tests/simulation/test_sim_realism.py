"""A simulated "Pre" AOR of XO-3 against the real one (AOR 46466816, shared data)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from astropy.io import fits
from photutils.geometry import circular_overlap_grid

from eclipsebench.config import load_config
from eclipsebench.simulation.aor import simulate_aor
from eclipsebench.simulation.plan import plan_challenge

pytestmark = pytest.mark.shared_data


def _electrons(files: list[Path]) -> np.ndarray:
    cubes = []
    for f in files:
        with fits.open(f) as h:
            hdr = h[0].header
            cubes.append(h[0].data.astype(float) * hdr["GAIN"] * hdr["EXPTIME"] / hdr["FLUXCONV"])
    # the first frame of each cube is dropped, as in the paper
    return np.array(cubes)[:, 1:].reshape(-1, 32, 32)


def _photometry(e: np.ndarray) -> dict[str, float]:
    """Peak pixel, 3-7 px annulus background, and the linear-centroid-detrended
    scatter of the r = 2.25 px aperture flux (center-of-light centroids, 7x7)."""
    e = e[np.isfinite(e[:, 10:21, 10:21]).all(axis=(1, 2))]
    yy, xx = np.mgrid[0:32, 0:32]
    ring = (np.hypot(xx - 15, yy - 15) >= 3) & (np.hypot(xx - 15, yy - 15) <= 7)
    bg = np.array([np.nanmean(im[ring]) for im in e])
    sub = e - bg[:, None, None]
    box = sub[:, 12:19, 12:19]
    k = np.arange(12, 19)
    tot = box.sum(axis=(1, 2))
    xc = (box.sum(axis=1) * k).sum(axis=1) / tot
    yc = (box.sum(axis=2) * k).sum(axis=1) / tot
    flux = np.array([np.nansum(circular_overlap_grid(-0.5 - x, 31.5 - x, -0.5 - y, 31.5 - y,
                                                     32, 32, 2.25, 1, 1) * im)
                     for im, x, y in zip(sub, xc, yc, strict=True)])
    design = np.column_stack([np.ones_like(xc), xc - xc.mean(), yc - yc.mean()])
    coef, *_ = np.linalg.lstsq(design, flux, rcond=None)
    return {"peak": float(np.median(e[:, 13:18, 13:18].max(axis=(1, 2)))),
            "background": float(np.median(bg)),
            "scatter": float(np.std(flux - design @ coef) / flux.mean())}


@pytest.fixture(scope="module")
def real(shared_irac):
    files = sorted((shared_irac / "real_xo3_peakup_46466816").glob("*_bcd.fits"))
    assert len(files) == 11
    return _photometry(_electrons(files))


def _simulated_pre(tmp_path: Path, overrides: list[str]) -> dict[str, float]:
    cfg = load_config(None, ["challenge.epochs=1"] + overrides)
    plan = plan_challenge(cfg.observation, 1, 3.1915239, cfg.challenge.seed)[0]
    simulate_aor(cfg, plan, 0, tmp_path, cfg.challenge.seed)
    files = sorted(tmp_path.glob("r20150000/ch2/bcd/*_bcd.fits"))
    assert len(files) == 11
    return _photometry(_electrons(files))


def test_irsa_prf_pre_aor_matches_the_real_one(real, shared_irac, tmp_path):
    """The PRFs the 2015 challenge used (warm_2015): peak 10%, background 30%, scatter 20%."""
    prf = shared_irac / "prf" / "warm_2015_ch2"
    sim = _simulated_pre(tmp_path, [f'simulation.prf="irsa:{prf}"'])
    assert sim["peak"] == pytest.approx(real["peak"], rel=0.10)
    assert sim["background"] == pytest.approx(real["background"], rel=0.30)
    assert sim["scatter"] == pytest.approx(real["scatter"], rel=0.20)
    header = fits.getheader(next(tmp_path.glob("r20150000/ch2/bcd/*_0000_0000_1_bcd.fits")))
    assert header["SIMPRF"] == "irsa:warm_2015_ch2"  # no absolute paths in headers
    assert str(shared_irac) not in repr(header)


def test_builtin_prf_pre_aor_peak_and_background(real, tmp_path):
    """The package's own PRF: peak and background; its detrended scatter is the photon
    limit, ~25% below the real one (real cubes have ~25% excess white noise)."""
    sim = _simulated_pre(tmp_path, [])
    assert sim["peak"] == pytest.approx(real["peak"], rel=0.10)
    assert sim["background"] == pytest.approx(real["background"], rel=0.30)
    photon = np.sqrt(0.9863 / 73246.0)
    assert sim["scatter"] == pytest.approx(photon, rel=0.08)
    assert sim["scatter"] < real["scatter"]
