"""One kind of run per folder, and the content of the inputs the folder was made from.

Every runner (``run``, ``trust``, ``campaign``) keeps, beside its own settings file, a marker
``DIR/eclipsebench.json``::

    {"kind": "trust",
     "inputs": {"table": {"what": "the table /data/aor.fits", "sha256": "..."}, ...}}

and takes the one lock file ``DIR/run.lock`` (:mod:`.lock`) while it works.

* A folder belongs to one kind of run: another runner is refused in one line
  before it writes anything (:func:`check_kind`), so ``trust --out`` into a
  finished ``run`` folder cannot overwrite its report.
* The inputs a run reads from outside its folder (a user's table, pixel map,
  the planet's elements) are recorded by content (:mod:`eclipsebench.io.digest`).
  A rerun whose inputs changed is refused in one line that says what changed
  and how to go on (:func:`claim`): the one rule of every runner, so a rerun
  never mixes an old answer with new inputs.

A folder made before the marker existed is recognised by its settings file
(``run_config.toml``, ``trust_config.json``); it is resumed only when its run
reads no input from outside the package (the caller says so), since what it
was made from was not recorded.
"""

from __future__ import annotations

import json
import os
import shutil
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..errors import EnvironmentFailure, InputError
from ..io.atomic import write_json
from ..io.digest import value_sha256
from ..progress import get_logger

__all__ = ["MARKER", "LOCK", "Input", "folder_kind", "check_kind", "claim",
           "planet_input", "check_free_space"]

log = get_logger("challenge")

#: The marker of a run folder: its kind and the content of its inputs.
MARKER = "eclipsebench.json"
#: The one lock file of every runner.
LOCK = "run.lock"
#: Settings files of each kind, which mark a folder made before :data:`MARKER` existed.
_SETTINGS = {"run_config.toml": "run", "trust_config.json": "trust",
             "campaign_config.json": "campaign"}


@dataclass(frozen=True)
class Input:
    """An external input of a run, by content.

    Attributes
    ----------
    name : str
        Its key in the marker (``"table"``, ``"pmap"``, ``"system"``).
    what : str
        How a message names it (``"the table /data/aor.fits"``).
    sha256 : str
        The digest of its content.
    """

    name: str
    what: str
    sha256: str


def _marker(root: Path) -> dict | None:
    path = root / MARKER
    if not path.is_file():
        return None
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError):
        raise InputError(f"{path}: unreadable marker of a run folder; remove the folder or use "
                         "another --out") from None
    if not isinstance(data, dict) or not isinstance(data.get("kind"), str):
        raise InputError(f"{path}: not the marker of a run folder (no 'kind'); remove it or use "
                         "another --out")
    return data


def folder_kind(root: str | Path) -> tuple[str, str] | None:
    """``(kind, the file that says so)`` of the run folder ``root``, or None for a new one."""
    root = Path(root)
    data = _marker(root)
    if data is not None:
        return data["kind"], MARKER
    for name, kind in _SETTINGS.items():
        if (root / name).is_file():
            return kind, name
    return None


def check_kind(root: str | Path, kind: str) -> None:
    """Refuse, in one line, a folder that holds another kind of run (nothing is written).

    Raises
    ------
    InputError
        ``root`` holds a run of another kind (its marker or settings file names it).
    """
    held = folder_kind(root)
    if held is not None and held[0] != kind:
        raise InputError(f"{root}: holds the output of 'eclipsebench {held[0]}' (see {held[1]}); "
                         f"'eclipsebench {kind}' writes into a folder of its own: use another "
                         "--out")


def claim(root: str | Path, kind: str, inputs: Mapping[str, Input], *,
          legacy_ok: bool) -> None:
    """Check ``root``'s kind and recorded inputs against this run's, then record them.

    Call it holding the folder's lock, before any other write.

    Parameters
    ----------
    root : path
        The run folder.
    kind : str
        ``"run"`` or ``"trust"``.
    inputs : mapping of str to Input
        This run's external inputs by content.
    legacy_ok : bool
        Whether a folder made before the marker existed may be resumed (its
        inputs are then recorded as they are now): true only when nothing it
        reads comes from outside the package.

    Raises
    ------
    InputError
        One line: the folder holds another kind of run; an input changed since
        the folder was made (which, its old and new digests, and how to go on);
        or an old folder whose inputs were not recorded.
    """
    root = Path(root)
    check_kind(root, kind)
    data = _marker(root)
    current = {name: {"what": i.what, "sha256": i.sha256} for name, i in inputs.items()}
    if data is None:
        held = folder_kind(root)
        if held is not None and not legacy_ok:
            whats = ", ".join(i.what for i in inputs.values()) or "its inputs"
            raise InputError(f"{root}: made by an earlier eclipsebench that did not record the "
                             f"content of {whats}, so a rerun cannot tell whether they changed; "
                             "use another --out or remove it")
    else:
        recorded = data.get("inputs") or {}
        for name in sorted(set(recorded) | set(current)):
            old = (recorded.get(name) or {}).get("sha256")
            new = (current.get(name) or {}).get("sha256")
            if old != new:
                what = (current.get(name) or recorded.get(name) or {}).get("what", name)
                raise InputError(f"{root}: {what} changed since this folder was made (sha256 "
                                 f"{_short(old)}, now {_short(new)}); use another --out or "
                                 "remove it")
        if data.get("kind") == kind and recorded == current:
            return
    write_json(root / MARKER, {"kind": kind, "inputs": current})


def _short(digest: str | None) -> str:
    return digest[:12] if digest else "none"


def planet_input(system: Any) -> Input:
    """A planet's full element set as an :class:`Input` (its references, citations only,
    left out): the same name with other elements is another input.

    ``system`` is a :class:`~eclipsebench.astro.catalogue.PlanetSystem`.
    """
    elements = {k: v for k, v in system.to_dict().items() if k != "references"}
    return Input("system", f"the elements of planet {system.name!r}", value_sha256(elements))


def _size(n_bytes: float) -> str:
    """``n_bytes`` in the largest unit that keeps it above 1 (decimal units, as ``df -H``).

    Examples
    --------
    >>> _size(1.39e9), _size(512)
    ('1.39 GB', '512 B')
    """
    for unit, scale in (("TB", 1e12), ("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if n_bytes >= scale:
            return f"{n_bytes / scale:.2f} {unit}"
    return f"{int(n_bytes)} B"


def check_free_space(root: str | Path, bytes_needed: int, what: str) -> None:
    """Say how much a run will write, and refuse it when that does not fit the free space.

    Parameters
    ----------
    root : path
        The run folder (it need not exist yet: its nearest existing folder is asked).
    bytes_needed : int
        The estimate of what this invocation will write (what is already
        written is not counted again by the caller).
    what : str
        What the estimate counts, for the message (``"40 twins' tables, ..."``).

    Raises
    ------
    EnvironmentFailure
        The estimate exceeds the free space of the file system (exit 3), before
        anything is written.
    """
    folder = Path(os.path.abspath(root))
    while not folder.exists() and folder.parent != folder:
        folder = folder.parent
    free = shutil.disk_usage(folder).free
    log.info("%s: about %s to write (%s); %s free there", root, _size(bytes_needed), what,
             _size(free))
    if bytes_needed > free:
        raise EnvironmentFailure(f"{root}: this run would write about {_size(bytes_needed)} "
                                 f"({what}) where {_size(free)} are free; free space there or "
                                 "use another --out, and rerun", folder=str(folder),
                                 bytes_needed=int(bytes_needed))
