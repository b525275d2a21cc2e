"""Every command works in a folder whose name has spaces and non-ASCII letters."""

from __future__ import annotations

import json

import pytest

from eclipsebench.photometry.table import read_photometry

TINY = ["observation.pre_cubes=1", "observation.frames_per_cube=2", "simulation.subsamples=1",
        "simulation.calibration_frames=2000"]


def _sets(items):
    return [a for item in items for a in ("--set", item)]


@pytest.mark.slow
def test_simulate_photometry_reduce_stats_and_run_in_a_unicode_folder(tmp_path, cli):
    root = tmp_path / "dir with spaces ü€ été"
    sim, phot = root / "sim ü", root / "phot ü"
    code, _, err = cli("simulate", *_sets(TINY), "--epochs", "1", "--workers", "1",
                       "--no-calibration", "--out", sim, "--quiet")
    assert code == 0, err
    code, out, err = cli("photometry", sim, "--out", phot, "--quiet", "--json")
    assert code == 0, err
    table_path = phot / "epoch_01.fits"
    meta = read_photometry(table_path).meta
    assert meta["INROOT"] == str(sim.resolve())  # stored escaped, read back whole
    assert meta["SIMDIR"] == str(sim.resolve())
    code, out, err = cli("reduce", table_path, "--method", "pld", "--prayer-bead", "0",
                         "--out", root / "résultat ü.json", "--json", "--quiet")
    assert code == 0, err
    assert json.loads((root / "résultat ü.json").read_text())["table"] == str(table_path)
    assert (root / "résultat ü.lc.ecsv").is_file()
    depths = root / "tiefen ü.csv"
    depths.write_text("method,epoch,depth_ppm,error_ppm\npld,1,1800,300\npld,2,1900,300\n"
                      "bliss,1,1850,250\nbliss,2,1700,260\n", encoding="utf-8")
    code, out, err = cli("stats", depths, "--bootstrap", "0", "--json")
    assert code == 0, err
    assert set(json.loads(out)["methods"]) == {"pld", "bliss"}
    code, out, err = cli("run", *_sets([*TINY, "challenge.epochs=2", 'run.methods=["pld"]',
                                        "run.bootstrap=50", "run.report=false",
                                        "run.empirical_photon_limit=false", "run.workers=1"]),
                         "--out", root / "runs" / "ü run", "--quiet", "--json")
    assert code == 0, err
    assert (root / "runs" / "ü run" / "summary.json").is_file()
    assert json.loads(out)["methods"]["pld"]
