"""Photometry from other pipelines: CSV, ECSV and FITS tables with only the columns a method needs.

Issue 16, point 1: a table with only ``time_bmjd, flux, flux_err, x, y`` (and
``noise_pixels``) reduces to the same depths as the package's full table of the
same frames; a method that needs a column the table lacks refuses in one line;
``columns`` / ``time_column`` / ``time_format`` map another pipeline's names;
binned tables are fitted at their own cadence.
"""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest
from astropy.table import Table
from astropy.time import Time

import eclipsebench as eb
from eclipsebench.astro.catalogue import get_system
from eclipsebench.astro.eclipse import EclipseShape
from eclipsebench.astro.orbit import eclipse_time_bmjd
from eclipsebench.cli import main
from eclipsebench.config.reduce import ReduceSection
from eclipsebench.errors import DataError, InputError
from eclipsebench.fit.data import epoch_data_from_table, median_cadence_s, standardise_table
from eclipsebench.fit.reduce import reduce_epoch, resolve_method_options
from eclipsebench.photometry.table import read_table, table_format

#: No prayer bead: the comparisons are of the least-squares depths, and fast.
FAST = replace(ReduceSection(), prayer_bead_shifts=0)
MINIMAL = ("time_bmjd", "flux", "flux_err", "x", "y", "noise_pixels")
#: GP on 240 s bins keeps the test at about a second (the option is the same for both tables).
METHODS = {"bliss": None, "kr-data": None, "gp": {"bin_seconds": 240.0}, "poly2": None}


@pytest.fixture(scope="module")
def full(kit):
    """A synthetic XO-3b epoch (12 s rows, 2664 frames) with every contract column."""
    system = get_system("XO-3b")
    t_true = eclipse_time_bmjd(system, 57000.0) + 0.003
    time = t_true + np.arange(-0.2, 0.17, 2 * kit.CADENCE_D)
    visible = EclipseShape(time, system).visible_fraction(t_true)
    table = kit.make_epoch_table(t_ecl=t_true, visible=visible, time=time, seed=5)
    rng = np.random.default_rng(9)
    table["width_x"] = 0.62 + 0.01 * np.sin(time * 90.0) + 0.002 * rng.standard_normal(len(time))
    table["width_y"] = 0.60 + 0.01 * np.cos(time * 70.0) + 0.002 * rng.standard_normal(len(time))
    return table


@pytest.fixture(scope="module")
def csv_path(full, tmp_path_factory):
    """The same frames as a CSV of another pipeline: six columns, no metadata."""
    path = tmp_path_factory.mktemp("other") / "lc.csv"
    Table({c: np.asarray(full[c]) for c in MINIMAL}).write(path, format="ascii.csv")
    return path


@pytest.fixture(scope="module")
def full_depths(full):
    return {m: reduce_epoch(full, m, options=FAST, system="XO-3b", method_options=resolve_method_options(m, FAST, o)).depth_ppm
            for m, o in METHODS.items()}


# --------------------------------------------------------------------------- acceptance
@pytest.mark.parametrize("method", list(METHODS))
def test_minimal_csv_gives_the_full_tables_depth(method, csv_path, full_depths):
    assert read_table(csv_path).colnames == list(MINIMAL)
    res = reduce_epoch(str(csv_path), method, options=FAST, system="XO-3b",
                       method_options=resolve_method_options(method, FAST, METHODS[method]))
    assert abs(res.depth_ppm - full_depths[method]) < 1.0
    assert res.cadence_s == pytest.approx(12.0, abs=1e-3)
    assert res.to_dict()["cadence_s"] == res.cadence_s


def test_pixel_methods_refuse_in_one_line(csv_path, capsys, tmp_path):
    for method in ("pld", "ica"):
        with pytest.raises(InputError) as exc:
            reduce_epoch(str(csv_path), method, options=FAST, system="XO-3b")
        msg = str(exc.value)
        assert msg == f"method '{method}' needs the column(s) stamp3 pixels (or p0..p8) in the " \
                      "photometry table"
    with pytest.raises(InputError, match="kr-pmap.*needs a pmap"):
        reduce_epoch(str(csv_path), "kr-pmap", options=FAST, system="XO-3b")
    code = main(["reduce", str(csv_path), "--method", "pld", "--system", "XO-3b",
                 "--out", str(tmp_path / "r.json")])
    err = capsys.readouterr().err
    assert code == 2
    assert err.count("\n") == 1 and "'pld'" in err and "stamp3 pixels (or p0..p8)" in err
    assert not (tmp_path / "r.json").exists()


