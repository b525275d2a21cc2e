"""The real observation a twin copies: its frames' times, pointing, fluxes and readout.

:func:`observation_from_table` reads what a photometry table made by
``eclipsebench photometry`` holds (per-frame times, centroids, aperture flux
and background in electrons, noise pixels, flags; the readout in its
metadata) into an :class:`Observation` of plain arrays.

A table from another pipeline (time, flux in any unit, flux_err, x, y; and
optionally noise pixels, background, frame numbers) is first completed by
:func:`complete_table`, which infers what it lacks and says so
(``docs/trust.md``, "Any table"):

- the flux scale in electrons from the real point-to-point scatter, taken as
  photon plus read noise (:func:`flux_scale_from_scatter`);
- the readout from the cadence (the subarray mode of that frame time), or
  the one named;
- the cubes from the frame numbers, else from gaps in time (and at most 64
  frames each; a frame missing inside a cube splits it), the AORs from gaps
  of more than a minute and 1.5 cube gaps;
- no background (0 e/px: its photon noise is then part of the inferred flux
  scale), no noise pixels (the motion within an exposure is then the most whose
  pilot twin is no redder than the real residuals:
  :func:`~eclipsebench.trust.recipe.bounded_recipe`).
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import astropy.units as u
import numpy as np
from astropy.table import Table

from ..config.photometry import PhotometrySection
from ..detector.constants import READOUT_MODES, ReadoutMode, readout_mode, ronoise_e
from ..errors import InputError

__all__ = ["Observation", "observation_from_table", "MIN_GOOD_FRAMES", "MIN_GOOD_FRAMES_PER_CUBE",
           "MIN_CALIBRATION_CUBES", "complete_table",
           "needs_completion", "flux_scale_from_scatter", "SUBARRAY_CUBE_FRAMES",
           "AOR_GAP_S", "completed_observation", "adopt_observation", "OBSERVATION_FILE",
           "check_several_aors"]

#: Fewer good frames than this cannot be twinned (nor reduced with any confidence).
MIN_GOOD_FRAMES = 100
#: Good frames a cube needs for the twins' calibration to use it: the motion within an
#: exposure and the sky's scatter are fitted on good frames spread over each such cube
#: (:func:`~eclipsebench.trust.twin.calibrate_motion`,
#: :func:`~eclipsebench.trust.twin.background_scatter_share`).
MIN_GOOD_FRAMES_PER_CUBE = 2
#: Cubes of at least :data:`MIN_GOOD_FRAMES_PER_CUBE` good frames a table needs: the
#: calibration matches the standard deviation over cubes of each cube's median noise pixels.
MIN_CALIBRATION_CUBES = 2

_COLUMNS = ("time_bmjd", "aorkey", "expid", "frame", "x", "y", "flux", "background",
            "noise_pixels", "flag")
#: Columns a completed table may lack (:func:`complete_table`): NaN in the Observation.
_OPTIONAL = ("noise_pixels",)
#: Frames in one subarray cube (IRAC's 64-frame BCD files).
SUBARRAY_CUBE_FRAMES = 64
#: A gap longer than this, and than 1.5 times the median gap between cubes, starts a new AOR
#: (within an AOR, cubes follow one another within seconds: 129.4 s apart for 2 s frames,
#: 128 s of which are frames; real epoch 1's Pre and Main AORs are 224 s apart).
AOR_GAP_S = 60.0
#: A step longer than this many cadences between frames starts a new cube.
_CUBE_GAP_CADENCES = 1.5
#: The cadence must be within this fraction of a subarray mode's frame time to name it.
_READOUT_MATCH = 0.05
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

    def calibration_cubes(self) -> list[np.ndarray]:
        """The good rows of each cube with at least :data:`MIN_GOOD_FRAMES_PER_CUBE` good
        frames, in time order: the cubes the twins' calibration spreads its frames over."""
        good = self.good
        return [c[good[c]] for c in self.cubes() if good[c].sum() >= MIN_GOOD_FRAMES_PER_CUBE]

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


