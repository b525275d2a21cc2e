"""Table round trip, binning, AOR/epoch grouping, simulated inputs (EPOCH, SIMDIR), CLI outputs."""

from __future__ import annotations

import json

import numpy as np
import pytest
from astropy.table import Table

from eclipsebench.cli import main
from eclipsebench.config.photometry import PhotometrySection
from eclipsebench.errors import InputError
from eclipsebench.io.bcd_read import find_bcd_files, group_epochs, read_bcd_header
from eclipsebench.photometry.binning import bin_indices, bin_table, bin_values
from eclipsebench.photometry.pipeline import photometry_tables
from eclipsebench.photometry.table import read_photometry, write_photometry


def test_bin_values_weighted_means_by_hand():
    v = np.array([1.0, 2.0, 4.0, 10.0, 20.0])
    w = np.array([1.0, 1.0, 2.0, 1.0, 3.0])
    bins = bin_indices(np.arange(5.0), n_frames=3)
    assert list(bins) == [0, 0, 0, 1, 1]
    means, wsum = bin_values(v, bins, w)
    assert means == pytest.approx([(1 + 2 + 8) / 4, (10 + 60) / 4])
    assert wsum == pytest.approx([4.0, 4.0])
    stamps = np.arange(5 * 4.0).reshape(5, 2, 2)
    m2, _ = bin_values(stamps, bins)
    assert m2[1] == pytest.approx((stamps[3] + stamps[4]) / 2)


def test_bin_indices_by_time_width_skip_empty_bins():
    t = np.array([0.0, 0.1, 0.25, 0.9, 0.95, 2.0])
    assert list(bin_indices(t, width_days=0.2)) == [0, 0, 1, 2, 2, 3]
    with pytest.raises(ValueError):
        bin_indices(t, n_frames=2, width_days=0.1)


def test_bin_table_uses_good_frames_and_inverse_variance():
    t = Table({"time_bmjd": np.arange(6.0), "flux": [1.0, 3.0, 100.0, 5.0, 7.0, 9.0],
               "flux_err": [1.0, 1.0, 1.0, 1.0, 2.0, 2.0], "x": np.arange(6.0),
               "aorkey": np.full(6, 7), "flag": [0, 0, 4, 0, 0, 0]})
    b = bin_table(t, n_frames=2)
    assert list(b["n_frames"]) == [2, 2, 1]
    assert b["flux"][0] == pytest.approx(2.0)
    assert b["flux"][1] == pytest.approx((5.0 / 1 + 7.0 / 4) / (1 + 0.25))
    assert b["flux_err"][1] == pytest.approx(1 / np.sqrt(1.25))
    assert "aorkey" not in b.colnames and "flag" not in b.colnames


def _write_aor(folder, make_bcd, make_star_cube, *, aorkey, n_cubes, start_bmjd, seed, **extra):
    for k in range(n_cubes):
        cube, _, _ = make_star_cube(8, seed=seed + k)
        make_bcd(folder, cube, aorkey=aorkey, expid=k, bmjd=start_bmjd + k * 20.0 / 86400,
                 **extra)