# --------------------------------------------------------------------------- names and times
def _foreign(full) -> Table:
    """Another pipeline's names: full JD times, upper-case columns, a flag column."""
    return Table({"BJD_TDB": np.asarray(full["time_bmjd"]) + 2400000.5,
                  "FLUX": np.asarray(full["flux"]), "FLUX_ERR": np.asarray(full["flux_err"]),
                  "XC": np.asarray(full["x"]), "YC": np.asarray(full["y"]),
                  "QUALITY": np.zeros(len(full), dtype=int)})


FOREIGN_COLUMNS = "flux=FLUX,flux_err=FLUX_ERR,x=XC,y=YC,flag=QUALITY"


def test_columns_and_time_format_on_the_command_line(full, full_depths, tmp_path, capsys):
    path = tmp_path / "pipeline.csv"
    _foreign(full).write(path, format="ascii.csv")
    out = tmp_path / "r.json"
    code = main(["reduce", str(path), "--method", "poly2", "--system", "XO-3b",
                 "--prayer-bead", "0", "--columns", FOREIGN_COLUMNS, "--time-column", "BJD_TDB",
                 "--time-format", "bjd", "--out", str(out)])
    assert code == 0, capsys.readouterr().err
    saved = json.loads(out.read_text())
    assert abs(saved["depth_ppm"] - full_depths["poly2"]) < 1.0
    assert saved["cadence_s"] == pytest.approx(12.0, abs=1e-3)

    # errors name the flags, one line, exit 2
    for extra, words in ((["--columns", "flux=NOPE"], ("--columns", "NOPE")),
                         (["--columns", "flux"], ("--columns", "NEW=OLD")),
                         (["--columns", "fluxx=FLUX"], ("--columns", "unknown column name")),
                         (["--time-column", "T"], ("--time-column", "'T'")),
                         (["--time-column", "BJD_TDB", "--time-format", "bmjd"],
                          ("--time-format", "full Julian dates"))):
        args = ["reduce", str(path), "--method", "poly2", "--system", "XO-3b",
                "--out", str(tmp_path / "bad.json")]
        if extra[0] != "--columns":
            args += ["--columns", FOREIGN_COLUMNS]
        assert main(args + extra) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and all(w in err for w in words), err
    with pytest.raises(SystemExit) as usage:     # a usage error: argparse's one line
        main(["reduce", str(path), "--method", "poly2", "--time-format", "utc"])
    assert usage.value.code == 2 and "--time-format" in capsys.readouterr().err


@pytest.mark.parametrize("fmt, offset", [("bjd", 2400000.5), ("bmjd", 0.0)])
def test_barycentric_time_formats(full, fmt, offset):
    t = Table({"t": np.asarray(full["time_bmjd"][:5]) + offset})
    s = standardise_table(t, time_column="t", time_format=fmt)
    assert np.allclose(s["time_bmjd"], full["time_bmjd"][:5], rtol=0, atol=1e-9)
    assert "BMJD_TDB" in s.meta["TIMESRC"]
    wrong = {"bjd": "bmjd", "bmjd": "bjd"}[fmt]
    with pytest.raises(InputError, match="time_format"):
        standardise_table(t, time_column="t", time_format=wrong)


