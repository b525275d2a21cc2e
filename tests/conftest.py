"""Shared test fixtures: where the real IRAC reference files live, data built once per run;
how the suite runs in parallel (``make test``: pytest-xdist, ``-n auto --dist loadfile``).

A parallel run hands out whole files: one worker runs the tests of a file, so a module
fixture is built once, not once per worker. The files whose tests start Dask clusters of
processes (``DASK_MODULES``) are handed out first, longest first, so that the two workers
each start with one and the short files fill in behind them; at most two clusters run at
once, one per worker, and a test elsewhere that starts a local cluster fails, saying so.
(xdist's own ``loadgroup`` does not group under pytest 9.2, whose node ids it can no longer
rename.) Each worker runs single-threaded (BLAS, numba), as the engine's tasks do: the
parallelism is across tests.
"""

from __future__ import annotations

import fcntl
import os
import pickle
import shutil
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SHARED_IRAC = (ROOT / ".." / "shared" / "data" / "irac").resolve()

#: With this variable naming a folder, a parallel run (pytest-xdist) writes there the test ids
#: each worker collected (``gw0.txt``...) and skips every test before its fixtures.
COLLECTED_IDS_ENV = "ECLIPSEBENCH_COLLECTED_IDS"


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_node_collection_finished(node, ids: list[str]) -> None:
    """The controller of a parallel run: ``ids`` is what worker ``node`` collected."""
    folder = os.environ.get(COLLECTED_IDS_ENV)
    if folder:
        (Path(folder) / f"{node.gateway.id}.txt").write_text("".join(f"{i}\n" for i in ids))


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """With ``COLLECTED_IDS_ENV`` set, every item is skipped, the doctests of ``src/`` and
    ``docs/`` too (a ``pytest_runtest_setup`` here sees only the items under ``tests/``)."""
    if os.environ.get(COLLECTED_IDS_ENV):
        skip = pytest.mark.skip(reason="only the collected ids were asked for")
        for item in items:
            item.add_marker(skip)


#: The test files that start Dask clusters of processes (``workers=2``, ``--workers 2``, the
#: default two workers of ``run``, ``simulate`` and ``trust``, the ``dask`` command), longest
#: first (``--durations``): a parallel run hands them out first, in this order.
DASK_MODULES = (
    "tests/challenge/test_campaign.py", "tests/trust/test_trust.py",
    "tests/challenge/test_runner.py", "tests/challenge/test_faults.py",
    "tests/engine/test_cluster.py", "tests/simulation/test_sim_challenge.py",
    "tests/engine/test_cluster_security.py", "tests/engine/test_engine.py",
)


def file_of(nodeid: str) -> str:
    """The file part of a test id (``tests/x/test_y.py::test_z[a]`` -> ``tests/x/test_y.py``)."""
    return nodeid.split("::", 1)[0]


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_make_scheduler(config: pytest.Config, log):
    """``--dist loadfile``: xdist's, handing out the files of ``DASK_MODULES`` first."""
    if config.getvalue("dist") != "loadfile":
        return None
    from xdist.scheduler import LoadScopeScheduling

    rank = {path: i for i, path in enumerate(DASK_MODULES)}

    class DaskFilesFirst(LoadScopeScheduling):
        def _split_scope(self, nodeid: str) -> str:
            return file_of(nodeid)

        def _assign_work_unit(self, node) -> None:
            # the first file by rank (the others keep their order): min returns the first
            first = min(self.workqueue, key=lambda scope: rank.get(scope, len(rank)))
            self.workqueue.move_to_end(first, last=False)
            super()._assign_work_unit(node)

    return DaskFilesFirst(config, log)


def pytest_configure(config: pytest.Config) -> None:
    if os.environ.get("PYTEST_XDIST_WORKER"):
        import numba
        import numpy  # noqa: F401 - load the BLAS libraries, then limit them
        import scipy.linalg  # noqa: F401
        from threadpoolctl import threadpool_limits

        threadpool_limits(limits=1)
        numba.set_num_threads(1)


@pytest.fixture(autouse=True)
def _local_clusters_only_in_the_dask_modules(request, monkeypatch):
    """A test outside ``DASK_MODULES`` that starts a local Dask cluster fails."""
    if file_of(request.node.nodeid) in DASK_MODULES:
        return
    from eclipsebench.engine import cluster

    def refuse(*args, **kwargs):
        raise AssertionError("this test starts a local Dask cluster: add its file to "
                             "DASK_MODULES in tests/conftest.py")

    monkeypatch.setattr(cluster, "_start_local", refuse)


