"""Issue 37: every input bounded and malformed inputs refused before any work.

Before: a configuration, catalogue or ``--pmap`` naming ``/dev/zero`` read
without end, a FIFO blocked for ever (the timeout guards each test).
"""

from __future__ import annotations

import os

import pytest


@pytest.fixture
def fifo(tmp_path):
    """A FIFO no one writes to: opening it to read would block for ever."""
    path = tmp_path / "fifo.toml"
    os.mkfifo(path)
    return path


@pytest.mark.timeout(60)
@pytest.mark.parametrize("special", ["/dev/zero", "fifo"])
@pytest.mark.parametrize("kind", ["config", "catalogue", "set-catalogue"])
def test_a_device_or_fifo_as_configuration_or_catalogue_is_one_line(kind, special, fifo,
                                                                   tmp_path, cli, bad):
    path = str(fifo) if special == "fifo" else special
    out = tmp_path / "sim"
    argv = {"config": ["simulate", path, "--out", out],
            "catalogue": ["lightcurve", "XO-3b", "--catalogue", path, "--out", out / "lc.ecsv"],
            "set-catalogue": ["simulate", "--set", f"system.catalogue={path}", "--out", out],
            }[kind]
    code, _, err = cli(*argv, "--quiet")
    bad.assert_one_line(code, err, path, "not a regular file")
    assert not out.exists()


@pytest.mark.timeout(60)
@pytest.mark.parametrize("special", ["/dev/zero", "fifo"])
def test_a_device_or_fifo_as_pmap_is_one_line(special, fifo, tmp_path, cli, bad):
    path = str(fifo) if special == "fifo" else special
    table = bad.xo3_table(tmp_path / "t.fits")
    out = tmp_path / "out"
    code, _, err = cli("reduce", table, "--method", "kr-pmap", "--pmap", path,
                       "--out", out / "r.json", "--quiet")
    bad.assert_one_line(code, err, path, "not a regular file")
    code, _, err = cli("trust", table, "--pmap", path, "--out", out, "--quiet")
    bad.assert_one_line(code, err, path, "not a regular file")
    assert not out.exists()


def test_a_configuration_above_its_size_limit_is_one_line(tmp_path, cli, bad, monkeypatch):
    import eclipsebench.config.base as base

    path = tmp_path / "big.toml"
    path.write_text("[challenge]\nseed = 1\n" + "# padding\n" * 200)
    monkeypatch.setattr(base, "MAX_TEXT_FILE_BYTES", 1000)   # the real limit is 16 MiB
    code, _, err = cli("config", path)
    bad.assert_one_line(code, err, str(path), "above the limit of 1000")


