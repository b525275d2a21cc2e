"""End to end on a tiny challenge: bytes, seeds, resume, truth, CLI errors."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np
import pytest
from astropy.io import fits
from astropy.table import Table

from eclipsebench.cli import main
from eclipsebench.config import load_config
from eclipsebench.simulation.challenge import simulate_challenge

TINY = ["challenge.epochs=1", "observation.pre_cubes=1", "observation.main_cubes=2",
        "simulation.calibration_frames=600"]


def _hashes(root: Path) -> dict[str, str]:
    return {p.relative_to(root).as_posix(): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(root.rglob("*")) if p.is_file()}


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    base = tmp_path_factory.mktemp("sim")
    out = {}
    for name, seed, workers in (("a", 7, 1), ("b", 7, 2), ("c", 8, 1)):
        cfg = load_config(None, TINY + [f"challenge.seed={seed}"])
        res = simulate_challenge(cfg, base / name, workers=workers)
        out[name] = (base / name, res)
    return out


def test_same_seed_same_bytes_different_seed_different_data(runs):
    """Run b used two worker processes, run a one: the bytes must not care."""
    (a, ra), (b, _), (c, _) = runs["a"], runs["b"], runs["c"]
    ha, hb, hc = _hashes(a), _hashes(b), _hashes(c)
    assert ha == hb
    cubes = [k for k in ha if k.endswith("_bcd.fits")]
    assert len(cubes) == 3 and ra.files == 6
    assert all(ha[k] != hc[k] for k in cubes)
    assert ha["truth.ecsv"] != hc["truth.ecsv"]
    assert ha["calibration/pmap_calibration.fits"] != hc["calibration/pmap_calibration.fits"]


def test_truth_lightcurves_and_headers_agree(runs):
    root, res = runs["a"]
    truth = Table.read(root / "truth.ecsv")
    for col in ("epoch", "aorkey_pre", "aorkey_main", "start_bmjd", "t_ecl_bmjd", "depth_ppm",
                "x_mean", "x_sd", "y_mean", "y_sd", "xy_cov", "seed", "noise_model",
                "ptg_a_sd_px", "ptg_tau_sd_s"):
        assert col in truth.colnames, col
    row = truth[0]
    assert row["aorkey_pre"] == 20150000 and row["aorkey_main"] == 20150001
    assert row["depth_ppm"] == pytest.approx(1875.0) and row["seed"] == 7
    lc = Table.read(root / "lightcurves" / "epoch_01.ecsv")
    assert len(lc) == 3 * 64
    assert row["x_sd"] == pytest.approx(np.std(lc["x_true"]))
    assert row["xy_cov"] == pytest.approx(np.mean((lc["x_true"] - lc["x_true"].mean())
                                                  * (lc["y_true"] - lc["y_true"].mean())))
    main_rows = lc[lc["aorkey"] == 20150001]
    with fits.open(root / "r20150001/ch2/bcd/SPITZER_I2_20150001_0001_0000_1_bcd.fits") as h:
        hdr = h[0].header
        data = h[0].data
    assert hdr["SIMULATE"] is True and hdr["NOISEMOD"] == "physical" and hdr["EXPID"] == 1
    x5, y5 = (float(v) for v in hdr["XYMEAN05"].strip("()").split(","))
    sel = main_rows[(main_rows["expid"] == 1) & (main_rows["frame"] == 4)]
    assert x5 == pytest.approx(sel["x_true"][0], abs=1e-4)
    assert y5 == pytest.approx(sel["y_true"][0], abs=1e-4)
    # the star is where the header says: brightest pixel is the nearest one
    j, i = np.unravel_index(np.argmax(data[4]), data[4].shape)
    assert (i, j) == (round(x5), round(y5))
    assert data.dtype == np.dtype(">f4") and data.shape == (64, 32, 32)
    # BMJD_OBS of the main AOR's cube 1: start + Pre AOR + gap + one cube interval
    start = row["start_bmjd"]
    assert hdr["BMJD_OBS"] == pytest.approx(start + (64 * 2.008 + 300.0 + 129.4) / 86400,
                                            abs=2e-7)
    cal = Table.read(root / "calibration" / "pmap_calibration.fits")
    assert len(cal) == 600 and set(("x", "y", "noise_pixels", "flux", "flux_err")) <= set(
        cal.colnames)
    assert np.all(np.abs(cal["x"] - 15.0) < 0.6) and np.all(cal["flux_err"] > 0)


def test_config_toml_is_the_effective_configuration(runs):
    root, _ = runs["c"]
    assert load_config(root / "config.toml") == load_config(None, TINY + ["challenge.seed=8"])


def test_rerun_resumes_and_regenerates_identical_files(runs, tmp_path):
    root, _ = runs["a"]
    cfg = load_config(None, TINY + ["challenge.seed=7"])
    before = _hashes(root)
    res = simulate_challenge(cfg, root, workers=1)
    assert res.skipped_aors == 2 and _hashes(root) == before
    # lose one cube and the epoch marker: only that AOR is redone, with the same bytes
    cube = root / "r20150001/ch2/bcd/SPITZER_I2_20150001_0000_0000_1_bcd.fits"
    cube.unlink()
    (root / ".simstate" / "epoch_01.json").unlink()
    res = simulate_challenge(cfg, root, workers=1)
    assert res.skipped_aors == 1 and _hashes(root) == before


def test_rerun_with_another_configuration_is_refused(runs, capsys):
    root, _ = runs["c"]
    args = ["simulate", "--out", str(root), "--seed", "9", "--no-calibration"]
    for s in TINY:
        args += ["--set", s]
    assert main(args) == 2
    assert "different configuration" in capsys.readouterr().err


def test_cli_json_summary_and_bad_values(tmp_path, capsys):
    args = ["simulate", "--out", str(tmp_path / "x"), "--epochs", "1", "--json", "--seed", "3",
            "--no-calibration"]
    for s in TINY[1:3]:
        args += ["--set", s]
    assert main(args) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["epochs"] == 1 and summary["truth_rows"] == 1 and summary["files"] == 6
    assert summary["calibration"] is None and summary["truth"][0]["seed"] == 3
    for override, key in (("simulation.flux_aperture_e=-5", "simulation.flux_aperture_e"),
                          ("observation.fowler=0", "observation.fowler"),
                          ("observation.x0_px=40", "observation.x0_px"),
                          ("simulation.pointing_ranges=['a_sd_px=U:1:0']",
                           "simulation.pointing_ranges")):
        code = main(["simulate", "--out", str(tmp_path / "y"), "--set", override])
        err = capsys.readouterr().err
        assert code == 2, override
        assert key in err and err.count("\n") == 1


def test_systematics_free_twin_holds_the_star_at_its_peakup_position(runs, tmp_path):
    cfg = load_config(None, TINY + ["challenge.seed=7", "simulation.pointing_motion=false",
                                    "simulation.flat_gain=true"])
    res = simulate_challenge(cfg, tmp_path, workers=1, calibration=False)
    row = res.truth_rows[0]
    lc = Table.read(tmp_path / "lightcurves" / "epoch_01.ecsv")
    for key, label in ((20150000, "pre"), (20150001, "main")):
        aor = lc[lc["aorkey"] == key]
        assert np.all(aor["x_true"] == row[f"x0_{label}_px"])
        assert np.all(aor["y_true"] == row[f"y0_{label}_px"])
    # only the two peak-ups differ: the spread is that of two positions
    assert row["x_sd"] == pytest.approx(np.std(lc["x_true"]))
    # the twin has the same peak-ups, pointing parameters and eclipse as its parent
    parent = runs["a"][1].truth_rows[0]
    for key in ("x0_pre_px", "y0_main_px", "ptg_a_sd_px", "ptg_theta_w_deg", "start_bmjd"):
        assert row[key] == parent[key], key
    with fits.open(tmp_path / "r20150000/ch2/bcd/SPITZER_I2_20150000_0000_0000_1_bcd.fits") as h:
        assert h[0].header["SIMPTG"] is False and h[0].header["SIMFLAT"] is True
