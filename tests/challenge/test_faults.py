"""Issue 28: faults during a run are one line, stop or resume cleanly, and keep the bytes.

Before: SIGTERM (a batch scheduler's wall-time limit) killed ``run`` with exit
143, no message and ``run.lock`` left behind; ``--quiet`` printed Dask's
"Restarting worker" lines and multiprocessing's "leaked semaphore" warning
when a worker died; a full disk gave 25-57 lines, went on for 30 s and
exited 2 as bad input; and a result written while Ctrl-C was unwinding had
no stamp and was redone.
"""

from __future__ import annotations

import errno
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import psutil
import pytest

import eclipsebench
from eclipsebench.challenge.runner import Layout, run_challenge
from eclipsebench.cli import main
from eclipsebench.config import load_config
from eclipsebench.engine.tasks import Task, run_tasks, stamp_path
from eclipsebench.errors import EXIT_ENVIRONMENT, EnvironmentFailure

# The tiny challenge of tests/challenge/test_runner.py, one method, one profile, no
# calibration set: the fewest tasks that still simulate, measure, reduce and score.
SMALL = ["challenge.epochs=2", "observation.pre_cubes=1", "observation.frames_per_cube=2",
         "simulation.subsamples=1", "simulation.write_calibration=false",
         'run.methods=["pld"]', 'run.profiles=["controlled"]', "run.bootstrap=50",
         "run.report=false", "run.empirical_photon_limit=false"]
#: generous: how long a step of the small run may take on a loaded machine
WAIT_S = 600.0


def _argv(out: Path, *extra: str) -> list[str]:
    argv = ["run", "--out", str(out), "--quiet", *extra]
    for item in SMALL:
        argv += ["--set", item]
    return argv


@pytest.fixture(scope="module")
def reference(tmp_path_factory) -> bytes:
    """summary.json of an undisturbed run, in this process."""
    root = tmp_path_factory.mktemp("reference")
    run_challenge(load_config(None, SMALL), root, workers=1)
    return (root / "summary.json").read_bytes()


def _start(argv: list[str], stderr_path: Path) -> subprocess.Popen:
    env = {**os.environ, "PYTHONPATH": str(Path(eclipsebench.__file__).parents[1])}
    with open(stderr_path, "wb") as err:
        return subprocess.Popen([sys.executable, "-m", "eclipsebench.cli", *argv],
                                stdout=subprocess.DEVNULL, stderr=err, env=env)


def _wait_for(path: Path, proc: subprocess.Popen) -> None:
    deadline = time.monotonic() + WAIT_S
    while not path.exists():
        assert proc.poll() is None, f"the run ended (exit {proc.returncode}) before {path}"
        assert time.monotonic() < deadline, f"no {path} after {WAIT_S:.0f} s"
        time.sleep(0.05)


@pytest.mark.slow
@pytest.mark.timeout(1800)
def test_sigterm_is_one_line_releases_the_lock_and_the_rerun_gives_the_same_bytes(
        tmp_path, reference, capsys):
    out = tmp_path / "run"
    proc = _start(_argv(out, "--workers", "1"), tmp_path / "stderr.txt")
    try:
        _wait_for(Layout(out).truth(), proc)
        proc.send_signal(signal.SIGTERM)
        code = proc.wait(timeout=WAIT_S)
    finally:
        proc.kill()
        proc.wait()
    err = (tmp_path / "stderr.txt").read_text().splitlines()
    assert code == 143, err
    assert err == ["eclipsebench run: interrupted by SIGTERM; rerun the same command to resume"]
    assert not Layout(out).lock.exists() and not Layout(out).summary.exists()
    assert main(_argv(out, "--workers", "1")) == 0
    capsys.readouterr()
    assert Layout(out).summary.read_bytes() == reference


def _worker_processes(pid: int) -> list[psutil.Process]:
    """The Dask worker processes under ``pid`` (spawned by multiprocessing, not its tracker)."""
    found = []
    for child in psutil.Process(pid).children(recursive=True):
        try:
            line = " ".join(child.cmdline())
        except psutil.NoSuchProcess:
            continue
        if "spawn_main" in line and "resource_tracker" not in line:
            found.append(child)
    return found


@pytest.mark.slow
@pytest.mark.timeout(1800)
def test_a_worker_killed_mid_run_is_silent_with_quiet(tmp_path, reference):
    out = tmp_path / "run"
    proc = _start(_argv(out, "--workers", "2"), tmp_path / "stderr.txt")
    try:
        _wait_for(Layout(out).truth(), proc)  # the photometry and reductions are next
        workers = _worker_processes(proc.pid)
        assert len(workers) == 2
        workers[0].kill()
        code = proc.wait(timeout=WAIT_S)
    finally:
        proc.kill()
        proc.wait()
    assert code == 0
    assert (tmp_path / "stderr.txt").read_text() == ""
    assert Layout(out).summary.read_bytes() == reference