# ----------------------------------------------------------------------------- tables
def _sparse_fits(path, n_rows: int):
    """A FITS table whose header says ``n_rows`` rows of 16 bytes: a sparse file (no data
    written), so a reader that trusts NAXIS2 before reading allocates nothing."""
    import numpy as np
    from astropy.io import fits

    hdu = fits.BinTableHDU.from_columns([fits.Column("time_bmjd", "D", array=np.zeros(1)),
                                         fits.Column("flux", "D", array=np.ones(1))])
    hdu.name = "PHOTOMETRY"
    hdu.header["NAXIS2"] = n_rows
    head = fits.PrimaryHDU().header.tostring().encode() + hdu.header.tostring().encode()
    size = len(head) + -(-16 * n_rows // 2880) * 2880
    with open(path, "wb") as fh:
        fh.write(head)
        fh.truncate(size)
    return path


def _long_csv(path, n_rows: int):
    with open(path, "wb") as fh:
        fh.write(b"time_bmjd,flux\n")
        fh.write(b"1,1\n" * n_rows)
    return path


@pytest.mark.parametrize("kind,command", [("fits", "reduce"), ("fits", "trust"),
                                          ("csv", "reduce"), ("csv", "trust"), ("csv", "stats")])
def test_a_table_over_the_row_limit_is_refused_before_it_is_read(kind, command, tmp_path, cli,
                                                                 bad):
    """The real limit, on cheap files: a sparse FITS (160 MB said, nothing written) and a
    40 MB CSV; refused in well under 5 CPU-seconds, nothing made in --out."""
    import time

    from eclipsebench.limits import MAX_FRAMES_PER_EPOCH

    n = MAX_FRAMES_PER_EPOCH + 1
    path = (_sparse_fits(tmp_path / "big.fits", n) if kind == "fits"
            else _long_csv(tmp_path / "big.csv", n))
    out = tmp_path / "out"
    argv = {"reduce": ["reduce", path, "--method", "pld", "--out", out / "r.json"],
            "trust": ["trust", path, "--out", out],
            "stats": ["stats", path]}[command]
    start = time.process_time()
    code, _, err = cli(*argv, "--quiet")
    cpu_s = time.process_time() - start
    bad.assert_one_line(code, err, str(path), f"{n} rows", str(MAX_FRAMES_PER_EPOCH))
    assert cpu_s < 5.0
    assert not out.exists()


def test_a_table_at_the_row_limit_is_counted_exactly(tmp_path):
    from eclipsebench.photometry.table import count_text_rows

    path = tmp_path / "t.csv"
    path.write_bytes(b"# c\n#c2\ntime_bmjd,flux\n1,2\n\n3,4\r\n\r\n5,6")
    assert count_text_rows(path) == 3
    path.write_bytes(b"time_bmjd,flux\n" + b"1,1\n" * 5)
    assert count_text_rows(path) == 5


# ----------------------------------------------------------------------------- YAML aliases
#: What trust needs in the metadata of a table ('eclipsebench photometry' records the readout).
READOUT = {"CHANNEL": 2, "READMODE": "SUB", "AFOWLNUM": 8, "AWAITPER": 184, "SAMPTIME": 0.01,
           "FRAMTIME": 2.0, "RONOISE": 9.4}


def _alias_bomb(levels: int = 9) -> str:
    """A YAML flow sequence of ``levels`` anchored lists, each nine aliases of the one before:
    9**levels strings once expanded (1.1 KB of text for 9 levels; 2.7 GB of JSON)."""
    items = ["&a0 [" + ", ".join(["lol"] * 9) + "]"]
    items += [f"&a{k} [" + ", ".join([f"*a{k - 1}"] * 9) + "]" for k in range(1, levels)]
    return "[" + ", ".join(items) + "]"


def _bomb_ecsv(path, bad, levels: int = 9):
    """The flat XO-3b table as ECSV, with the readout and a YAML alias bomb in its metadata."""
    from astropy.table import Table

    plain = bad.xo3_table(path.with_suffix(".fits"))
    table = Table.read(plain)
    table.meta.update(READOUT)
    table.meta["BOMB"] = "PLACEHOLDER"
    table.write(path, format="ascii.ecsv")
    text = path.read_text()
    assert text.count("PLACEHOLDER") == 1
    path.write_text(text.replace("PLACEHOLDER", _alias_bomb(levels)))
    plain.unlink()
    return path


def test_ecsv_metadata_that_aliases_expand_past_the_limit_are_refused(tmp_path, bad):
    import time

    from eclipsebench.errors import DataError
    from eclipsebench.photometry.table import read_table

    path = _bomb_ecsv(tmp_path / "bomb.ecsv", bad)
    assert len(_alias_bomb()) < 2000   # 1.1 KB of YAML
    start = time.process_time()
    with pytest.raises(DataError, match="expand through YAML aliases to [0-9]{10} char") \
            as caught:
        read_table(path)
    assert time.process_time() - start < 5.0
    assert str(path) in str(caught.value) and "\n" not in str(caught.value)


def test_ecsv_metadata_with_an_alias_astropy_writes_are_read(tmp_path):
    """astropy writes the same list under two keys as an anchor and an alias: that is read."""
    from astropy.table import Table

    from eclipsebench.photometry.table import read_table

    shared = [1, 2, 3]
    Table({"time_bmjd": [1.0, 2.0]}, meta={"A": shared, "B": shared}).write(
        tmp_path / "t.ecsv", format="ascii.ecsv")
    assert "*id001" in (tmp_path / "t.ecsv").read_text()
    assert read_table(tmp_path / "t.ecsv").meta["B"] == [1, 2, 3]


def test_ecsv_metadata_that_refer_to_themselves_are_refused(tmp_path):
    from eclipsebench.errors import DataError
    from eclipsebench.photometry.table import read_table

    path = tmp_path / "t.ecsv"
    path.write_text("# %ECSV 1.0\n# ---\n# datatype:\n# - {name: a, datatype: float64}\n"
                    "# meta: {X: &x [1, *x]}\na\n1.0\n")
    with pytest.raises(DataError, match="cannot be expanded"):
        read_table(path)


def test_metadata_are_never_serialised_into_a_header_past_the_limit(tmp_path):
    """Shared references (as a YAML reader builds them) are not expanded past the limit."""
    import yaml
    from astropy.table import Table

    from eclipsebench.errors import InputError
    from eclipsebench.limits import MAX_TABLE_HEADER_BYTES
    from eclipsebench.photometry.table import write_photometry

    bomb = yaml.safe_load(_alias_bomb(7))   # 4.8 M strings once expanded: 34 MB of JSON
    table = Table({"time_bmjd": [1.0, 2.0]}, meta={"BOMB": bomb})
    with pytest.raises(InputError, match=f"BOMB.*{MAX_TABLE_HEADER_BYTES}"):
        write_photometry(table, tmp_path / "t.fits")
    assert not (tmp_path / "t.fits").exists()


@pytest.mark.timeout(300)
@pytest.mark.parametrize("command", ["trust", "reduce"])
def test_an_alias_bomb_table_stays_under_1_gb(command, tmp_path, bad):
    """The whole command in a fresh process: one line, exit 2, peak memory under 1 GB.

    The peak is the child's own ``VmHWM``: ``ru_maxrss`` also carries the peak of the
    process that spawned it (Linux keeps the old memory's high-water mark across
    ``vfork`` + ``exec``), so under xdist it read the pytest worker's 1.0 GB. The address
    space is capped at 4 GB so that a reader that expands the bomb (7 GB per twin before
    issue 37) fails here instead of exhausting the machine."""
    import subprocess
    import sys

    path = _bomb_ecsv(tmp_path / "bomb.ecsv", bad)
    out = tmp_path / "out"
    argv = {"trust": ["trust", str(path), "--out", str(out), "--methods", "poly2",
                      "--sampler", "leastsq", "--twins", "10", "--depth", "2000",
                      "--workers", "1", "--system", "XO-3b"],
            "reduce": ["reduce", str(path), "--method", "poly2", "--sampler", "leastsq",
                       "--out", str(out / "r.json"), "--system", "XO-3b"]}[command]
    script = ("import resource, sys\n"
              "resource.setrlimit(resource.RLIMIT_AS, (4 * 2**30, 4 * 2**30))\n"
              "from eclipsebench.cli import main\n"
              f"code = main({argv + ['--quiet']!r})\n"
              "print(next(line.split()[1] for line in open('/proc/self/status')\n"
              "           if line.startswith('VmHWM:')))\n"
              "sys.exit(code)\n")
    run = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                         timeout=280)
    err = run.stderr.splitlines()
    bad.assert_one_line(run.returncode, err, str(path), "YAML aliases")
    assert int(run.stdout.split()[-1]) < 2**20   # KiB: under 1 GiB
    assert not out.exists()


