"""Channel 1 and every readout mode in the simulator (issue 16 points 3 and 4).

Unit checks of the per-channel constants, the ``[observation]`` readout
defaults, the headers and paths of channel-1 and full-array files, the
channel-1 builtin PRF and the 3.6 um light curve; then three small epochs
simulated, measured and reduced with BLISS (the acceptance): channel 1
(2 s subarray), the full array with the star far from the centre, and the
0.1 s subarray; each recovers its true depth within 4 sigma.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from astropy.io import fits
from astropy.table import Table

from eclipsebench.astro.catalogue import system_for
from eclipsebench.astro.orbit import eclipse_time_bmjd
from eclipsebench.cli import main
from eclipsebench.config import detector as D
from eclipsebench.config import load_config
from eclipsebench.detector import constants as C
from eclipsebench.errors import ConfigError
from eclipsebench.instrument.prf import BuiltinPRF, GainPolynomial, load_gainmap_coefficients
from eclipsebench.io.bcd_read import read_bcd, read_bcd_header
from eclipsebench.io.bcd_write import AorWriter, bcd_path
from eclipsebench.io.header_template import BcdHeaderInfo
from eclipsebench.photometry.estimators import aperture_flux, centroid_col
from eclipsebench.photometry.table import read_photometry
from eclipsebench.simulation.from_config import frame_model_from_config, light_curve_of
from eclipsebench.simulation.plan import JD_OFFSET_BMJD
from eclipsebench.simulation.star import make_star_imager


# ----------------------------------------------------------------------------- constants
def test_channel_constants_come_from_the_real_headers_and_iracsim():
    ch1, ch2 = C.channel_constants(1), C.channel_constants(2)
    # the real channel-1 header of AOR 41629440 and IRACSIM's channel-1 branch
    assert (ch1.gain_e_per_dn, ch1.fluxconv, ch1.read_noise_iracsim2015_e) == (3.7, 0.1253, 15.8)
    assert C.ronoise_e(1, C.SUB_0P1S) == 16.9
    assert (ch2.gain_e_per_dn, ch2.fluxconv, C.ronoise_e(2, C.SUB_2S)) == (3.71, 0.1469, 9.4)
    assert ch1.band_um[1] < ch2.band_um[0] and ch1.effective_wavelength_um == 3.551
    assert ch1.sweet_spot_px == ch2.sweet_spot_px == (15, 15)
    assert ch1.peakup_target_px == (15.198, 15.020) and ch2.peakup_target_px == (15.15, 15.20)
    assert ch1.pixel_solid_angle_sr > ch2.pixel_solid_angle_sr
    with pytest.raises(Exception, match="channel"):
        C.channel_constants(3)


@pytest.mark.parametrize("name", sorted(C.READOUT_MODES))
def test_every_mode_has_a_read_noise_and_a_cadence(name):
    mode = C.READOUT_MODES[name]
    for channel in (1, 2):
        assert C.ronoise_e(channel, mode) > 0
    assert C.mode_key(mode) == name
    assert C.frame_interval_default_s(mode) == pytest.approx(mode.t_int_s + 0.008)
    assert C.cube_interval_default_s(mode) >= mode.frames_per_file * mode.t_int_s


def test_read_noise_of_follows_the_channel_and_the_readout():
    cfg = load_config(None, ["observation.channel=1", "observation.readout=sub_0p1s"])
    assert D.read_noise_of(cfg) == 16.9
    assert (D.gain_of(cfg), D.fluxconv_of(cfg)) == (3.7, 0.1253)
    cfg = load_config(None, ["observation.channel=1", "simulation.noise_model=iracsim2015"])
    assert D.read_noise_of(cfg) == 15.8
    cfg = load_config(None, ["observation.readout=full_12s"])
    assert D.read_noise_of(cfg) == 10.4
    cfg = load_config(None, ["simulation.fluxconv=0.1447", "simulation.gain_e_per_dn=3.8"])
    assert (D.gain_of(cfg), D.fluxconv_of(cfg)) == (3.8, 0.1447)


# ----------------------------------------------------------------------------- configuration
def test_default_observation_is_the_2015_challenge():
    obs = load_config(None, []).observation
    assert (obs.channel, obs.readout, obs.fowler, obs.wait, obs.sample_time_s) == \
        (2, "sub_2s", 8, 184, 0.01)
    assert (obs.pre_cubes, obs.main_cubes, obs.frames_per_cube) == (11, 233, 64)
    assert (obs.frame_interval_s, obs.cube_interval_s, obs.x0_px, obs.y0_px) == \
        (2.008, 129.4, 15.15, 15.20)


@pytest.mark.parametrize("name", sorted(C.READOUT_MODES))
def test_a_readout_sets_fowler_wait_tick_array_and_cadence(name):
    mode = C.READOUT_MODES[name]
    obs = load_config(None, [f"observation.readout={name}", "observation.channel=1"]).observation
    assert obs.readout_mode() is mode
    assert (obs.fowler, obs.wait, obs.sample_time_s) == (mode.fowler, mode.wait,
                                                         mode.sample_time_s)
    assert obs.frames_per_cube == (64 if mode.subarray else 1)
    assert obs.array_px == (32 if mode.subarray else 256)
    # the 2015 challenge's AOR durations in every mode
    assert obs.main_cubes * obs.cube_interval_s == pytest.approx(233 * 129.4,
                                                                 abs=obs.cube_interval_s)
    target = C.channel_constants(1).target_px(mode.subarray)
    assert (obs.x0_px, obs.y0_px) == target
    model = frame_model_from_config(load_config(None, [f"observation.readout={name}"]))
    assert model.shape == mode.shape and model.mode is mode


def test_a_key_that_disagrees_with_the_readout_is_one_error_naming_it():
    with pytest.raises(ConfigError) as exc:
        load_config(None, ["observation.readout=sub_0p1s", "observation.fowler=8"])
    assert exc.value.key == "observation.fowler" and "custom" in str(exc.value)
    obs = load_config(None, ["observation.readout=custom", "observation.fowler=4",
                             "observation.wait=10"]).observation
    assert obs.readout_mode().n_max == 18 and obs.readout_mode().subarray
    assert obs.frame_interval_s == pytest.approx(0.188)
    for bad, key in (("observation.channel=3", "observation.channel"),
                     ("observation.readout=sub_1s", "observation.readout"),
                     ("observation.x0_px=40", "observation.x0_px")):
        with pytest.raises(ConfigError) as exc:
            load_config(None, [bad])
        assert exc.value.key == key
    with pytest.raises(ConfigError) as exc:
        load_config(None, ["observation.readout=full_2s", "observation.frames_per_cube=64"])
    assert exc.value.key == "observation.frames_per_cube"
    # on the full array the star may be anywhere
    obs = load_config(None, ["observation.readout=full_2s", "observation.x0_px=40.3",
                             "observation.y0_px=201.7"]).observation
    assert (obs.x0_px, obs.y0_px) == (40.3, 201.7)


# ----------------------------------------------------------------------------- files
def _info(**changes) -> BcdHeaderInfo:
    base = dict(aorkey=20150001, aorlabel="t", object_name="XO-3", epoch=1, seed=1,
                noise_model="physical", fowler=2, wait=6, sample_time_s=0.01, frame_time_s=0.1,
                frame_interval_s=0.108, exptime_s=0.08, frames_per_cube=64, fluxconv=0.1253,
                gain_e_per_dn=3.7, read_noise_e=16.9, ra_deg=65.47, dec_deg=57.82,
                star_x_px=15.2, star_y_px=15.0, channel=1)
    base.update(changes)
    return BcdHeaderInfo(**base)


@pytest.mark.parametrize("subarray", [True, False])
def test_channel1_and_full_array_files_read_back(tmp_path, subarray):
    info = _info() if subarray else _info(
        fowler=4, wait=2, sample_time_s=0.2, frame_time_s=2.0, frame_interval_s=2.008,
        exptime_s=1.2, frames_per_cube=1, read_noise_e=16.0, star_x_px=130.2, star_y_px=127.0,
        subarray=False)
    n, (ny, nx) = info.frames_per_cube, info.shape
    data = np.arange(n * ny * nx, dtype=np.float32).reshape(n, ny, nx)
    writer = AorWriter(tmp_path, info)
    p_bcd, _ = writer.write_cube(expid=3, bcd_mjysr=data, bunc_mjysr=data, bmjd_obs=57000.0,
                                 mjd_obs=56999.99, date_obs="2014-12-08T23:45:36.000")
    assert p_bcd == bcd_path(tmp_path, 20150001, 3, channel=1)
    assert p_bcd.parent.parent.name == "ch1" and p_bcd.name.startswith("SPITZER_I1_")
    h = fits.getheader(p_bcd)
    assert (h["CHNLNUM"], h["READMODE"], h["AREADMOD"]) == (1, "SUB" if subarray else "FULL",
                                                           int(subarray))
    assert h["FOVID"] == (70 if subarray else 67) and h["NAXIS"] == (3 if subarray else 2)
    parsed = read_bcd_header(p_bcd)
    assert (parsed.channel, parsed.subarray, parsed.n_frames, parsed.ny) == \
        (1, subarray, n, ny)
    assert (parsed.fowler, parsed.wait, parsed.read_noise_e, parsed.gain) == \
        (info.fowler, info.wait, info.read_noise_e, 3.7)
    np.testing.assert_array_equal(read_bcd(parsed).data, data)


# ----------------------------------------------------------------------------- PRF and L(t)
def test_channel1_builtin_prf_follows_the_channel1_gain_map():
    prf = BuiltinPRF(channel=1)
    flat = BuiltinPRF(channel=1, gain=False)
    total = flat.render(np.array([15.0, 15.3]), np.array([15.0, 14.8])).sum(axis=(1, 2))
    np.testing.assert_allclose(total, 1.0, atol=1e-4)
    coeff = load_gainmap_coefficients(1)
    pmap = GainPolynomial.from_dict(coeff["pmap_poly"])
    (u0, u1), (v0, v1) = pmap.box  # the phases where the map's occupancy exceeds 20
    assert u0 > -0.2 and u1 > 0.4 and v0 > -0.2 and v1 > 0.4
    gx, gy = np.meshgrid(15.0 + np.linspace(u0 + 0.05, u1 - 0.05, 9),
                         15.0 + np.linspace(v0 + 0.05, v1 - 0.05, 9))
    im = prf.render(gx.ravel(), gy.ravel())
    xc, yc = centroid_col(im, around=(15, 15))
    ratio = aperture_flux(im, xc, yc, coeff["builtin"]["aperture_radius_px"]) / pmap.evaluate(xc, yc)
    assert np.std(ratio / ratio.mean()) < 0.004
    # clamped outside the trusted box: bounded over the whole pixel
    g = prf.gain.evaluate(*np.meshgrid(15 + np.linspace(-0.5, 0.5, 21),
                                       15 + np.linspace(-0.5, 0.5, 21)))
    assert 0.9 < g.min() and g.max() < 1.15
    # the channel-1 gain map varies more than channel 2's (the paper: ~8% against ~4%)
    ch2 = GainPolynomial.from_dict(load_gainmap_coefficients(2)["pmap_poly"])
    span1 = np.ptp(pmap.evaluate(gx.ravel(), gy.ravel()))
    span2 = np.ptp(ch2.evaluate(gx.ravel(), gy.ravel()))
    assert span1 > span2


def test_channel1_light_curve_is_at_3p6_micron():
    cfg1 = load_config(None, ["observation.channel=1", "system.fix_depth_ppm=0"])
    cfg2 = load_config(None, ["system.fix_depth_ppm=0"])
    lc1, lc2 = light_curve_of(cfg1), light_curve_of(cfg2)
    assert lc1.options["wavelength_um"] == 3.551 and lc2.options["wavelength_um"] == 4.5095
    # a hot planet on the Wien side: a smaller flux ratio at 3.6 um than at 4.5 um
    assert 0 < lc1.depth_ppm < lc2.depth_ppm
    explicit = load_config(None, ["observation.channel=1", "system.wavelength_um=3.6"])
    assert light_curve_of(explicit).options["wavelength_um"] == 3.6


def test_star_imager_on_the_full_array_defines_the_flux_at_the_target():
    cfg = load_config(None, ["observation.readout=full_2s", "observation.x0_px=60.4",
                             "observation.y0_px=190.7"])
    sub = make_star_imager(load_config(None, ["observation.x0_px=15.4", "observation.y0_px=14.7"]))
    full = make_star_imager(cfg)
    assert full.aperture_per_unit == pytest.approx(sub.aperture_per_unit, rel=1e-9)


# ----------------------------------------------------------------------------- end to end
def _window_start(cfg_sets: list[str]) -> str:
    """observation.start_times_jd putting an eclipse 0.14 d after the window's start."""
    system = system_for(load_config(None, cfg_sets).system)
    t_ecl = eclipse_time_bmjd(system, 57205.8)
    return f"observation.start_times_jd=[{t_ecl - 0.14 - JD_OFFSET_BMJD:.6f}]"


