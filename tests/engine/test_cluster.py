"""An existing Dask cluster (`run --scheduler`): same summary bytes as one process.

A scheduler and two single-threaded workers are started as separate
processes on loopback, the way a cluster operator would (`dask scheduler`,
`dask worker`, with the Dask configuration docs/runner.md recommends), and
are always torn down.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from contextlib import contextmanager
from pathlib import Path

import dask
import pytest
from distributed import Client

from eclipsebench.cli import main

from ..conftest import TINY_RUN_SETS

# the tiny challenge of tests/challenge/test_runner.py: two epochs of 233 two-frame cubes, two
# methods (run once per test run in one process, tests/conftest.py)
TINY = TINY_RUN_SETS

DASK = Path(sys.executable).with_name("dask")
STARTUP_S = 45.0

#: The worker configuration of docs/runner.md ("An existing Dask cluster").
WORKER_CONFIG = """\
distributed:
  nanny:
    pre-spawn-environ:
      MALLOC_TRIM_THRESHOLD_: null
      NUMBA_NUM_THREADS: 1
  worker:
    profile:
      enabled: false
"""


def _alive(pgid: int) -> bool:
    try:
        os.killpg(pgid, 0)
    except ProcessLookupError:
        return False
    return True


def _wait_gone(pgid: int, timeout_s: float) -> bool:
    deadline = time.monotonic() + timeout_s
    while _alive(pgid):
        if time.monotonic() > deadline:
            return False
        time.sleep(0.1)
    return True


def _stop(procs: list[subprocess.Popen]) -> None:
    """SIGTERM each process group we started (a nanny and its worker), then SIGKILL."""
    for p in procs:
        if _alive(p.pid):
            os.killpg(p.pid, signal.SIGTERM)
    for p in procs:
        try:
            p.wait(timeout=15)
        except subprocess.TimeoutExpired:
            pass
        if not _wait_gone(p.pid, 15):
            os.killpg(p.pid, signal.SIGKILL)
            p.wait(timeout=10)
            _wait_gone(p.pid, 10)


def _log_tail(path: Path) -> str:
    return path.read_text()[-2000:] if path.is_file() else ""


@contextmanager
def dask_cluster(folder: Path, n_workers: int = 2):
    """A scheduler and ``n_workers`` workers on 127.0.0.1; yields (address, processes)."""
    config_dir = folder / "dask-config"
    config_dir.mkdir()
    (config_dir / "eclipsebench.yaml").write_text(WORKER_CONFIG)
    env = {**os.environ, "DASK_CONFIG": str(config_dir)}
    scheduler_file = folder / "scheduler.json"
    procs: list[subprocess.Popen] = []
    logs: list[Path] = []

    def start(name: str, args: list[str]) -> None:
        log = folder / f"{name}.log"
        logs.append(log)
        with open(log, "wb") as fh:  # the child keeps its own descriptor
            procs.append(subprocess.Popen([str(DASK), *args], stdout=fh, stderr=subprocess.STDOUT,
                                          env=env, cwd=folder, start_new_session=True))

    def wait_for(what: str, ready) -> None:
        deadline = time.monotonic() + STARTUP_S
        while not ready():
            dead = [(p.args, log) for p, log in zip(procs, logs, strict=True)
                    if p.poll() is not None]
            if dead:
                raise RuntimeError(f"{dead[0][0]} exited while waiting for {what}:\n"
                                   + _log_tail(dead[0][1]))
            if time.monotonic() > deadline:
                raise TimeoutError(f"no {what} after {STARTUP_S:.0f} s:\n"
                                   + "\n".join(_log_tail(log) for log in logs))
            time.sleep(0.2)

    try:
        start("scheduler", ["scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
                            "--scheduler-file", str(scheduler_file)])
        wait_for("scheduler file", scheduler_file.is_file)
        address = json.loads(scheduler_file.read_text())["address"]
        for i in range(n_workers):
            start(f"worker{i}", ["worker", "--scheduler-file", str(scheduler_file),
                                 "--host", "127.0.0.1", "--nthreads", "1", "--nworkers", "1",
                                 "--no-dashboard", "--name", f"w{i}",
                                 "--local-directory", str(folder / f"worker{i}")])
        with Client(address, timeout="20s") as client:
            client.wait_for_workers(n_workers, timeout=STARTUP_S)
            assert len(client.scheduler_info(n_workers=-1)["workers"]) == n_workers
        yield address, procs
    finally:
        _stop(procs)


def _run(out: Path, *execution: str) -> int:
    args = ["run", "--out", str(out), "--quiet", *execution]
    for item in TINY:
        args += ["--set", item]
    return main(args)


@pytest.mark.slow  # ~30 s: a tiny run and a cluster's start-up (the one-process run is shared)
@pytest.mark.timeout(240)  # the signal interrupts a hung run; the cluster is still torn down
@pytest.mark.skipif(not DASK.is_file(), reason="no dask command beside this Python")
def test_scheduler_gives_the_same_summary_bytes_as_one_process(tmp_path, capsys, tiny_run_once):
    one_process, _, _ = tiny_run_once   # the same settings run in one process (tests/conftest.py)
    with dask_cluster(tmp_path) as (address, procs):
        assert address.startswith("tcp://127.0.0.1:")
        with Client(address, timeout="20s") as client:  # the documented worker configuration
            assert set(client.run(os.getenv, "MALLOC_TRIM_THRESHOLD_").values()) == {None}
            assert set(client.run(os.getenv, "NUMBA_NUM_THREADS").values()) == {"1"}
            assert set(client.run(dask.config.get, "distributed.worker.profile.enabled")
                       .values()) == {False}
        assert _run(tmp_path / "cluster", "--scheduler", address) == 0
        timings = (tmp_path / "cluster" / "timings.ecsv").read_text()
        assert f"dask scheduler {address}" in timings
        assert all(p.poll() is None for p in procs)  # still up after the run's client left
    assert all(not _alive(p.pid) for p in procs)  # torn down, nanny and worker alike
    one = (one_process / "summary.json").read_bytes()
    assert (tmp_path / "cluster" / "summary.json").read_bytes() == one
    capsys.readouterr()