def _check_cubes(obs: Observation, source: str) -> None:
    """One line naming the table unless :data:`MIN_CALIBRATION_CUBES` cubes hold
    :data:`MIN_GOOD_FRAMES_PER_CUBE` good frames or more (what the twins' calibration needs)."""
    usable = len(obs.calibration_cubes())
    if usable >= MIN_CALIBRATION_CUBES:
        return
    cubes = obs.cubes()
    most = max(int(obs.good[c].sum()) for c in cubes)
    raise InputError(
        f"{source}: {usable} of {len(cubes)} cubes (aorkey, expid) hold "
        f"{MIN_GOOD_FRAMES_PER_CUBE} or more good frames (at most {most} in a cube): expected "
        f"at least {MIN_CALIBRATION_CUBES} such cubes, as the twins' motion within an exposure "
        "and sky scatter are calibrated on good frames spread over each cube and on the spread "
        "of the noise pixels from cube to cube (photometry flags each cube's first frame by "
        "default, so cubes of 2 frames hold 1)")


def observation_from_table(table, source: str = "the photometry table") -> Observation:
    """The :class:`Observation` of a photometry table (``eclipsebench photometry``'s).

    Raises
    ------
    InputError
        One line naming the table and the missing column or metadata key;
        times that are not finite, repeated or out of order; a flux whose
        median over the good frames is not positive; or fewer than
        :data:`MIN_GOOD_FRAMES` good frames, or fewer than
        :data:`MIN_CALIBRATION_CUBES` cubes with :data:`MIN_GOOD_FRAMES_PER_CUBE`
        good frames (cubes of 2 frames whose first is flagged, as photometry flags
        a cube's first frame, hold 1).
    """
    missing = [c for c in _COLUMNS if c not in table.colnames and c not in _OPTIONAL]
    if missing:
        raise InputError(f"{source}: missing column(s) {', '.join(missing)} (trust needs a "
                         "table made by 'eclipsebench photometry': per-frame background in "
                         "electrons, noise pixels and flags)")
    meta = dict(table.meta or {})
    absent = [k for k in _READOUT_KEYS if k not in meta]
    if absent:
        raise InputError(f"{source}: metadata lacks {', '.join(absent)} (trust needs the readout "
                         "that 'eclipsebench photometry' records; measure the BCDs again)")
    mode = ReadoutMode("observed", _meta_number(meta, "AFOWLNUM", source, int),
                       _meta_number(meta, "AWAITPER", source, int),
                       _meta_number(meta, "SAMPTIME", source),
                       _meta_number(meta, "FRAMTIME", source),
                       str(meta["READMODE"]).strip().upper() == "SUB")
    if not mode.subarray:
        raise InputError(f"{source}: READMODE {meta['READMODE']!r}: twins are simulated for "
                         "subarray observations (READMODE SUB)")
    n = len(table)
    cols = {c: (np.asarray(table[c]) if c in table.colnames else np.full(n, np.nan))
            for c in _COLUMNS}
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
    _check_cubes(obs, source)
    star_e = float(np.median(obs.flux_e[obs.good]))
    if not star_e > 0:
        raise InputError(f"{source}: column flux: the median of the good frames is {star_e:.6g} "
                         "electrons; expected the star's aperture flux in electrons (positive)")
    if obs.channel not in (1, 2):
        raise InputError(f"{source}: CHANNEL = {obs.channel}: expected 1 or 2 (the warm "
                         "mission's channels)")
    return obs