def _simulate_measure_reduce(root, sets: list[str]):
    sets = sets + [_window_start(sets)]
    args = [a for s in sets for a in ("--set", s)]
    assert main(["simulate", "--out", str(root / "sim"), "--epochs", "1", "--no-calibration",
                 "--quiet", "--workers", "1", *args]) == 0
    assert main(["photometry", str(root / "sim"), "--out", str(root / "phot"), "--quiet"]) == 0
    out = root / "bliss.json"
    # least squares: these tests are about the modes' frames, not the posterior
    assert main(["reduce", str(root / "phot" / "epoch_01.fits"), "--method", "bliss",
                 "--sampler", "leastsq", "--out", str(out), "--quiet"]) == 0
    truth = Table.read(root / "sim" / "truth.ecsv", format="ascii.ecsv")[0]
    lc = Table.read(root / "sim" / "lightcurves" / "epoch_01.ecsv", format="ascii.ecsv")
    return (truth, lc, read_photometry(root / "phot" / "epoch_01.fits"),
            json.loads(out.read_text()))


def _depth_within_4_sigma(result, truth) -> None:
    depth, err = result["depth_ppm"], result["depth_err_ppm"]
    assert math.isfinite(depth) and 0 < err < 1200, (depth, err)
    assert abs(depth - truth["depth_ppm"]) < 4 * err, (depth, err, truth["depth_ppm"])


