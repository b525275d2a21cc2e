"""Output paths checked before any work, and folders a failed command leaves empty.

Every command that writes calls :func:`check_output_path` on its ``--out``
(and other output options) before reading or computing anything, so a path
that cannot be written (an existing folder where a file is expected, a
parent that is a regular file, a read-only folder, a pseudo file system such
as ``/proc``) is one line and exit code 2 instead of an internal error after
the work. The check creates nothing: a probe file is made and removed in the
nearest existing folder.

:func:`missing_folders` and :func:`remove_empty_folders` let the command line
remove the folders a failed or interrupted command created and left empty.
"""

from __future__ import annotations

import contextlib
import errno
import os
import re
import tempfile
from pathlib import Path
from typing import Literal

from ..errors import InputError

__all__ = ["check_output_path", "check_plot_path", "missing_folders", "remove_empty_folders",
           "SAFE_NAME", "is_safe_name", "check_name", "check_inside", "check_links_inside"]

#: A name that becomes one component of a path (a challenge's name, a method's, a
#: label): a letter or digit, then letters, digits, ``.``, ``_`` or ``-``. No ``/``,
#: no ``..``, no leading dot (hidden files, the stamps), no spaces or control characters.
SAFE_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9._-]*")
#: Longest name accepted (a file name is at most 255 bytes; room for suffixes).
MAX_NAME_CHARS = 100


def is_safe_name(name: object) -> bool:
    """Whether ``name`` can be one path component as it is (:data:`SAFE_NAME`).

    Examples
    --------
    >>> [is_safe_name(n) for n in ("kr-pmap", "xo3b-2015", "a/b", "../x", ".hidden", "")]
    [True, True, False, False, False, False]
    """
    return (isinstance(name, str) and len(name) <= MAX_NAME_CHARS
            and SAFE_NAME.fullmatch(name) is not None)


def check_name(key: str, name: object) -> str:
    """Return ``name`` if it is one safe path component; InputError naming ``key`` otherwise.

    Raises
    ------
    InputError
        One line naming ``key``, the name and the characters allowed.
    """
    if not is_safe_name(name):
        raise InputError(f"{key} {name!r}: expected a name of letters, digits, '.', '_' and '-' "
                         f"starting with a letter or digit (at most {MAX_NAME_CHARS} characters; "
                         "it becomes a folder or file name)")
    return str(name)


def check_inside(path: str | os.PathLike, root: str | os.PathLike) -> Path:
    """Return ``path`` if, resolved (symbolic links followed), it lies inside ``root``.

    A run folder that holds a symbolic link (``results -> elsewhere``, from an
    unpacked archive, say) would otherwise have its outputs written through it.

    Raises
    ------
    InputError
        One line naming the output, where it leads and the folder it must stay in.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> check_inside(d / "results" / "a.json", d) == d / "results" / "a.json"
    True
    """
    base = Path(os.path.realpath(root))
    real = Path(os.path.realpath(path))
    if real != base and base not in real.parents:
        raise InputError(f"{path}: leads to {real}, outside the run folder {base} (a symbolic "
                         "link inside it?); outputs stay in the run folder: remove the link or "
                         "use another --out")
    return Path(path)

Expect = Literal["file", "folder"]


def _exists(path: Path, option: str, shown: Path) -> bool:
    try:
        os.stat(path)
    except FileNotFoundError:
        return False
    except NotADirectoryError:
        return False  # a parent is a regular file: reported by the caller
    except PermissionError:
        raise InputError(f"{option} {shown}: permission denied reading {path.parent}") from None
    except OSError as exc:
        raise InputError(f"{option} {shown}: cannot inspect {path} ({exc.strerror})") from None
    return True


def _nearest_existing(path: Path, option: str, shown: Path) -> Path:
    folder = path
    while not _exists(folder, option, shown):
        if folder.parent == folder:
            break
        folder = folder.parent
    return folder


