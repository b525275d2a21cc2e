"""Header cards of simulated IRAC channel-1 and channel-2 BCD files (subarray or full array).

The keywords, their order, formats and comments follow a real warm-mission
BCD header (pipeline S19.2.0, XO-3, AORKEY 46466816; channel 1: S18.18.0,
HD 209458, AORKEY 41629440); the values that describe an observation are
computed by the simulator, the rest are typed in from those headers. Cards are
kept as ``(keyword, value, comment)`` tuples so that
:mod:`eclipsebench.io.bcd_write` can format the few that change from cube to
cube without building an astropy header per file.

Per channel (:data:`CHANNEL_CARDS`): ``FOVID``/``FOVNAME`` (70/67 for the
channel-1 subarray/array, 77/74 for channel 2, as IRACSIM's ``iracsim.pro``
and ``spitzer_fov.pro``), the CD matrix and ``PXSCAL1/2`` of the real header
of that channel (they depend on the roll angle; any valid matrix serves).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["Card", "format_card", "format_cards", "end_header", "format_header", "BcdHeaderInfo", "bcd_cards", "bunc_cards",
           "cube_cards", "sim_cards", "IRAC_TURN_ON_MJD_UTC", "XO3_RA_DEG", "XO3_DEC_DEG", "CD_MATRIX_DEG",
           "CHANNEL_CARDS"]

Card = tuple[str, object, str]

# AINTBEG/ATIMEEND count seconds since IRAC was turned on. The real cube
# 0000 of AOR 46466816 has MJD_OBS = 56270.4731344 (UTC) and
# AINTBEG = 21011060.76 s, which fixes the turn-on epoch used here.
IRAC_TURN_ON_MJD_UTC = 56270.4731344 - 21011060.76 / 86400.0
# XO-3 (RA_RQST, DEC_RQST of the real header) and the real CD matrix (deg/px).
XO3_RA_DEG = 65.469452237357
XO3_DEC_DEG = 57.817333722922
CD_MATRIX_DEG = ((0.000144772485275896, -0.000302888712014758),
                 (-0.000302008826913906, -0.000147183662865151))
#: What the header says per channel: FOV ids and names (subarray, full array),
#: the CD matrix (deg/px) and PXSCAL1/2 of the channel's real header.
CHANNEL_CARDS: dict[int, dict[str, Any]] = {
    1: {"fov_sub": (70, "IRAC_Center_of_3.6umSub-array"),
        "fov_full": (67, "IRAC_Center_of_3.6&5.8umArray"),
        "cd": ((-9.96078618101942e-05, 0.000327975181020821),
               (0.000325252187504057, 0.000101638740134936)),
        "pxscal": (-1.22457237448543, 1.23610681621358)},
    2: {"fov_sub": (77, "IRAC_Center_of_4.5umSub-Array"),
        "fov_full": (74, "IRAC_Center_of_4.5&8.0umArray"),
        "cd": CD_MATRIX_DEG,
        "pxscal": (-1.20566164841875, 1.21232159435749)},
}


def _format_value(value: object) -> str:
    if isinstance(value, bool):
        return f"{'T' if value else 'F':>20}"
    if isinstance(value, (int, np.integer)):
        return f"{int(value):>20d}"
    if isinstance(value, (float, np.floating)):
        v = float(value)
        if not math.isfinite(v):
            raise ValueError(f"FITS header values must be finite, got {v}")
        text = repr(v).upper()
        if "E" in text and "." not in text.split("E")[0]:
            mant, exp = text.split("E")
            text = f"{mant}.E{exp}"
        if len(text) > 20:
            text = f"{v:.14G}"
            if "." not in text and "E" not in text:
                text += "."
        return f"{text:>20}"
    if isinstance(value, str):
        escaped = value.replace("'", "''")
        return f"'{escaped:<8}'".ljust(20)
    raise TypeError(f"cannot write {value!r} in a FITS header")


def format_card(key: str, value: object = None, comment: str = "") -> bytes:
    """One 80-byte FITS card (fixed format), ASCII.

    ``key`` of ``"COMMENT"``/``"HISTORY"`` writes commentary text (``value``).
    ``key`` of ``""`` writes a blank card.

    Examples
    --------
    >>> format_card("NAXIS", 3, "number of axes")[:30]
    b'NAXIS   =                    3'
    """
    key = key.upper()
    if key in ("COMMENT", "HISTORY", ""):
        text = f"{key:<8}{'' if value is None else str(value)}"
    else:
        if len(key) > 8:
            raise ValueError(f"FITS keyword {key!r} is longer than 8 characters")
        text = f"{key:<8}= {_format_value(value)}"
        if comment:
            text += f" / {comment}"
    text = text[:80].ljust(80)
    data = text.encode("ascii")
    if len(data) != 80:
        raise ValueError(f"card {key!r} is not ASCII")
    return data


def format_cards(cards: Iterable[Card]) -> bytes:
    """The 80-byte cards of ``cards``, concatenated (no END, no padding)."""
    return b"".join(format_card(key, value, comment) for key, value, comment in cards)


def end_header(card_bytes: bytes) -> bytes:
    """Append END and blank padding to a multiple of 2880 bytes."""
    out = card_bytes + b"END".ljust(80)
    return out + b" " * ((-len(out)) % 2880)


def format_header(cards: Iterable[Card]) -> bytes:
    """A complete FITS header (cards, END, blank padding to 2880 bytes)."""
    return end_header(format_cards(cards))


@dataclass(frozen=True)
class BcdHeaderInfo:
    """What the header of one AOR's cubes must say (everything per-AOR)."""

    aorkey: int
    aorlabel: str
    object_name: str
    epoch: int
    seed: int
    noise_model: str
    fowler: int
    wait: int
    sample_time_s: float
    frame_time_s: float
    frame_interval_s: float
    exptime_s: float
    frames_per_cube: int
    fluxconv: float
    gain_e_per_dn: float
    read_noise_e: float
    ra_deg: float
    dec_deg: float
    star_x_px: float
    star_y_px: float
    pointing_motion: bool = True
    flat_gain: bool = False
    prf: str = "builtin"
    channel: int = 2
    subarray: bool = True
    #: the catalogue planet rendered (``SYSTEM``): what a reduction of these cubes uses
    system_name: str = ""

    @property
    def shape(self) -> tuple[int, int]:
        """(ny, nx) of a frame: 32 x 32 subarray or 256 x 256 full array."""
        return (32, 32) if self.subarray else (256, 256)


