"""One run per folder: a lock file held with a kernel lock (``flock``) while a run works.

The file ``run.lock`` holds ``pid host flock`` for the messages, but what
decides is the kernel's ``flock`` on it: the kernel releases it when its
holder ends in any way (killed, crashed), so there is no stale lock to
detect and no window between "the lock is stale" and "take it over" in
which two runs could both take it (issue 28). A second run into the same
folder is refused with one line naming the lock file and the holder's pid.

A lock file without the ``flock`` mark was written by a version that did
not hold a kernel lock: its pid decides, as it did then (a live process on
this host, or any process on another host, holds it).

The lock file is opened without following a symbolic link (``O_NOFOLLOW``)
and must be a regular file with one link: a link planted at its name (a
symbolic link, or a hard link to a file of the user's) is refused in one
line, never written through.
"""

from __future__ import annotations

import contextlib
import errno
import fcntl
import os
import socket
import stat
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from ..errors import InputError

__all__ = ["run_lock"]

#: The last word of a lock file whose holder keeps a kernel lock on it.
FLOCK_MARK = "flock"
#: Attempts at locking the file at the path (another run may replace it meanwhile).
_ATTEMPTS = 5


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # exists, owned by another user
        return True
    return True


def _read(fd: int) -> list[str]:
    os.lseek(fd, 0, os.SEEK_SET)
    return os.read(fd, 4096).decode("utf-8", "replace").split()


def _legacy_holder(words: list[str]) -> tuple[int, str] | None:
    """(pid, host) of a live holder named by a lock file without the kernel-lock mark."""
    if len(words) < 2 or not words[0].isdigit() or words[-1] == FLOCK_MARK:
        return None
    pid, host = int(words[0]), words[1]
    if host != socket.gethostname():
        return pid, host  # cannot tell from here: assume it is alive
    return (pid, host) if pid != os.getpid() and _pid_alive(pid) else None


def _same_file(fd: int, path: Path) -> bool:
    try:
        a, b = os.fstat(fd), os.stat(path)
    except FileNotFoundError:
        return False
    return (a.st_dev, a.st_ino) == (b.st_dev, b.st_ino)


def _refusal(path: Path, words: list[str]) -> InputError:
    pid = words[0] if words and words[0].isdigit() else ""
    host = words[1] if len(words) > 1 and words[1] != FLOCK_MARK else ""
    who = f"pid {pid}" if pid else "starting"
    if pid and host and host != socket.gethostname():
        who += f" on {host}"
    return InputError(f"{path}: another run ({who}) is working in this folder; wait for it to "
                      "finish or use another --out")


def _open(path: Path) -> int:
    """``path`` opened for the lock, never through a link; InputError for a planted link."""
    try:
        fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW | os.O_CLOEXEC, 0o644)
    except OSError as exc:
        if exc.errno == errno.ELOOP:
            raise InputError(f"{path}: the lock file is a symbolic link; remove it (a run never "
                             "writes through a link)") from None
        raise
    info = os.fstat(fd)
    if not stat.S_ISREG(info.st_mode) or info.st_nlink != 1:
        os.close(fd)
        what = ("not a regular file" if not stat.S_ISREG(info.st_mode)
                else f"a file with {info.st_nlink} links (a hard link to another file?)")
        raise InputError(f"{path}: the lock file is {what}; remove it (a run never writes "
                         "into a file linked elsewhere)")
    return fd


def _acquire(path: Path) -> int:
    """A descriptor of ``path`` holding its kernel lock; InputError when another run holds it."""
    for _ in range(_ATTEMPTS):
        fd = _open(path)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            words = _read(fd)
            os.close(fd)
            raise _refusal(path, words) from None
        except BaseException:
            os.close(fd)
            raise
        if _same_file(fd, path):  # not a file its last holder removed as we opened it
            return fd
        os.close(fd)
    raise InputError(f"{path}: could not take the lock (other runs are starting)")


@contextmanager
def run_lock(path: str | os.PathLike) -> Iterator[Path]:
    """Hold ``path`` (a kernel lock on it) for the duration of the block.

    Raises
    ------
    InputError
        Another live process holds the lock (the message names the file and pid).
    """
    path = Path(path)
    fd = _acquire(path)
    try:
        legacy = _legacy_holder(_read(fd))
        if legacy is not None:
            raise _refusal(path, [str(legacy[0]), legacy[1]])
        os.ftruncate(fd, 0)
        os.lseek(fd, 0, os.SEEK_SET)
        os.write(fd, f"{os.getpid()} {socket.gethostname()} {FLOCK_MARK}\n".encode())
        yield path
    finally:
        with contextlib.suppress(OSError):
            if _same_file(fd, path) and _read(fd)[:1] == [str(os.getpid())]:
                path.unlink()  # removed while still locked: nobody can have taken it
        os.close(fd)  # the kernel lock goes with the descriptor
