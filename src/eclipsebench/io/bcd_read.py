"""Read Spitzer/IRAC BCD products (archive or simulated) into arrays and frame times.

File names follow the archive: ``SPITZER_I<ch>_<AORKEY>_<EXPID>_<DCE>_<ver>_bcd.fits``
with optional ``_bunc.fits`` (uncertainty, MJy/sr) and ``_bimsk.fits``
(bit mask) companions. Subarray files are cubes of 32x32 frames (64 per
file); full-array files are single 256x256 frames.

Frame times
-----------
``BMJD_OBS`` is the barycentric MJD of the start of the data-collection event
(DCE). On the archive files it is a *UTC* timestamp moved to the barycentre
(``BMJD_OBS - MJD_OBS`` is the light-travel time alone; the real headers give
``ET_OBS - UTCS_OBS = TDB - UTC`` = 67.184 s in December 2012). We therefore

1. take frame ``k`` of a file to start at ``BMJD_OBS + k * dt_frame``, where
   ``dt_frame`` is FRAMTIME unless ``AINTBEG``/``ATIMEEND`` say the frames are
   spaced more widely: ``(ATIMEEND - AINTBEG - FRAMTIME) / (n - 1)`` when that
   is >= FRAMTIME (the simulator's convention, 2.008 s); on the real cubes it
   is 1.968 s < FRAMTIME, so FRAMTIME (2 s) is used;
2. put its mid-exposure at the centre of the Fowler reads,
   ``(2 FN + WT + 1) / 2 * SAMPTIME`` after the frame start (1.005 s for the
   2 s subarray readout; FRAMTIME / 2 when the readout is unknown);
3. convert from UTC to TDB with astropy (leap seconds + 32.184 s + the
   periodic TDB-TT term): ``time_bmjd = tdb(BMJD_OBS + t_k / 86400)``.

The time scale of ``BMJD_OBS`` is taken from ``TIMESYS`` when the header has
it; otherwise it is UTC for archive files and TDB for files written by the
eclipsebench simulator (``SIMULATE = T``; :mod:`eclipsebench.io.bcd_write`
writes BMJD_TDB into ``BMJD_OBS``).

Units
-----
BCD values are MJy/sr; electrons per pixel are ``BCD * GAIN * EXPTIME / FLUXCONV``
(paper Appendix A: ``BCD = FLUXCONV * e / (GAIN * t_exp)``).
"""

from __future__ import annotations

import contextlib
import math
import os
import re
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from astropy.io import fits
from astropy.time import Time

from ..detector.constants import ReadoutMode, ronoise_e
from ..errors import DataError, InputError

__all__ = ["BCD_NAME", "TARGET_KEYS", "BcdInfo", "BcdCube", "Epoch", "find_bcd_files", "read_bcd_header",
           "read_bcd", "frame_times_bmjd", "group_epochs", "electrons_per_mjysr"]

BCD_NAME = re.compile(r"^SPITZER_I(?P<ch>[1-4])_(?P<aorkey>\d+)_(?P<expid>\d+)_(?P<dce>\d+)_"
                      r"(?P<ver>\d+)_bcd\.fits$")
_REQUIRED = ("BMJD_OBS", "FRAMTIME", "EXPTIME", "GAIN", "FLUXCONV")
SECONDS_PER_DAY = 86400.0


@dataclass(frozen=True)
class BcdInfo:
    """What the pipeline needs from one BCD file's header and name."""

    path: Path
    channel: int
    aorkey: int
    expid: int
    dce: int
    n_frames: int
    ny: int
    nx: int
    subarray: bool
    bmjd_obs: float
    tdb: bool
    framtime_s: float
    exptime_s: float
    gain: float
    fluxconv: float
    fowler: int
    wait: int
    read_noise_e: float
    frame_interval_s: float = 0.0
    sample_time_s: float = 0.01
    epoch: int | None = None
    simulate: bool = False
    extra: dict = field(default_factory=dict, compare=False)

    @property
    def electrons_per_mjysr(self) -> float:
        """Factor that turns MJy/sr into electrons per pixel per frame."""
        return electrons_per_mjysr(self.gain, self.exptime_s, self.fluxconv)

    @property
    def extra_target(self) -> dict:
        """The target cards of the header (:data:`TARGET_KEYS` present)."""
        return {k: self.extra[k] for k in TARGET_KEYS if k in self.extra}

    @property
    def start_bmjd(self) -> float:
        """Mid-exposure time of the first frame, BMJD_TDB."""
        return float(frame_times_bmjd(self)[0])