def test_aors_within_a_day_form_one_epoch(tmp_path, make_bcd, make_star_cube):
    _write_aor(tmp_path / "r1" / "ch2" / "bcd", make_bcd, make_star_cube, aorkey=1, n_cubes=2,
               start_bmjd=57000.0, seed=1)
    _write_aor(tmp_path / "r2" / "ch2" / "bcd", make_bcd, make_star_cube, aorkey=2, n_cubes=3,
               start_bmjd=57000.03, seed=5)
    _write_aor(tmp_path / "r3" / "ch2" / "bcd", make_bcd, make_star_cube, aorkey=3, n_cubes=2,
               start_bmjd=57003.0, seed=9)
    infos = [read_bcd_header(p) for p in find_bcd_files(tmp_path)]
    epochs = group_epochs(infos)
    assert [e.aorkeys for e in epochs] == [(1, 2), (3,)]
    assert [e.number for e in epochs] == [1, 2]
    # no gap splits: every AOR one epoch (a campaign's epoch of real Pre and Main AORs;
    # it raised KeyError: 0, the first AOR opening no epoch when the gap is infinite)
    whole = group_epochs(infos, gap_days=float("inf"))
    assert [e.aorkeys for e in whole] == [(1, 2, 3)] and whole[0].number == 1
    out = tmp_path / "out"
    assert main(["photometry", str(tmp_path), "--out", str(out), "--quiet"]) == 0
    t1 = read_photometry(out / "epoch_01.fits")
    t2 = read_photometry(out / "epoch_02.fits")
    assert len(t1) == 5 * 8 and len(t2) == 2 * 8
    assert set(np.unique(t1["aorkey"])) == {1, 2}
    assert np.all(np.diff(np.asarray(t1["time_bmjd"])) > 0)
    # several epochs cannot go to one file
    assert main(["photometry", str(tmp_path), "--out", str(tmp_path / "one.fits"),
                 "--quiet"]) == 2


