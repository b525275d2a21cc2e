"""The system catalogue: planets with literature values and their references.

The built-in catalogue is ``eclipsebench/data/systems.toml`` (one table per
planet); a user catalogue is a TOML file of the same form, given by path.
Names match case-insensitively, ignoring spaces, hyphens, underscores and
brackets (``xo3b`` finds ``XO-3b``); a table's optional ``aliases = [...]``
gives more names it is found by (``xo3b-challenge2015`` finds
``XO-3b (2015 challenge)``, the 2015 data challenge's elements).

A planet in no catalogue is given by its values: on the command line as
``--planet KEY=VALUE`` pairs (:func:`system_from_pairs`), in a configuration
as a ``[system.planet]`` table (:func:`system_for`), or to the Python API as
a mapping (:func:`as_system`); each is checked exactly as a catalogue row.

Examples
--------
>>> s = get_system("XO-3b")
>>> s.period_days, s.ecc
(3.1915239, 0.2769)
>>> c = get_system("xo3b-challenge2015")
>>> c.name, c.ecc, c.omega_deg
('XO-3b (2015 challenge)', 0.2884, 346.0)
"""

from __future__ import annotations

import math
import re
import tomllib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, fields
from functools import cached_property
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..errors import InputError
from ..io.inputs import read_input_bytes
from ..limits import MAX_TEXT_FILE_BYTES
from .times import BMJD_OFFSET

if TYPE_CHECKING:  # pragma: no cover
    from .orbit import OrbitClock

__all__ = ["PlanetSystem", "get_system", "list_systems", "load_catalogue", "system_from_mapping",
           "planet_table_from_pairs", "system_from_pairs", "system_for", "as_system",
           "host_star", "system_for_object", "system_from_meta",
           "PLANET_KEYS", "REQUIRED_KEYS"]

_REQUIRED = ("period_days", "t_transit_bjd", "ecc", "omega_deg", "inc_deg", "a_rs", "rp_rs",
             "teff_star_k")