def _star_found(table, lc, tol_px: float) -> None:
    good = np.asarray(table["flag"]) == 0
    assert good.mean() > 0.9
    order = np.argsort(np.asarray(lc["time_bmjd"]))
    x_true = np.interp(table["time_bmjd"], np.asarray(lc["time_bmjd"])[order],
                       np.asarray(lc["x_true"])[order])
    y_true = np.interp(table["time_bmjd"], np.asarray(lc["time_bmjd"])[order],
                       np.asarray(lc["y_true"])[order])
    assert np.median(np.abs(np.asarray(table["x"]) - x_true)[good]) < tol_px
    assert np.median(np.abs(np.asarray(table["y"]) - y_true)[good]) < tol_px


@pytest.mark.slow
def test_channel1_epoch_reduced_with_bliss_recovers_its_depth(tmp_path):
    sets = ["observation.channel=1", "observation.pre_cubes=1", "observation.frames_per_cube=16",
            "observation.main_cubes=110", "observation.cube_interval_s=220.0",
            "simulation.subsamples=2"]
    truth, lc, table, result = _simulate_measure_reduce(tmp_path, sets)
    files = sorted((tmp_path / "sim").rglob("*_bcd.fits"))
    assert files and all(f.name.startswith("SPITZER_I1_") and f.parents[1].name == "ch1"
                         for f in files)
    h = fits.getheader(files[0])
    assert (h["CHNLNUM"], h["FLUXCONV"], h["GAIN"], h["RONOISE"]) == (1, 0.1253, 3.7, 10.8)
    assert table.meta["CHANNEL"] == 1
    assert np.median(table["flux"]) == pytest.approx(73246.0, rel=0.03)
    _star_found(table, lc, 0.05)
    _depth_within_4_sigma(result, truth)


