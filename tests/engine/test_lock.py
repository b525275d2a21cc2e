"""The run lock is a kernel lock (issue 28): released when its holder dies, never taken twice.

Before, the lock was a file whose pid was checked: two runs that both found
a stale file could both take it (the check and the removal were two steps),
and a file naming a dead pid was taken over even while another run held it.
"""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
from pathlib import Path

import pytest

import eclipsebench
from eclipsebench.engine.lock import run_lock
from eclipsebench.errors import InputError

HOLD = """
import sys, time
from eclipsebench.engine.lock import run_lock
with run_lock(sys.argv[1]):
    print("held", flush=True)
    time.sleep(120)
"""


def _dead_pid() -> int:
    p = subprocess.Popen([sys.executable, "-c", "pass"])
    p.wait()
    return p.pid


@pytest.fixture
def holder(tmp_path):
    """Another process holding ``tmp_path/run.lock``; killed at the end."""
    env = {**os.environ, "PYTHONPATH": str(Path(eclipsebench.__file__).parents[1])}
    lock = tmp_path / "run.lock"
    proc = subprocess.Popen([sys.executable, "-c", HOLD, str(lock)], stdout=subprocess.PIPE,
                            env=env, text=True)
    try:
        assert proc.stdout.readline().strip() == "held"
        yield proc, lock
    finally:
        proc.kill()
        proc.wait()
        proc.stdout.close()


def test_a_held_lock_is_refused_whatever_its_file_says(holder):
    proc, lock = holder
    assert lock.read_text().split()[:2] == [str(proc.pid), socket.gethostname()]
    with pytest.raises(InputError, match=f"pid {proc.pid}"):
        with run_lock(lock):
            pass
    # what a second run that judged the file stale would have written: the kernel still says no
    lock.write_text(f"{_dead_pid()} {socket.gethostname()}\n")
    with pytest.raises(InputError, match="another run"):
        with run_lock(lock):
            pass


def test_the_lock_of_a_killed_holder_is_free_at_once(holder):
    proc, lock = holder
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    assert lock.is_file()  # left behind, but no longer held
    with run_lock(lock):
        assert lock.read_text().split()[0] == str(os.getpid())
        with pytest.raises(InputError, match=f"pid {os.getpid()}"):  # not twice, not even here
            with run_lock(lock):
                pass
    assert not lock.exists()


def test_a_legacy_lock_file_of_a_live_process_is_respected(tmp_path):
    lock = tmp_path / "run.lock"
    lock.write_text(f"{os.getppid()} {socket.gethostname()}\n")  # no kernel lock, live pid
    with pytest.raises(InputError, match=f"pid {os.getppid()}"):
        with run_lock(lock):
            pass
    lock.write_text(f"{_dead_pid()} {socket.gethostname()}\n")  # stale
    with run_lock(lock):
        pass
    assert not lock.exists()


def test_a_hard_link_at_the_lock_s_name_does_not_change_the_linked_file(tmp_path):
    """Issue 37: a hard link named run.lock had its target rewritten by the run."""
    precious = tmp_path / "precious.txt"
    precious.write_text("keep me\n")
    lock = tmp_path / "run" / "run.lock"
    lock.parent.mkdir()
    os.link(precious, lock)
    with pytest.raises(InputError, match="2 links"):
        with run_lock(lock):
            pass
    assert precious.read_text() == "keep me\n"
    lock.unlink()
    lock.symlink_to(precious)                # a symbolic link is not followed either
    with pytest.raises(InputError, match="symbolic link"):
        with run_lock(lock):
            pass
    assert precious.read_text() == "keep me\n"