@pytest.mark.parametrize("fmt", ["jd", "mjd"])
def test_times_at_the_observer_need_scale_observer_and_coordinates(full, fmt):
    """jd/mjd are times at the observer: converted with the target's RA/Dec (astro/timescales)."""
    offset = 2400000.5 if fmt == "jd" else 0.0
    t = Table({"t": np.asarray(full["time_bmjd"][:5]) + offset})
    with pytest.raises(InputError, match="need their scale: give time_scale"):
        standardise_table(t, time_column="t", time_format=fmt)
    with pytest.raises(InputError, match="need observer X,Y,Z,MJD"):
        standardise_table(t, time_column="t", time_format=fmt, time_scale="tdb")
    with pytest.raises(InputError, match="need the target's RA and Dec"):
        standardise_table(t, time_column="t", time_format=fmt, time_scale="tdb",
                          observer="geocentre")
    s = standardise_table(t, time_column="t", time_format=fmt, time_scale="tdb",
                          observer="geocentre", target=get_system("XO-3b"))
    delay_s = (np.asarray(s["time_bmjd"]) - np.asarray(full["time_bmjd"][:5])) * 86400.0
    assert 0 < abs(delay_s).min() and abs(delay_s).max() < 500.0   # the Roemer delay, < 1 AU / c
    assert "geocentre" in s.meta["TIMECONV"] and fmt.upper() in s.meta["TIMECONV"]
    with pytest.raises(InputError, match="unknown time scale 'gps'"):
        standardise_table(t, time_column="t", time_format=fmt, time_scale="gps",
                          observer="geocentre", target=get_system("XO-3b"))


def test_time_columns_as_astropy_time_keep_their_scale(full):
    bmjd = np.asarray(full["time_bmjd"][:4])
    s = standardise_table(Table({"time_bmjd": Time(bmjd, format="mjd", scale="tdb")}))
    assert np.allclose(s["time_bmjd"], bmjd, rtol=0, atol=1e-9)
    utc = standardise_table(Table({"time_bmjd": Time(bmjd, format="mjd", scale="utc")}))
    tdb_minus_utc_s = (np.asarray(utc["time_bmjd"]) - bmjd) * 86400.0   # leap seconds + 32.184
    assert np.all((66.0 < tdb_minus_utc_s) & (tdb_minus_utc_s < 70.0))
    assert "BMJD_UTC" in utc.meta["TIMECONV"]
    with pytest.raises(InputError, match="astropy Time in scale 'utc'"):
        standardise_table(Table({"time_bmjd": Time(bmjd, format="mjd", scale="utc")}),
                          time_scale="tdb")


def test_library_keywords_and_their_errors(full, full_depths):
    res = eb.reduce(_foreign(full), "poly2", system="XO-3b", prayer_bead_shifts=0,
                    columns=dict(p.split("=") for p in FOREIGN_COLUMNS.split(",")),
                    time_column="BJD_TDB", time_format="bjd")
    assert abs(res.depth_ppm - full_depths["poly2"]) < 1.0
    with pytest.raises(InputError, match=r"^columns: flux=NOPE: the table has no column"):
        eb.reduce(_foreign(full), "poly2", system="XO-3b", columns={"flux": "NOPE"})
    with pytest.raises(InputError, match=r"^time_format: 'gps' is not one of"):
        eb.reduce(full, "poly2", system="XO-3b", time_format="gps")


# --------------------------------------------------------------------------- formats
def test_ecsv_and_foreign_fits_with_pixel_columns(full, tmp_path):
    pld_full = reduce_epoch(full, "pld", options=FAST, system="XO-3b").depth_ppm
    cols = {c: np.asarray(full[c]) for c in MINIMAL}
    stamps = np.asarray(full["stamp3"]).reshape(len(full), 9)
    cols.update({f"p{k}": stamps[:, k] for k in range(9)})
    ecsv = tmp_path / "lc.ecsv"
    fits_path = tmp_path / "lc.fits"
    Table(cols).write(ecsv, format="ascii.ecsv")
    Table(cols).write(fits_path)   # astropy's writer: no PHOTOMETRY extension, no contract
    assert table_format(ecsv) == "ecsv" and table_format(fits_path) == "fits"
    for path in (ecsv, fits_path):
        res = reduce_epoch(str(path), "pld", options=FAST, system="XO-3b")
        assert abs(res.depth_ppm - pld_full) < 1.0, path


