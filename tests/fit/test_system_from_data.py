"""Issue 26 point 1: the planet comes from the data, never silently from the challenge."""

from __future__ import annotations

import numpy as np
import pytest
from astropy.io import fits
from astropy.table import Table

from eclipsebench.astro.catalogue import host_star, system_for_object, system_from_meta
from eclipsebench.cli import main
from eclipsebench.config.photometry import PhotometrySection
from eclipsebench.errors import InputError
from eclipsebench.fit.target import system_of_table
from eclipsebench.io.bcd_read import read_bcd_header
from eclipsebench.photometry.pipeline import photometry_tables

from ..badinput.conftest import star_cube, write_cube


def test_an_archive_object_names_its_planet_through_the_catalogue():
    assert system_for_object("XO-3 ch2 peak-up").name == "XO-3b"
    assert system_for_object("wasp14").name == "WASP-14b"
    assert system_for_object("HD 189733 b").name == "HD 189733b"
    assert system_for_object("XO-31") is None          # another star, not XO-3
    assert system_for_object("calibration star") is None
    assert host_star("XO-3b (2015 challenge)") is None  # a qualified row is never a star's


def test_a_simulation_s_system_wins_over_its_object():
    system, source = system_from_meta({"SYSTEM": "XO-3b (2015 challenge)", "OBJECT": "XO-3"})
    assert system.name == "XO-3b (2015 challenge)" and "SYSTEM" in source


def test_a_table_naming_no_planet_asks_for_one():
    with pytest.raises(InputError, match="names no object.*--system NAME"):
        system_of_table({})
    with pytest.raises(InputError, match="OBJECT 'M31' names no planet"):
        system_of_table({"OBJECT": "M31"})
    assert system_of_table({"OBJECT": "M31"}, system="XO-3b").name == "XO-3b"


def test_a_csv_without_an_object_exits_2_naming_system(tmp_path, capsys):
    n = 400
    t = np.linspace(56241.75, 56242.10, n)
    Table({"time_bmjd": t, "flux": np.ones(n), "flux_err": np.full(n, 1e-3),
           "x": np.full(n, 15.0), "y": np.full(n, 15.0)}).write(tmp_path / "lc.csv")
    code = main(["reduce", str(tmp_path / "lc.csv"), "--method", "bliss", "--sampler", "leastsq",
                 "--out", str(tmp_path / "r.json")])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "--system" in err, err
    assert not (tmp_path / "r.json").exists()


def test_an_aorkey_written_as_a_string_of_digits_is_an_aorkey(tmp_path):
    """The 2015 challenge's public cubes write AORKEY = '20150000' (a string)."""
    for name, key in (("int", 20150000), ("str", "20150000")):
        for k in range(2):
            write_cube(tmp_path / name, star_cube(64, seed=k), expid=k, aorkey=20150000,
                       AORKEY=key)
    path = next((tmp_path / "str").glob("*_bcd.fits"))
    assert fits.getheader(path)["AORKEY"] == "20150000"
    assert read_bcd_header(path).aorkey == 20150000
    (_, a), = photometry_tables(tmp_path / "int", PhotometrySection())
    (_, b), = photometry_tables(tmp_path / "str", PhotometrySection())
    for col in a.colnames:
        assert np.array_equal(np.asarray(a[col]), np.asarray(b[col]), equal_nan=True), col


@pytest.mark.shared_data
@pytest.mark.slow
def test_real_epoch1_is_reduced_with_xo3b_from_its_headers(real_epoch1_table, tmp_path):
    """Without --system the table's OBJECT ('XO-3 ch2 peak-up') gives XO-3b: the same bytes as
    with --system XO-3b (issue 26's acceptance)."""
    out = tmp_path / "r.json"
    common = ["reduce", str(real_epoch1_table), "--method", "segpoly", "--profile", "paper",
              "--sampler", "leastsq", "--out", str(out), "--quiet"]
    assert main(common) == 0
    found = out.read_bytes()
    assert main(common + ["--system", "XO-3b"]) == 0
    assert out.read_bytes() == found
    import json
    assert json.loads(found)["system"] == "XO-3b"