def check_several_aors(table, obs: Observation, source: str) -> None:
    """Refuse, in one line naming the table, a whole phase curve's table without the AORs
    its fit needs: no column ``aorkey`` (another pipeline's table, whose AORs
    :func:`complete_table` would infer from gaps, counts as none) or a single AOR.

    A phase curve's fit gives every AOR after the first its own flux offset
    (:mod:`eclipsebench.fit.model.phase_curve`), so its twins are made only of
    a table that names each frame's AOR, and of more than one.
    """
    inferred = json.loads(str((table.meta or {}).get("INFERRED") or "{}"))
    if "aorkey" not in table.colnames or "cubes" in inferred:
        raise InputError(f"{source}: no column aorkey: twins of a whole phase curve need each "
                         "frame's AOR (its fit gives every AOR after the first a flux offset); "
                         "expected a column aorkey naming at least 2 AORs")
    keys = np.unique(obs.aorkey)
    if keys.size < 2:
        raise InputError(f"{source}: column aorkey: one AOR ({keys[0]}); a whole phase curve "
                         "spans several, expected at least 2 (twin a single AOR with --event "
                         "eclipse or transit)")


# ----------------------------------------------------------------------------- any table
def needs_completion(table) -> bool:
    """Whether ``table`` lacks what a twin copies (columns or the readout): another
    pipeline's table, completed by :func:`complete_table` before it is twinned."""
    meta = table.meta or {}
    return any(c not in table.colnames for c in _COLUMNS if c not in _OPTIONAL) \
        or any(k not in meta for k in _READOUT_KEYS)


def _point_to_point_sigma(values: np.ndarray) -> float:
    """The per-frame scatter of ``values`` from its first differences: 1.4826 MAD / sqrt(2)."""
    d = np.diff(values)
    return float(1.4826 * np.median(np.abs(d - np.median(d))) / math.sqrt(2.0))


def flux_scale_from_scatter(flux: np.ndarray, *, aperture_px2: float, read_noise_e: float,
                            background: np.ndarray | None = None) -> tuple[float, dict]:
    """Electrons per unit of ``flux``, from its point-to-point scatter as photon + read noise.

    With ``g`` electrons per unit, a frame's variance in electrons is the
    photon noise of the star and the sky in the aperture plus the read noise
    of its pixels (paper Appendix A.3): ``g^2 s^2 = g (F + A B) + A RN^2``,
    ``s`` the scatter (:func:`_point_to_point_sigma`, which the slow
    astrophysical and pointing changes do not reach), ``F`` the median flux,
    ``B`` the median background per pixel in the same unit (0 when not
    given) and ``A`` the aperture's area; ``g`` is the positive root. Noise
    beyond photon and read noise (the gain's response to jitter within a
    frame) makes ``s`` larger, and the scale a lower bound: the twins are
    then as noisy as the table, not less.

    Returns
    -------
    gain : float
        Electrons per unit of ``flux``.
    detail : dict
        ``scatter``, ``median_flux``, ``relative_scatter_ppm``, ``flux_e``.

    Raises
    ------
    ValueError
        No scatter (constant flux) or a flux that is not positive.

    Examples
    --------
    >>> rng = np.random.default_rng(1)
    >>> f = (2.0e5 + rng.normal(0, np.sqrt(2.0e5 + 16 * 10.0**2), 20000)) / 1000.0
    >>> g, _ = flux_scale_from_scatter(f, aperture_px2=16.0, read_noise_e=10.0)
    >>> round(g / 1000.0, 1)
    1.0
    """
    f = np.asarray(flux, float)
    level = float(np.median(f))
    sigma = _point_to_point_sigma(f)
    if not (np.isfinite(level) and level > 0):
        raise ValueError(f"median flux {level:.4g}: expected a positive flux")
    if not (np.isfinite(sigma) and sigma > 0):
        raise ValueError("the flux has no frame-to-frame scatter")
    sky = 0.0 if background is None else max(0.0, float(np.median(background)))
    b = level + aperture_px2 * sky
    c = aperture_px2 * read_noise_e ** 2
    gain = (b + math.sqrt(b * b + 4.0 * sigma * sigma * c)) / (2.0 * sigma * sigma)
    return gain, {"scatter": sigma, "median_flux": level,
                  "relative_scatter_ppm": 1e6 * sigma / level, "flux_e": gain * level}


