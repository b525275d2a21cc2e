"""Issue 17's binned-CSV acceptance on a *simulated* phase curve.

The built-in ``xo3b-phase-curve`` (one whole orbit of the 2015 challenge's
XO-3b, AORs of at most 12 h after a Pre AOR, physical noise) at a sparse
cadence so that the test runs in seconds: cubes of 8 two-second frames every
8 minutes (about 4,600 frames). Its photometry is binned to one row per cube
and written as a CSV of another pipeline; BLISS on the CSV gives the
amplitude and offset that it gives on the frames, within 1 sigma.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from astropy.table import Table

from eclipsebench.cli import main
from eclipsebench.config.reduce import ReduceSection
from eclipsebench.fit.reduce import reduce_epoch
from eclipsebench.photometry.table import read_table

SPARSE = ["observation.frames_per_cube=8", "observation.cube_interval_s=480.0",
          "simulation.subsamples=2"]
OPTIONS = replace(ReduceSection(), event="phase-curve", prayer_bead_shifts=0)


@pytest.fixture(scope="module")
def simulated(tmp_path_factory):
    """(good frames of the simulated phase curve, the same binned per cube as a CSV)."""
    root = tmp_path_factory.mktemp("pc_sim")
    args = [a for s in SPARSE for a in ("--set", s)]
    assert main(["simulate", "xo3b-phase-curve", "--out", str(root / "sim"), "--no-calibration",
                 "--quiet", "--workers", "1", *args]) == 0
    assert main(["photometry", str(root / "sim"), "--out", str(root / "phot"), "--quiet"]) == 0
    table = read_table(root / "phot" / "epoch_01.fits")
    good = table[np.asarray(table["flag"]) == 0]
    cube = np.asarray(good["aorkey"]).astype(np.int64) * 10_000 + np.asarray(good["expid"])
    keys, index, counts = np.unique(cube, return_inverse=True, return_counts=True)
    binned = Table({name: np.bincount(index, weights=np.asarray(good[name], dtype=float))
                    / counts for name in ("time_bmjd", "flux", "x", "y")})
    binned["flux_err"] = np.sqrt(np.bincount(index, weights=np.asarray(good["flux_err"]) ** 2)) \
        / counts
    binned["aorkey"] = keys // 10_000
    path = root / "phase_curve_cubes.csv"
    binned.write(path, format="ascii.csv")
    truth = Table.read(root / "sim" / "truth.ecsv", format="ascii.ecsv")[0]
    return good, path, truth


@pytest.mark.slow
def test_simulated_phase_curve_binned_to_csv_gives_the_frames_amplitude_and_offset(simulated):
    frames, csv, truth = simulated
    assert len(np.unique(np.asarray(frames["aorkey"]))) >= 7   # Pre + 12-h Main AORs
    unbinned = reduce_epoch(frames, "bliss", options=OPTIONS).to_dict()
    # a CSV names no planet: given, as for another pipeline's table
    binned = reduce_epoch(str(csv), "bliss", options=OPTIONS,
                          system=str(frames.meta["SYSTEM"])).to_dict()
    assert binned["cadence_s"] == pytest.approx(480.0, rel=0.01)
    assert binned["n_frames"] < unbinned["n_frames"] / 6
    for key, unit in (("phase_amplitude", "ppm"), ("phase_offset", "deg")):
        a, b = unbinned[f"{key}_{unit}"], binned[f"{key}_{unit}"]
        assert abs(a - b) < unbinned[f"{key}_err_{unit}"], (key, a, b)
    # and both against the simulator's truth, within 3 sigma (4,600 frames: a weak curve)
    for res in (unbinned, binned):
        assert abs(res["phase_amplitude_ppm"] - truth["phase_amplitude_ppm"]) \
            < 3 * res["phase_amplitude_err_ppm"]