def check_output_path(path: str | os.PathLike, option: str = "--out",
                      expect: Expect = "file") -> Path:
    """Check that ``path`` can be written as a file (or created as a folder); return it.

    Parameters
    ----------
    path : path
        The output the command will write.
    option : str
        The option to name in the message, e.g. ``"--out"``.
    expect : "file" or "folder"
        What the command will write at ``path``.

    Raises
    ------
    InputError
        One line naming ``option`` and ``path`` and what was expected when
        ``path`` is an existing folder but a file is expected (or a file but
        a folder is expected), a parent is a regular file, or the nearest
        existing folder cannot be written (permission, read-only or pseudo
        file system).
    """
    text = os.fspath(path)
    what = "a folder" if expect == "folder" else "a file name"
    if not str(text).strip():
        raise InputError(f"{option}: expected {what}, got an empty path")
    p = Path(text)
    absolute = Path(os.path.abspath(p))
    if _exists(absolute, option, p):
        if expect == "file" and absolute.is_dir():
            raise InputError(f"{option} {p}: is an existing folder; expected {what}")
        if expect == "folder" and not absolute.is_dir():
            raise InputError(f"{option} {p}: exists and is not a folder; expected {what}")
    start = absolute if expect == "folder" else absolute.parent
    folder = _nearest_existing(start, option, p)
    if not folder.is_dir():
        raise InputError(f"{option} {p}: {folder} is a file, not a folder; expected {what} "
                         "in a folder")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise InputError(f"{option} {p}: permission denied: cannot write in {folder}")
    try:
        fd, probe = tempfile.mkstemp(prefix=".eclipsebench-probe-", dir=folder)
    except OSError as exc:
        reason = exc.strerror or str(exc)
        if exc.errno in (errno.ENOENT, errno.ENOTDIR, errno.EINVAL):
            reason = "not a writable file system"
        elif exc.errno in (errno.EACCES, errno.EPERM):
            reason = "permission denied"
        elif exc.errno == errno.EROFS:
            reason = "read-only file system"
        raise InputError(f"{option} {p}: cannot write in {folder} ({reason})") from None
    os.close(fd)
    with contextlib.suppress(OSError):
        os.unlink(probe)
    return p


def check_plot_path(path: str | os.PathLike, option: str = "--plot") -> Path:
    """:func:`check_output_path` for a figure, whose suffix must be a Matplotlib format.

    A name without a suffix is written as PNG.
    """
    p = check_output_path(path, option, "file")
    suffix = p.suffix.lower().lstrip(".")
    if suffix:
        # matplotlib (about 0.5 s to import) only when a plot is asked for.
        from matplotlib.backend_bases import FigureCanvasBase

        formats = FigureCanvasBase.get_supported_filetypes()
        if suffix not in formats:
            raise InputError(f"{option} {p}: unknown figure format '.{suffix}' (expected one of "
                             + ", ".join("." + f for f in sorted(formats)) + ")")
    return p


def missing_folders(path: str | os.PathLike | None) -> list[Path]:
    """``path`` and its ancestors that do not exist yet, deepest first.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> [p.relative_to(d).as_posix() for p in missing_folders(d / "a" / "b")]
    ['a/b', 'a']
    """
    if path is None or not str(os.fspath(path)).strip():
        return []
    out = []
    p = Path(os.path.abspath(os.fspath(path)))
    while p.parent != p:
        try:
            if os.path.lexists(p):
                break
        except OSError:
            break
        out.append(p)
        p = p.parent
    return out


def remove_empty_folders(folders: list[Path]) -> None:
    """Remove each of ``folders`` (deepest first) that is now an empty folder."""
    for folder in folders:
        with contextlib.suppress(OSError):
            if folder.is_dir() and not folder.is_symlink():
                folder.rmdir()  # only succeeds when empty


def check_links_inside(root: str | os.PathLike) -> None:
    """Refuse a symbolic link anywhere under ``root`` that leads out of it.

    Outputs that no task declares (a simulated AOR's cubes) are written into
    folders of the run; one walk of the existing folder (links not followed)
    finds every link before any work.

    Raises
    ------
    InputError
        One line naming the first link that leads out of ``root`` and where.
    """
    base = os.path.realpath(root)
    if not os.path.isdir(base):
        return
    folders = [base]
    while folders:  # scandir's entries know whether they are links: no stat per file
        with os.scandir(folders.pop()) as entries:
            for entry in entries:
                if entry.is_symlink():
                    check_inside(entry.path, base)
                elif entry.is_dir(follow_symlinks=False):
                    folders.append(entry.path)
