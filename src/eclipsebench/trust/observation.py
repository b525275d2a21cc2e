"""The real observation a twin copies: its frames' times, pointing, fluxes and readout.

:func:`observation_from_table` reads what a photometry table made by
``eclipsebench photometry`` holds (per-frame times, centroids, aperture flux
and background in electrons, noise pixels, flags; the readout in its
metadata) into an :class:`Observation` of plain arrays. Tables from other
pipelines lack the background in electrons and the readout, so they cannot
be twinned (one line says so).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..detector.constants import ReadoutMode
from ..errors import InputError

__all__ = ["Observation", "observation_from_table", "MIN_GOOD_FRAMES"]

#: Fewer good frames than this cannot be twinned (nor reduced with any confidence).
MIN_GOOD_FRAMES = 100

_COLUMNS = ("time_bmjd", "aorkey", "expid", "frame", "x", "y", "flux", "background",
            "noise_pixels", "flag")
_READOUT_KEYS = ("CHANNEL", "READMODE", "AFOWLNUM", "AWAITPER", "SAMPTIME", "FRAMTIME",
                 "RONOISE")


@dataclass(frozen=True)
class Observation:
    """One real observation as arrays, one entry per frame in time order.

    Attributes
    ----------
    time_bmjd : ndarray
        Mid-exposure times, BMJD_TDB.
    aorkey, expid, frame : ndarray of int
        Which AOR, cube and frame of the cube each row is.
    x_px, y_px : ndarray
        The measured centroid (detector pixels, 0-based): the twin's pointing.
    flux_e, background_e_per_px : ndarray
        Aperture flux and annulus background, electrons.
    noise_pixels : ndarray
        Noise pixels (px^2), the size of the image the twin's motion is matched to.
    flag : ndarray of int
        Photometry flags (0: good).
    channel : int
    mode : ReadoutMode
    read_noise_e : float
    meta : dict
        The table's metadata, copied into each twin's table.
    """

    time_bmjd: np.ndarray
    aorkey: np.ndarray
    expid: np.ndarray
    frame: np.ndarray
    x_px: np.ndarray
    y_px: np.ndarray
    flux_e: np.ndarray
    background_e_per_px: np.ndarray
    noise_pixels: np.ndarray
    flag: np.ndarray
    channel: int
    mode: ReadoutMode
    read_noise_e: float
    meta: dict[str, Any] = field(default_factory=dict, compare=False)

    @property
    def n_frames(self) -> int:
        return int(self.time_bmjd.size)

    @property
    def good(self) -> np.ndarray:
        """Frames with no flag and finite measurements."""
        finite = np.isfinite(self.x_px) & np.isfinite(self.y_px) & np.isfinite(self.flux_e) \
            & np.isfinite(self.background_e_per_px)
        return (self.flag == 0) & finite

    def track_px(self) -> tuple[np.ndarray, np.ndarray]:
        """The centroid track with the unmeasured frames filled from their neighbours in time."""
        ok = np.isfinite(self.x_px) & np.isfinite(self.y_px)
        x = np.interp(self.time_bmjd, self.time_bmjd[ok], self.x_px[ok])
        y = np.interp(self.time_bmjd, self.time_bmjd[ok], self.y_px[ok])
        return x, y

    def cubes(self) -> list[np.ndarray]:
        """Row indices of each cube (one AORKEY and EXPID), in time order."""
        key = self.aorkey.astype(np.int64) * 100_000 + self.expid.astype(np.int64)
        starts = np.flatnonzero(np.r_[True, key[1:] != key[:-1]])
        return np.split(np.arange(self.n_frames), starts[1:])

    def aors(self) -> list[np.ndarray]:
        """Row indices of each AOR, in time order."""
        starts = np.flatnonzero(np.r_[True, self.aorkey[1:] != self.aorkey[:-1]])
        return np.split(np.arange(self.n_frames), starts[1:])


def _meta_number(meta: Mapping[str, Any], key: str, source: str, kind=float):
    value = meta.get(key)
    try:
        out = kind(value)
    except (TypeError, ValueError):
        raise InputError(f"{source}: metadata {key} = {value!r}: expected a number (trust needs "
                         "a table made by 'eclipsebench photometry', which records the "
                         "readout)") from None
    if not np.isfinite(out) or out < 0:
        raise InputError(f"{source}: metadata {key} = {value!r}: expected a non-negative number")
    return out


def _check_times(time_bmjd: np.ndarray, source: str) -> None:
    """One line naming the table unless every time is finite, distinct and in order.

    A twin copies the real frames one for one, and the real table is reduced
    as it is: rows out of order, repeated or without a time are refused before
    any work (``eclipsebench photometry`` writes one row per frame, in time order).
    """
    bad = np.flatnonzero(~np.isfinite(time_bmjd))
    if bad.size:
        raise InputError(f"{source}: column time_bmjd: {bad.size} rows have no finite time "
                         f"(first: row {bad[0] + 1}); expected a finite time for every frame")
    ordered = np.sort(time_bmjd)
    same = np.flatnonzero(np.diff(ordered) == 0)
    if same.size:
        rows = np.flatnonzero(time_bmjd == ordered[same[0]])[:2] + 1
        raise InputError(f"{source}: column time_bmjd: {same.size} rows repeat another's time "
                         f"(first: rows {rows[0]} and {rows[1]}, BMJD {ordered[same[0]]!r}); "
                         "expected one row per frame")
    back = np.flatnonzero(np.diff(time_bmjd) < 0)
    if back.size:
        raise InputError(f"{source}: column time_bmjd: the rows are not in time order ({back.size} "
                         f"steps back, first at row {back[0] + 2}); sort the table by time_bmjd")


def observation_from_table(table, source: str = "the photometry table") -> Observation:
    """The :class:`Observation` of a photometry table (``eclipsebench photometry``'s).

    Raises
    ------
    InputError
        One line naming the table and the missing column or metadata key;
        times that are not finite, repeated or out of order; a flux whose
        median over the good frames is not positive; or fewer than
        :data:`MIN_GOOD_FRAMES` good frames.
    """
    missing = [c for c in _COLUMNS if c not in table.colnames]
    if missing:
        raise InputError(f"{source}: no column {missing[0]} (trust needs a table made by "
                         "'eclipsebench photometry': per-frame background in electrons, noise "
                         "pixels and flags)")
    meta = dict(table.meta or {})
    absent = [k for k in _READOUT_KEYS if k not in meta]
    if absent:
        raise InputError(f"{source}: metadata lacks {absent[0]} (trust needs the readout that "
                         "'eclipsebench photometry' records; measure the BCDs again)")
    mode = ReadoutMode("observed", _meta_number(meta, "AFOWLNUM", source, int),
                       _meta_number(meta, "AWAITPER", source, int),
                       _meta_number(meta, "SAMPTIME", source),
                       _meta_number(meta, "FRAMTIME", source),
                       str(meta["READMODE"]).strip().upper() == "SUB")
    if not mode.subarray:
        raise InputError(f"{source}: READMODE {meta['READMODE']!r}: twins are simulated for "
                         "subarray observations (READMODE SUB)")
    cols = {c: np.asarray(table[c]) for c in _COLUMNS}
    _check_times(np.asarray(cols["time_bmjd"], dtype=float), source)
    obs = Observation(
        time_bmjd=cols["time_bmjd"].astype(float), aorkey=cols["aorkey"].astype(np.int64),
        expid=cols["expid"].astype(np.int64), frame=cols["frame"].astype(np.int64),
        x_px=cols["x"].astype(float), y_px=cols["y"].astype(float),
        flux_e=cols["flux"].astype(float), background_e_per_px=cols["background"].astype(float),
        noise_pixels=cols["noise_pixels"].astype(float), flag=cols["flag"].astype(np.int64),
        channel=_meta_number(meta, "CHANNEL", source, int), mode=mode,
        read_noise_e=_meta_number(meta, "RONOISE", source), meta=meta)
    n_good = int(obs.good.sum())
    if n_good < MIN_GOOD_FRAMES:
        raise InputError(f"{source}: {n_good} good frames: expected at least {MIN_GOOD_FRAMES} "
                         "to simulate twins of the observation")
    star_e = float(np.median(obs.flux_e[obs.good]))
    if not star_e > 0:
        raise InputError(f"{source}: column flux: the median of the good frames is {star_e:.6g} "
                         "electrons; expected the star's aperture flux in electrons (positive)")
    if obs.channel not in (1, 2):
        raise InputError(f"{source}: CHANNEL = {obs.channel}: expected 1 or 2 (the warm "
                         "mission's channels)")
    return obs

