"""Issue 28: smaller messages say what to type.

Before: ``reduce --method kr-pmap`` without a map named the library's argument
("needs a pmap"), and a table of another pipeline without the package's
column names listed the missing columns without saying how to map them.
"""

from __future__ import annotations

import numpy as np
from astropy.table import Table


def test_kr_pmap_without_a_map_names_the_pmap_option(tmp_path, cli, bad):
    table = bad.xo3_table(tmp_path / "epoch_01.fits")
    before = bad.snapshot(tmp_path)
    code, _, err = cli("reduce", table, "--method", "kr-pmap", "--sampler", "leastsq")
    bad.assert_one_line(code, err, "--pmap", "--method kr-pmap", str(table))
    assert bad.snapshot(tmp_path) == before


def test_another_pipelines_columns_are_named_with_the_options_that_map_them(tmp_path, cli,
                                                                           bad):
    n = 300
    path = tmp_path / "theirs.csv"
    Table({"BJD": 2457000.5 + np.arange(n) / 1000.0, "FLUX": np.ones(n),
           "FLUX_ERR": np.full(n, 0.01), "XC": np.full(n, 15.0), "YC": np.full(n, 15.0)}
          ).write(path)
    code, _, err = cli("reduce", path, "--method", "pld", "--sampler", "leastsq")
    bad.assert_one_line(code, err, str(path), "missing column(s) time_bmjd, flux, flux_err, x, y",
                        "--columns flux=FLUX,flux_err=FLUX_ERR,x=XC,y=YC",
                        "--time-column BJD --time-format bjd")
    code, _, err = cli("reduce", path, "--method", "pld", "--sampler", "leastsq",
                       "--columns", "flux=FLUX,flux_err=FLUX_ERR,x=XC")
    bad.assert_one_line(code, err, "missing column(s) time_bmjd, y", "--columns y=YC")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["theirs.csv"]