@dataclass(frozen=True)
class PlanetSystem:
    """One star-planet system.

    Attributes
    ----------
    name : str
    period_days : float
        Orbital period.
    t_transit_bjd : float
        An observed mid-transit time, BJD_TDB.
    ecc, omega_deg : float
        Eccentricity and argument of periastron of the planet's orbit (deg).
    inc_deg : float
        Orbital inclination (deg).
    a_rs, rp_rs : float
        Semi-major axis and planet radius in stellar radii.
    teff_star_k : float
        Stellar effective temperature (K); the star is a blackbody at this
        temperature in the flux ratio.
    r_star_rsun : float
        Stellar radius in solar radii (sets the light-travel time only).
    ld_quadratic : tuple of float
        Quadratic limb-darkening coefficients (u1, u2) at 4.5 um for transits.
    v_mag : float or None
        V magnitude of the star.
    ra_deg, dec_deg : float or None
        The star's right ascension and declination (J2000, degrees): the
        direction of the barycentric correction of times taken at the
        observer (:mod:`eclipsebench.astro.timescales`).
    references : dict
        Source of each value, ``{field: "citation"}``.
    """

    name: str
    period_days: float
    t_transit_bjd: float
    ecc: float
    omega_deg: float
    inc_deg: float
    a_rs: float
    rp_rs: float
    teff_star_k: float
    r_star_rsun: float = 1.0
    ld_quadratic: tuple[float, float] = (0.1, 0.1)
    v_mag: float | None = None
    ra_deg: float | None = None
    dec_deg: float | None = None
    references: dict[str, str] = field(default_factory=dict, compare=False, hash=False)

    def __post_init__(self) -> None:
        self.validate()

    def validate(self) -> None:
        """Raise :class:`InputError` (one line naming the value) for an impossible system."""
        def bad(key: str, expected: str) -> None:
            value = getattr(self, key)
            raise InputError(f"system {self.name!r}: {key} = {value!r}, expected {expected}")

        for key in _REQUIRED + ("r_star_rsun",):
            value = getattr(self, key)
            if not isinstance(value, (int, float)) or isinstance(value, bool) \
                    or not math.isfinite(value):
                bad(key, "a finite number")
        if not 0.0 <= self.ecc < 1.0:
            bad("ecc", "0 <= e < 1")
        if self.period_days <= 0:
            bad("period_days", "a positive period")
        if self.a_rs < 1.0:
            bad("a_rs", "a/R* >= 1 (the planet orbits outside the star)")
        if self.a_rs * (1.0 - self.ecc) <= 1.0 + self.rp_rs:
            raise InputError(f"system {self.name!r}: periastron a(1-e) = "
                             f"{self.a_rs * (1 - self.ecc):.3g} R*, expected > 1 + Rp/R* "
                             "(the planet would graze the star)")
        if self.rp_rs <= 0.0:
            bad("rp_rs", "Rp/R* > 0")
        if self.rp_rs >= 1.0:
            bad("rp_rs", "Rp/R* < 1")
        if not 0.0 < self.inc_deg <= 180.0:
            bad("inc_deg", "0 < i <= 180 deg")
        if self.teff_star_k <= 0:
            bad("teff_star_k", "a positive temperature in K")
        if self.r_star_rsun <= 0:
            bad("r_star_rsun", "a positive radius in solar radii")
        if len(self.ld_quadratic) != 2:
            bad("ld_quadratic", "two coefficients [u1, u2]")
        for key, low, high in (("ra_deg", 0.0, 360.0), ("dec_deg", -90.0, 90.0)):
            value = getattr(self, key)
            if value is not None and (not isinstance(value, (int, float))
                                      or isinstance(value, bool) or not math.isfinite(value)
                                      or not low <= value <= high):
                bad(key, f"degrees from {low:g} to {high:g}")
        if (self.ra_deg is None) != (self.dec_deg is None):
            bad("ra_deg" if self.ra_deg is None else "dec_deg",
                "a value with the other coordinate (give both ra_deg and dec_deg)")

    # -------------------------------------------------------------- derived values
    @property
    def t_transit_bmjd(self) -> float:
        """The catalogue transit time as BMJD_TDB."""
        return self.t_transit_bjd - BMJD_OFFSET

    @property
    def impact_parameter(self) -> float:
        """Transit impact parameter ``b = a cos i (1 - e^2)/(1 + e sin omega)``."""
        w = math.radians(self.omega_deg)
        return (self.a_rs * math.cos(math.radians(self.inc_deg))
                * (1 - self.ecc ** 2) / (1 + self.ecc * math.sin(w)))

    @cached_property
    def clock(self) -> OrbitClock:
        """The orbit's geometric clock (built once per system)."""
        from .orbit import OrbitClock  # numpy, scipy: the catalogue alone stays light (CLI)

        return OrbitClock(self)

    def to_dict(self) -> dict[str, Any]:
        out = {f.name: getattr(self, f.name) for f in fields(self)}
        out["ld_quadratic"] = list(self.ld_quadratic)
        out["references"] = dict(self.references)
        return out


def _normalise(name: str) -> str:
    return "".join(ch for ch in name.lower() if ch.isalnum())


def _aliases(name: str, table: dict[str, Any], where: str = "") -> list[str]:
    """The table's ``aliases`` (a list of names; empty when absent)."""
    aliases = table.get("aliases", [])
    if not isinstance(aliases, list) or not all(isinstance(a, str) and a.strip()
                                                for a in aliases):
        raise InputError(f"{where}system {name!r}: aliases must be a list of names")
    return aliases


def system_from_mapping(name: str, table: dict[str, Any], *, source: str = "") -> PlanetSystem:
    """Build a :class:`PlanetSystem` from one catalogue table, with one-line errors.

    The table's ``aliases`` (other names to look it up by) are checked and
    not stored.
    """
    where = f"{source}: " if source else ""
    if not isinstance(table, dict):
        raise InputError(f"{where}system {name!r}: expected a table of values")
    _aliases(name, table, where)
    table = {k: v for k, v in table.items() if k != "aliases"}
    known = {f.name for f in fields(PlanetSystem)} - {"name"}
    unknown = sorted(set(table) - known)
    if unknown:
        raise InputError(f"{where}system {name!r}: unknown key {unknown[0]!r} "
                         f"(known: {', '.join(sorted(known))})")
    missing = [k for k in _REQUIRED if k not in table]
    if missing:
        raise InputError(f"{where}system {name!r}: missing {', '.join(missing)}")
    kwargs = dict(table)
    if "ld_quadratic" in kwargs:
        kwargs["ld_quadratic"] = tuple(float(u) for u in kwargs["ld_quadratic"])
    if "references" in kwargs and not isinstance(kwargs["references"], dict):
        raise InputError(f"{where}system {name!r}: references must be a table "
                         "{field = \"citation\"}")
    try:
        return PlanetSystem(name=name, **kwargs)
    except InputError as exc:
        raise InputError(f"{where}{exc}") from None
    except TypeError as exc:
        raise InputError(f"{where}system {name!r}: {exc}") from None