def _axis_cards(info: BcdHeaderInfo) -> list[Card]:
    """NAXIS cards: a (n, 32, 32) subarray cube, or one 256 x 256 full-array frame (2-D,
    as the archive writes them)."""
    ny, nx = info.shape
    if info.subarray:
        return [("NAXIS", 3, "STANDARD FITS FORMAT"), ("NAXIS1", nx, "STANDARD FITS FORMAT"),
                ("NAXIS2", ny, "STANDARD FITS FORMAT"),
                ("NAXIS3", info.frames_per_cube, "STANDARD FITS FORMAT")]
    return [("NAXIS", 2, "STANDARD FITS FORMAT"), ("NAXIS1", nx, "STANDARD FITS FORMAT"),
            ("NAXIS2", ny, "STANDARD FITS FORMAT")]


def _wcs_cards(info: BcdHeaderInfo) -> list[Card]:
    # The star (0-based x, y) sits at FITS pixel (x + 1, y + 1); CRVAL is the
    # sky position of CRPIX so that the star lands at (RA, Dec) to first order.
    crpix = 16.5 if info.subarray else 128.5
    dx = info.star_x_px + 1.0 - crpix
    dy = info.star_y_px + 1.0 - crpix
    chan = CHANNEL_CARDS[info.channel]
    (c11, c12), (c21, c22) = chan["cd"]
    cosd = math.cos(math.radians(info.dec_deg))
    crval1 = info.ra_deg - (c11 * dx + c12 * dy) / cosd
    crval2 = info.dec_deg - (c21 * dx + c22 * dy)
    return [
        ("CRPIX1", crpix, "Reference pixel along axis 1"),
        ("CRPIX2", crpix, "Reference pixel along axis 2"),
        ("CRVAL1", crval1, "[deg] RA at CRPIX1,CRPIX2"),
        ("CRVAL2", crval2, "[deg] DEC at CRPIX1,CRPIX2"),
        ("RADESYS", "ICRS", "International Celestial Reference System"),
        ("EQUINOX", 2000.0, "Equinox for ICRS celestial coord. system"),
        ("CD1_1", c11, "CD matrix element"),
        ("CD1_2", c12, "CD matrix element"),
        ("CD2_1", c21, "CD matrix element"),
        ("CD2_2", c22, "CD matrix element"),
        ("CTYPE1", "RA---TAN", "RA---TAN (simulated: no distortion)"),
        ("CTYPE2", "DEC--TAN", "DEC--TAN (simulated: no distortion)"),
        ("PXSCAL1", chan["pxscal"][0], "[arcsec/pix] Scale for axis 1 at CRPIX1,CRPIX2"),
        ("PXSCAL2", chan["pxscal"][1], "[arcsec/pix] Scale for axis 2 at CRPIX1,CRPIX2"),
        ("RA_RQST", info.ra_deg, "[deg] Requested RA at CRPIX1, CRPIX2"),
        ("DEC_RQST", info.dec_deg, "[deg] Requested Dec at CRPIX1, CRPIX2"),
        ("RA_REF", info.ra_deg, "[deg] Commanded RA (J2000) of ref. position"),
        ("DEC_REF", info.dec_deg, "[deg] Commanded Dec (J2000) of ref. position"),
    ]


