"""``noise_model = "iracsim2015"`` against the public 2015 challenge cube, and ``"none"``.

The public cube (AORKEY 20150000, EXPID 0000: 64 frames, true positions in
XYMEAN01..64) measured with our photometry (r = 2.25 px, 3-7 px annulus,
first frame dropped): net flux 73,173 e, annulus background 111 e/px, and the
rms of the fluxes about a quadratic in the true positions 1.57 +- 0.14 times
sqrt(flux) over its 63 frames (issue 15), which sets IRACSIM's NOISE_FACTOR
(0.907). A small simulated epoch goes
through the same recipe: each 64-frame cube gets its own quadratic, as the
public cube did (six parameters on 63 frames take 5% off the rms when the
star moves). docs/simulate.md explains the model and the numbers.
"""

from __future__ import annotations

import numpy as np
import pytest
from astropy.io import fits

from eclipsebench.config import load_config
from eclipsebench.photometry.measure import measure_stack
from eclipsebench.simulation.aor import simulate_aor
from eclipsebench.simulation.stage import challenge_plans
from eclipsebench.simulation.star import IRACSIM2015_ANNULUS_WING_PER_E, StarImager, make_prf

CUBE_FLUX_E = 73173.0
CUBE_BACKGROUND_E_PER_PX = 111.0
CUBE_SCATTER_RATIO, CUBE_SCATTER_ERR = 1.57, 0.14
N_CUBES = 5


def _simulate(tmp_path, overrides: list[str], seed: int = 2015):
    """The Pre AOR of epoch 1 (five cubes): frames in electrons and the per-frame truth."""
    cfg = load_config(None, ["challenge.epochs=1", f"observation.pre_cubes={N_CUBES}",
                             f"challenge.seed={seed}"] + overrides)
    plan = challenge_plans(cfg)[0]
    truth = simulate_aor(cfg, plan, 0, tmp_path, seed, show_progress=False)
    cubes = []
    for path in sorted(tmp_path.glob("r*/ch2/bcd/*_bcd.fits")):
        with fits.open(path) as hdul:
            hdr = hdul[0].header
            cubes.append(hdul[0].data.astype(float) * hdr["GAIN"] * hdr["EXPTIME"]
                         / hdr["FLUXCONV"])
    return cfg, np.concatenate(cubes), truth


def _recipe(cfg, frames_e: np.ndarray, truth: dict) -> dict[str, float]:
    """Net flux, median annulus background, and the per-cube quadratic scatter ratio."""
    keep = truth["frame"] != 0                       # first frame of each cube dropped
    m = measure_stack(frames_e[keep], guess_x=15, guess_y=15, options=cfg.photometry)
    flux = m["flux"]
    x, y, cube = truth["x_true"][keep], truth["y_true"][keep], truth["expid"][keep]
    residuals = []
    for c in np.unique(cube):
        k = cube == c
        dx, dy = x[k] - x[k].mean(), y[k] - y[k].mean()
        design = np.column_stack([np.ones(k.sum()), dx, dy, dx * dx, dx * dy, dy * dy])
        coef, *_ = np.linalg.lstsq(design, flux[k], rcond=None)
        residuals.append(flux[k] - design @ coef)
    r = np.concatenate(residuals)
    return {"flux": float(flux.mean()), "background": float(np.median(m["background"])),
            "scatter_ratio": float(r.std() / np.sqrt(flux.mean()))}


@pytest.fixture(scope="module")
def iracsim2015(tmp_path_factory):
    cfg, frames, truth = _simulate(tmp_path_factory.mktemp("iracsim2015"),
                                   ["simulation.noise_model=iracsim2015"])
    return _recipe(cfg, frames, truth)


def test_iracsim2015_flux_is_the_cubes(iracsim2015):
    """IRACSIM's (n+1)-th sub-sample adds no light: 72,685 e (the +9% of before is gone)."""
    assert iracsim2015["flux"] == pytest.approx(CUBE_FLUX_E, rel=0.03)