def load_catalogue(catalogue: str | Path | None = None) -> dict[str, dict[str, Any]]:
    """The raw tables of a catalogue (built-in when ``catalogue`` is None or empty)."""
    if catalogue in (None, ""):
        text = resources.files("eclipsebench.data").joinpath("systems.toml").read_text("utf-8")
        source = "built-in catalogue"
    else:
        path = Path(catalogue)
        source = str(path)
        # a regular file within the stated size: not a device (/dev/zero) nor a FIFO
        raw = read_input_bytes(path, "catalogue file", MAX_TEXT_FILE_BYTES)
        try:
            text = raw.decode("utf-8")
        except UnicodeDecodeError as exc:
            raise InputError(f"{path}: not UTF-8 text (byte 0x{raw[exc.start]:02x} at offset "
                             f"{exc.start}); expected a UTF-8 TOML catalogue") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{source}: not valid TOML ({exc})") from None
    systems = data.get("systems", data)
    if not isinstance(systems, dict):
        raise InputError(f"{source}: expected tables of systems")
    return {k: v for k, v in systems.items() if isinstance(v, dict)}


def list_systems(catalogue: str | Path | None = None) -> list[str]:
    """Names of the systems in a catalogue (built-in by default)."""
    return list(load_catalogue(catalogue))


def get_system(name: str, catalogue: str | Path | None = None) -> PlanetSystem:
    """Look a planet up by name.

    Parameters
    ----------
    name : str
        Planet name or alias, e.g. ``"XO-3b"`` or ``"xo3b-challenge2015"``
        (case, spaces, hyphens and brackets ignored).
    catalogue : str or Path, optional
        A user TOML catalogue; searched first, then the built-in one.

    Raises
    ------
    InputError
        For an unknown name or impossible values (e >= 1, a/R* < 1,
        Rp/R* <= 0, ...), with one line naming the problem.
    """
    sources = []
    if catalogue not in (None, ""):
        sources.append((str(catalogue), load_catalogue(catalogue)))
    sources.append(("", load_catalogue(None)))
    key = _normalise(name)
    for source, tables in sources:
        for sys_name, table in tables.items():
            if _normalise(sys_name) == key:
                return system_from_mapping(sys_name, table, source=source)
        for sys_name, table in tables.items():
            where = f"{source}: " if source else ""
            if key in {_normalise(a) for a in _aliases(sys_name, table, where)}:
                return system_from_mapping(sys_name, table, source=source)
    known = sorted({n for _, tables in sources for n in tables})
    searched = " and ".join(["the built-in catalogue"] + [s for s, _ in sources if s])
    raise InputError(f"unknown planet {name!r} (searched {searched}; known: {', '.join(known)})")


# ------------------------------------------------------------------ planets given by value
#: The keys of a planet given by value (``--planet KEY=VALUE``): its name and
#: every catalogue field but the references.
PLANET_KEYS = ("name",) + tuple(f.name for f in fields(PlanetSystem)
                                if f.name not in ("name", "references"))
#: The values every planet needs (a catalogue row, ``--planet`` or ``[system.planet]``).
REQUIRED_KEYS = _REQUIRED


def _pair_value(key: str, text: str, item: str) -> Any:
    """One ``--planet`` value: a number, two numbers for ``ld_quadratic``, text for ``name``."""
    def number(part: str) -> float:
        try:
            value = float(part)
        except ValueError:
            raise InputError(f"--planet {item!r}: expected a number for {key}") from None
        if not math.isfinite(value):
            raise InputError(f"--planet {item!r}: expected a finite number for {key}")
        return value

    if key == "name":
        if not text:
            raise InputError(f"--planet {item!r}: expected a planet name")
        return text
    if key == "ld_quadratic":
        parts = [p.strip() for p in text.strip("[]() ").split(",")]
        if len(parts) != 2:
            raise InputError(f"--planet {item!r}: expected two coefficients, ld_quadratic=U1,U2")
        return [number(p) for p in parts]
    return number(text)