def built_once(tmp_path_factory: pytest.TempPathFactory, name: str,
               build: Callable[[Path], None]) -> Path:
    """A folder ``name`` that ``build(folder)`` fills once per test run, for every worker.

    A session fixture runs once per pytest-xdist worker; this one builds under a kernel lock in
    the folder the workers' temporary folders share (the run's own one when serial), and the
    other workers wait and then read it. Only for data the tests read and never change.
    """
    base = tmp_path_factory.getbasetemp()
    if os.environ.get("PYTEST_XDIST_WORKER"):
        base = base.parent
    folder = base / name
    with open(base / f"{name}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)   # released when the file closes, or its process ends
        if not (base / f"{name}.done").is_file():
            shutil.rmtree(folder, ignore_errors=True)   # a build that died half-way
            folder.mkdir()
            build(folder)
            (base / f"{name}.done").touch()
    return folder


def page_built_in_an_svg_process(body: str) -> Path:
    """Run ``body`` (Python that builds a page and binds its path to ``page``) in a fresh
    process whose matplotlib backend is svg; check that the backend is still svg afterwards
    and that pyplot was never imported, and return the page's path."""
    script = ("import sys\nimport matplotlib\nbefore = matplotlib.get_backend()\n" + body
              + "\nprint(before, matplotlib.get_backend(), 'matplotlib.pyplot' in sys.modules, "
              "page)\n")
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          env={**os.environ, "MPLBACKEND": "svg"}, check=False)
    assert done.returncode == 0, done.stderr
    before, after, pyplot, page = done.stdout.split()
    assert before.lower() == "svg" and after.lower() == "svg" and pyplot == "False"
    return Path(page)


@pytest.fixture(scope="session")
def shared_irac() -> Path:
    """``../shared/data/irac`` (tests using it carry the ``shared_data`` marker)."""
    if not SHARED_IRAC.is_dir():
        pytest.skip("../shared/data/irac is not beside this checkout")
    return SHARED_IRAC


@pytest.fixture(scope="session")
def real_epoch1_table(shared_irac, tmp_path_factory) -> Path:
    """Our photometry (built-in settings) of real epoch 1 (``real_xo3_eclipse1``), as a FITS
    table written once per test run (tests only read it)."""
    from eclipsebench.api import measure

    out = built_once(tmp_path_factory, "real_epoch1",
                     lambda folder: measure(shared_irac / "real_xo3_eclipse1", folder))
    return out / "epoch_01.fits"


#: The trust run of real epoch 1 that tests/trust reads (issue 36's acceptance): ten twins
#: made with BLISS's real fit (the first method), reduced by BLISS, KR/Data and PLD by least
#: squares, in one process.
REAL_EPOCH1_TRUST_OPTIONS = ["--twins", "10", "--sampler", "leastsq", "--methods",
                             "bliss,kr-data,pld", "--quiet", "--workers", "1"]


@pytest.fixture(scope="session")
def real_epoch1_trust(real_epoch1_table, tmp_path_factory) -> Path:
    """The folder of ``eclipsebench trust`` on real epoch 1 (``REAL_EPOCH1_TRUST_OPTIONS``),
    run once per test run for every file that reads it (tests only read it): its twins, their
    reductions and ``trust.json``. About 100 s of CPU, the suite's largest single command."""
    def build(folder: Path) -> None:
        from eclipsebench.cli import main

        assert main(["trust", str(real_epoch1_table), "--out", str(folder / "trust"),
                     *REAL_EPOCH1_TRUST_OPTIONS]) == 0

    return built_once(tmp_path_factory, "real_epoch1_trust", build) / "trust"


#: The tiny challenge of tests/challenge/test_runner.py and tests/engine/test_cluster.py: two
#: epochs of 233 two-frame cubes (the eclipse stays inside the Main AOR), one sub-sample, two
#: methods in both profiles.
TINY_RUN_SETS = ["challenge.epochs=2", "observation.pre_cubes=1", "observation.frames_per_cube=2",
                 "simulation.subsamples=1", "simulation.calibration_frames=2000",
                 'run.methods=["pld", "bliss"]', "run.bootstrap=50", "run.report=false",
                 "run.empirical_photon_limit=false"]


