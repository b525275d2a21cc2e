"""One run per folder: a lock file created atomically (``O_EXCL``) holding the owner's pid.

A second run into the same folder is refused with one line naming the lock
file; a lock whose process is gone (killed, machine rebooted) is stale and
is taken over.
"""

from __future__ import annotations

import os
import socket
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from ..errors import InputError

__all__ = ["run_lock"]

#: A lock file still empty after this long was left by a process killed while creating it.
_EMPTY_GRACE_S = 10.0


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # exists, owned by another user
        return True
    return True


def _holder(path: Path) -> tuple[int, str] | None:
    """(pid, host) of a live holder of ``path``, or None when the lock is stale."""
    try:
        text = path.read_text()
        age = time.time() - path.stat().st_mtime
    except FileNotFoundError:
        return None
    parts = text.split()
    if len(parts) < 2 or not parts[0].isdigit():
        # being written right now by its creator, or left empty by a killed one
        return (0, "") if age < _EMPTY_GRACE_S else None
    pid, host = int(parts[0]), parts[1]
    if host != socket.gethostname():
        return pid, host  # cannot tell from here: assume it is alive
    return (pid, host) if _pid_alive(pid) else None


def _create(path: Path) -> bool:
    try:
        fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644)
    except FileExistsError:
        return False
    with os.fdopen(fd, "w") as fh:
        fh.write(f"{os.getpid()} {socket.gethostname()}\n")
    return True


@contextmanager
def run_lock(path: str | os.PathLike) -> Iterator[Path]:
    """Hold ``path`` for the duration of the block.

    Raises
    ------
    InputError
        Another live process holds the lock (the message names the file and pid).
    """
    path = Path(path)
    for _ in range(3):
        if _create(path):
            break
        holder = _holder(path)
        if holder is not None:
            who = f"pid {holder[0]}" + (f" on {holder[1]}" if holder[1] and
                                        holder[1] != socket.gethostname() else "")
            raise InputError(f"{path}: another run ({who if holder[0] else 'starting'}) is "
                             "working in this folder; wait for it to finish or use another "
                             "--out (remove the file if that run is gone)")
        try:  # stale: take it over
            path.unlink()
        except FileNotFoundError:
            pass
    else:
        raise InputError(f"{path}: could not take the lock (other runs are starting)")
    try:
        yield path
    finally:
        try:
            if path.read_text().split()[:1] == [str(os.getpid())]:
                path.unlink()
        except FileNotFoundError:
            pass