def planet_table_from_pairs(pairs: Sequence[str]) -> tuple[str, dict[str, Any]]:
    """The name and the catalogue table of ``--planet KEY=VALUE`` pairs, not yet checked.

    Parameters
    ----------
    pairs : sequence of str
        ``"name=..."`` and one ``"KEY=VALUE"`` per catalogue field
        (:data:`PLANET_KEYS`); ``ld_quadratic=U1,U2``.

    Returns
    -------
    name : str
    table : dict
        The values as a catalogue row (``{"period_days": 3.19, ...}``).

    Raises
    ------
    InputError
        One line naming the pair: not KEY=VALUE, an unknown or repeated key,
        a value that is not a number, or no ``name``.

    Examples
    --------
    >>> planet_table_from_pairs(["name=test-b", "period_days=3.2", "ld_quadratic=0.1,0.2"])
    ('test-b', {'period_days': 3.2, 'ld_quadratic': [0.1, 0.2]})
    """
    table: dict[str, Any] = {}
    for item in pairs:
        key, sep, text = (part.strip() for part in item.partition("="))
        if not sep or not key:
            raise InputError(f"--planet {item!r}: expected KEY=VALUE, e.g. period_days=3.19")
        if key not in PLANET_KEYS:
            raise InputError(f"--planet {item!r}: unknown key {key!r} "
                             f"(known: {', '.join(PLANET_KEYS)})")
        if key in table:
            raise InputError(f"--planet: {key} is given twice")
        table[key] = _pair_value(key, text, item)
    name = table.pop("name", None)
    if name is None:
        raise InputError("--planet: missing name (give name=... with the other values)")
    return name, table


def system_from_pairs(pairs: Sequence[str]) -> PlanetSystem:
    """A :class:`PlanetSystem` from ``--planet KEY=VALUE`` pairs, checked as a catalogue row.

    Examples
    --------
    >>> s = system_from_pairs(["name=test-b", "period_days=3.19", "t_transit_bjd=2454449.868",
    ...                        "ecc=0.28", "omega_deg=347", "inc_deg=84.2", "a_rs=7.07",
    ...                        "rp_rs=0.09", "teff_star_k=6429"])
    >>> s.name, s.period_days, s.references
    ('test-b', 3.19, {})
    >>> system_from_pairs(["name=test-b", "period_days=3.19"])
    Traceback (most recent call last):
    ...
    eclipsebench.errors.InputError: --planet: system 'test-b': missing t_transit_bjd, ecc, \
omega_deg, inc_deg, a_rs, rp_rs, teff_star_k
    """
    name, table = planet_table_from_pairs(pairs)
    return system_from_mapping(name, table, source="--planet")


def system_for(section: Any) -> PlanetSystem:
    """The planet of a ``[system]`` configuration section.

    Its ``planet`` table when one is given (the planet's own values, named
    ``name``), else ``name`` looked up in ``catalogue`` and the built-in
    catalogue. ``section`` is a :class:`~eclipsebench.config.system.SystemSection`
    or anything with ``name``, ``catalogue`` and (optionally) ``planet``.

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> system_for(SimpleNamespace(name="XO-3b", catalogue="", planet={})).ecc
    0.2769
    """
    planet = getattr(section, "planet", None)
    if planet:
        return system_from_mapping(section.name, dict(planet), source="[system] planet")
    return get_system(section.name, section.catalogue or None)


def as_system(system: Any, catalogue: str | Path | None = None) -> PlanetSystem:
    """A :class:`PlanetSystem` from a name, a mapping of its values, or itself.

    Parameters
    ----------
    system : str, Mapping or PlanetSystem
        A name (looked up in ``catalogue``, then the built-in catalogue), or
        a mapping with ``name`` and the catalogue fields (checked as a row).
    catalogue : str or Path, optional

    Examples
    --------
    >>> as_system({"name": "test-b", "period_days": 3.19, "t_transit_bjd": 2454449.868,
    ...            "ecc": 0.0, "omega_deg": 90.0, "inc_deg": 86.0, "a_rs": 7.0,
    ...            "rp_rs": 0.1, "teff_star_k": 6000.0}).a_rs
    7.0
    """
    if isinstance(system, PlanetSystem):
        return system
    if isinstance(system, str):
        return get_system(system, catalogue)
    if isinstance(system, Mapping):
        table = dict(system)
        name = table.pop("name", None)
        if not isinstance(name, str) or not name.strip():
            raise InputError("system: a mapping of the planet's values needs its name, "
                             "name = \"...\"")
        return system_from_mapping(name, table, source="system")
    raise InputError(f"system: expected a planet name, a mapping of its values or a "
                     f"PlanetSystem, got {type(system).__name__}")