def _readout(cadence_s: float, readout: str | None, source: str) -> tuple[ReadoutMode, str]:
    if readout is not None:
        mode = readout_mode(readout)
        if not mode.subarray:
            raise InputError(f"--readout {readout}: twins are simulated for subarray "
                             "observations (sub_*)")
        return mode, f"{mode.name} (given)"
    if not (np.isfinite(cadence_s) and cadence_s > 0):
        raise InputError(f"{source}: no cadence to infer the readout from; give --readout")
    best = min((m for m in READOUT_MODES.values() if m.subarray),
               key=lambda m: abs(m.frame_time_s - cadence_s))
    if abs(best.frame_time_s - cadence_s) > _READOUT_MATCH * best.frame_time_s:
        raise InputError(f"{source}: a cadence of {cadence_s:.4g} s is no subarray frame time "
                         f"(0.02, 0.1, 0.4 or 2 s); give --readout")
    return best, f"{best.name} (from the cadence, {cadence_s:.4g} s)"


def _cubes(time_bmjd: np.ndarray, frame: np.ndarray | None, cadence_s: float
           ) -> tuple[np.ndarray, np.ndarray, np.ndarray, str]:
    """AOR number, cube number within it and frame number of each row (time order)."""
    step_s = np.diff(time_bmjd) * 86400.0
    gaps = step_s[step_s > _CUBE_GAP_CADENCES * cadence_s]
    aor_gap_s = max(AOR_GAP_S, 1.5 * float(np.median(gaps)) if gaps.size else 0.0)
    new_aor = np.r_[True, step_s > aor_gap_s]
    if frame is not None:
        new_cube = np.r_[True, np.diff(frame) <= 0] | new_aor
        how = "cubes from the frame numbers"
    else:
        new_cube = np.r_[True, step_s > _CUBE_GAP_CADENCES * cadence_s] | new_aor
        how = (f"cubes from gaps over {_CUBE_GAP_CADENCES:g} cadences, at most "
               f"{SUBARRAY_CUBE_FRAMES} frames each")
    # at most 64 frames per cube
    cube_id = np.cumsum(new_cube) - 1
    index_in = np.arange(time_bmjd.size) - np.flatnonzero(new_cube)[cube_id]
    new_cube |= (index_in > 0) & (index_in % SUBARRAY_CUBE_FRAMES == 0)
    aor = np.cumsum(new_aor)
    cube_id = np.cumsum(new_cube) - 1
    starts = np.flatnonzero(new_cube)
    frame_no = np.arange(time_bmjd.size) - starts[cube_id]
    first_cube_of_aor = np.maximum.accumulate(np.where(new_aor, cube_id, 0))
    expid = cube_id - first_cube_of_aor
    return aor.astype(np.int64), expid.astype(np.int64), frame_no.astype(np.int64), \
        f"{how}, AORs from gaps over {aor_gap_s:.4g} s"


