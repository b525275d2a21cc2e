"""Write files so that a reader never sees half of one.

Everything is written to a temporary file in the destination folder and then
renamed over the destination (``os.replace`` is atomic on POSIX), so an
interrupted run leaves either the old file, the complete new one, or nothing.
A write that fails because of the machine (a full disk, a quota, a folder
that became unwritable) is an :class:`~eclipsebench.errors.EnvironmentFailure`
naming the destination, its folder and the bytes needed when known; any other
failed write is a :class:`~eclipsebench.errors.DataError` naming the
destination. Either way the temporary file is removed.

Within :func:`confined_to` (the engine holds it around every task of a run,
in whichever process runs it) each write checks, when it starts and again
just before the rename, that its folder's real path lies inside the run
folder: a symbolic link made inside the run folder while the run works
cannot send an output elsewhere (the checks of :mod:`.paths` run before the
work only).
"""

from __future__ import annotations

import contextlib
import errno
import json
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path

from ..errors import ENVIRONMENT_ERRNOS, DataError, EnvironmentFailure
from .paths import check_inside

__all__ = ["atomic_path", "write_bytes", "write_text", "write_json", "confined_to"]

#: The run folders writes are confined to in this process (innermost last).
_ROOTS: list[Path] = []


@contextlib.contextmanager
def confined_to(root: str | os.PathLike | None) -> Iterator[None]:
    """Within the block, refuse any atomic write whose folder resolves outside ``root``.

    ``None`` confines nothing (a write outside a run).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> with confined_to(d / "run"):
    ...     _ = write_text(d / "run" / "a.txt", "in")
    ...     try:
    ...         _ = write_text(d / "b.txt", "out")
    ...     except Exception as exc:
    ...         print(type(exc).__name__)
    InputError
    """
    if root is None:
        yield
        return
    _ROOTS.append(Path(os.path.realpath(root)))
    try:
        yield
    finally:
        _ROOTS.pop()


def _check_confined(dest: Path) -> None:
    if _ROOTS:
        check_inside(dest.parent, _ROOTS[-1])


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike, suffix: str | None = None, *,
                size_bytes: int | None = None) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; rename it to ``path`` on success.

    On an exception the temporary file is removed and ``path`` is untouched.
    The temporary name keeps the destination's suffix (unless ``suffix`` is
    given) so that writers which choose a format by extension still work.
    ``size_bytes``, when the caller knows it, is named in the message of a
    write that fails for want of space.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> with atomic_path(d / "a.txt") as tmp:
    ...     _ = tmp.write_text("hello")
    >>> (d / "a.txt").read_text()
    'hello'
    """
    dest = Path(path)
    _check_confined(dest)   # before any folder is made through a link
    try:
        dest.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp_name = tempfile.mkstemp(
            prefix=f".{dest.name}.",
            suffix=".tmp" + (suffix if suffix is not None else dest.suffix), dir=dest.parent)
    except OSError as exc:
        raise _write_error(dest, exc, size_bytes=size_bytes) from None
    os.close(fd)
    tmp = Path(tmp_name)
    tmp.unlink()  # writers such as astropy refuse to overwrite an existing file
    try:
        yield tmp
        _check_confined(dest)   # a link made while the file was written
        os.replace(tmp, dest)
    except BaseException as exc:
        with contextlib.suppress(OSError):
            tmp.unlink()
        if isinstance(exc, OSError):
            raise _write_error(dest, exc, nothing_written=True, size_bytes=size_bytes) from None
        raise


def _write_error(dest: Path, exc: OSError, *, nothing_written: bool = False,
                 size_bytes: int | None = None) -> Exception:
    """The one-line error of a failed write: the machine's (EnvironmentFailure) or the file's."""
    tail = "; nothing was written" if nothing_written else ""
    if exc.errno in ENVIRONMENT_ERRNOS:
        needed = f", {size_bytes} bytes needed" if size_bytes is not None else ""
        hint = ("free space there and rerun" if exc.errno in (errno.ENOSPC, errno.EDQUOT)
                else "raise the file-size limit (ulimit -f) and rerun"
                if exc.errno == errno.EFBIG else "make it writable and rerun" if exc.errno in (errno.EACCES, errno.EPERM,
                                                                    errno.EROFS)
                else "rerun when the device is back")
        return EnvironmentFailure(f"{dest}: cannot write in {dest.parent} ({_reason(exc)}"
                                  f"{needed}){tail}; {hint}",
                                  folder=str(dest.parent), bytes_needed=size_bytes)
    return DataError(dest, f"cannot write ({_reason(exc)}){tail}")


def _reason(exc: OSError) -> str:
    """``strerror`` of an OSError, or its text when it has none (e.g. numpy's short writes)."""
    if exc.errno == errno.ENOSPC:
        return "no space left on the device"
    if exc.strerror:
        return exc.strerror
    text = str(exc).strip()
    return text.splitlines()[0] if text else type(exc).__name__


def write_bytes(path: str | os.PathLike, data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically and return the path."""
    with atomic_path(path, size_bytes=len(data)) as tmp:
        tmp.write_bytes(data)
    return Path(path)


def write_text(path: str | os.PathLike, text: str) -> Path:
    """Write ``text`` (UTF-8) to ``path`` atomically and return the path."""
    return write_bytes(path, text.encode("utf-8"))


def write_json(path: str | os.PathLike, obj: object) -> Path:
    """Write ``obj`` as indented, key-sorted JSON atomically (stable bytes)."""
    return write_text(path, json.dumps(obj, indent=2, sort_keys=True, allow_nan=True) + "\n")
