"""Broken inputs give one-line errors naming the file, or flags; never a crash or a wrong table."""

from __future__ import annotations

import shutil

import numpy as np
import pytest
from astropy.io import fits

from eclipsebench.cli import main
from eclipsebench.config.photometry import PhotometrySection
from eclipsebench.errors import DataError
from eclipsebench.io.bcd_read import read_bcd, read_bcd_header
from eclipsebench.photometry.clean import FLAG_BITS
from eclipsebench.photometry.pipeline import photometry_tables
from eclipsebench.photometry.table import read_photometry

REAL = "real_xo3_peakup_46466816"
NAME = "SPITZER_I2_46466816_0002_0000_2_bcd.fits"


def _copy_real(shared_irac, tmp_path, names=(NAME,)):
    for name in names:
        shutil.copy(shared_irac / REAL / name, tmp_path / name)
    return tmp_path / names[0]


def _one_line_error(capsys, argv):
    code = main(argv)
    err = capsys.readouterr().err.strip().splitlines()
    return code, err


@pytest.mark.shared_data
def test_truncated_file_is_a_data_error_naming_it(shared_irac, tmp_path, capsys):
    path = _copy_real(shared_irac, tmp_path)
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])
    with pytest.raises(DataError, match="truncated") as info:
        read_bcd_header(path)
    assert NAME in str(info.value)
    code, err = _one_line_error(capsys, ["photometry", str(tmp_path), "--out",
                                         str(tmp_path / "o.fits"), "--quiet"])
    assert code == 2 and len(err) == 1 and NAME in err[0] and "truncated" in err[0]
    assert not (tmp_path / "o.fits").exists()


@pytest.mark.shared_data
def test_header_only_file_is_a_data_error(shared_irac, tmp_path):
    path = _copy_real(shared_irac, tmp_path)
    data = path.read_bytes()
    path.write_bytes(data[:2880 * 3])  # a few header blocks, no END card
    with pytest.raises(DataError, match=NAME):
        read_bcd_header(path)


@pytest.mark.shared_data
def test_missing_bmjd_obs_is_a_data_error(shared_irac, tmp_path, capsys):
    path = _copy_real(shared_irac, tmp_path)
    with fits.open(path, mode="update") as hdul:
        del hdul[0].header["BMJD_OBS"]
    with pytest.raises(DataError, match="lacks BMJD_OBS"):
        read_bcd_header(path)
    code, err = _one_line_error(capsys, ["photometry", str(tmp_path), "--out",
                                         str(tmp_path / "o.fits"), "--quiet"])
    assert code == 2 and len(err) == 1 and "BMJD_OBS" in err[0] and NAME in err[0]


def test_wrong_naxis_is_a_data_error(tmp_path, make_bcd):
    path = make_bcd(tmp_path, np.ones((64, 32, 32)))
    fits.PrimaryHDU(np.ones((32, 32), np.float32), header=fits.getheader(path)).writeto(
        path, overwrite=True)
    with pytest.raises(DataError, match="NAXIS=2"):
        read_bcd_header(path)
    path2 = make_bcd(tmp_path, np.ones((4, 16, 16)), expid=1)
    with pytest.raises(DataError, match="expected a subarray cube"):
        read_bcd_header(path2)


def test_wrong_units_and_non_numeric_keywords(tmp_path, make_bcd):
    path = make_bcd(tmp_path, np.ones((4, 32, 32)), BUNIT="DN")
    with pytest.raises(DataError, match="BUNIT"):
        read_bcd_header(path)
    path = make_bcd(tmp_path, np.ones((4, 32, 32)), expid=1, GAIN="three")
    with pytest.raises(DataError, match="GAIN"):
        read_bcd_header(path)


def test_not_fits_at_all(tmp_path):
    path = tmp_path / "SPITZER_I2_1_0000_0000_1_bcd.fits"
    path.write_text("hello")
    with pytest.raises(DataError, match="SPITZER_I2_1_0000_0000_1_bcd.fits"):
        read_bcd(path)