@pytest.mark.slow
def test_full_array_epoch_star_anywhere_is_found_and_its_depth_recovered(tmp_path):
    sets = ["observation.readout=full_2s", "observation.x0_px=60.4", "observation.y0_px=190.7",
            "observation.pre_cubes=3", "observation.main_cubes=170",
            "observation.cube_interval_s=140.0", "simulation.subsamples=2"]
    truth, lc, table, result = _simulate_measure_reduce(tmp_path, sets)
    files = sorted((tmp_path / "sim").rglob("*_bcd.fits"))
    assert len(files) == 173 and fits.getheader(files[0])["NAXIS"] == 2
    assert fits.getdata(files[0]).shape == (256, 256)
    _star_found(table, lc, 0.05)
    assert abs(np.median(table["x"]) - 60.4) < 0.3 and abs(np.median(table["y"]) - 190.7) < 0.3
    _depth_within_4_sigma(result, truth)


@pytest.mark.slow
def test_0p1s_subarray_epoch_reduced_with_bliss_recovers_its_depth(tmp_path):
    sets = ["observation.channel=1", "observation.readout=sub_0p1s", "observation.pre_cubes=1",
            "observation.main_cubes=60", "observation.cube_interval_s=400.0",
            "simulation.subsamples=2"]
    truth, lc, table, result = _simulate_measure_reduce(tmp_path, sets)
    h = fits.getheader(sorted((tmp_path / "sim").rglob("*_bcd.fits"))[0])
    assert (h["AFOWLNUM"], h["AWAITPER"], h["FRAMTIME"], h["EXPTIME"]) == (2, 6, 0.1, 0.08)
    assert h["RONOISE"] == 16.9
    t = np.asarray(table["time_bmjd"]) * 86400.0
    inside = np.diff(t)[np.asarray(table["frame"])[1:] > 0]
    assert np.allclose(inside, 0.108, atol=1e-3)
    _star_found(table, lc, 0.05)
    _depth_within_4_sigma(result, truth)


def test_a_header_without_ronoise_takes_the_channel_and_mode_value(tmp_path):
    writer = AorWriter(tmp_path, _info())
    data = np.zeros((64, 32, 32), np.float32)
    p_bcd, _ = writer.write_cube(expid=0, bcd_mjysr=data, bunc_mjysr=data, bmjd_obs=57000.0,
                                 mjd_obs=56999.99, date_obs="2014-12-08T23:45:36.000")
    with fits.open(p_bcd, mode="update") as hdul:
        del hdul[0].header["RONOISE"]
    assert read_bcd_header(p_bcd).read_noise_e == 16.9  # channel 1, 0.1 s
