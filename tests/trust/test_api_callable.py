"""``eb.trust`` is the function whatever ran before it (issue 36 point 7).

Importing the subpackage ``eclipsebench.trust`` (which ``eb.reduce``, ``eb.read_photometry``
and ``eb.methods`` do through the API module) once bound it over the lazy API name, so
``eb.trust(...)`` raised ``TypeError: 'module' object is not callable``.
"""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

SRC = Path(__file__).resolve().parents[2] / "src"

SCRIPT = textwrap.dedent("""
    import sys
    import numpy as np
    from astropy.table import Table
    import eclipsebench as eb
    import eclipsebench.trust.run   # the subpackage loaded explicitly as well

    assert "bliss" in eb.methods()
    try:
        eb.read_photometry("no/such/epoch_01.fits")
    except eb.InputError:
        pass
    n = 12800
    t = 56241.80 + np.arange(n) * 2.0 / 86400.0
    rng = np.random.default_rng(1)
    table = Table({"time_bmjd": t, "flux": 1.0 + 1e-4 * rng.standard_normal(n),
                   "flux_err": np.full(n, 1e-4), "x": 15.0 + 0.01 * rng.standard_normal(n),
                   "y": 15.0 + 0.01 * rng.standard_normal(n)})
    res = eb.reduce(table, "poly2", system="XO-3b", sampler="leastsq", prayer_bead_shifts=0)
    assert np.isfinite(res.depth_ppm)
    assert callable(eb.trust), type(eb.trust)
    try:
        eb.trust("no/such/table.fits", sys.argv[1], twins=10)
    except eb.InputError as exc:
        print("refused:", exc)
    import eclipsebench.trust.result as result_module   # the subpackage is still importable
    assert result_module.TrustResult is not None
    assert callable(eb.trust)
""")


def test_eb_trust_is_callable_after_other_calls(tmp_path):
    done = subprocess.run([sys.executable, "-c", SCRIPT, str(tmp_path / "trust")],
                          capture_output=True, text=True, timeout=300,
                          env={"PYTHONPATH": str(SRC), "PATH": "/usr/bin:/bin"})
    assert done.returncode == 0, done.stderr[-2000:]
    assert "refused: no/such/table.fits: no such photometry table" in done.stdout