@dataclass
class BcdCube:
    """One BCD file read: frames in MJy/sr, optional uncertainty and mask."""

    info: BcdInfo
    data: np.ndarray                 # (n_frames, ny, nx) float32, MJy/sr
    unc: np.ndarray | None = None    # same shape, MJy/sr
    mask: np.ndarray | None = None   # same shape, int32 bits

    @property
    def time_bmjd(self) -> np.ndarray:
        """Mid-exposure time of each frame, BMJD_TDB."""
        return frame_times_bmjd(self.info)


@dataclass(frozen=True)
class Epoch:
    """AORs observed together: number (1-based) and their files in time order."""

    number: int
    aorkeys: tuple[int, ...]
    files: tuple[BcdInfo, ...]


def electrons_per_mjysr(gain: float, exptime_s: float, fluxconv: float) -> float:
    """``GAIN * EXPTIME / FLUXCONV``: electrons per pixel for 1 MJy/sr.

    Examples
    --------
    >>> round(electrons_per_mjysr(3.71, 1.92, 0.1447), 4)
    49.2274
    """
    return float(gain) * float(exptime_s) / float(fluxconv)


def find_bcd_files(input_dir: str | os.PathLike, channel: int | None = None) -> list[Path]:
    """All ``*_bcd.fits`` files under ``input_dir`` (recursively), sorted by name.

    Raises
    ------
    InputError
        If ``input_dir`` is not a folder, holds no BCD file, or holds several
        channels and ``channel`` is not given.
    """
    root = Path(input_dir)
    if root.is_file() and BCD_NAME.match(root.name):
        files = [root]
    elif not root.is_dir():
        raise InputError(f"{root}: no such folder (expected a folder of IRAC *_bcd.fits files)")
    else:
        files = sorted(_walk_bcd(root), key=lambda p: p.name)
    if channel is not None:
        files = [p for p in files if _name_channel(p) == int(channel)]
    if not files:
        what = f"channel {channel} " if channel is not None else ""
        raise InputError(f"{root}: no IRAC {what}BCD files (SPITZER_I<ch>_<AORKEY>_<EXPID>_"
                         "<DCE>_<ver>_bcd.fits) found")
    channels = sorted({_name_channel(p) for p in files})
    if len(channels) > 1:
        raise InputError(f"{root}: files of channels {channels}; choose one with --channel")
    return files


def _name_channel(path: Path) -> int:
    """The IRAC channel in a BCD file name (``SPITZER_I<ch>_...``); the walk keeps only such names."""
    match = BCD_NAME.match(path.name)
    if match is None:
        raise InputError(f"{path}: not an IRAC BCD file name")
    return int(match["ch"])


def _walk_bcd(root: Path) -> list[Path]:
    """Every archive-named BCD file under ``root``; an unreadable folder is an error."""
    def refuse(exc: OSError) -> None:
        where = exc.filename or root
        if isinstance(exc, PermissionError):
            raise InputError(f"{where}: permission denied (cannot list this folder of IRAC "
                             "BCD files)") from None
        raise InputError(f"{where}: cannot list this folder ({exc.strerror or exc})") from None

    if not os.access(root, os.R_OK | os.X_OK):
        refuse(PermissionError(13, "Permission denied", str(root)))
    found: list[Path] = []
    for folder, dirs, names in os.walk(root, onerror=refuse, followlinks=True):
        dirs.sort()
        found.extend(Path(folder) / n for n in names if BCD_NAME.match(n))
    return found


