"""Input files checked before they are read: regular files only, within a stated size.

A configuration, a catalogue or a pixel map is read whole, so a device
(``/dev/zero`` reads without end), a FIFO (blocks until a writer comes) or a
file of gigabytes would hang or exhaust memory. :func:`check_input_file`
refuses each in one line naming the file (exit code 2) before anything is
read; :func:`read_input_bytes` reads a checked file through one descriptor,
opened without blocking, so a FIFO is refused instead of waited on. The
limits are ``eclipsebench.limits``'s ``MAX_TEXT_FILE_BYTES`` and
``MAX_PMAP_FILE_BYTES``.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

from ..errors import InputError
from ..limits import size_problem

__all__ = ["check_input_file", "read_input_bytes"]


def _check_stat(path: Path, st: os.stat_result, what: str, limit_bytes: int) -> None:
    if stat.S_ISDIR(st.st_mode):
        raise InputError(f"{path}: is a folder; expected a {what}")
    if not stat.S_ISREG(st.st_mode):
        raise InputError(f"{path}: not a regular file (a device, FIFO or socket); expected a "
                         f"{what}")
    if st.st_size > limit_bytes:
        raise InputError(f"{path}: {size_problem(st.st_size, limit_bytes, 'bytes')} for a "
                         f"{what}")


def check_input_file(path: str | os.PathLike[str], what: str, limit_bytes: int) -> Path:
    """Refuse ``path`` unless it is a regular file of at most ``limit_bytes``.

    Parameters
    ----------
    path : path
        The file named by the user (a symbolic link is followed).
    what : str
        What the file should be, for the message: ``"configuration file (TOML)"``.
    limit_bytes : int
        The largest size accepted (a constant of ``eclipsebench.limits``).

    Returns
    -------
    Path
        ``path``, for chaining.

    Raises
    ------
    InputError
        One line naming the file: missing, unreadable, a folder, not a
        regular file (``/dev/zero``, a FIFO), or above ``limit_bytes``.

    Examples
    --------
    >>> check_input_file("/dev/zero", "configuration file", 100)
    Traceback (most recent call last):
    ...
    eclipsebench.errors.InputError: /dev/zero: not a regular file (a device, FIFO or socket); expected a configuration file
    """
    p = Path(path)
    try:
        st = os.stat(p)
    except FileNotFoundError:
        raise InputError(f"{p}: no such {what}") from None
    except OSError as exc:
        raise InputError(f"{p}: cannot read ({exc.strerror})") from None
    _check_stat(p, st, what, limit_bytes)
    return p


def read_input_bytes(path: str | os.PathLike[str], what: str, limit_bytes: int) -> bytes:
    """The bytes of ``path``, checked as :func:`check_input_file` through the open descriptor.

    The file is opened without blocking (a FIFO opens at once and is then
    refused) and its status taken from the descriptor, so what is checked is
    what is read; at most ``limit_bytes + 1`` bytes are read (a file that grew
    is refused all the same).

    Raises
    ------
    InputError
        As :func:`check_input_file`.
    """
    p = Path(path)
    try:
        fd = os.open(p, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
    except FileNotFoundError:
        raise InputError(f"{p}: no such {what}") from None
    except IsADirectoryError:
        raise InputError(f"{p}: is a folder; expected a {what}") from None
    except OSError as exc:
        raise InputError(f"{p}: cannot read ({exc.strerror})") from None
    with os.fdopen(fd, "rb") as fh:
        _check_stat(p, os.fstat(fd), what, limit_bytes)
        try:
            data = fh.read(limit_bytes + 1)
        except OSError as exc:
            raise InputError(f"{p}: cannot read ({exc.strerror})") from None
    if len(data) > limit_bytes:
        raise InputError(f"{p}: {size_problem(len(data), limit_bytes, 'bytes')} for a {what}")
    return data