def test_iracsim2015_annulus_background_is_the_cubes(iracsim2015):
    """Sky 55.4 e/px under the 2015 PRFs' wings (55.0 e/px): 110.6 e/px measured."""
    assert iracsim2015["background"] == pytest.approx(CUBE_BACKGROUND_E_PER_PX, rel=0.20)


def test_iracsim2015_scatter_agrees_with_the_cube(iracsim2015):
    """IRACSIM's compounding noise at the cube's NOISE_FACTOR, measured as the cube was.

    Issue 15's window is 1.40-1.75 around the cube's 1.57 +- 0.14. The
    compounding noise alone gives sqrt(3.31 x 57/63) = 1.73 with factor 1
    (1.80 measured here with factor 1: the simulated pointing adds its
    residuals); the factor 0.907 read off the cube's pixels scales that.
    """
    ratio = iracsim2015["scatter_ratio"]
    assert 1.40 <= ratio <= 1.75
    sim_err = ratio / np.sqrt(2 * N_CUBES * 63)
    assert abs(ratio - CUBE_SCATTER_RATIO) < 2.0 * np.hypot(CUBE_SCATTER_ERR, sim_err)


def test_iracsim2015_noise_factor_scales_the_noise(tmp_path):
    """The noise (pointing and gain switched off) is the factor times sqrt(3.31), ~1.65."""
    fixed = ["simulation.noise_model=iracsim2015", "simulation.pointing_motion=false",
             "simulation.flat_gain=true", "observation.peakup_scatter_px=0"]
    ratios = {}
    for factor in (0.907, 1.0):
        cfg, frames, truth = _simulate(tmp_path / str(factor),
                                       fixed + [f"simulation.noise_factor={factor}"])
        keep = truth["frame"] != 0
        flux = measure_stack(frames[keep], guess_x=15, guess_y=15, options=cfg.photometry)["flux"]
        ratios[factor] = flux.std() / np.sqrt(flux.mean())
    assert ratios[1.0] == pytest.approx(np.sqrt(3.31), rel=0.06)
    assert ratios[0.907] / ratios[1.0] == pytest.approx(0.907, rel=0.03)


def test_noise_factor_needs_iracsim2015():
    from eclipsebench.errors import ConfigError
    with pytest.raises(ConfigError, match="noise_factor"):
        load_config(None, ["simulation.noise_factor=0.9"])


@pytest.mark.shared_data
def test_iracsim2015_wing_constant_is_the_2015_prfs(shared_irac):
    """The 2015 PRFs put 7.51e-4 of the aperture flux per pixel in the 3-7 px annulus."""
    prf = make_prf(f"irsa:{shared_irac / 'prf' / 'warm_2015_ch2'}")
    star = StarImager(prf, x_ref_px=15.15, y_ref_px=15.20, radius_px=2.25)
    assert star.annulus_per_unit / star.aperture_per_unit == pytest.approx(
        IRACSIM2015_ANNULUS_WING_PER_E, rel=2e-3)


def test_noise_model_none_two_seeds_give_identical_fluxes(tmp_path):
    """Noise-free frames: with the pointing held fixed the seed changes nothing.

    (The seed still draws the pointing parameters and the peak-up scatter, so
    they are held fixed here; with physical noise the same two seeds differ.)
    """
    fixed = ["simulation.pointing_motion=false", "observation.peakup_scatter_px=0",
             "observation.pre_cubes=2"]
    out = {}
    for model in ("none", "physical"):
        for seed in (1, 2):
            cfg, frames, truth = _simulate(tmp_path / f"{model}{seed}",
                                           [f"simulation.noise_model={model}"] + fixed, seed)
            keep = truth["frame"] != 0
            m = measure_stack(frames[keep], guess_x=15, guess_y=15, options=cfg.photometry)
            out[model, seed] = m["flux"]
    np.testing.assert_array_equal(out["none", 1], out["none", 2])
    assert not np.array_equal(out["physical", 1], out["physical", 2])
    # no noise: the fluxes scatter by far less than the photon noise (~270 e)
    assert out["none", 1].std() < 1.0
    assert out["none", 1].mean() == pytest.approx(73246.0, rel=0.02)
