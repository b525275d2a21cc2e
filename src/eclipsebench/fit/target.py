"""Which planet a reduction fits: the one asked for, else the one the data name.

A real observation is never reduced with the simulated challenge's planet by
default: the planet comes from ``system=`` (``--system``, ``--planet``), a
configuration that names one, or the table's own metadata (``SYSTEM`` written
by the simulator, ``OBJECT`` from the archive's headers, looked up through
the catalogue). A table that names no planet the catalogue knows stops the
reduction with one line asking for the planet.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from ..astro.catalogue import PlanetSystem, as_system, system_for, system_from_meta
from ..config.system import CHALLENGE_SYSTEM
from ..errors import InputError

__all__ = ["names_a_system", "system_of_table"]


def names_a_system(section: Any) -> bool:
    """Whether a ``[system]`` section names a planet of its own (not the built-in default)."""
    return bool(getattr(section, "planet", None)) or section.name != CHALLENGE_SYSTEM


def system_of_table(meta: Mapping[str, Any], *, system: Any = None, section: Any = None,
                    source: str = "the table", hint: str = "--system NAME") -> PlanetSystem:
    """The planet to fit to a table.

    Parameters
    ----------
    meta : mapping
        The photometry table's metadata (``SYSTEM``, ``OBJECT``, ...).
    system : str, mapping or PlanetSystem, optional
        The planet asked for; wins over everything else.
    section : SystemSection, optional
        The configuration's ``[system]``: used when it names a planet of its
        own (:func:`names_a_system`); its ``catalogue`` is searched first.
    source : str
        The table, as errors name it.
    hint : str
        How the caller gives a planet (``--system NAME`` or ``system=...``).

    Raises
    ------
    InputError
        One line naming the table, what its metadata say and ``hint``, when
        no planet is asked for and the table names none the catalogue knows.

    Examples
    --------
    >>> system_of_table({"OBJECT": "XO-3 ch2 peak-up"}).name
    'XO-3b'
    >>> system_of_table({"OBJECT": "XO-3"}, system="WASP-14b").name
    'WASP-14b'
    """
    catalogue = (getattr(section, "catalogue", "") or None) if section is not None else None
    if system is not None:
        return as_system(system, catalogue)
    if section is not None and names_a_system(section):
        return system_for(section)
    found, why = system_from_meta(meta, catalogue)
    if found is None:
        raise InputError(f"{source}: {why}; give the planet with {hint} (or --planet "
                         "KEY=VALUE for one in no catalogue)")
    return found
