"""epoch_data_from_table: good frames, time order, columns, clear errors."""

from __future__ import annotations

import numpy as np
import pytest
from astropy.table import Table

from eclipsebench.errors import InputError
from eclipsebench.fit.data import aperture_column, epoch_data_from_table


def _table(n=10):
    rng = np.random.default_rng(0)
    t = Table({"time_bmjd": 57000.0 + np.arange(n)[::-1] * 1e-3, "x": rng.normal(15, 0.1, n),
               "y": rng.normal(15, 0.1, n), "noise_pixels": np.full(n, 7.0),
               "flux": np.arange(n, dtype=float) + 100.0, "flux_err": np.ones(n),
               "flag": np.zeros(n, dtype=np.int32), "aorkey": np.full(n, 1),
               "stamp3": np.arange(n * 9, dtype=float).reshape(n, 3, 3),
               "flux_r2p50": np.arange(n, dtype=float) * 2 + 100.0})
    return t


def test_keeps_good_frames_in_time_order():
    t = _table()
    t["flag"][[1, 4]] = 2
    t["flux"][6] = np.nan
    d = epoch_data_from_table(t)
    assert len(d) == 7
    assert np.all(np.diff(d.time_bmjd) > 0)
    # rows were in reverse time order: flux of the earliest kept frame is the last row's
    assert d.flux[0] == 109.0
    assert d.pixels.shape == (7, 9)
    assert np.array_equal(d.pixels[0], np.arange(81, 90, dtype=float))
    assert d.meta["n_frames_flagged"] == 2 and d.meta["n_frames_nonfinite"] == 1


def test_missing_columns_are_all_named():
    t = _table()
    t.remove_columns(["x", "flux_err"])
    with pytest.raises(InputError, match=r"missing column\(s\) x, flux_err"):
        epoch_data_from_table(t)


def test_all_flagged_is_an_error():
    t = _table()
    t["flag"][:] = 1
    with pytest.raises(InputError, match="all 10 frames are flagged"):
        epoch_data_from_table(t)


def test_other_aperture_and_stamp_options():
    t = _table()
    noise = np.random.default_rng(3).standard_normal(len(t))
    t["flux"] = 100.0 + noise
    t["flux_r2p50"] = 150.0 + 2.0 * noise
    assert aperture_column(2.5) == "flux_r2p50"
    d = epoch_data_from_table(t, radius_px=2.5, stamp="none")
    assert d.pixels is None
    assert d.flux[0] == 150.0 + 2.0 * noise[-1]
    # error scaled by the ratio of frame-to-frame scatters (2x here)
    assert np.allclose(d.flux_err, 2.0)
    with pytest.raises(InputError, match="flux_r3p00"):
        epoch_data_from_table(t, radius_px=3.0)
    with pytest.raises(InputError, match="stamp"):
        epoch_data_from_table(t, stamp="stamp7")
