"""Issue 16's CSV acceptance on a *simulated* epoch: the Main AOR's frames as another pipeline's CSV.

A short epoch is simulated (one Pre cube and 110 Main cubes of 16 frames,
eclipse inside), measured with the package's photometry, and the Main AOR's
good frames written as a CSV of only ``time_bmjd, flux, flux_err, x, y,
noise_pixels``. BLISS, KR/Data, GP and poly2 give the same depth from the CSV
as from the full photometry table of the same frames (within 1 ppm); PLD
refuses the CSV in one line naming the pixels it needs.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from astropy.table import Table

from eclipsebench.astro.catalogue import system_for
from eclipsebench.cli import main
from eclipsebench.config import load_config
from eclipsebench.config.reduce import ReduceSection
from eclipsebench.fit.prepare import resolve_method_options
from eclipsebench.fit.reduce import reduce_epoch
from eclipsebench.photometry.table import read_table

from ..conftest import simulate_eclipse_epoch

FAST = replace(ReduceSection(), prayer_bead_shifts=0)
MINIMAL = ("time_bmjd", "flux", "flux_err", "x", "y", "noise_pixels")
METHODS = {"bliss": None, "kr-data": None, "gp": {"bin_seconds": 240.0}, "poly2": None}
SETS = ["observation.pre_cubes=1", "observation.frames_per_cube=16",
        "observation.main_cubes=110", "observation.cube_interval_s=220.0",
        "simulation.subsamples=2"]


@pytest.fixture(scope="module")
def main_aor(tmp_path_factory):
    """(full photometry table of the Main AOR's good frames, the same as a six-column CSV)."""
    root = tmp_path_factory.mktemp("sim_csv")
    path = simulate_eclipse_epoch(root, SETS, 0.14)
    table = read_table(path)
    keys = np.unique(np.asarray(table["aorkey"]))
    assert len(keys) == 2
    keep = (np.asarray(table["aorkey"]) == keys.max()) & (np.asarray(table["flag"]) == 0)
    full = table[keep]
    full.meta = {k: v for k, v in table.meta.items() if k != "SIMDIR"}
    csv = root / "main_aor.csv"
    Table({c: np.asarray(full[c]) for c in MINIMAL}).write(csv, format="ascii.csv")
    return full, csv


@pytest.mark.slow
@pytest.mark.parametrize("method", list(METHODS))
def test_simulated_main_aor_csv_gives_the_full_tables_depth(method, main_aor):
    full, csv = main_aor
    assert read_table(csv).colnames == list(MINIMAL)
    kwargs = {"options": FAST,
              "method_options": resolve_method_options(method, FAST, METHODS[method])}
    from_full = reduce_epoch(full, method, **kwargs)
    # a CSV names no planet: given, as for another pipeline's table
    from_csv = reduce_epoch(str(csv), method, system=system_for(load_config(None, SETS).system),
                            **kwargs)
    assert from_csv.n_frames == from_full.n_frames <= len(full)
    assert abs(from_csv.depth_ppm - from_full.depth_ppm) < 1.0, (from_csv.depth_ppm,
                                                                  from_full.depth_ppm)
    assert 500.0 < from_full.depth_ppm < 3500.0


@pytest.mark.slow
def test_pld_refuses_the_simulated_csv_naming_the_pixels(main_aor, tmp_path, capsys):
    _, csv = main_aor
    code = main(["reduce", str(csv), "--method", "pld", "--out", str(tmp_path / "r.json"),
                 "--system", "XO-3b (2015 challenge)", "--quiet"])
    err = capsys.readouterr().err
    assert code == 2
    assert err.count("\n") == 1 and "'pld'" in err and "stamp3 pixels (or p0..p8)" in err
    assert not (tmp_path / "r.json").exists()