def complete_table(table: Table, source: str, *, readout: str | None = None,
                   channel: int | None = None) -> tuple[Table, dict[str, Any]]:
    """Another pipeline's table (package names, BMJD_TDB: ``standardise_table``) made
    twinnable: what a twin copies, inferred where the table does not give it.

    Parameters
    ----------
    table : Table
        ``time_bmjd, flux, flux_err, x, y``; optionally ``noise_pixels``,
        ``background`` (per pixel, in the flux's unit), ``frame`` (the frame
        number in its cube), ``flag``.
    source : str
        The table, as errors name it.
    readout : str, optional
        A subarray readout mode (``sub_2s``...); default: the one whose frame
        time is the cadence.
    channel : int, optional
        The IRAC channel (default: the table's ``CHANNEL``, else 2, said so).

    Returns
    -------
    table : Table
        Time-ordered rows with ``aorkey, expid, frame, flag``, flux, its
        error and the background in electrons, the readout in the metadata
        and ``INFERRED`` (JSON) saying what was inferred.
    inferred : dict
        The same, as a dict.

    Raises
    ------
    InputError
        One line naming the table: fewer than :data:`MIN_GOOD_FRAMES` good
        frames, a flux with no frame-to-frame scatter, a cadence that is no
        subarray frame time (give ``readout``), a channel other than 1 or 2.
    """
    meta = dict(table.meta or {})
    time = np.asarray(table["time_bmjd"], float)
    order = np.argsort(time, kind="stable")
    time = time[order]

    def col(name):
        c = table[name]
        return np.asarray(getattr(c, "value", c), float)[order]

    flux, err, x, y = (col(c) for c in ("flux", "flux_err", "x", "y"))
    flag = (np.asarray(table["flag"])[order].astype(np.int64) if "flag" in table.colnames
            else np.zeros(time.size, np.int64))
    good = (flag == 0) & np.isfinite(time) & np.isfinite(flux) & np.isfinite(err) \
        & (err > 0) & np.isfinite(x) & np.isfinite(y)
    if int(good.sum()) < MIN_GOOD_FRAMES:
        raise InputError(f"{source}: {int(good.sum())} good frames: expected at least "
                         f"{MIN_GOOD_FRAMES} to infer the flux scale and simulate twins")
    inferred: dict[str, Any] = {}
    frame = col("frame").astype(np.int64) if "frame" in table.colnames else None
    cadence_s = float(np.median(np.diff(time[good])) * 86400.0)
    mode, inferred["readout"] = _readout(cadence_s, readout, source)
    ch = channel if channel is not None else meta.get("CHANNEL")
    if ch is None:
        ch, inferred["channel"] = 2, "2 (assumed: the table does not say; give --channel)"
    else:
        inferred["channel"] = f"{int(ch)} ({'given' if channel is not None else 'CHANNEL'})"
    ch = int(ch)
    if ch not in (1, 2):
        raise InputError(f"{source}: channel {ch}: expected 1 or 2 (the warm mission's)")
    read_noise = ronoise_e(ch, mode)
    aorkey, expid, frame_no, inferred["cubes"] = _cubes(time, frame, mode.frame_time_s)
    background = col("background") if "background" in table.colnames else None
    unit = table["flux"].unit
    if unit is not None and u.Unit(unit) in (u.electron, u.ct):
        scale, inferred["flux_scale"] = 1.0, f"the flux is in {unit} (no scale inferred)"
    else:
        area = math.pi * PhotometrySection().radius_px ** 2
        try:
            scale, detail = flux_scale_from_scatter(
                flux[good], aperture_px2=area, read_noise_e=read_noise,
                background=None if background is None else background[good])
        except ValueError as exc:
            raise InputError(f"{source}: cannot infer the flux scale in electrons ({exc})") \
                from None
        inferred["flux_scale"] = (
            f"{scale:.6g} electrons per unit of flux, from the point-to-point scatter "
            f"({detail['relative_scatter_ppm']:.0f} ppm per frame) as photon noise plus "
            f"{read_noise:g} e read noise in a {PhotometrySection().radius_px:g} px aperture "
            f"({'with' if background is not None else 'without'} the background): "
            f"{detail['flux_e']:.4g} electrons per frame")
        inferred["flux_scale_e_per_unit"] = scale
    if background is None:
        background = np.zeros(time.size)
        inferred["background"] = ("none in the table: 0 e/px (the sky's photon noise is in the "
                                  "inferred flux scale)")
    else:
        inferred["background"] = "the table's, in the flux's unit per pixel, scaled"
    if "noise_pixels" not in table.colnames:
        inferred["noise_pixels"] = ("none in the table: the motion within an exposure is set "
                                    "by the real residuals alone (twins.motion_bound)")
    columns = {"time_bmjd": time, "aorkey": aorkey, "expid": expid, "frame": frame_no,
               "x": x, "y": y, "flux": flux * scale, "flux_err": err * scale,
               "background": background * scale, "flag": np.where(good, 0, np.maximum(flag, 1))}
    if "noise_pixels" in table.colnames:
        columns["noise_pixels"] = col("noise_pixels")
    out = Table(columns)
    for name in ("flux", "flux_err"):
        out[name].unit = u.electron
    out["background"].unit = u.electron / u.pix**2
    keep = {k: v for k, v in meta.items() if k not in _READOUT_KEYS}
    out.meta.update(keep)
    out.meta.update({"CHANNEL": ch, "READMODE": "SUB", "AFOWLNUM": mode.fowler,
                     "AWAITPER": mode.wait, "SAMPTIME": mode.sample_time_s,
                     "FRAMTIME": mode.frame_time_s, "RONOISE": read_noise,
                     "INFERRED": json.dumps(inferred, sort_keys=True)})
    return out, inferred


