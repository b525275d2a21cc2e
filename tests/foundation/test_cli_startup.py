"""The command line starts fast: building the parser imports nothing heavy.

Each command's work imports what it needs (numba, astropy, scikit-learn,
Dask, matplotlib); ``eclipsebench --version`` and ``eclipsebench reduce
--help`` only build the parser. The time it takes is a benchmark
(``bench/bench_cli_startup.py``, BENCHMARKS.md), not a test; here we check
what was imported, in a fresh interpreter.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

import eclipsebench

#: Packages none of which the parser may import (each costs 0.1-1 s to load).
HEAVY = ("numba", "astropy", "sklearn", "dask", "distributed", "matplotlib", "numpy", "scipy",
         "batman", "emcee", "photutils", "tqdm", "asyncio", "ssl")

_PROBE = """
import json, sys
{body}
print(json.dumps(sorted(m for m in {heavy!r} if m in sys.modules)))
"""


def _heavy_after(body: str) -> list[str]:
    """The heavy packages a fresh interpreter has imported after running ``body``."""
    env = {**os.environ, "PYTHONPATH": str(Path(eclipsebench.__file__).resolve().parents[1])}
    done = subprocess.run([sys.executable, "-c", _PROBE.format(body=body, heavy=HEAVY)],
                          capture_output=True, text=True, env=env, timeout=120, check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def test_the_probe_sees_a_heavy_import():
    """The check can fail: importing the fitter shows up."""
    assert {"numba", "astropy"} <= set(_heavy_after("import eclipsebench.fit.reduce"))


def test_building_the_parser_imports_nothing_heavy():
    assert _heavy_after("from eclipsebench.cli import build_parser\nbuild_parser()") == []


@pytest.mark.parametrize("argv", [["--version"], ["--help"], ["reduce", "--help"],
                                  ["run", "--help"], ["lightcurve", "--help"],
                                  ["photon-limit", "--help"], ["trust", "--help"]])
def test_version_and_help_import_nothing_heavy(argv):
    body = ("import contextlib, io\nfrom eclipsebench.cli import main\n"
            "with contextlib.redirect_stdout(io.StringIO()):\n"
            "    try:\n"
            f"        main({argv!r})\n"
            "    except SystemExit:\n"
            "        pass")
    assert _heavy_after(body) == []
