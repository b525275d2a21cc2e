"""Time columns of any table to BMJD_TDB: the one conversion shared by reduce and trust.

A table from another pipeline gives its times as full or modified Julian
dates (``jd``, ``mjd``: at the observer) or barycentric ones (``bjd``,
``bmjd``), in UTC, TT or TDB, stamped at the start, middle or end of each
frame. :func:`to_bmjd_tdb` turns them into the package's time: the
mid-exposure BMJD_TDB (``BJD_TDB - 2400000.5``; Eastman et al. 2010, PASP
122, 935, the convention of the paper's Table 1). :func:`describe` says what
was done, for every result.

The steps, in order:

1. the format's offset: ``jd`` and ``bjd`` less 2400000.5;
2. the stamp moved to mid-exposure: ``start`` plus half a frame time,
   ``end`` less half (the frame time given, or the table's median cadence);
3. the time scale to TDB with astropy (UTC: leap seconds + 32.184 s + the
   periodic TDB - TT term; TT: the periodic term);
4. for times at the observer (``jd``, ``mjd``), the light-travel time to
   the solar system barycentre (the Roemer delay ``r . n / c``, ``r`` the
   observer's barycentric position and ``n`` the unit vector to the target
   from its RA/Dec; astropy's builtin ephemeris, erfa's ``epv00``). The
   Shapiro and Einstein delays (< 0.1 ms) are left out.

Spitzer is not at the geocentre. It trails the Earth on its own heliocentric
orbit: on real epoch 1 (2012-11-10, ``SPTZR_X/Y/Z`` of the BCD headers) it was
1.10 AU from the Earth, and its light-travel time to the barycentre along
XO-3's direction differed from the geocentre's by 372 s (499 s per AU of
separation at most). Times at the observer therefore need the observer:
``observer="geocentre"`` (right for a ground-based or near-Earth telescope)
or the spacecraft's heliocentric J2000 position in km with the UTC MJD it
holds for (``SPTZR_X, SPTZR_Y, SPTZR_Z, MJD_OBS`` of any BCD header of the
observation). The spacecraft is then carried along with the Earth: its
heliocentric position is turned about the ecliptic pole by the angle the
Earth moved since that MJD (Spitzer trails the Earth on a near-circular
orbit of almost the same period). On real epoch 1, the UTC ``MJD_OBS`` of
each of its 244 cubes converted so, with the position of any one header
(the first, the 121st or the last), agrees with the archive's ``BMJD_OBS``
(made by the SSC from Spitzer's ephemeris) within 0.14 s over the 8.8 hours;
holding the offset from the Earth fixed instead gave 1.5 s
(``tests/astro/test_timescales.py``). A target's coordinates wrong by one
arcminute move the correction by at most 0.15 s.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import InputError
from .times import TIME_AT, TIME_FORMATS, TIME_SCALES

__all__ = ["TIME_FORMATS", "TIME_SCALES", "TIME_AT", "TimeSpec", "to_bmjd_tdb",
           "parse_observer", "barycentric_delay_s", "GEOCENTRE"]

#: The observer at the Earth's centre.
GEOCENTRE = "geocentre"
_C_KM_S = 299792.458
_SECONDS_PER_DAY = 86400.0
_ASTROPY_NAMES = {"utc": "utc", "tt": "tt", "tdb": "tdb"}


def parse_observer(value: Any, label: str = "observer") -> str | tuple[float, float, float, float]:
    """``"geocentre"`` or ``(x_km, y_km, z_km, mjd_utc)`` from text or a sequence.

    Examples
    --------
    >>> parse_observer("geocenter")
    'geocentre'
    >>> parse_observer("146271657.86,-43074165.74,-17215418.41,56241.7547877")[3]
    56241.7547877
    """
    if isinstance(value, str):
        text = value.strip().lower()
        if text in ("geocentre", "geocenter", "earth"):
            return GEOCENTRE
        parts: Sequence[Any] = [p for p in text.split(",")]
    elif isinstance(value, Sequence):
        parts = list(value)
    else:
        parts = []
    try:
        numbers = [float(p) for p in parts]
    except (TypeError, ValueError):
        numbers = []
    if len(numbers) != 4 or not all(math.isfinite(v) for v in numbers):
        raise InputError(f"{label} {value!r}: expected 'geocentre' or X,Y,Z,MJD (the "
                         "spacecraft's heliocentric J2000 position in km and the UTC MJD it "
                         "holds for: SPTZR_X, SPTZR_Y, SPTZR_Z, MJD_OBS of a BCD header)")
    if math.hypot(*numbers[:3]) < 1.0e7:
        raise InputError(f"{label} {value!r}: a heliocentric position in km is about 1.5e8 "
                         "(SPTZR_X, SPTZR_Y, SPTZR_Z of a BCD header)")
    return (numbers[0], numbers[1], numbers[2], numbers[3])


@dataclass(frozen=True)
class TimeSpec:
    """How a table gives its times (:func:`to_bmjd_tdb`).

    Attributes
    ----------
    format : {"bmjd", "bjd", "mjd", "jd"}
        ``b``: already barycentric; otherwise at the observer.
    scale : {"utc", "tt", "tdb"} or None
        None: TDB for barycentric formats; a time at the observer needs it.
    at : {"start", "mid", "end"}
        Where in its frame each stamp lies.
    observer : "geocentre", (x_km, y_km, z_km, mjd_utc) or None
        Where the times were taken (only for ``jd``/``mjd``).
    frame_time_s : float or None
        The frame time, for ``at`` other than ``mid`` (None: the median cadence).
    """

    format: str = "bmjd"
    scale: str | None = None
    at: str = "mid"
    observer: Any = None
    frame_time_s: float | None = None

    @property
    def barycentric(self) -> bool:
        return TIME_FORMATS[self.format][1]

    def is_plain(self) -> bool:
        """The package's own time (BMJD_TDB at mid-exposure): nothing to convert."""
        return self.format == "bmjd" and self.scale in (None, "tdb") and self.at == "mid"

    def check(self, labels: Mapping[str, str] | None = None) -> TimeSpec:
        """This spec with the observer parsed; InputError in one line for a bad value."""
        names = {"time_format": "time_format", "time_scale": "time_scale", "time_at": "time_at",
                 "observer": "observer", **dict(labels or {})}
        if self.format not in TIME_FORMATS:
            raise InputError(f"{names['time_format']}: {self.format!r} is not one of "
                             f"{', '.join(TIME_FORMATS)}")
        if self.scale is not None and self.scale not in TIME_SCALES:
            raise InputError(f"{names['time_scale']}: unknown time scale {self.scale!r} "
                             f"(expected one of {', '.join(TIME_SCALES)})")
        if self.at not in TIME_AT:
            raise InputError(f"{names['time_at']}: {self.at!r} is not one of "
                             f"{', '.join(TIME_AT)}")
        if self.frame_time_s is not None and not (math.isfinite(self.frame_time_s)
                                                  and self.frame_time_s > 0):
            raise InputError(f"frame time {self.frame_time_s!r}: expected seconds > 0")
        observer = None if self.observer is None else parse_observer(self.observer,
                                                                     names["observer"])
        if self.barycentric and observer is not None:
            raise InputError(f"{names['observer']}: the times are barycentric "
                             f"({names['time_format']} {self.format}); an observer applies to "
                             "jd or mjd times")
        if not self.barycentric:
            if self.scale is None:
                raise InputError(f"{names['time_format']} {self.format}: times at the observer "
                                 f"need their scale: give {names['time_scale']} "
                                 f"{'|'.join(TIME_SCALES)}")
            if observer is None:
                raise InputError(f"{names['time_format']} {self.format}: times at the observer "
                                 f"need {names['observer']} X,Y,Z,MJD (SPTZR_X, SPTZR_Y, "
                                 "SPTZR_Z, MJD_OBS of a BCD header of the observation) or "
                                 f"{names['observer']} geocentre (for Spitzer wrong by minutes)")
        return TimeSpec(self.format, self.scale, self.at, observer, self.frame_time_s)