#: The completed table of another pipeline's observation, in the trust folder.
OBSERVATION_FILE = "observation.fits"


def completed_observation(path: str, *, system: Any = None, system_section: Any = None,
                          hint: str = "--system NAME", columns: Mapping[str, str] | None = None,
                          time_column: str | None = None, time_format: str | None = None,
                          time_options: Mapping[str, Any] | None = None,
                          readout: str | None = None, channel: int | None = None,
                          labels: Mapping[str, str] | None = None) -> Table | None:
    """The table at ``path`` completed for twins (:func:`complete_table`), or None when it is
    an ``eclipsebench photometry`` table given without column or time options (twinned as
    it is).

    The columns and times are mapped as ``reduce`` maps them
    (:func:`~eclipsebench.fit.data.standardise_table`, the planet's coordinates for
    times at the observer) and checked (:func:`~eclipsebench.fit.data.check_columns`).
    Nothing is written. The completed table's ``SOURCE`` is ``path``.
    """
    from ..fit.data import check_columns, standardise_table
    from ..fit.target import system_of_table
    from ..photometry.table import read_table

    raw = read_table(path)
    given = bool(columns or time_column or time_format or time_options)
    if not given and readout is None and channel is None and not needs_completion(raw):
        return None
    raw.meta.setdefault("FILENAME", str(path))
    target = (system_of_table(raw.meta, system=system, section=system_section,
                              source=str(path), hint=hint)
              if time_format in ("jd", "mjd") else None)
    table = standardise_table(raw, columns=columns, time_column=time_column,
                              time_format=time_format, target=target, labels=labels,
                              **dict(time_options or {}))
    check_columns(table, str(path), labels=labels)
    if not needs_completion(table) and readout is None and channel is None:
        table.meta["SOURCE"] = str(path)
        return table
    done, _ = complete_table(table, str(path), readout=readout, channel=channel)
    done.meta["SOURCE"] = str(path)
    return done


def adopt_observation(table: Table, root, write) -> str:
    """Write the completed ``table`` as the trust folder's :data:`OBSERVATION_FILE` (once the
    run's settings were checked) and return its path; a folder holding another one is
    refused. ``write(table, path)`` writes a photometry table (atomically)."""
    import filecmp
    import tempfile
    from pathlib import Path

    from ..engine.folder import check_kind
    from ..io.paths import check_links_inside

    if Path(root).is_dir():   # another kind of run, or a link out: refused before any write
        check_kind(root, "trust")
        check_links_inside(Path(root))
    final = Path(root) / OBSERVATION_FILE
    config = Path(root) / "trust_config.json"   # the run's settings (TrustLayout.config)
    if config.is_file() and not final.is_file():
        raise InputError(f"{root}: holds a trust run of another table; use another --out or "
                         "remove it")
    if final.is_file():
        with tempfile.TemporaryDirectory() as tmp:
            probe = Path(tmp) / OBSERVATION_FILE
            write(table, probe)
            if not filecmp.cmp(probe, final, shallow=False):
                raise InputError(f"{root}: holds a trust run of another table or other column "
                                 f"and time options ({OBSERVATION_FILE}); use another --out "
                                 "or remove it")
        return str(final.resolve())
    final.parent.mkdir(parents=True, exist_ok=True)
    write(table, final)
    return str(final.resolve())