@pytest.fixture(scope="session")
def tiny_run_once(tmp_path_factory) -> tuple[Path, dict, list[str]]:
    """The tiny challenge (``TINY_RUN_SETS``) run in one process, once per test run for every
    file that uses it: ``(its run folder, the summary run_challenge returned, the keys of the
    tasks it ran)``. Tests only read the folder; one that changes it works on a copy."""
    def build(folder: Path) -> None:
        from eclipsebench.challenge.runner import run_challenge
        from eclipsebench.config import load_config

        (folder / "run").mkdir()
        summary, report = run_challenge(load_config(None, TINY_RUN_SETS), folder / "run",
                                        workers=1)
        (folder / "returned.pickle").write_bytes(pickle.dumps((summary, list(report.ran))))

    out = built_once(tmp_path_factory, "tiny_run", build)
    summary, ran = pickle.loads((out / "returned.pickle").read_bytes())
    return out / "run", summary, ran


def simulate_eclipse_epoch(root: Path, sets: list[str], lead_d: float) -> Path:
    """Simulate one short epoch (configuration ``sets``) that starts ``lead_d`` days before an
    eclipse of the configured planet, measure it; the photometry table's path."""
    from eclipsebench.astro.catalogue import system_for
    from eclipsebench.astro.orbit import eclipse_time_bmjd
    from eclipsebench.cli import main
    from eclipsebench.config import load_config
    from eclipsebench.simulation.plan import JD_OFFSET_BMJD

    t_ecl = eclipse_time_bmjd(system_for(load_config(None, sets).system), 57205.8)
    sets = sets + [f"observation.start_times_jd=[{t_ecl - lead_d - JD_OFFSET_BMJD:.6f}]"]
    args = [a for s in sets for a in ("--set", s)]
    assert main(["simulate", "--out", str(root / "sim"), "--epochs", "1", "--no-calibration",
                 "--quiet", "--workers", "1", *args]) == 0
    assert main(["photometry", str(root / "sim"), "--out", str(root / "phot"), "--quiet"]) == 0
    return root / "phot" / "epoch_01.fits"


#: The small simulated observation of tests/trust (and a campaign's first epoch): one short
#: epoch of 81 16-frame cubes, two sub-samples, starting 0.12 d before an eclipse.
SMALL_OBSERVATION_SETS = ["observation.pre_cubes=1", "observation.frames_per_cube=16",
                          "observation.main_cubes=80", "observation.cube_interval_s=220.0",
                          "simulation.subsamples=2"]
SMALL_OBSERVATION_LEAD_D = 0.12


@pytest.fixture(scope="session")
def small_observation_table(tmp_path_factory) -> Path:
    """The photometry table of the small simulated observation (``SMALL_OBSERVATION_SETS``),
    simulated and measured once per test run for every file that uses it (tests only read it;
    one that changes it works on a copy)."""
    out = built_once(tmp_path_factory, "small_observation",
                     lambda folder: simulate_eclipse_epoch(folder, SMALL_OBSERVATION_SETS,
                                                           SMALL_OBSERVATION_LEAD_D))
    return out / "phot" / "epoch_01.fits"


def real_epoch1_jd_utc(table, shared_irac: Path):
    """The times of a photometry table of real epoch 1 as JD_UTC at the observer (Spitzer),
    from the archive's own headers: each cube's ``MJD_OBS`` (UTC at Spitzer) less its
    ``BMJD_OBS`` moved to TDB, added to each frame's BMJD_TDB. Independent of
    ``astro/timescales.py``; also the observer (first header's ``SPTZR_X/Y/Z, MJD_OBS``)."""
    import numpy as np
    from astropy.io import fits
    from astropy.time import Time

    shift, observer = {}, None
    for f in sorted((shared_irac / "real_xo3_eclipse1").glob("r*/ch2/bcd/*_bcd.fits")):
        h = fits.getheader(f)
        bmjd_tdb = Time(h["BMJD_OBS"], format="mjd", scale="utc").tdb.mjd
        shift[(int(h["AORKEY"]), int(h["EXPID"]))] = h["MJD_OBS"] - bmjd_tdb
        if observer is None:
            observer = f"{h['SPTZR_X']},{h['SPTZR_Y']},{h['SPTZR_Z']},{h['MJD_OBS']}"
    keys = zip(np.asarray(table["aorkey"]), np.asarray(table["expid"]), strict=True)
    delta = np.array([shift[(int(a), int(e))] for a, e in keys])
    return np.asarray(table["time_bmjd"], float) + delta + 2400000.5, observer