# ----------------------------------------------------------------------------- trust inputs
FAST = ["--methods", "poly2", "--sampler", "leastsq", "--twins", "10", "--workers", "1",
        "--quiet"]


def _trust_table(path, bad, change=None):
    """The flat XO-3b table with the readout trust needs, ``change(table)`` applied, as
    'eclipsebench photometry' writes it."""
    from eclipsebench.photometry.table import read_table, write_photometry

    table = read_table(bad.xo3_table(path.with_name("base.fits")))
    table.meta.update(READOUT)
    if change is not None:
        change(table)
    write_photometry(table, path)
    return path


def _swap(table):
    table["time_bmjd"][[10, 11]] = table["time_bmjd"][[11, 10]]


def _repeat(table):
    table["time_bmjd"][300] = table["time_bmjd"][12]


def _nan(table):
    table["time_bmjd"][5] = float("nan")


def _negate(table):
    table["flux"] = -table["flux"]


@pytest.mark.parametrize("change,names", [
    (_swap, ["time_bmjd", "not in time order", "row 12"]),
    (_repeat, ["time_bmjd", "repeat", "rows 13 and 301"]),
    (_nan, ["time_bmjd", "no finite time", "row 6"]),
    (_negate, ["column flux", "positive"]),
])
def test_malformed_trust_tables_are_one_line_before_any_work(change, names, tmp_path, cli, bad):
    """Before: out of order, all the work then an internal error; repeated or NaN times, two
    lines after the work; a negated flux, 11 lines naming pointing.a_fbm_px."""
    path = _trust_table(tmp_path / "t.fits", bad, change)
    out = tmp_path / "out"
    code, _, err = cli("trust", path, "--out", out, "--depth", "2000", *FAST)
    bad.assert_one_line(code, err, str(path), *names)
    assert "pointing" not in err[0]
    assert not out.exists()


