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
    """The check can fail: importing the fitter and the photometry's kernels shows up."""
    assert {"numba", "astropy"} <= set(
        _heavy_after("import eclipsebench.fit.reduce, eclipsebench.photometry.kernels"))


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


#: What ``eclipsebench reduce`` does not need before its fit (issue 40's start-up: about
#: 0.5 s of CPU when ``eclipsebench.api`` imported them all). The engine's ``cluster`` module
#: is light: every command's parser reads its options.
NOT_FOR_REDUCE = ("eclipsebench.challenge", "eclipsebench.simulation", "eclipsebench.stats",
                  "eclipsebench.engine.tasks", "eclipsebench.trust", "eclipsebench.report",
                  "eclipsebench.photometry.pipeline", "scipy.stats", "dask", "distributed")


def test_reduce_reaches_its_fit_without_the_challenge_the_statistics_or_the_engine(tmp_path):
    table = tmp_path / "lc.csv"
    rows = [f"{57234.34 + i * 2.0 / 86400:.7f},1.0,0.002,15.0,15.1" for i in range(200)]
    table.write_text("time_bmjd,flux,flux_err,x,y\n" + "\n".join(rows) + "\n", encoding="utf-8")
    argv = ["reduce", str(table), "--method", "bliss", "--sampler", "leastsq", "--system",
            "XO-3b", "--quiet", "--out", str(tmp_path / "r.json")]
    body = ("import eclipsebench.fit.reduce as fit\n"
            "def stop(*args, **kwargs):\n"
            "    raise SystemExit(0)\n"
            "fit.reduce_epoch = stop\n"
            "import eclipsebench.api as api\n"
            "api.reduce_epoch = stop\n"
            "from eclipsebench.cli import main\n"
            "try:\n"
            f"    main({argv!r})\n"
            "except SystemExit as exc:\n"
            "    assert exc.code == 0, exc.code\n"
            f"print(json.dumps(sorted(m for m in sys.modules if m.startswith({NOT_FOR_REDUCE!r}))))")
    env = {**os.environ, "PYTHONPATH": str(Path(eclipsebench.__file__).resolve().parents[1])}
    done = subprocess.run([sys.executable, "-c", "import json, sys\n" + body],
                          capture_output=True, text=True, env=env, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    loaded = json.loads(done.stdout.strip().splitlines()[-1])
    assert loaded == [], loaded
    assert not (tmp_path / "r.json").exists()          # stopped before the fit


@pytest.mark.parametrize("given, expected", [(None, "4"), ("8", "8")])
def test_blas_threads_sleep_at_once_unless_the_environment_says(given, expected):
    """OpenBLAS reads ``OPENBLAS_THREAD_TIMEOUT`` when numpy loads it: the command line sets
    it (issue 40: idle threads spinning doubled a fit's CPU) before any command imports numpy,
    and keeps a value the user gave."""
    body = ("import contextlib, io, os, sys\n"
            "from eclipsebench.cli import main\n"
            "before = 'numpy' in sys.modules\n"
            "with contextlib.redirect_stdout(io.StringIO()):\n"
            "    code = main(['photon-limit', '--flux-net', '70858', '--flux-aperture', '70917',"
            " '--flux-background', '463', '--frames', '14912', '--depth-ppm', '1520'])\n"
            "print(json.dumps([code, before, 'numpy' in sys.modules,"
            " os.environ.get('OPENBLAS_THREAD_TIMEOUT')]))")
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_THREAD_TIMEOUT"}
    env["PYTHONPATH"] = str(Path(eclipsebench.__file__).resolve().parents[1])
    if given is not None:
        env["OPENBLAS_THREAD_TIMEOUT"] = given
    done = subprocess.run([sys.executable, "-c", "import json\n" + body], capture_output=True,
                          text=True, env=env, timeout=120)
    assert done.returncode == 0, done.stderr[-2000:]
    assert json.loads(done.stdout.strip().splitlines()[-1]) == [0, False, True, expected]


def test_the_process_command_freezes_what_it_leaves_and_an_in_process_call_does_not():
    """``main()`` run as the process's command (no ``argv``) freezes the objects left out of
    the garbage collector, whose last pass at exit cost about 0.3 s of CPU (issue 40); a call
    with ``argv`` (a notebook, a test) leaves the collector alone."""
    body = ("import contextlib, gc, io, sys\n"
            "from eclipsebench.cli import main\n"
            "argv = ['photon-limit', '--flux-net', '70858', '--flux-aperture', '70917',"
            " '--flux-background', '463', '--frames', '14912', '--depth-ppm', '1520']\n"
            "with contextlib.redirect_stdout(io.StringIO()):\n"
            "    main(argv)\n"
            "    given = gc.get_freeze_count()\n"
            "    sys.argv = ['eclipsebench', *argv]\n"
            "    main()\n"
            "print(json.dumps([given, gc.get_freeze_count() > 0]))")
    env = {**os.environ, "PYTHONPATH": str(Path(eclipsebench.__file__).resolve().parents[1])}
    done = subprocess.run([sys.executable, "-c", "import json\n" + body], capture_output=True,
                          text=True, env=env, timeout=120)
    assert done.returncode == 0, done.stderr[-2000:]
    assert json.loads(done.stdout.strip().splitlines()[-1]) == [0, True]


def test_a_least_squares_bliss_reduction_never_imports_numba(tmp_path):
    """Its fit calls no compiled kernel (they load at their first call, ``eclipsebench.jit``):
    numba's 0.3 s of import is not part of its start-up."""
    table = tmp_path / "lc.csv"
    rows = [f"{57234.40 + i * 4.0 / 86400:.7f},{1 + 1e-4 * (i % 7)},0.002,"
            f"{15.0 + 0.01 * (i % 5)},{15.1 + 0.01 * (i % 3)}" for i in range(6000)]
    table.write_text("time_bmjd,flux,flux_err,x,y\n" + "\n".join(rows) + "\n", encoding="utf-8")
    argv = ["reduce", str(table), "--method", "bliss", "--sampler", "leastsq", "--system",
            "XO-3b", "--quiet", "--out", str(tmp_path / "r.json")]
    body = ("import contextlib, io\nfrom eclipsebench.cli import main\n"
            "with contextlib.redirect_stdout(io.StringIO()):\n"
            f"    assert main({argv!r}) == 0\n")
    heavy = _heavy_after(body)
    assert (tmp_path / "r.json").is_file()
    assert "numba" not in heavy and "astropy" in heavy, heavy