def bcd_cards(info: BcdHeaderInfo) -> tuple[list[Card], list[Card]]:
    """The per-AOR cards of a BCD cube, split around the per-cube block.

    Returns ``(before, after)``: the cube header is ``before`` + the cards of
    :func:`cube_cards` + ``after``.
    """
    fovid, fovname = CHANNEL_CARDS[info.channel]["fov_sub" if info.subarray else "fov_full"]
    before: list[Card] = [
        ("SIMPLE", True, "Fits standard"),
        ("BITPIX", -32, "FOUR-BYTE SINGLE PRECISION FLOATING POINT"),
        *_axis_cards(info),
        ("ORIGIN", "eclipsebench", "Organization generating this FITS file"),
        ("CREATOR", "eclipsebench simulate", "SW version used to create this FITS file"),
        ("TELESCOP", "Spitzer", "SPITZER Space Telescope"),
        ("INSTRUME", "IRAC", "SPITZER Space Telescope instrument ID"),
        ("CHNLNUM", info.channel, "1 digit instrument channel number"),
        ("EXPTYPE", "sci", "Exposure Type"),
        ("REQTYPE", "AOR", "Request type (AOR, IER, or  SER)"),
        ("AOT_TYPE", "IracMapPC", "Observation template type"),
        ("AORLABEL", info.aorlabel, "AOR Label"),
        ("FOVID", fovid, "Field of View ID"),
        ("FOVNAME", fovname, "Field of View Name"),
        ("", None, ""),
        ("COMMENT", "  / TIME AND EXPOSURE INFORMATION", ""),
        ("", None, ""),
    ]
    after: list[Card] = [
        ("TIMESYS", "TDB", "Time scale of BMJD_OBS (simulated data: TDB)"),
        ("AORTIME", info.frame_time_s, "[sec] Frameset selected in IRAC AOT"),
        ("SAMPTIME", info.sample_time_s, "[sec] Sample integration time"),
        ("FRAMTIME", info.frame_time_s, "[sec] Time spent integrating (whole array)"),
        ("EXPTIME", info.exptime_s, "[sec] Effective integration time per pixel"),
        ("AFOWLNUM", info.fowler, "Fowler number"),
        ("AWAITPER", info.wait, "[0.2 sec] Wait period"),
        ("ANUMREPS", 1, "Number of repeat integrations"),
        ("AREADMOD", 1 if info.subarray else 0, "Full (0) or subarray (1)"),
        ("APEDSIG", 0, "0=Normal, 1=Pedestal, 2=Signal"),
        ("", None, ""),
        ("COMMENT", "  / TARGET AND POINTING INFORMATION", ""),
        ("", None, ""),
        ("OBJECT", info.object_name, "Target Name"),
        ("OBJTYPE", "TargetFixedCluster", "Object Type"),
        *_wcs_cards(info),
        ("", None, ""),
        ("COMMENT", "  / PHOTOMETRY", ""),
        ("", None, ""),
        ("BUNIT", "MJy/sr", "Units of image data"),
        ("FLUXCONV", info.fluxconv, "Flux Conv. factor (MJy/sr per DN/sec)"),
        ("GAIN", info.gain_e_per_dn, "e/DN conversion"),
        ("RONOISE", info.read_noise_e, "[Electrons] Readout Noise from Array"),
        ("", None, ""),
        ("COMMENT", "  / IRAC MAPPING KEYWORDS", ""),
        ("", None, ""),
        ("READMODE", "SUB" if info.subarray else "FULL", "Readout mode (full or sub)"),
        ("PKUPMODE", "PCRS", "Peakup mode (none, IRS, or PCRS)"),
        ("", None, ""),
        ("COMMENT", "  / DATA FLOW KEYWORDS", ""),
        ("", None, ""),
        ("AORKEY", info.aorkey, "AOR or EIR key. Astrnmy Obs Req/Instr Eng Req"),
    ]
    return before, after


