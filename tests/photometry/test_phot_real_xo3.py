"""Acceptance on the 11 real XO-3 peak-up cubes of AOR 46466816 (../shared/data/irac)."""

from __future__ import annotations

import numpy as np
import pytest
from astropy.io import fits
from photutils.aperture import CircularAperture, aperture_photometry

from eclipsebench.cli import main
from eclipsebench.photometry.clean import FLAG_BITS
from eclipsebench.photometry.table import read_photometry

pytestmark = pytest.mark.shared_data

# Table 1 (xo3meas) of the paper, epoch starting JD 2455000 + 1270.9776 (Pre AOR 46466816)
TABLE1_X, TABLE1_SX, TABLE1_Y, TABLE1_SY = 15.13, 0.06, 15.12, 0.05


@pytest.fixture(scope="module")
def real_table(tmp_path_factory, shared_irac):
    folder = shared_irac / "real_xo3_peakup_46466816"
    out = tmp_path_factory.mktemp("real") / "xo3.fits"
    assert main(["photometry", str(folder), "--out", str(out), "--quiet"]) == 0
    return folder, read_photometry(out)


def test_every_frame_is_read_or_flagged_with_a_reason(real_table):
    folder, table = real_table
    files = sorted(folder.glob("*_bcd.fits"))
    assert len(files) == 11
    assert len(table) == sum(fits.getheader(f)["NAXIS3"] for f in files) == 704
    flag = np.asarray(table["flag"])
    known = np.bitwise_or.reduce(list(FLAG_BITS.values()))
    assert np.all((flag & ~known) == 0)
    first = np.asarray(table["frame"]) == 0
    assert np.all(flag[first] & FLAG_BITS["first_frame"])
    assert np.count_nonzero(flag == 0) >= 650
    good = flag == 0
    for name in ("x", "y", "x_gauss", "y_gauss", "flux", "flux_err", "background", "noise_pixels"):
        assert np.all(np.isfinite(table[name][good])), name
    assert table.meta["FLAGCNT"]["total"] == 704
    assert table.meta["FLAGBITS"] == FLAG_BITS
    assert len(table.meta["INPUTS"]) == 11 and table.meta["EPOCH"] == 1
    assert table.meta["AORKEYS"] == [46466816]
    assert "SIMDIR" not in table.meta


def test_centroid_is_on_pixel_15_15_near_table1(real_table):
    _, table = real_table
    good = np.asarray(table["flag"]) == 0
    x, y = float(np.mean(table["x"][good])), float(np.mean(table["y"][good]))
    assert round(x) == 15 and round(y) == 15
    # the Pre AOR alone (settling) against the two-AOR means and spreads of Table 1
    assert abs(x - TABLE1_X) < 2 * TABLE1_SX
    assert abs(y - TABLE1_Y) < 2 * TABLE1_SY


def test_center_of_light_is_photutils_centroid_com_on_the_real_frames(real_table):
    """Our x, y are the paper's Eqs. x_centroid, y_centroid exactly (so the Pre AOR's
    offset from Table 1's two-AOR means is the pointing's, not the centroider's)."""
    from photutils.centroids import centroid_com

    folder, table = real_table
    good = np.flatnonzero(np.asarray(table["flag"]) == 0)[::7]
    cubes = {}
    for k in good:
        expid, frame = int(table["expid"][k]), int(table["frame"][k])
        if expid not in cubes:
            path = next(folder.glob(f"SPITZER_I2_46466816_{expid:04d}_*_bcd.fits"))
            with fits.open(path) as hdul:
                h = hdul[0].header
                cubes[expid] = hdul[0].data.astype(float) * h["GAIN"] * h["EXPTIME"] / h["FLUXCONV"]
        img = cubes[expid][frame]
        px, py = int(table["peak_x"][k]), int(table["peak_y"][k])
        yy, xx = np.mgrid[0:32, 0:32]
        d2 = (xx - px) ** 2 + (yy - py) ** 2
        ring = (d2 >= 9) & (d2 <= 49) & np.isfinite(img)
        box = img[py - 3:py + 4, px - 3:px + 4] - img[ring].mean()
        cx, cy = centroid_com(box)
        assert table["x"][k] == pytest.approx(px - 3 + cx, abs=1e-6)
        assert table["y"][k] == pytest.approx(py - 3 + cy, abs=1e-6)  # float32 data


def test_times_are_mid_exposure_bmjd_tdb(real_table):
    folder, table = real_table
    h = fits.getheader(folder / "SPITZER_I2_46466816_0003_0000_2_bcd.fits")
    rows = np.flatnonzero(np.asarray(table["expid"]) == 3)
    t = np.asarray(table["time_bmjd"])[rows]
    tdb_minus_utc_s = h["ET_OBS"] - h["UTCS_OBS"]  # 67.184 s, from the header itself
    mid_s = (2 * h["AFOWLNUM"] + h["AWAITPER"] + 1) / 2 * h["SAMPTIME"]
    expected = h["BMJD_OBS"] + (tdb_minus_utc_s + mid_s + h["FRAMTIME"] * np.arange(64)) / 86400
    assert np.max(np.abs(t - expected)) * 86400 < 0.01  # seconds
    assert np.all(np.diff(np.asarray(table["time_bmjd"])) > 0)


def test_fluxes_equal_photutils_exact_on_the_same_background_subtracted_frames(real_table):
    folder, table = real_table
    worst = 0.0
    n = 0
    for path in sorted(folder.glob("*_bcd.fits")):
        h = fits.getheader(path)
        cube = fits.getdata(path).astype(float) * h["GAIN"] * h["EXPTIME"] / h["FLUXCONV"]
        for k in np.flatnonzero(np.asarray(table["expid"]) == h["EXPID"]):
            if table["flag"][k] & FLAG_BITS["cosmic_ray"]:
                continue  # a replaced pixel: not the same frame
            frame = cube[table["frame"][k]] - table["background"][k]
            ref = aperture_photometry(frame, CircularAperture((table["x"][k], table["y"][k]), 2.25),
                                      method="exact")["aperture_sum"][0]
            worst = max(worst, abs(table["flux"][k] / ref - 1.0))
            n += 1
    assert n >= 680
    assert worst < 1e-6


def test_flux_err_is_close_to_the_paper_noise_level(real_table):
    _, table = real_table
    good = np.asarray(table["flag"]) == 0
    flux = np.asarray(table["flux"])[good]
    err = np.asarray(table["flux_err"])[good]
    # paper Section 3.3: sigma ~ 268 e for ~70,900 e; ours scales as sqrt(flux)
    assert np.median(err) == pytest.approx(268 * np.sqrt(np.median(flux) / 70858), rel=0.05)
    # the frame-to-frame scatter (after a running median) is of that order too
    diff = np.diff(flux) / np.sqrt(2)
    assert 0.7 < np.std(diff) / np.median(err) < 1.6
