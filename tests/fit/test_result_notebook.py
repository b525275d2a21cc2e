"""Results as notebook objects (issue 29): repr, HTML, plot, QTable, read back from files.

The real epoch 1 (``../shared/data/irac/real_xo3_eclipse1``) measured once per
test run, reduced with PLD as the issue's acceptance does it.
"""

from __future__ import annotations

import json
import math
import warnings

import astropy.units as u
import numpy as np
import pytest
from astropy.table import QTable, Table
from astropy.time import Time

import eclipsebench as eb
from eclipsebench.cli import main
from eclipsebench.fit.result.display import html_repr, text_repr

pytestmark = pytest.mark.shared_data


@pytest.fixture(scope="module")
def table_path(real_epoch1_table):
    """``eb.measure`` of real epoch 1 (built-in settings), once per test run (tests/conftest.py)."""
    return real_epoch1_table


@pytest.fixture(scope="module")
def pld(table_path):
    return eb.reduce(eb.read_photometry(table_path), "pld", system="XO-3b")


def test_repr_is_short_and_the_html_names_depth_and_error(pld):
    text = repr(pld)
    assert len(text.splitlines()) == 2 and len(text) < 400   # was a 1.5-2 kB single line
    assert text.startswith("EpochResult: pld, epoch 1, XO-3b, controlled profile")
    page = pld._repr_html_()
    assert len(page.encode()) < 2000
    assert f"{pld.depth_ppm:.1f} ± {pld.depth_err_ppm:.1f} ppm" in page
    for word in ("beta_red", "chi2_red", "rms", "227 bins of 14525 frames"):
        assert word in page


def test_plot_gives_figures(pld):
    from matplotlib.figure import Figure

    fig = pld.plot()
    assert isinstance(fig, Figure) and len(fig.axes) == 2
    assert "controlled profile" in fig.axes[0].get_title()
    corner = pld.plot(kind="corner")
    assert len(corner.axes) == len(pld.chain["names"]) ** 2
    with pytest.raises(eb.InputError, match="kind 'x'"):
        pld.plot(kind="x")


def test_to_table_is_a_qtable_with_units_and_tdb_time(pld, table_path):
    t = pld.to_table()
    assert isinstance(t, QTable) and isinstance(t["time"], Time)
    assert t["time"].scale == "tdb" and t["time"].format == "mjd"
    assert t["flux_corrected"].unit == u.dimensionless_unscaled
    assert {"flux_err", "systematics_model", "astro_model", "residual"} <= set(t.colnames)
    assert np.median(t["systematics_model"].value) == pytest.approx(1.0)
    assert np.all(t["flux_err"].value > 0)
    phot = eb.read_photometry(table_path)   # the relative error of the table's fluxes
    relative = np.median(phot["flux_err"].value / phot["flux"].value)
    assert np.median(t["flux_err"].value) == pytest.approx(relative, rel=0.05)


def test_bic_reports_its_points(pld):
    d = pld.to_dict()
    assert d["n_points"] == d["n_frames"] == 14525   # the light curve's points, as before
    assert d["bic_n_points"] == 227                  # PLD's likelihood is over its bins
    assert d["bic_data"] == "227 bins of 14525 frames"
    assert d["eclipsebench_version"] == eb.__version__


def test_read_result_equals_the_result_written_by_reduce(pld, table_path, tmp_path, capsys):
    out = tmp_path / "r.json"
    assert main(["reduce", str(table_path), "--method", "pld", "--system", "XO-3b",
                 "--out", str(out)]) == 0
    assert "comparable only with fits of the same points" in capsys.readouterr().out
    back = eb.read_result(out)
    assert back == pld   # every compared field
    for name, values in pld.lightcurve.items():
        np.testing.assert_array_equal(back.lightcurve[name], values)
    np.testing.assert_array_equal(back.chain["samples"], pld.chain["samples"])
    assert list(back.chain["names"]) == list(pld.chain["names"])
    written = json.loads(out.read_text())
    assert {k: v for k, v in back.to_dict().items() if k in written} == {
        k: v for k, v in written.items() if k in back.to_dict()}
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        lc = Table.read(tmp_path / "r.lc.ecsv")   # no warning
    assert lc["time_bmjd"].unit == u.day and lc.meta["TIMESYS"] == "TDB"
    assert {"flux_err", "systematics_model"} <= set(lc.colnames)
    assert lc["flux_corrected"].description


def test_read_result_refuses_bad_files_in_one_line(tmp_path):
    missing = tmp_path / "none.json"
    with pytest.raises(eb.InputError, match=f"{missing}: no such result file"):
        eb.read_result(missing)
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    with pytest.raises(eb.InputError, match="bad.json: not a result file"):
        eb.read_result(bad)
    failed = tmp_path / "failed.json"
    failed.write_text(json.dumps({"method": "pld", "epoch": 1, "failed": True,
                                  "error": "no frames", "depth_ppm": None}))
    with pytest.raises(eb.InputError, match="failed.json: a failed reduction"):
        eb.read_result(failed)


def test_repr_helpers_take_a_dict_of_fields():
    fields = {"method": "pld", "epoch": 2, "system": "XO-3b", "profile": "paper",
              "depth_ppm": 1800.04, "depth_err_ppm": 50.0, "rms_ppm": 4000.0,
              "beta_red": math.nan}
    assert text_repr("TrustResult", fields) == (
        "TrustResult: pld, epoch 2, XO-3b, paper profile\n"
        "  depth 1800.0 ± 50.0 ppm | rms 4000.0 ppm | beta_red n/a")
    assert "<b>depth 1800.0 ± 50.0 ppm</b>" in html_repr("TrustResult", fields)