def test_simulated_inputs_use_epoch_headers_and_record_simdir(tmp_path, make_bcd, make_star_cube,
                                                              capsys):
    sim = tmp_path / "challenge"
    (sim / "calibration").mkdir(parents=True)
    (sim / "truth.ecsv").write_text("# marks the simulation root for the folder walk\n")
    # two AORs 5 days apart but labelled as one epoch, and one AOR of epoch 2 the same day
    _write_aor(sim / "r10" / "ch2" / "bcd", make_bcd, make_star_cube, aorkey=10, n_cubes=1,
               start_bmjd=57000.0, seed=1, SIMULATE=True, EPOCH=1)
    _write_aor(sim / "r11" / "ch2" / "bcd", make_bcd, make_star_cube, aorkey=11, n_cubes=1,
               start_bmjd=57005.0, seed=2, SIMULATE=True, EPOCH=1)
    _write_aor(sim / "r12" / "ch2" / "bcd", make_bcd, make_star_cube, aorkey=12, n_cubes=1,
               start_bmjd=57005.01, seed=3, SIMULATE=True, EPOCH=2)
    out = tmp_path / "phot"
    assert main(["photometry", str(sim / "r10" / ".."), "--out", str(out), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert [e["aorkeys"] for e in summary["epochs"]] == [[10, 11], [12]]
    assert summary["frames"] == 24 and summary["flagged"]["first_frame"] == 3
    t = read_photometry(out / "epoch_01.fits")
    assert t.meta["SIMDIR"] == str(sim.resolve())
    assert t.meta["EPOCH"] == 1 and t.meta["SIMULATE"]
    # simulated BMJD_OBS is already TDB: no UTC->TDB shift
    assert t["time_bmjd"][0] == pytest.approx(57000.0 + 1.005 / 86400, abs=1e-9)


def test_mixed_epoch_headers_are_refused(tmp_path, make_bcd, make_star_cube):
    _write_aor(tmp_path, make_bcd, make_star_cube, aorkey=1, n_cubes=1, start_bmjd=57000.0,
               seed=1, EPOCH=1)
    _write_aor(tmp_path, make_bcd, make_star_cube, aorkey=2, n_cubes=1, start_bmjd=57000.1,
               seed=2)
    with pytest.raises(InputError, match="EPOCH"):
        list(photometry_tables(tmp_path, PhotometrySection()))


def test_table_round_trip_keeps_units_shapes_and_metadata(tmp_path, make_bcd, make_star_cube):
    _write_aor(tmp_path / "in", make_bcd, make_star_cube, aorkey=5, n_cubes=2, start_bmjd=57000.0,
               seed=4)
    opt = PhotometrySection(centroid="gauss-fixed", variable_apertures=((1.0, 0.0), (0.8, 0.5)))
    (_, table), = photometry_tables(tmp_path / "in", opt)
    path = write_photometry(table, tmp_path / "t.fits")
    back = read_photometry(path)
    assert back.colnames == table.colnames
    assert back["stamp3"].shape == (16, 3, 3) and back["stamp5"].shape == (16, 5, 5)
    assert str(back["flux"].unit) == "electron" and str(back["x"].unit) == "pix"
    assert str(back["background"].unit) == "electron / pix2"
    assert back.meta["OPTIONS"]["centroid"] == "gauss-fixed"
    assert back.meta["INPUTS"] == ["SPITZER_I2_5_0000_0000_1_bcd.fits",
                                   "SPITZER_I2_5_0001_0000_1_bcd.fits"]
    assert back.meta["EB_VERSION"]
    for name in ("x", "flux", "flux_err", "x_gfix", "flux_va0p80b0p50", "radius_va0p80b0p50"):
        np.testing.assert_array_equal(np.asarray(back[name]), np.asarray(table[name]))
    assert np.array_equal(back["x"], back["x_gfix"])
    assert not list(tmp_path.glob(".t.fits.*"))  # no temporary left behind


def test_cli_radius_and_radii_options(tmp_path, make_bcd, make_star_cube):
    _write_aor(tmp_path / "in", make_bcd, make_star_cube, aorkey=5, n_cubes=1, start_bmjd=57000.0,
               seed=4)
    out = tmp_path / "t.fits"
    assert main(["photometry", str(tmp_path / "in"), "--out", str(out), "--radius", "3.1",
                 "--radii", "2", "3", "--centroid", "gauss", "--quiet",
                 "--set", "photometry.background=median"]) == 0
    t = read_photometry(out)
    assert {"flux_r2p00", "flux_r3p00"} <= set(t.colnames)
    assert "flux_r2p25" not in t.colnames
    assert np.array_equal(t["background"], t["background_median"])
    assert t.meta["RADIUS"] == 3.1
    assert np.all(t["flux"][1:] > t["flux_r3p00"][1:])


def test_full_array_frames_are_cut_about_the_star_and_reported_in_detector_pixels(
        tmp_path, gaussian_prf):
    from astropy.io import fits

    e_per_mjysr = 3.71 * 10.4 / 0.1253
    for k, (x, y) in enumerate([(100.3, 140.7), (100.35, 140.62), (100.28, 140.75)]):
        img = gaussian_prf(x, y, 0.6, 5e4, shape=(256, 256)) + 20.0
        h = fits.Header()
        h.update({"CHNLNUM": 2, "BMJD_OBS": 57000.0 + k * 14 / 86400, "FRAMTIME": 12.0,
                  "EXPTIME": 10.4, "SAMPTIME": 0.2, "GAIN": 3.71, "FLUXCONV": 0.1253,
                  "BUNIT": "MJy/sr", "READMODE": "FULL", "AORKEY": 777, "EXPID": k,
                  "DCENUM": 0, "AFOWLNUM": 8, "AWAITPER": 44, "RONOISE": 9.4})
        path = tmp_path / f"SPITZER_I2_777_{k:04d}_0000_1_bcd.fits"
        fits.PrimaryHDU((img / e_per_mjysr).astype(np.float32), header=h).writeto(path)
    (_, table), = photometry_tables(tmp_path, PhotometrySection(centroid="gauss"))
    assert len(table) == 3 and np.all(table["flag"] == 0)  # no first-frame flag for full array
    assert table["x"][0] == pytest.approx(100.3, abs=0.01)
    assert table["y"][0] == pytest.approx(140.7, abs=0.01)
    assert np.all(table["stamp_x"] == 100) and np.all(table["stamp_y"] == 141)
    assert table["flux_r4p00"][0] == pytest.approx(5e4, rel=2e-3)
    # mid-exposure of a full-array frame: (2 FN + WT + 1) / 2 x 0.2 s = 6.1 s after the start
    from astropy.time import Time
    expected = Time(57000.0 + 6.1 / 86400, format="mjd", scale="utc").tdb.mjd
    assert table["time_bmjd"][0] == pytest.approx(expected, abs=1e-8)