@pytest.mark.filterwarnings("always")   # as on the command line: not made errors by pytest
def test_a_truncated_fits_table_is_one_line_even_quiet(tmp_path, cli, bad):
    """Before: astropy's "File may have been truncated" twice (its log and ours), then the
    error about reshaping an array."""
    path = _trust_table(tmp_path / "t.fits", bad)
    data = path.read_bytes()
    path.write_bytes(data[:len(data) // 2])
    out = tmp_path / "out"
    for argv in (["trust", path, "--out", out, *FAST],
                 ["reduce", path, "--method", "poly2", "--out", out / "r.json", "--quiet"]):
        code, _, err = cli(*argv)
        bad.assert_one_line(code, err, str(path), "truncated", "smaller than the expected size")
    assert not out.exists()


@pytest.mark.parametrize("depth", ["300000", "100000", "1e308"])
def test_a_depth_beyond_what_a_fit_returns_is_one_line(depth, tmp_path, cli, bad):
    """Before: --depth 300000 gave exit 0 with a bias of -200000 ppm and an SD of 0 (every twin's
    fit stopped on the bound), 1e308 eleven lines naming pointing.a_fbm_px."""
    path = _trust_table(tmp_path / "t.fits", bad)
    out = tmp_path / "out"
    code, _, err = cli("trust", path, "--out", out, "--depth", depth, *FAST)
    bad.assert_one_line(code, err, "--depth", "100000 ppm")
    assert not out.exists()


@pytest.mark.parametrize("event", ["eclipse", "phase-curve", "transit"])
def test_the_depth_limit_is_the_fit_s_bound(event):
    import numpy as np

    from eclipsebench.astro.catalogue import get_system
    from eclipsebench.fit.model import AstroModel, depth_limit_ppm

    phase = "harmonic1" if event == "phase-curve" else "flat"
    model = AstroModel(57000.0 + np.arange(200) / 500.0, get_system("XO-3b"), phase=phase,
                       event=event)
    size_limit = model.bounds[1][model.names.index("rp_rs" if event == "transit" else "depth")]
    assert model.depth_ppm(size_limit) == pytest.approx(depth_limit_ppm(event), rel=1e-12)


# ----------------------------------------------------------------------------- list options
@pytest.mark.parametrize("override,key", [
    ("reduce.beta_bin_minutes=[1.0, inf]", "reduce.beta_bin_minutes"),
    ("reduce.beta_bin_minutes=[nan, 30.0]", "reduce.beta_bin_minutes"),
    ("photometry.variable_apertures=[[1.0, inf]]", "photometry.variable_apertures[0]"),
    ("photometry.variable_apertures=[[1.0, nan]]", "photometry.variable_apertures[0]"),
])
def test_a_list_option_with_an_infinite_or_nan_item_is_one_line(override, key, tmp_path, cli,
                                                                  bad):
    """Before: beta_bin_minutes = [1.0, inf] was accepted, with two warnings and another
    beta_red; a variable aperture's b of inf or nan reached the photometry."""
    code, _, err = cli("config", "--set", override)
    bad.assert_one_line(code, err, key, "finite")
    out = tmp_path / "run"
    code, _, err = cli("run", "--set", override, "--out", out, "--quiet")
    bad.assert_one_line(code, err, key, "finite")
    assert not out.exists()


def test_a_method_option_list_with_nan_is_refused():
    from eclipsebench.decorrelate import get_method
    from eclipsebench.decorrelate.base import parse_method_options
    from eclipsebench.errors import InputError

    with pytest.raises(InputError, match="hyperparameters.*item 4 is nan.*finite"):
        parse_method_options(get_method("gp"), {"hyperparameters": [1, 2, 3, 4, float("nan")]})
    with pytest.raises(InputError, match="segment_fractions.*finite"):
        parse_method_options(get_method("segpoly"), {"segment_fractions": [0.5, float("inf")]})


# ----------------------------------------------------------------------------- drawn names
def test_a_planet_name_with_a_dollar_is_drawn_literally(tmp_path, cli):
    """Before: lightcurve --plot for a planet named XO$-3_$b crashed in matplotlib's math text
    (exit 1: "ParseSyntaxException")."""
    planet = {"name": "XO$-3_$b", "period_days": 3.1915239, "t_transit_bjd": 2454449.86816,
              "ecc": 0.2769, "omega_deg": 347.2, "inc_deg": 84.2, "a_rs": 7.07, "rp_rs": 0.0905,
              "teff_star_k": 6781.0, "r_star_rsun": 1.377}
    args = [a for k, v in planet.items() for a in ("--planet", f"{k}={v}")]
    plot = tmp_path / "lc.png"
    code, out, err = cli("lightcurve", *args, "--hours", "2", "--plot", plot, "--json")
    assert code == 0, err
    assert plot.stat().st_size > 0 and "XO$-3_$b" in out


def test_literal_text_draws_the_dollar():
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.cbook import is_math_text
    from matplotlib.figure import Figure

    from eclipsebench.fit.result.plot import literal_text

    for name in ("XO-3$b$", "X$O\\x$b", "a $x$ and $y$"):
        assert is_math_text(name) and not is_math_text(literal_text(name))
        fig = Figure()
        FigureCanvasAgg(fig)
        fig.add_subplot(1, 1, 1).set_title(literal_text(name))
        fig.canvas.draw()   # math text would raise on X$O\x$b
