"""Another pipeline's table of real epoch 1 with its times as JD_UTC at Spitzer: converted to
BMJD_TDB (``astro/timescales.py``), its mid-eclipse time equals the BMJD_TDB table's."""

from __future__ import annotations

import json

import numpy as np
import pytest
from astropy.table import Table

from eclipsebench.cli import main
from eclipsebench.photometry.table import read_photometry

from ..conftest import real_epoch1_jd_utc

pytestmark = pytest.mark.shared_data

COLUMNS = ("flux", "flux_err", "x", "y")


@pytest.fixture(scope="module")
def tables(real_epoch1_table, shared_irac, tmp_path_factory):
    full = read_photometry(real_epoch1_table)
    good = np.asarray(full["flag"]) == 0
    root = tmp_path_factory.mktemp("jd_utc")
    jd, observer = real_epoch1_jd_utc(full, shared_irac)
    bmjd = Table({"time_bmjd": np.asarray(full["time_bmjd"])[good],
                  **{c: np.asarray(full[c])[good] for c in COLUMNS}})
    jd_table = Table({"JD_UTC": jd[good], **{c: np.asarray(full[c])[good] for c in COLUMNS}})
    bmjd.write(root / "bmjd.csv", format="ascii.csv")
    jd_table.write(root / "jd.csv", format="ascii.csv")
    return root, observer


def _reduce(path, out, *extra):
    assert main(["reduce", str(path), "--method", "poly2", "--sampler", "leastsq",
                 "--system", "XO-3b", "--out", str(out), *extra]) == 0
    return json.loads(out.read_text())


def test_a_jd_utc_table_gives_the_bmjd_tables_mid_time(tables, capsys):
    root, observer = tables
    plain = _reduce(root / "bmjd.csv", root / "bmjd.json")
    jd = _reduce(root / "jd.csv", root / "jd.json", "--time-column", "JD_UTC", "--time-format",
                 "jd", "--time-scale", "utc", "--observer", observer)
    assert abs(jd["t_ecl_bmjd"] - plain["t_ecl_bmjd"]) * 86400.0 < 2.0
    assert jd["depth_ppm"] == pytest.approx(plain["depth_ppm"], abs=1.0)
    assert "JD_UTC" in jd["time_conversion"] and "spacecraft" in jd["time_conversion"]
    assert "time_conversion" not in plain
    assert "times         JD_UTC: JD_UTC at frame mid" in capsys.readouterr().out


@pytest.mark.parametrize("extra, words", [
    (["--time-scale", "utc"], "need --observer X,Y,Z,MJD"),
    (["--observer", "geocentre"], "need their scale: give --time-scale"),
])
def test_times_at_the_observer_without_what_they_need_are_refused(tables, capsys, extra, words):
    root, _ = tables
    out = root / "refused.json"
    code = main(["reduce", str(root / "jd.csv"), "--method", "poly2", "--system", "XO-3b",
                 "--out", str(out), "--time-column", "JD_UTC", "--time-format", "jd", *extra])
    err = capsys.readouterr().err
    assert code == 2 and words in err and err.count("\n") == 1 and not out.exists(), err


def test_an_unknown_time_scale_is_a_usage_error(tables, capsys):
    root, _ = tables
    with pytest.raises(SystemExit) as stop:
        main(["reduce", str(root / "jd.csv"), "--method", "poly2", "--time-format", "jd",
              "--time-scale", "gps", "--out", str(root / "gps.json")])
    assert stop.value.code == 2 and "--time-scale" in capsys.readouterr().err
    assert not (root / "gps.json").exists()