_MISSING = object()
_EXPECTED = {float: "a finite number", int: "an integer"}


def _card_text(header: fits.Header, key: str) -> str:
    """The value as written in the card, for messages about values astropy cannot parse."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            image = header.cards[key]._image or header.cards[key].image
    except Exception:
        return "?"
    text = image[10:] if image[8:10] == "= " else image[8:]
    return text.split("/", 1)[0].strip() or "?"


def _card(header: fits.Header, key: str, path: Path, kind=float, default=_MISSING, *,
          digits: bool = False):
    """Header value ``key`` as ``kind`` (float or int), or ``default`` when absent.

    ``digits``: a string of digits is read as the integer it spells (the 2015
    challenge's public cubes write ``AORKEY = '20150000'``).

    Raises
    ------
    DataError
        Naming the file and the key when the card is missing (and no default),
        unparsable (``BMJD_OBS = NaN``), not a number or not finite.
    """
    expected = _EXPECTED.get(kind, kind.__name__)
    value: Any = None
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # astropy "fixes" some bad cards with a warning
            present = key in header
            value = header[key] if present else None
    except Exception:  # astropy's VerifyError or VerifyWarning for an unparsable card
        raise DataError(path, f"header {key} = {_card_text(header, key)}: unparsable card; "
                              f"expected {expected}") from None
    if not present:
        if default is _MISSING:
            raise DataError(path, f"header lacks {key}")
        return default
    if digits and isinstance(value, str) and value.strip().isdigit():
        value = int(value.strip())
    try:
        if isinstance(value, bool) or isinstance(value, str) and kind is int:
            raise ValueError
        number = float(value)
        out = kind(number)
        if kind is int and out != number:
            raise ValueError
    except (TypeError, ValueError, OverflowError):
        raise DataError(path, f"header {key} = {value!r}: expected {expected}") from None
    if kind is float and not math.isfinite(out):
        raise DataError(path, f"header {key} = {value!r}: expected {expected}")
    return out


@contextlib.contextmanager
def _open(path: Path):
    """Open a FITS file, turning every failure and warning into a DataError."""
    try:
        fh = open(path, "rb")  # noqa: SIM115 - closed by the with block below
    except FileNotFoundError:
        raise DataError(path, "no such file") from None
    except OSError as exc:
        raise DataError(path, f"cannot read ({exc.strerror})") from None
    with fh:
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("error")
                hdul = fits.open(fh, memmap=False, lazy_load_hdus=False)
        except Exception as exc:  # astropy raises OSError, ValueError, VerifyWarning...
            text = str(exc).splitlines()[0] if str(exc) else ""
            raise DataError(path, f"not a readable FITS file ({type(exc).__name__}: {text})") \
                from None
        with hdul:
            yield hdul


def _check_complete(path: Path, hdu) -> None:
    """Refuse files shorter than their header says (truncated downloads)."""
    size = path.stat().st_size
    expected = hdu._data_offset + hdu._data_size if hdu._data_offset is not None else None
    if expected is not None and size < expected:
        raise DataError(path, f"truncated: {size} bytes, the header needs {expected}")


def read_bcd_header(path: str | os.PathLike) -> BcdInfo:
    """Parse and check the header of one BCD file (the data are not read).

    Raises
    ------
    DataError
        Naming the file when it is unreadable or truncated, has the wrong
        shape (anything but n x 32 x 32 or 256 x 256), or lacks a keyword
        needed for times or units (BMJD_OBS, FRAMTIME, EXPTIME, GAIN, FLUXCONV).
    """
    path = Path(path)
    m = BCD_NAME.match(path.name)
    if m is None:
        raise DataError(path, "name does not follow SPITZER_I<ch>_<AORKEY>_<EXPID>_<DCE>_<ver>"
                              "_bcd.fits")
    with _open(path) as hdul:
        hdu = hdul[0]
        header = hdu.header
        _check_complete(path, hdu)
        naxis = header.get("NAXIS", 0)
        shape = tuple(int(header.get(f"NAXIS{k}", 0)) for k in range(naxis, 0, -1))
        if naxis == 3 and shape[1:] == (32, 32) and shape[0] >= 1:
            n_frames, ny, nx, subarray = shape[0], 32, 32, True
        elif naxis == 2 and shape == (256, 256):
            n_frames, ny, nx, subarray = 1, 256, 256, False
        elif naxis == 3 and shape == (1, 256, 256):
            n_frames, ny, nx, subarray = 1, 256, 256, False
        else:
            raise DataError(path, f"NAXIS={naxis} shape {shape}: expected a subarray cube "
                                  "(n, 32, 32) or a full-array frame (256, 256)")
        bunit = str(header.get("BUNIT", "MJy/sr")).strip()
        if bunit.replace(" ", "").lower() != "mjy/sr":
            raise DataError(path, f"BUNIT = {bunit!r}: expected MJy/sr")
        values = {key: _card(header, key, path) for key in _REQUIRED}
        for key in ("FRAMTIME", "EXPTIME", "GAIN", "FLUXCONV"):
            if values[key] <= 0:
                raise DataError(path, f"header {key} = {values[key]}: expected a positive number")
        readmode = str(header.get("READMODE", "SUB" if subarray else "FULL")).strip().upper()
        if subarray != (readmode == "SUB"):
            raise DataError(path, f"READMODE = {readmode!r} does not match the data shape {shape}")
        chnl = _card(header, "CHNLNUM", path, int, int(m["ch"]))
        if chnl != int(m["ch"]):
            raise DataError(path, f"CHNLNUM = {chnl} but the name says channel {m['ch']}")
        aorkey = _card(header, "AORKEY", path, int, int(m["aorkey"]), digits=True)
        if aorkey != int(m["aorkey"]):
            raise DataError(path, f"AORKEY = {aorkey} but the name says {m['aorkey']}")
        sample_s = _card(header, "SAMPTIME", path, float, 0.01 if subarray else 0.2)
        if sample_s <= 0:
            raise DataError(path, f"header SAMPTIME = {sample_s}: expected a positive number")
        fowler = _card(header, "AFOWLNUM", path, int, None)
        wait = _card(header, "AWAITPER", path, int, None)
        if fowler is None or wait is None:  # EXPTIME = (FN + WT) dt, FRAMTIME = (2 FN + WT) dt
            fowler = round((values["FRAMTIME"] - values["EXPTIME"]) / sample_s)
            wait = round(values["EXPTIME"] / sample_s) - fowler
        epoch = _card(header, "EPOCH", path, int, None)
        expid = _card(header, "EXPID", path, int, int(m["expid"]))
        if expid != int(m["expid"]):
            raise DataError(path, f"EXPID = {expid} but the name says {m['expid']} (a copied "
                                  "or renamed cube?)")
        dce = _card(header, "DCENUM", path, int, int(m["dce"]))
        simulate = bool(header.get("SIMULATE", False))
        timesys = str(header.get("TIMESYS", "TDB" if simulate else "UTC")).strip().upper()
        if timesys not in ("UTC", "TDB"):
            raise DataError(path, f"TIMESYS = {timesys!r}: expected UTC or TDB")
        tdb = timesys == "TDB"
        interval = values["FRAMTIME"]
        if n_frames > 1 and "AINTBEG" in header and "ATIMEEND" in header:
            spread = (_card(header, "ATIMEEND", path) - _card(header, "AINTBEG", path)
                      - values["FRAMTIME"])
            candidate = spread / (n_frames - 1)
            if values["FRAMTIME"] <= candidate < 1.1 * values["FRAMTIME"]:
                interval = candidate
        fowler, wait = max(int(fowler), 1), max(int(wait), 0)
        read_noise = _card(header, "RONOISE", path, float, None)
        if read_noise is None:  # the channel's RONOISE for this readout (detector.constants)
            mode = ReadoutMode("header", fowler, wait, sample_s, values["FRAMTIME"], subarray)
            read_noise = ronoise_e(chnl, mode) if chnl in (1, 2) else ronoise_e(2, mode)
        return BcdInfo(
            path=path, channel=chnl, aorkey=aorkey, expid=expid,
            dce=dce, n_frames=n_frames, ny=ny, nx=nx,
            subarray=subarray, bmjd_obs=values["BMJD_OBS"], tdb=tdb,
            framtime_s=values["FRAMTIME"], exptime_s=values["EXPTIME"], gain=values["GAIN"],
            fluxconv=values["FLUXCONV"], fowler=fowler, wait=wait,
            read_noise_e=read_noise, frame_interval_s=interval,
            sample_time_s=sample_s, epoch=epoch, simulate=simulate,
            extra={"SIMSEED": header.get("SIMSEED"), "NOISEMOD": header.get("NOISEMOD"),
                   **_target_cards(header)})


#: What a table keeps of the target (``docs/contracts.md``): the archive's keys, and
#: ``SYSTEM``, the catalogue planet a simulation rendered (simulated cubes only).
TARGET_KEYS = ("OBJECT", "RA_REF", "DEC_REF", "AORLABEL", "DATE_OBS", "SYSTEM")


def _target_cards(header: fits.Header) -> dict:
    """The target cards present in ``header`` (text stripped, numbers finite), by name."""
    out: dict = {}
    for key in TARGET_KEYS:
        value = header.get(key)
        if isinstance(value, str) and value.strip():
            out[key] = value.strip()
        elif isinstance(value, (int, float)) and not isinstance(value, bool) \
                and math.isfinite(value):
            out[key] = float(value)
    return out


def frame_times_bmjd(info: BcdInfo) -> np.ndarray:
    """Mid-exposure BMJD_TDB of each frame of a file (see the module notes)."""
    k = np.arange(info.n_frames, dtype=float)
    interval = info.frame_interval_s if info.frame_interval_s > 0 else info.framtime_s
    mid = 0.5 * (2 * info.fowler + info.wait + 1) * info.sample_time_s
    if not 0.0 < mid <= info.framtime_s:
        mid = 0.5 * info.framtime_s
    t = info.bmjd_obs + (k * interval + mid) / SECONDS_PER_DAY
    if info.tdb:
        return t
    day = np.floor(t[0])
    tdb = Time(day, t - day, format="mjd", scale="utc").tdb
    return (tdb.jd1 - 2400000.5) + tdb.jd2


def _read_companion(path: Path, suffix: str, shape: tuple[int, ...], dtype) -> np.ndarray | None:
    comp = path.with_name(path.name[: -len("_bcd.fits")] + f"_{suffix}.fits")
    if not comp.exists():
        return None
    with _open(comp) as hdul:
        _check_complete(comp, hdul[0])
        data = hdul[0].data
        if data is None or data.size != int(np.prod(shape)):
            raise DataError(comp, f"shape {None if data is None else data.shape} does not match "
                                  f"its BCD {shape}")
        return np.asarray(data, dtype=dtype).reshape(shape)


def read_bcd(path: str | os.PathLike | BcdInfo, *, unc: bool = False,
             mask: bool = True) -> BcdCube:
    """Read one BCD file (and its ``_bunc``/``_bimsk`` companions when present).

    Parameters
    ----------
    path : path or BcdInfo
        The ``*_bcd.fits`` file (or its parsed header).
    unc, mask : bool
        Also read the uncertainty cube / the bit-mask cube if the file exists.

    Returns
    -------
    BcdCube
        ``data`` has shape (n_frames, ny, nx), float32, MJy/sr.
    """
    info = path if isinstance(path, BcdInfo) else read_bcd_header(path)
    with _open(info.path) as hdul:
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("error")
                raw = hdul[0].data
        except Exception as exc:
            raise DataError(info.path, f"data unreadable ({type(exc).__name__})") from None
        if raw is None:
            raise DataError(info.path, "no data in the primary HDU")
        shape = (info.n_frames, info.ny, info.nx)
        data = np.asarray(raw, dtype=np.float32).reshape(shape)
    cube = BcdCube(info=info, data=data)
    if unc:
        cube.unc = _read_companion(info.path, "bunc", shape, np.float32)
    if mask:
        cube.mask = _read_companion(info.path, "bimsk", shape, np.int32)
    return cube


def _refuse_duplicates(infos: list[BcdInfo], by_aor: dict[int, list[BcdInfo]]) -> None:
    """Refuse a cube present twice: same AORKEY/EXPID/DCE, or overlapping frame times.

    Within an AOR (files in time order) a cube must start after the previous
    cube's last frame has started; a copied cube (same BMJD_OBS) would
    otherwise put duplicated, or backwards, times into the table.
    """
    seen: dict[tuple[int, int, int, int], Path] = {}
    for info in infos:
        key = (info.channel, info.aorkey, info.expid, info.dce)
        if key in seen:
            raise DataError(info.path, f"duplicate: the same cube (AORKEY {info.aorkey}, EXPID "
                                       f"{info.expid}, DCE {info.dce}) as {seen[key].name}; "
                                       "remove one of them")
        seen[key] = info.path
    for files in by_aor.values():
        for prev, cur in zip(files, files[1:], strict=False):
            interval = prev.frame_interval_s if prev.frame_interval_s > 0 else prev.framtime_s
            last_start = prev.bmjd_obs + (prev.n_frames - 1) * interval / SECONDS_PER_DAY
            if cur.bmjd_obs < last_start or cur.bmjd_obs == prev.bmjd_obs:
                raise DataError(cur.path, f"duplicate: BMJD_OBS = {cur.bmjd_obs!r} falls inside "
                                          f"the frames of {prev.path.name} (BMJD_OBS = "
                                          f"{prev.bmjd_obs!r}); expected cubes that follow "
                                          "each other in time (a copied cube?)")


def group_epochs(infos: list[BcdInfo], gap_days: float = 1.0) -> list[Epoch]:
    """Group files into AORs and AORs into epochs, each in time order.

    AORs whose start times lie within ``gap_days`` of the previous AOR's start
    form one epoch; when every file carries an ``EPOCH`` header (simulated
    data) that number is used instead.

    Raises
    ------
    InputError
        If some files carry ``EPOCH`` and others do not, or one AOR's files
        disagree about it.
    """
    if not infos:
        return []
    by_aor: dict[int, list[BcdInfo]] = {}
    for info in infos:
        by_aor.setdefault(info.aorkey, []).append(info)
    for files in by_aor.values():
        files.sort(key=lambda i: (i.bmjd_obs, i.expid, i.dce))
    _refuse_duplicates(infos, by_aor)
    aors = sorted(by_aor, key=lambda a: by_aor[a][0].bmjd_obs)
    has_epoch = [i.epoch is not None for i in infos]
    if any(has_epoch) and not all(has_epoch):
        raise InputError(f"{infos[0].path.parent}: some BCD files carry an EPOCH header and "
                         "others do not; process simulated and real data separately")
    groups: dict[int, list[int]] = {}
    if all(has_epoch):
        for a in aors:
            epochs = {i.epoch for i in by_aor[a] if i.epoch is not None}   # all are, here
            if len(epochs) != 1:
                raise InputError(f"AOR {a}: its files carry different EPOCH headers {sorted(epochs)}")
            groups.setdefault(epochs.pop(), []).append(a)
    else:
        number = 0
        last_start = -np.inf
        for a in aors:
            start = by_aor[a][0].bmjd_obs
            if not groups or start - last_start > gap_days:   # gap_days may be inf
                number += 1
                groups[number] = []
            groups[number].append(a)
            last_start = start
    return [Epoch(number=num, aorkeys=tuple(groups[num]),
                  files=tuple(f for a in groups[num] for f in by_aor[a]))
            for num in sorted(groups)]
