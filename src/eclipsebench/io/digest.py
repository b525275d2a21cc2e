"""What an input *is*: SHA-256 of a file's bytes, of several files, of a JSON-able value.

A run folder records its external inputs (a photometry table, a pixel map,
the planet's elements) by these digests, never by path or name alone, so a
file replaced at the same path or a planet edited under the same name is
seen (:mod:`eclipsebench.engine.folder`). The engine's task stamps hash
outputs with the same function.
"""

from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from .plain import json_safe

__all__ = ["file_sha256", "files_sha256", "value_sha256"]

#: Bytes read at a time while hashing (a table is streamed, never held whole).
_BLOCK = 1 << 20


def file_sha256(path: str | os.PathLike) -> str:
    """SHA-256 (hex) of the bytes of the file at ``path``, streamed.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "a.txt"
    >>> _ = p.write_bytes(b"abc")
    >>> file_sha256(p)[:16]
    'ba7816bf8f01cfea'
    """
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(_BLOCK), b""):
            h.update(block)
    return h.hexdigest()


def files_sha256(paths: Iterable[str | os.PathLike]) -> str:
    """One SHA-256 over several files: each file's name and the digest of its bytes, by name.

    The folder a file lies in does not count, so the same map files copied
    elsewhere give the same digest; a file renamed, added or changed does not.
    """
    h = hashlib.sha256()
    for path in sorted(Path(p) for p in paths):
        h.update(f"{path.name}\0{file_sha256(path)}\n".encode())
    return h.hexdigest()


def value_sha256(value: Any) -> str:
    """SHA-256 of a JSON-able value in a canonical form (sorted keys, no spaces).

    Examples
    --------
    >>> value_sha256({"b": 1, "a": (2.0, 3)}) == value_sha256({"a": [2.0, 3], "b": 1})
    True
    """
    text = json.dumps(json_safe(value, nonfinite="repr"), sort_keys=True, separators=(",", ":"), allow_nan=False)
    return hashlib.sha256(text.encode()).hexdigest()
