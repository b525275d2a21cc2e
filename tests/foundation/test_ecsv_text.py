"""The light curves' ECSV writer gives astropy's bytes (io/ecsv.py)."""

from __future__ import annotations

import io

import numpy as np
from astropy.table import MaskedColumn, Table

from eclipsebench.io.ecsv import ecsv_text


def _astropy(table: Table) -> str:
    buf = io.StringIO()
    table.write(buf, format="ascii.ecsv")
    return buf.getvalue()


def test_float_columns_give_astropys_bytes_for_awkward_values():
    g = np.random.default_rng(7)
    awkward = np.array([0.0, -0.0, 1.0, 0.1, 1e-300, 5e-324, 1e22, -1.5e16, 123456789.123456789,
                        np.nan, np.inf, -np.inf, 57234.518690123, 2.0 ** 53, 1 / 3])
    t = Table({"time_bmjd": 57234.3 + g.random(awkward.size), "flux": awkward,
               "flux_err": g.lognormal(size=awkward.size) * 1e-4},
              meta={"method": "bliss", "depth_ppm": 1820.24, "TIMESYS": "TDB"})
    t["time_bmjd"].unit = "d"
    t["flux"].description = "decorrelated flux: flux / systematics_model"
    assert ecsv_text(t) == _astropy(t)


def test_other_tables_are_written_by_astropy_itself():
    t = Table({"epoch": np.arange(3), "depth_ppm": [1.0, 2.0, 3.0]})
    m = Table({"x": MaskedColumn([1.0, 2.0], mask=[False, True])})
    empty = Table({"x": np.zeros(0)})
    for table in (t, m, empty):
        assert ecsv_text(table) == _astropy(table)