@pytest.mark.slow
@pytest.mark.timeout(1800)
def test_a_full_disk_is_one_line_stops_the_run_and_the_rerun_gives_the_same_bytes(
        tmp_path, reference, capsys, monkeypatch):
    out = tmp_path / "run"
    real_replace = os.replace
    refused = []

    def replace(src, dst, *args, **kwargs):  # the disk fills when the results are written
        if f"{os.sep}results{os.sep}" in str(dst):
            refused.append(str(dst))
            raise OSError(errno.ENOSPC, "No space left on device")
        return real_replace(src, dst, *args, **kwargs)

    monkeypatch.setattr(os, "replace", replace)
    code = main(_argv(out, "--workers", "1"))
    monkeypatch.setattr(os, "replace", real_replace)
    err = capsys.readouterr().err.splitlines()
    assert code == EXIT_ENVIRONMENT, err
    assert len(err) == 1 and "no space left" in err[0] and str(out / "results" / "pld") in err[0]
    assert "Traceback" not in err[0] and "internal error" not in err[0]
    assert len(refused) == 1  # stopped at the first: the other epoch was not tried
    assert not Layout(out).lock.exists() and not Layout(out).summary.exists()
    assert main(_argv(out, "--workers", "1")) == 0
    capsys.readouterr()
    assert Layout(out).summary.read_bytes() == reference


def write_then_interrupt(path: str) -> None:
    """A task whose output is whole when Ctrl-C arrives (as during a run's shutdown)."""
    Path(path).write_text("whole\n")
    raise KeyboardInterrupt


def write(path: str) -> None:
    Path(path).write_text("whole\n")


def test_a_result_written_while_interrupted_gets_its_stamp(tmp_path):
    out = tmp_path / "a.txt"
    with pytest.raises(KeyboardInterrupt):
        run_tasks([Task("a", "a", write_then_interrupt, (str(out),), (out,))])
    task = Task("a", "a", write, (str(out),), (out,))
    assert stamp_path(task).is_file()
    assert run_tasks([task]).skipped == ["a"]  # before: redone once


def exhaust_memory(path: str) -> None:
    raise MemoryError("Unable to allocate 964 GiB")


def test_a_task_out_of_memory_stops_the_run_naming_the_task(tmp_path):
    first, second = tmp_path / "a.txt", tmp_path / "b.txt"
    tasks = [Task("simulate/r1", "simulate", exhaust_memory, (str(first),), (first,)),
             Task("simulate/r2", "simulate", write, (str(second),), (second,))]
    with pytest.raises(EnvironmentFailure, match=r"out of memory in task simulate/r1 "
                                                 r"\(Unable to allocate 964 GiB\)"):
        run_tasks(tasks)
    assert not second.exists()  # stopped at the first


def disk_full(path: str) -> None:
    """A task whose write fails for want of space (as io.atomic reports it)."""
    from eclipsebench.io.atomic import write_bytes

    real = os.replace

    def replace(src, dst, *args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device")

    os.replace = replace
    try:
        write_bytes(path, b"x" * 1000)
    finally:
        os.replace = real


@pytest.mark.slow  # a 2-worker cluster: ~15 s
@pytest.mark.timeout(300)
def test_a_full_disk_on_a_dask_worker_is_said_once_and_stops_the_run(tmp_path, capfd):
    import cloudpickle

    cloudpickle.register_pickle_by_value(sys.modules[__name__])
    full = tmp_path / "results" / "a.json"
    later = [tmp_path / f"later{i}.txt" for i in range(6)]
    tasks = [Task("full", "reduce", disk_full, (str(full),), (full,))]
    tasks += [Task(f"later{i}", "reduce", write, (str(p),), (p,), deps=("full",))
              for i, p in enumerate(later)]
    with pytest.raises(EnvironmentFailure) as failure:
        run_tasks(tasks, workers=2)
    assert failure.value.folder == str(full.parent) and failure.value.bytes_needed == 1000
    assert "no space left" in str(failure.value) and "1000 bytes needed" in str(failure.value)
    assert not any(p.exists() for p in later)
    out, err = capfd.readouterr()
    assert "Compute Failed" not in err and "Traceback" not in err, err


def test_the_errors_cross_from_a_worker_whole():
    """Before: a DataError or ConfigError raised on a Dask worker could not be unpickled."""
    import pickle

    from eclipsebench.errors import ConfigError, DataError

    for exc in (DataError("/x/t.fits", "truncated"), ConfigError("run.bootstrap", "too many"),
                EnvironmentFailure("/f/a: no space", folder="/f", bytes_needed=10)):
        back = pickle.loads(pickle.dumps(exc))
        assert type(back) is type(exc) and str(back) == str(exc)
        assert vars(back) == vars(exc)