def test_pixel_columns_become_stamps():
    n = 4
    cube5 = np.arange(n * 25, dtype=float).reshape(n, 5, 5)
    flat = {f"p{k}": cube5.reshape(n, 25)[:, k] for k in range(25)}
    s = standardise_table(Table(flat))
    assert np.array_equal(s["stamp5"], cube5)
    assert np.array_equal(s["stamp3"], cube5[:, 1:4, 1:4])
    with pytest.raises(InputError, match=r"p0\.\.p8 \(3 x 3\) or p0\.\.p24.*has p0, p1, p2"):
        standardise_table(Table({f"p{k}": np.ones(n) for k in range(3)}))
    s = standardise_table(Table({"stamp3": np.ones((n, 9))}))
    assert s["stamp3"].shape == (n, 3, 3)
    with pytest.raises(InputError, match="column 'stamp3': expected 3 x 3 pixels"):
        standardise_table(Table({"stamp3": np.ones((n, 8))}))


def test_unreadable_and_empty_tables(tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("a,b\n1,2,3,4\n")
    with pytest.raises(DataError, match="not a readable CSV photometry table"):
        read_table(bad)
    empty = tmp_path / "empty.csv"
    empty.write_text("time_bmjd,flux\n")
    with pytest.raises(DataError, match="no rows"):
        read_table(empty)


def test_flag_is_optional_and_widths_are_read(full):
    t = Table({c: np.asarray(full[c]) for c in ("time_bmjd", "flux", "flux_err", "x", "y",
                                                 "width_x", "width_y")})
    t["width_x"][3] = np.nan        # widths are not part of the finite-value cut
    d = epoch_data_from_table(t)
    assert len(d) == len(full) and d.meta["n_frames_flagged"] == 0
    assert np.isnan(d.width_x[3]) and d.width_y is not None
    assert len(d.subset(np.arange(10)).width_x) == 10
    assert d.meta["cadence_s"] == pytest.approx(12.0, abs=1e-3)


# --------------------------------------------------------------------------- PSF widths
def test_poly_psf_width_uses_the_tables_widths(full, csv_path, tmp_path):
    path = tmp_path / "widths.csv"
    Table({c: np.asarray(full[c]) for c in MINIMAL + ("width_x", "width_y")}).write(
        path, format="ascii.csv")
    psf_width = resolve_method_options("poly2", FAST, {"psf_width": True})
    res = reduce_epoch(str(path), "poly2", options=FAST, system="XO-3b",
                       method_options=psf_width)
    assert res.diagnostics["psf_width"] is True
    assert {"sys_psfw_x_per_px", "sys_psfw_y_per_px"} <= set(res.params)
    assert abs(res.depth_ppm - 1875.0) < 4 * res.depth_err_ppm
    with pytest.raises(InputError, match="option 'psf_width'.*width_x, width_y"):
        reduce_epoch(str(csv_path), "poly2", options=FAST, system="XO-3b",
                     method_options=psf_width)


# --------------------------------------------------------------------------- binned tables
def test_binned_table_is_fitted_at_its_cadence(full, kit, tmp_path):
    """One row per 32 frames of 12 s (384 s): the fit's cadence, beta_red and depth."""
    per = 32
    n = len(full) // per * per

    def binned(name):
        return np.asarray(full[name][:n], dtype=float).reshape(-1, per).mean(axis=1)

    table = Table({c: binned(c) for c in ("time_bmjd", "flux", "x", "y", "noise_pixels")})
    table["flux_err"] = binned("flux_err") / np.sqrt(per)
    path = tmp_path / "binned.csv"
    table.write(path, format="ascii.csv")
    assert median_cadence_s(table["time_bmjd"]) == pytest.approx(384.0, abs=1e-3)
    for method, opts in (("poly2", {"bin_frames": 1}), ("bliss", None)):
        res = reduce_epoch(str(path), method, options=ReduceSection(sampler="leastsq"),
                           system="XO-3b",
                           method_options=resolve_method_options(method, FAST, opts))
        assert res.cadence_s == pytest.approx(384.0, abs=1e-3)
        assert res.n_points + sum(res.n_frames_dropped.values()) == len(table)
        assert np.isfinite(res.beta_red) and res.depth_err_prayer_bead_ppm is not None
        assert abs(res.depth_ppm - kit.TRUE_DEPTH * 1e6) < 4 * res.depth_err_ppm, method