# ------------------------------------------------------------------ the planet of the data
_PLANET_LETTER = re.compile(r"^(?P<host>.*?\S)[\s-]*(?P<letter>[b-z])$")


def host_star(planet_name: str) -> str | None:
    """The host star of a planet name (``"XO-3b"`` -> ``"XO-3"``, ``"55 Cnc e"`` -> ``"55 Cnc"``).

    None for a name that does not end in a planet letter, such as the challenge's
    ``"XO-3b (2015 challenge)"``: a qualified row is never found by its star.

    Examples
    --------
    >>> host_star("HD 189733b"), host_star("55 Cnc e"), host_star("XO-3b (2015 challenge)")
    ('HD 189733', '55 Cnc', None)
    """
    m = _PLANET_LETTER.match(planet_name.strip())
    return m["host"] if m else None


def _starts_with_star(text: str, star: str) -> bool:
    """``text`` (normalised) begins with ``star`` (normalised) and no digit follows it
    (``XO-3 ch2`` is XO-3, ``XO-31`` is not)."""
    rest = text[len(star):] if text.startswith(star) else None
    return rest is not None and not rest[:1].isdigit()


def system_for_object(object_name: str, catalogue: str | Path | None = None
                      ) -> PlanetSystem | None:
    """The catalogue planet a header's ``OBJECT`` names, or None.

    ``OBJECT`` is free text written by the observer (``"XO-3 ch2 peak-up"``):
    it names a planet when, spaces, hyphens and case ignored, it begins with
    the planet's name or its host star's and no digit follows
    (``"XO-3 ch2 peak-up"`` -> XO-3b). A user catalogue is searched first; a
    star with several planets in the catalogue names none of them.

    Examples
    --------
    >>> system_for_object("XO-3 ch2 peak-up").name
    'XO-3b'
    >>> system_for_object("XO-31") is None
    True
    """
    text = _normalise(object_name)
    if not text:
        return None
    sources = ([(str(catalogue), load_catalogue(catalogue))] if catalogue not in (None, "")
               else []) + [("", load_catalogue(None))]
    for source, tables in sources:
        found = []
        for name in tables:
            star = host_star(name)
            keys = [_normalise(name)] + ([_normalise(star)] if star else [])
            if star is not None and any(_starts_with_star(text, k) for k in keys):
                found.append(name)
        if len(found) == 1:
            return system_from_mapping(found[0], tables[found[0]], source=source)
        if len(found) > 1:
            return None
    return None


def system_from_meta(meta: Mapping[str, Any], catalogue: str | Path | None = None
                     ) -> tuple[PlanetSystem | None, str]:
    """The planet a photometry table's metadata names, and where that came from.

    A simulation's tables carry ``SYSTEM`` (the catalogue planet it rendered);
    archive data carry the observer's ``OBJECT`` (:func:`system_for_object`).
    Returns ``(None, why)`` when neither names a planet the catalogue knows.

    Examples
    --------
    >>> system, source = system_from_meta({"OBJECT": "XO-3 ch2 peak-up"})
    >>> system.name, source
    ('XO-3b', "OBJECT 'XO-3 ch2 peak-up'")
    >>> system_from_meta({})[1]
    'the table names no object'
    """
    simulated = str(meta.get("SYSTEM", "") or "").strip()
    if simulated:
        return get_system(simulated, catalogue), f"SYSTEM {simulated!r}"
    obj = str(meta.get("OBJECT", "") or "").strip()
    if not obj:
        return None, "the table names no object"
    system = system_for_object(obj, catalogue)
    if system is None:
        return None, f"OBJECT {obj!r} names no planet of the catalogue"
    return system, f"OBJECT {obj!r}"