def sim_cards(info: BcdHeaderInfo) -> list[Card]:
    """Cards that mark the file as simulated and say how."""
    return [
        ("", None, ""),
        ("COMMENT", "  / SIMULATION (eclipsebench, after IRACSIM; Ingalls et al. 2016 App. A)", ""),
        ("", None, ""),
        ("SIMULATE", True, "SIMULATED data, not a Spitzer observation"),
        ("SIMSEED", info.seed, "Seed of the simulated challenge"),
        ("NOISEMOD", info.noise_model, "Noise model (physical or iracsim2015)"),
        ("EPOCH", info.epoch, "Simulated epoch (1-based)"),
        ("SIMPRF", info.prf, "PRF used by the simulator"),
        ("SIMPTG", info.pointing_motion, "Pointing motion on (F: star held fixed)"),
        ("SIMFLAT", info.flat_gain, "Intra-pixel gain switched off"),
        *([("SYSTEM", info.system_name, "Catalogue planet the simulation rendered")]
          if info.system_name else []),
    ]


def cube_cards(*, date_obs: str, mjd_obs: float, bmjd_obs: float, aintbeg: float,
               atimeend: float, expid: int, aorkey: int, xy_mean: Sequence[tuple[float, float]]
               | None = None) -> tuple[list[Card], list[Card]]:
    """The cards that change from cube to cube.

    Returns ``(times, ids)``: the time block (goes before the per-AOR
    exposure cards) and the identifiers plus ``XYMEANnn`` (go after).
    ``xy_mean`` are the true mean (x, y) per frame, 0-based pixel coordinates.
    """
    times: list[Card] = [
        ("DATE_OBS", date_obs, "Date & time (UTC) at DCE start"),
        ("MJD_OBS", round(mjd_obs, 7), "[days] MJD in UTC at DCE start (,JD-2400000.5)"),
        ("BMJD_OBS", round(bmjd_obs, 7), "[days] Solar System Barycenter Mod. Julian Date"),
        ("AINTBEG", round(aintbeg, 2), "[Secs since IRAC turn-on] Time of integ. start"),
        ("ATIMEEND", round(atimeend, 2), "[Secs since IRAC turn-on] Time of integ. end"),
    ]
    ids: list[Card] = [
        ("DS_IDENT", f"ads/sa.spitzer#{aorkey:010d}", "Data Set Identification for ADS/journals"),
        ("EXPID", int(expid), "Exposure ID (0-9999)"),
        ("DCENUM", int(expid), "DCE number (0-9999)"),
    ]
    if xy_mean is not None:
        for j, (x, y) in enumerate(xy_mean, start=1):
            ids.append((f"XYMEAN{j:02d}", f"({x:.4f},{y:.4f})",
                        f"True mean (x,y) of frame {j}, 0-based px"))
    return times, ids


def bunc_cards(info: BcdHeaderInfo) -> tuple[list[Card], list[Card]]:
    """The per-AOR cards of an uncertainty (``_bunc``) cube, split like :func:`bcd_cards`."""
    before: list[Card] = [
        ("SIMPLE", True, "STANDARD FITS FORMAT"),
        ("BITPIX", -32, "FOUR-BYTE SINGLE PRECISION FLOATING POINT"),
        *_axis_cards(info),
        ("TELESCOP", "Spitzer", "Spitzer Space Telescope"),
        ("INSTRUME", "IRAC", "Spitzer Space Telescope instrument ID"),
        ("CHNLNUM", info.channel, "1 digit instrument channel number"),
    ]
    after: list[Card] = [
        ("RONOISE", info.read_noise_e, "[Electrons] Readout Noise"),
        ("FRAMTIME", info.frame_time_s, "[sec] Time spent integrating (whole array)"),
        ("EXPTIME", info.exptime_s, "[sec] Effective integration time per pixel"),
        ("BUNIT", "MJy/sr", "Units of image data"),
        ("AORKEY", info.aorkey, "AOR or EIR key. Astrnmy Obs Req/Instr Eng Req"),
    ]
    return before, after