def test_all_nan_frame_and_nan_pixel_are_flagged_not_dropped(tmp_path, make_bcd, make_star_cube):
    cube, _, _ = make_star_cube(64, seed=1)
    cube[10] = np.nan           # a whole frame
    cube[20, 15, 15] = np.nan   # one pixel inside the aperture
    cube[30, 2, 2] = np.nan     # one pixel far from the star: harmless
    cube[31, 15, 21] = np.nan   # in the background annulus only: skipped, harmless
    make_bcd(tmp_path, cube)
    (_, table), = photometry_tables(tmp_path, PhotometrySection())
    assert len(table) == 64
    flag = np.asarray(table["flag"])
    assert flag[10] & FLAG_BITS["nonfinite"] and flag[20] & FLAG_BITS["nonfinite"]
    assert flag[30] == 0 and flag[31] == 0
    assert np.isfinite(table["background"][31]) and table["background_npix"][31] < \
        table["background_npix"][32]
    assert np.isnan(table["flux"][10]) and np.isnan(table["flux"][20])
    assert table.meta["FLAGCNT"]["nonfinite"] == 2


def test_cosmic_ray_in_the_aperture_is_flagged_and_repaired(tmp_path, make_bcd, make_star_cube):
    cube, _, _ = make_star_cube(64, seed=2)
    cube[40, 16, 14] += 5000.0
    make_bcd(tmp_path, cube)
    (_, table), = photometry_tables(tmp_path, PhotometrySection())
    flag = np.asarray(table["flag"])
    assert flag[40] & FLAG_BITS["cosmic_ray"]
    assert np.count_nonzero(flag & FLAG_BITS["cosmic_ray"]) <= 2
    # the repaired frame's flux is back among the others (the hit alone adds 7%)
    ref = np.median(table["flux_r4p00"])
    assert abs(table["flux_r4p00"][40] - ref) < 0.01 * ref


def test_fatal_bimsk_bits_flag_the_frame(tmp_path, make_bcd, make_star_cube):
    cube, _, _ = make_star_cube(8, seed=3)
    path = make_bcd(tmp_path, cube)
    mask = np.zeros(cube.shape, np.int16)
    mask[5, 15, 16] = 512   # radhit inside the aperture
    mask[6, 15, 16] = 4     # optical ghost: not fatal by default
    fits.PrimaryHDU(mask).writeto(path.with_name(path.name.replace("_bcd", "_bimsk")))
    (_, table), = photometry_tables(tmp_path, PhotometrySection(cosmic_ray_window=0))
    flag = np.asarray(table["flag"])
    assert flag[5] & FLAG_BITS["bimsk"]
    assert not flag[6] & FLAG_BITS["bimsk"]


def test_unreadable_table_is_a_data_error(tmp_path):
    bad = tmp_path / "t.fits"
    bad.write_text("nope")
    with pytest.raises(DataError, match="t.fits"):
        read_photometry(bad)


def test_centroid_outliers_catch_bad_pixels_not_pointing_excursions(tmp_path, make_bcd,
                                                                     gaussian_prf):
    rng = np.random.default_rng(8)
    n = 128
    xs = 15.1 + 0.01 * rng.standard_normal(n)
    ys = 15.0 + 0.01 * rng.standard_normal(n)
    ys[50:90] -= 0.08 * np.sin(np.linspace(0, np.pi, 40))  # a 40-frame pointing excursion
    cube = np.stack([gaussian_prf(x, y, 0.6, 7e4) for x, y in zip(xs, ys, strict=True)]) + 5.0
    cube = rng.poisson(cube).astype(float)
    cube[100, 17, 12] += 3000.0  # a hit in the box corner (CR rejection switched off)
    make_bcd(tmp_path, cube)
    opt = PhotometrySection(cosmic_ray_window=0)
    (_, table), = photometry_tables(tmp_path, opt)
    flag = np.asarray(table["flag"])
    assert flag[100] & FLAG_BITS["centroid_outlier"]
    assert not np.any(flag[50:90] & FLAG_BITS["centroid_outlier"])
    assert np.count_nonzero(flag & FLAG_BITS["centroid_outlier"]) <= 2
