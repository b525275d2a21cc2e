"""Issue 36 points 3, 5, 6: twins of another pipeline's table, the mid-time, the ranking.

Another pipeline's table (time, flux in any unit, flux_err, x, y) is completed by inference
(``trust/observation.py::complete_table``) and twinned; methods that need stamps are skipped;
the answer puts the line to quote first, says whether the twins rank the methods and how
often each would be recommended, and scores the mid-eclipse time.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from astropy.table import Table

from eclipsebench.cli import main
from eclipsebench.photometry.table import read_photometry, read_table
from eclipsebench.trust.observation import (
    OBSERVATION_FILE,
    complete_table,
    flux_scale_from_scatter,
)
from eclipsebench.trust.run import trust_settings

from ..conftest import real_epoch1_jd_utc

FAST = ["--sampler", "leastsq", "--twins", "10", "--quiet", "--system", "XO-3b", "--workers", "1"]
UNIT = 1.0 / 3737.0     # electrons to an arbitrary unit


def _foreign(table, rows=None) -> Table:
    """Only time_bmjd, flux, flux_err, x, y of the good frames, the flux in arbitrary units."""
    good = np.flatnonzero(np.asarray(table["flag"]) == 0)
    good = good if rows is None else good[:rows]
    return Table({"time_bmjd": np.asarray(table["time_bmjd"])[good],
                  "flux": np.asarray(table["flux"])[good] * UNIT,
                  "flux_err": np.asarray(table["flux_err"])[good] * UNIT,
                  "x": np.asarray(table["x"])[good], "y": np.asarray(table["y"])[good]})


@pytest.fixture(scope="module")
def small(tmp_path_factory, small_observation_table):
    root = tmp_path_factory.mktemp("any_table")
    full = read_table(small_observation_table)
    _foreign(full).write(root / "other.csv", format="ascii.csv")
    return root, full


def test_the_flux_scale_and_the_cubes_are_inferred(small):
    root, full = small
    done, inferred = complete_table(_foreign(full), "other.csv")
    good = np.asarray(full["flag"]) == 0
    truth = float(np.median(np.asarray(full["flux"])[good]))
    assert np.median(done["flux"]) == pytest.approx(truth, rel=0.15), inferred["flux_scale"]
    assert inferred["readout"].startswith("sub_2s (from the cadence")
    assert inferred["channel"].startswith("2 (assumed")
    # the cubes: 16-frame cubes with gaps between them, found from the gaps (a frame missing
    # inside a cube, here one cosmic ray, splits it: 82 found for 81)
    n_cubes = len({(a, e) for a, e in zip(full["aorkey"][good], full["expid"][good],
                                          strict=True)})
    found = len({(a, e) for a, e in zip(done["aorkey"], done["expid"], strict=True)})
    assert n_cubes <= found <= 1.02 * n_cubes
    assert len(set(done["aorkey"])) == len(set(full["aorkey"][good]))
    with pytest.raises(ValueError, match="no frame-to-frame scatter"):
        flux_scale_from_scatter(np.ones(200), aperture_px2=16.0, read_noise_e=10.0)


def test_another_pipelines_table_is_twinned_with_pixel_methods_skipped(small, capsys):
    root, _ = small
    out = root / "trust_other"
    assert main(["trust", str(root / "other.csv"), "--out", str(out),
                 "--methods", "poly2,pld,ica"] + FAST) == 0
    summary = json.loads((out / "trust.json").read_text())
    assert set(summary["skipped"]) == {"pld", "ica"} and set(summary["methods"]) == {"poly2"}
    assert summary["source_table"] == str(root / "other.csv")
    assert summary["table"] == str((out / OBSERVATION_FILE).resolve())
    assert {"flux_scale", "readout", "cubes", "background", "noise_pixels"} <= set(
        summary["inferred"])
    # the line to quote first, the ranking, the bootstrap frequencies, the mid-time
    assert summary["quote"]["method"] == summary["recommended"]
    s = summary["methods"]["poly2"]
    if summary["recommended"]:
        assert summary["quote"]["text"].startswith("poly2: depth")
    assert sum(summary["recommended_frequency"].values()) == pytest.approx(1.0)
    assert 0 <= s["recommended_frequency"] <= 1 and "text" in summary["ranking"]
    assert s["t_n_twins"] == 10 and s["t_rmse_s"] > 0 and s["t_honest_err_s"] >= s["t_err_s"]
    ecsv = Table.read(out / "trust.ecsv", format="ascii.ecsv")
    assert "recommended_frequency" in ecsv.colnames and ecsv["t_rmse_s"].unit == "s"
    page = (out / "report" / "index.html").read_text()
    assert "Quote:" in page and "recommended in (%)" in page and "mid-eclipse time" in page
    assert "Inferred" in page
    # no noise pixels: the motion within an exposure is what the real residuals allow
    bound = summary["twins"]["motion_bound"]
    assert bound["photometry_only"] and len(bound["steps"]) > 1
    assert "the most whose pilot twin is no redder" in page
    text = capsys.readouterr().out
    assert text.startswith("quote ") and "\nranking " in text and "inferred      flux_scale" in text
    assert "twins' PSF    the committed PSF (no noise pixels in the table)" in text
    # the same command resumes; another table into the same folder is refused
    assert main(["trust", str(root / "other.csv"), "--out", str(out),
                 "--methods", "poly2,pld,ica"] + FAST) == 0
    other = read_table(root / "other.csv")
    other["flux"] *= 1.0 + 0.5 * (np.arange(len(other)) % 2)     # another table
    other.write(root / "other2.csv", format="ascii.csv")
    capsys.readouterr()
    assert main(["trust", str(root / "other2.csv"), "--out", str(out),
                 "--methods", "poly2,pld,ica"] + FAST) == 2
    assert "another table" in capsys.readouterr().err


@pytest.mark.parametrize("make, words", [
    (lambda t: t.__setitem__("flux", np.full(len(t), 5.0)), "no frame-to-frame scatter"),
    (lambda t: t.remove_rows(slice(90, None)), "90 good frames"),
    (lambda t: t.__setitem__("time_bmjd", t["time_bmjd"] + 2400000.5), "full Julian dates"),
])
def test_a_table_that_cannot_be_twinned_is_one_line_and_nothing_written(small, tmp_path,
                                                                        capsys, make, words):
    _, full = small
    table = _foreign(full)
    make(table)
    table.write(tmp_path / "bad.csv", format="ascii.csv")
    out = tmp_path / "trust"
    assert main(["trust", str(tmp_path / "bad.csv"), "--out", str(out),
                 "--methods", "poly2"] + FAST) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and words in err, err
    assert str(tmp_path / "bad.csv") in err or "--time-format" in err, err
    assert not out.exists()


def test_an_unknown_time_scale_or_a_missing_observer_writes_nothing(small, tmp_path, capsys):
    root, _ = small
    out = tmp_path / "trust"
    with pytest.raises(SystemExit) as stop:
        main(["trust", str(root / "other.csv"), "--out", str(out), "--time-format", "mjd",
              "--time-scale", "gps"] + FAST)
    assert stop.value.code == 2 and "--time-scale" in capsys.readouterr().err
    assert main(["trust", str(root / "other.csv"), "--out", str(out), "--time-format", "mjd",
                 "--time-scale", "utc"] + FAST) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--observer" in err and not out.exists(), err


@pytest.mark.shared_data
def test_a_jd_utc_table_of_real_epoch1_is_twinned_at_the_bmjd_tables_times(
        real_epoch1_table, shared_irac, tmp_path):
    """The completed observations of the same frames given as BMJD_TDB and as JD_UTC at
    Spitzer (each cube's MJD_OBS from the archive) hold the same times within 0.2 s."""
    full = read_photometry(real_epoch1_table)
    plain = _foreign(full)
    plain.write(tmp_path / "bmjd.csv", format="ascii.csv")
    jd, observer = real_epoch1_jd_utc(full, shared_irac)
    as_jd = plain.copy()
    as_jd["time_bmjd"] = jd[np.asarray(full["flag"]) == 0]
    as_jd.rename_column("time_bmjd", "JD_UTC")
    as_jd.write(tmp_path / "jd.csv", format="ascii.csv")
    from eclipsebench.config.reduce import ReduceSection

    common = {"reduce": ReduceSection(sampler="leastsq"), "system": "XO-3b", "n_twins": 10,
              "methods": ["bliss"]}
    a = trust_settings(tmp_path / "bmjd.csv", tmp_path / "a", **common)
    b = trust_settings(tmp_path / "jd.csv", tmp_path / "b", time_column="JD_UTC",
                       time_format="jd", time_options={"time_scale": "utc",
                                                       "observer": observer}, **common)
    ta, tb = read_table(a.table), read_table(b.table)
    assert np.abs(np.asarray(ta["time_bmjd"]) - np.asarray(tb["time_bmjd"])).max() * 86400 < 0.2
    assert "JD_UTC" in tb.meta["TIMECONV"] and "TIMECONV" not in ta.meta
