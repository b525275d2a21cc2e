"""BCD files: names, card formats readable by astropy, data round trip, times."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
from astropy.io import fits

from eclipsebench.io.bcd_write import AorWriter, bcd_path, bmjd_to_utc, bunc_path, cube_bytes
from eclipsebench.io.header_template import BcdHeaderInfo, format_card, format_header


def _info(**kw):
    base = dict(aorkey=20150003, aorlabel="xo3b-2015_e02_main", object_name="XO-3", epoch=2,
                seed=11, noise_model="physical", fowler=8, wait=184, sample_time_s=0.01,
                frame_time_s=2.0, frame_interval_s=2.008, exptime_s=1.92, frames_per_cube=64,
                fluxconv=0.1469, gain_e_per_dn=3.71, read_noise_e=9.4, ra_deg=65.4694522,
                dec_deg=57.8173337, star_x_px=15.1, star_y_px=15.2)
    base.update(kw)
    return BcdHeaderInfo(**base)


def test_archive_file_names(tmp_path):
    p = bcd_path(tmp_path, 20150001, 7)
    assert p.relative_to(tmp_path).as_posix() == \
        "r20150001/ch2/bcd/SPITZER_I2_20150001_0007_0000_1_bcd.fits"
    assert bunc_path(tmp_path, 20150001, 7).name == "SPITZER_I2_20150001_0007_0000_1_bunc.fits"


def test_cards_are_fixed_format():
    assert format_card("NAXIS", 3, "x") == b"NAXIS   =                    3 / x".ljust(80)
    assert format_card("SIMULATE", True)[:30] == b"SIMULATE=                    T"
    assert format_card("OBJECT", "XO-3")[:20] == b"OBJECT  = 'XO-3    '"
    assert format_card("ALPHA", 1e-5)[10:30].strip() == b"1.E-05"
    h = format_header([("SIMPLE", True, ""), ("BITPIX", 8, ""), ("NAXIS", 0, "")])
    assert len(h) == 2880 and h[240:243] == b"END"


def test_written_cube_reads_back_with_all_keywords(tmp_path):
    rng = np.random.default_rng(0)
    cube = rng.normal(size=(64, 32, 32)).astype(np.float32)
    unc = np.abs(cube) * 0.1
    xy = np.column_stack([15.1 + 0.001 * np.arange(64), 15.2 - 0.001 * np.arange(64)])
    w = AorWriter(tmp_path, _info())
    mjd, iso = bmjd_to_utc(np.array([57208.8]), 65.4694522, 57.8173337)
    p_bcd, p_unc = w.write_cube(expid=5, bcd_mjysr=cube, bunc_mjysr=unc, bmjd_obs=57208.8,
                                mjd_obs=float(mjd[0]), date_obs=iso[0], xy_mean=xy)
    with fits.open(p_bcd) as hdul:
        hdul.verify("exception")
        h = hdul[0].header
        np.testing.assert_array_equal(hdul[0].data, cube)
    for key in ("BMJD_OBS", "MJD_OBS", "DATE_OBS", "AINTBEG", "ATIMEEND", "AFOWLNUM",
                "AWAITPER", "AREADMOD", "READMODE", "FRAMTIME", "EXPTIME", "SAMPTIME", "AORKEY",
                "EXPID", "AORLABEL", "OBJECT", "CHNLNUM", "CRPIX1", "CD1_1", "CTYPE2", "BUNIT",
                "FLUXCONV", "GAIN", "RONOISE", "SIMULATE", "SIMSEED", "NOISEMOD", "EPOCH"):
        assert key in h, key
    assert h["SIMULATE"] is True and h["SIMSEED"] == 11 and h["EPOCH"] == 2
    assert h["AORKEY"] == 20150003 and h["EXPID"] == 5 and h["READMODE"] == "SUB"
    assert h["AFOWLNUM"] == 8 and h["AWAITPER"] == 184 and h["AREADMOD"] == 1
    assert h["XYMEAN01"] == "(15.1000,15.2000)" and h["XYMEAN64"] == "(15.1630,15.1370)"
    assert h["ATIMEEND"] - h["AINTBEG"] == pytest.approx(63 * 2.008 + 2.0, abs=0.02)
    with fits.open(p_unc) as hdul:
        hdul.verify("exception")
        np.testing.assert_array_equal(hdul[0].data, unc)
        assert hdul[0].header["AORKEY"] == 20150003
    assert len(cube_bytes(cube)) % 2880 == 0


def test_utc_times_are_barycentric_minus_a_plausible_delay():
    bmjd = np.array([56270.4752315, 57208.8])
    mjd, iso = bmjd_to_utc(bmjd, 65.4694522, 57.8173337)
    delay_s = (bmjd - mjd) * 86400.0
    # TDB - UTC is 67-69 s in 2012-2015; the Roemer delay is at most ~500 s
    assert np.all(np.abs(delay_s - 68.0) < 510.0)
    assert iso[0].startswith("2012-12-09T")
    # the real header of this cube says MJD_OBS = 56270.4731344 (as seen from Spitzer)
    assert abs(mjd[0] - 56270.4731344) * 86400 < 400.0


@pytest.mark.parametrize("ra_deg, dec_deg", [(65.4694522, 57.8173337), (297.4, -47.5),
                                             (0.0, 89.99), (181.0, -89.99)])
def test_the_geocentric_light_travel_time_is_astropys_to_the_bit(ra_deg, dec_deg):
    """The delay without astropy's ITRS -> GCRS rotation of the geocentre (issue 40: it read
    the IERS-A table, 1.4 s a process) is astropy's own, bit for bit, from 2004 to 2020."""
    from astropy import units as u
    from astropy.coordinates import EarthLocation, SkyCoord
    from astropy.time import Time

    from eclipsebench.io.bcd_write import geocentric_light_travel_time

    bmjd = np.random.default_rng(7).uniform(53000.0, 59000.0, 1500)
    geocentre = EarthLocation.from_geocentric(0.0, 0.0, 0.0, unit=u.m)
    time = Time(bmjd, format="mjd", scale="tdb", location=geocentre)
    star = SkyCoord(ra_deg * u.deg, dec_deg * u.deg, frame="icrs")
    theirs = time.light_travel_time(star, kind="barycentric")
    ours = geocentric_light_travel_time(time, star)
    assert ours.scale == "tdb"
    assert np.array_equal(ours.jd1, theirs.jd1) and np.array_equal(ours.jd2, theirs.jd2)


def test_utc_times_read_no_earth_rotation_table():
    """A process that simulates converts its times without loading the IERS tables."""
    code = ("import numpy as np\n"
            "from eclipsebench.io.bcd_write import bmjd_to_utc\n"
            "bmjd_to_utc(np.array([57208.8]), 65.4694522, 57.8173337)\n"
            "from astropy.utils import iers\n"
            "print(iers.IERS_Auto.iers_table is None, iers.IERS_B.iers_table is None)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.split() == ["True", "True"], out.stdout + out.stderr
