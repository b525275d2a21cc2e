"""Write simulated IRAC BCD cubes (``_bcd.fits`` and ``_bunc.fits``) as the archive names them.

Files go to ``ROOT/r<AORKEY>/ch<N>/bcd/SPITZER_I<N>_<AORKEY>_<EXPID:04d>_0000_1_bcd.fits``
(and ``..._bunc.fits``): a primary HDU with a float32 (64, 32, 32) subarray
cube, or one (256, 256) full-array frame, in MJy/sr. Headers are formatted here directly from card tuples (see
:mod:`eclipsebench.io.header_template`) because a challenge has ~10,000 of
them; every file is written atomically.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
from astropy import constants as const
from astropy import units as u
from astropy.coordinates import (
    EarthLocation,
    SkyCoord,
    SphericalRepresentation,
    UnitSphericalRepresentation,
    get_body_barycentric,
)
from astropy.time import Time, TimeDelta

from .atomic import write_bytes
from .header_template import (
    IRAC_TURN_ON_MJD_UTC,
    BcdHeaderInfo,
    bcd_cards,
    bunc_cards,
    cube_cards,
    end_header,
    format_cards,
    sim_cards,
)

__all__ = ["bcd_path", "bunc_path", "AorWriter", "bmjd_to_utc", "geocentric_light_travel_time",
           "cube_bytes"]


def bcd_path(root: str | Path, aorkey: int, expid: int, channel: int = 2) -> Path:
    """``ROOT/r<AORKEY>/ch<N>/bcd/SPITZER_I<N>_<AORKEY>_<EXPID:04d>_0000_1_bcd.fits``.

    Examples
    --------
    >>> bcd_path("d", 20150001, 7, channel=1).as_posix()
    'd/r20150001/ch1/bcd/SPITZER_I1_20150001_0007_0000_1_bcd.fits'
    """
    ch = int(channel)
    return (Path(root) / f"r{aorkey}" / f"ch{ch}" / "bcd"
            / f"SPITZER_I{ch}_{aorkey}_{expid:04d}_0000_1_bcd.fits")


def bunc_path(root: str | Path, aorkey: int, expid: int, channel: int = 2) -> Path:
    """The ``_bunc.fits`` beside :func:`bcd_path`."""
    p = bcd_path(root, aorkey, expid, channel)
    return p.with_name(p.name.replace("_bcd.fits", "_bunc.fits"))


def bmjd_to_utc(bmjd: np.ndarray, ra_deg: float, dec_deg: float) -> tuple[np.ndarray, list[str]]:
    """MJD (UTC) and ISO ``DATE_OBS`` strings of barycentric times ``bmjd`` (TDB).

    Removes the Roemer delay of a geocentric observer toward (RA, Dec)
    (:func:`geocentric_light_travel_time`) and TDB - UTC (astropy, built-in
    ephemeris). Spitzer trailed the Earth by up to ~0.6 AU, so the real
    ``MJD_OBS`` differs by up to a few minutes from this geocentric value;
    nothing downstream uses ``MJD_OBS`` for timing.
    """

    bmjd = np.atleast_1d(np.asarray(bmjd, dtype=float))
    star = SkyCoord(ra_deg * u.deg, dec_deg * u.deg, frame="icrs")
    geocentre = EarthLocation.from_geocentric(0.0, 0.0, 0.0, unit=u.m)
    guess = Time(bmjd, format="mjd", scale="tdb", location=geocentre)
    for _ in range(2):
        ltt = geocentric_light_travel_time(guess, star)
        guess = Time(bmjd, format="mjd", scale="tdb", location=geocentre) - ltt
    utc = guess.utc
    utc.precision = 3
    return np.asarray(utc.mjd, dtype=float), [str(s) for s in np.atleast_1d(utc.isot)]


def geocentric_light_travel_time(time: Time, star: SkyCoord) -> TimeDelta:
    """``time.light_travel_time(star, kind="barycentric")`` of an observer at the geocentre.

    The same arithmetic as astropy's, without its rotation of the observer
    from ITRS to GCRS (which reads the IERS-A table: 0.7 s of CPU in each
    process that simulates): the geocentre is the origin in every frame, so
    astropy's barycentric position of the observer is the Earth's (the
    built-in ephemeris, ``erfa.epv00`` at ``time`` in TDB, in au, as its GCRS
    -> ICRS transform takes it) plus a geocentric offset of 0 m, and the
    correction is its dot product with the star's unit vector over c. That
    sum is taken as astropy takes it (the zero offset in spherical
    coordinates, the sum turned back into them), so the values are the same,
    to the bit (``tests/simulation/test_sim_bcd_write.py``).

    Parameters
    ----------
    time : astropy.time.Time
        The times (any scale; the Earth is placed at their TDB).
    star : astropy.coordinates.SkyCoord
        The target.

    Returns
    -------
    astropy.time.TimeDelta
        The barycentric minus the geocentric arrival time, TDB.
    """
    earth = get_body_barycentric("earth", time.tdb)   # erfa.epv00, au, as astropy's GCRS -> ICRS
    zero = np.zeros(earth.shape)
    origin = SphericalRepresentation(lon=zero * u.rad, lat=zero * u.rad, distance=zero * u.m)
    # astropy's sum: a spherical geocentric offset plus the Earth, spherical again, in metres
    observer = (origin + earth).to_cartesian()
    towards = star.icrs.represent_as(UnitSphericalRepresentation).to_cartesian()
    return TimeDelta(observer.dot(towards) / const.c, scale="tdb")


def cube_bytes(cube: np.ndarray) -> bytes:
    """The data block of a float32 cube: big-endian, zero-padded to 2880 bytes."""
    data = np.ascontiguousarray(cube, dtype=">f4").tobytes()
    return data + b"\0" * ((-len(data)) % 2880)


class AorWriter:
    """Writes the cubes of one AOR, formatting only the per-cube cards each time.

    Parameters
    ----------
    root : path
        The challenge folder ``DIR``.
    info : BcdHeaderInfo
        Everything the headers say that is constant over the AOR.
    """

    def __init__(self, root: str | Path, info: BcdHeaderInfo):
        self.root = Path(root)
        self.info = info
        before, after = bcd_cards(info)
        self._bcd_before, self._bcd_after = format_cards(before), format_cards(after)
        self._sim = format_cards(sim_cards(info))
        before, after = bunc_cards(info)
        self._bunc_before, self._bunc_after = format_cards(before), format_cards(after)

    def with_info(self, **changes) -> AorWriter:
        """A writer for the same folder with some header values changed."""
        return AorWriter(self.root, replace(self.info, **changes))

    def headers(self, *, expid: int, bmjd_obs: float, mjd_obs: float, date_obs: str,
                xy_mean: np.ndarray | None) -> tuple[bytes, bytes]:
        """The BCD and BUNC header bytes of cube ``expid``."""
        aintbeg = (mjd_obs - IRAC_TURN_ON_MJD_UTC) * 86400.0
        n = self.info.frames_per_cube
        # ATIMEEND: end of the last frame's integration.
        atimeend = aintbeg + (n - 1) * self.info.frame_interval_s + self.info.frame_time_s
        pairs = None if xy_mean is None else [(float(x), float(y)) for x, y in xy_mean]
        times, ids = cube_cards(date_obs=date_obs, mjd_obs=mjd_obs, bmjd_obs=bmjd_obs,
                                aintbeg=aintbeg, atimeend=atimeend, expid=expid,
                                aorkey=self.info.aorkey, xy_mean=pairs)
        t = format_cards(times)
        bunc_ids = format_cards(c for c in ids if not c[0].startswith("XYMEAN"))
        h_bcd = end_header(self._bcd_before + t + self._bcd_after + format_cards(ids) + self._sim)
        h_bunc = end_header(self._bunc_before + t + self._bunc_after + bunc_ids + self._sim)
        return h_bcd, h_bunc

    def write_cube(self, *, expid: int, bcd_mjysr: np.ndarray, bunc_mjysr: np.ndarray,
                   bmjd_obs: float, mjd_obs: float, date_obs: str,
                   xy_mean: np.ndarray | None = None) -> tuple[Path, Path]:
        """Write cube ``expid`` (``_bunc`` first, then ``_bcd``) and return both paths."""
        n = self.info.frames_per_cube
        shape = (n, *self.info.shape)
        if bcd_mjysr.shape != shape or bunc_mjysr.shape != shape:
            raise ValueError(f"cubes must be {shape}, got {bcd_mjysr.shape} and "
                             f"{bunc_mjysr.shape}")
        h_bcd, h_bunc = self.headers(expid=expid, bmjd_obs=bmjd_obs, mjd_obs=mjd_obs,
                                     date_obs=date_obs, xy_mean=xy_mean)
        p_bcd = bcd_path(self.root, self.info.aorkey, expid, self.info.channel)
        p_bunc = bunc_path(self.root, self.info.aorkey, expid, self.info.channel)
        write_bytes(p_bunc, h_bunc + cube_bytes(bunc_mjysr))
        write_bytes(p_bcd, h_bcd + cube_bytes(bcd_mjysr))
        return p_bcd, p_bunc
