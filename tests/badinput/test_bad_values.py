"""Bad option values and odd tables: one line on stderr naming the option, exit 2."""

from __future__ import annotations

import pytest
from astropy.table import Table


@pytest.mark.parametrize("value", ["nan", "inf", "-inf", "NaN"])
def test_lightcurve_start_must_be_finite(value, cli, bad):
    with pytest.raises(SystemExit) as info:
        cli("lightcurve", "--start", value)
    assert info.value.code == 2


def test_lightcurve_start_nan_one_line(capsys, bad):
    from eclipsebench.cli import main

    for value in ("nan", "inf"):
        with pytest.raises(SystemExit) as info:
            main(["lightcurve", "--start", value])
        err = capsys.readouterr().err.splitlines()
        bad.assert_one_line(info.value.code, err, "--start", value, "finite")


def test_photon_limit_aperture_below_net_is_refused(cli, bad):
    code, out, err = cli("photon-limit", "--flux-net", "70858", "--flux-aperture", "100",
                         "--flux-background", "463", "--frames", "14912", "--depth-ppm", "1520")
    bad.assert_one_line(code, err, "--flux-aperture", "--flux-net")
    assert out == ""


@pytest.mark.parametrize("content,expected", [
    (b"\xef\xbb\xbfmethod,epoch,depth_ppm,error_ppm\na,1,1800,50\na,2,1850,50\n",
     "byte-order mark"),
    (b"\xff\xfem\x00", "byte-order mark"),
    (b"method,epoch,depth_ppm,error_ppm\na,1,1800,50\na,2,1850,50\n,3,1800,50\n",
     "blank method name in row 3"),
    (b"method,epoch,depth_ppm,error_ppm\na,1,1800,50\n  ,2,1850,50\na,3,1800,50\n",
     "blank method name in row 2"),
])
def test_stats_bom_and_blank_method(content, expected, tmp_path, cli, bad):
    path = tmp_path / "depths.csv"
    path.write_bytes(content)
    code, out, err = cli("stats", path)
    bad.assert_one_line(code, err, str(path), expected)
    assert "--" not in err[0] and out == ""


def test_blank_method_in_ecsv(tmp_path, cli, bad):
    path = tmp_path / "depths.ecsv"
    Table({"method": ["a", "a", ""], "epoch": [1, 2, 3], "depth_ppm": [1.0, 2.0, 3.0],
           "error_ppm": [1.0, 1.0, 1.0]}).write(path, format="ascii.ecsv")
    code, _, err = cli("stats", path)
    bad.assert_one_line(code, err, str(path), "blank method name in row 3")


def test_bare_command_prints_usage_on_stderr(cli, bad):
    code, out, err = cli()
    bad.assert_one_line(code, err, "usage: eclipsebench COMMAND", "photometry")
    assert out == ""


def test_reduce_refuses_a_zero_error(tmp_path, cli, bad):
    table = bad.xo3_table(tmp_path / "epoch_01.fits", noise=0.0)
    before = bad.snapshot(tmp_path)
    code, out, err = cli("reduce", table, "--method", "segpoly", "--prayer-bead", "0", "--quiet")
    bad.assert_one_line(code, err, str(table), "segpoly", "error")
    assert out == ""
    assert bad.snapshot(tmp_path) == before  # no result, no light curve
