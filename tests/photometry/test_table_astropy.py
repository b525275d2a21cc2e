"""Photometry tables the astropy way (issue 29) and byte-reproducible (issue 28)."""

from __future__ import annotations

import shutil
import warnings

import astropy.units as u
import numpy as np
from astropy.io import fits
from astropy.table import Table

from eclipsebench.cli import main
from eclipsebench.photometry.table import read_photometry


def _write_sim(root, make_bcd, make_star_cube):
    """A tiny simulated input under ``root``: one AOR of two 8-frame cubes, EPOCH 1."""
    (root / "calibration").mkdir(parents=True)
    (root / "truth.ecsv").write_text("# marks the simulation root\n")
    for k in range(2):
        cube, _, _ = make_star_cube(8, seed=3 + k)
        make_bcd(root / "r7" / "ch2" / "bcd", cube, aorkey=7, expid=k,
                 bmjd=57000.0 + k * 20.0 / 86400, SIMULATE=True, EPOCH=1)


def test_table_read_of_a_photometry_fits_emits_no_warning(tmp_path, make_bcd, make_star_cube):
    _write_sim(tmp_path / "sim", make_bcd, make_star_cube)
    assert main(["photometry", str(tmp_path / "sim"), "--out", str(tmp_path / "phot"),
                 "--quiet"]) == 0
    path = tmp_path / "phot" / "epoch_01.fits"
    with warnings.catch_warnings():
        warnings.simplefilter("error")   # the old 'electron' TUNITn gave 21 UnitsWarnings
        plain = Table.read(path)
    assert plain["flux"].unit == u.ct and plain["background"].unit == u.ct / u.pix**2
    assert plain["x"].unit == u.pix and plain["time_bmjd"].unit == u.day
    header = fits.getheader(path, "PHOTOMETRY")
    assert (header["TIMESYS"], header["MJDREF"], header["TIMEUNIT"]) == ("TDB", 0.0, "d")
    comments = {header[f"TTYPE{k}"]: header.get(f"TCOMM{k}")
                for k in range(1, header["TFIELDS"] + 1)}
    assert all(comments.values()), [n for n, c in comments.items() if not c]
    assert "BMJD" in comments["time_bmjd"]
    ours = read_photometry(path)   # our reader: electrons, descriptions, absolute SIMDIR
    assert ours["flux"].unit == u.electron and ours["background"].unit == u.electron / u.pix**2
    assert ours["flux"].description == comments["flux"]
    assert ours.meta["SIMDIR"] == str((tmp_path / "sim").resolve())


def test_two_photometry_runs_into_different_folders_write_identical_bytes(
        tmp_path, make_bcd, make_star_cube):
    _write_sim(tmp_path / "run_a" / "sim", make_bcd, make_star_cube)
    shutil.copytree(tmp_path / "run_a" / "sim", tmp_path / "elsewhere" / "run_b" / "sim")
    tables = []
    for run in (tmp_path / "run_a", tmp_path / "elsewhere" / "run_b"):
        assert main(["photometry", str(run / "sim"), "--out", str(run / "photometry"),
                     "--quiet"]) == 0
        tables.append(run / "photometry" / "epoch_01.fits")
    a, b = (p.read_bytes() for p in tables)
    assert a == b   # before: CHECKSUM's write time, INROOT/SIMDIR's absolute folders differed
    with fits.open(tables[1], checksum=True) as hdul:   # the fixed-comment checksums verify
        hdul.verify("exception")
        assert hdul["PHOTOMETRY"].header["CHECKSUM"]
    back = [read_photometry(p) for p in tables]
    assert back[1].meta["SIMDIR"] == str((tmp_path / "elsewhere" / "run_b" / "sim").resolve())
    assert back[1].meta["INROOT"] == str((tmp_path / "elsewhere" / "run_b" / "sim").resolve())
    np.testing.assert_array_equal(back[0]["flux"], back[1]["flux"])