def _unit_vector(ra_deg: float, dec_deg: float) -> np.ndarray:
    ra, dec = math.radians(ra_deg), math.radians(dec_deg)
    return np.array([math.cos(dec) * math.cos(ra), math.cos(dec) * math.sin(ra), math.sin(dec)])


#: The ecliptic pole (J2000 obliquity 23.4392911 deg) in ICRS axes.
_ECLIPTIC_POLE = np.array([0.0, -math.sin(math.radians(23.4392911)),
                           math.cos(math.radians(23.4392911))])


def _rotate(vector: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """``vector`` turned by each ``angle`` (rad) about the ecliptic pole: shape (3, n)."""
    k = _ECLIPTIC_POLE
    c, s = np.cos(angle), np.sin(angle)
    return (np.outer(vector, c) + np.outer(np.cross(k, vector), s)
            + np.outer(k * (k @ vector), 1.0 - c))


def barycentric_delay_s(mjd: np.ndarray, scale: str, ra_deg: float, dec_deg: float,
                        observer: Any = GEOCENTRE) -> np.ndarray:
    """The light-travel time (s) from the observer to the barycentre along the target's
    direction, ``r . n / c`` (module docstring, step 4): add it to a time at the observer.

    Examples
    --------
    >>> d = barycentric_delay_s(np.array([56241.7547877]), "utc", 65.46955, 57.81720)
    >>> round(float(d[0]), 1)       # the geocentre's; Spitzer's was 372 s less
    360.6
    """
    from astropy.coordinates import get_body_barycentric
    from astropy.time import Time

    t = Time(np.asarray(mjd, float), format="mjd", scale=_ASTROPY_NAMES[scale])
    earth_km = get_body_barycentric("earth", t).xyz.to_value("km")
    if observer == GEOCENTRE:
        r_km = earth_km
    else:
        x, y, z, mjd_ref = observer
        t_ref = Time(float(mjd_ref), format="mjd", scale="utc")
        sun_ref = get_body_barycentric("sun", t_ref).xyz.to_value("km")
        earth_ref = get_body_barycentric("earth", t_ref).xyz.to_value("km") - sun_ref
        sun_km = get_body_barycentric("sun", t).xyz.to_value("km")
        # the spacecraft's heliocentric position turned about the ecliptic pole with the Earth
        angle = np.arctan2(_ECLIPTIC_POLE @ np.cross(earth_ref, (earth_km - sun_km).T).T,
                           earth_ref @ (earth_km - sun_km))
        r_km = sun_km + _rotate(np.array([x, y, z], float), angle)
    return np.asarray(_unit_vector(ra_deg, dec_deg) @ r_km / _C_KM_S, dtype=float)


def to_bmjd_tdb(values: np.ndarray, spec: TimeSpec, *, ra_deg: float | None = None,
                dec_deg: float | None = None, cadence_s: float | None = None,
                label: str = "the time column", coords_hint: str = "--planet ra_deg=... "
                "dec_deg=...") -> tuple[np.ndarray, dict[str, Any]]:
    """Mid-exposure BMJD_TDB from a table's times, and what was done (module docstring).

    Parameters
    ----------
    values : ndarray
        The times as the table gives them (days), finite or NaN.
    spec : TimeSpec
        Checked (:meth:`TimeSpec.check`).
    ra_deg, dec_deg : float, optional
        The target (J2000); needed for times at the observer.
    cadence_s : float, optional
        The frame time when ``spec`` gives none (default: the median time step).
    label, coords_hint : str
        How errors name the column and how to give the coordinates.

    Returns
    -------
    bmjd : ndarray
    conversion : dict
        ``format``, ``scale``, ``at``, ``shift_s`` (to mid-exposure),
        ``barycentric`` (what light-travel time was added: ``"none"``, the
        geocentre's or the spacecraft's), ``delay_s`` (its mean), ``text``
        (one line for a result).

    Examples
    --------
    >>> spec = TimeSpec("bjd", "utc").check()
    >>> t, how = to_bmjd_tdb(np.array([2456242.2546553]), spec)
    >>> round(float(t[0] - 56241.7546553) * 86400, 2)    # TDB - UTC in November 2012
    67.18
    """
    offset_d, barycentric = TIME_FORMATS[spec.format]
    days = np.asarray(values, dtype=float) - offset_d
    shift_s = 0.0
    if spec.at != "mid":
        if cadence_s is None:
            steps = np.diff(np.sort(days[np.isfinite(days)]))
            cadence_s = float(np.median(steps)) * _SECONDS_PER_DAY if steps.size else None
        frame_s = spec.frame_time_s if spec.frame_time_s is not None else cadence_s
        if frame_s is None or not math.isfinite(frame_s) or frame_s <= 0:
            raise InputError(f"{label}: stamps at the frame's {spec.at} need the frame time "
                             "(give the readout, or a table of at least two frames)")
        shift_s = (0.5 if spec.at == "start" else -0.5) * float(frame_s)
        days = days + shift_s / _SECONDS_PER_DAY
    scale = spec.scale or "tdb"
    conversion: dict[str, Any] = {"format": spec.format, "scale": scale, "at": spec.at,
                                  "shift_s": shift_s, "barycentric": "none (already barycentric)",
                                  "delay_s": 0.0}
    finite = np.isfinite(days)
    out = np.full(days.shape, np.nan)
    if np.any(finite):
        from astropy.time import Time

        t = Time(days[finite], format="mjd", scale=_ASTROPY_NAMES[scale])
        out[finite] = t.tdb.mjd
        if not barycentric:
            if ra_deg is None or dec_deg is None:
                raise InputError(f"{label}: {spec.format} times are at the observer and need "
                                 f"the target's RA and Dec ({coords_hint})")
            delay = barycentric_delay_s(days[finite], scale, ra_deg, dec_deg, spec.observer)
            out[finite] += delay / _SECONDS_PER_DAY
            if spec.observer == GEOCENTRE:
                where = "the geocentre (astropy's builtin ephemeris)"
            else:
                x, y, z, mjd_ref = spec.observer
                where = (f"the spacecraft at heliocentric ({x:.0f}, {y:.0f}, {z:.0f}) km on MJD "
                         f"{mjd_ref:.5f} UTC, carried with the Earth")
            conversion.update(barycentric=f"light-travel time from {where} toward RA "
                                          f"{ra_deg:.5f}, Dec {dec_deg:.5f} deg",
                              delay_s=float(np.mean(delay)))
    conversion["text"] = (f"{spec.format.upper()}_{scale.upper()} at frame {spec.at}"
                          + (f" ({shift_s:+.3f} s to mid-exposure)" if shift_s else "")
                          + (f"; {conversion['barycentric']} (mean {conversion['delay_s']:.3f} s)"
                             if not barycentric else "")
                          + " -> BMJD_TDB at mid-exposure")
    return out, conversion
