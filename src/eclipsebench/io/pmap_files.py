"""Pixel-map files for KR/Pmap: the calibration-star table and the SSC's gridded warm pmap.

The two kinds of map (paper Appendix B.4; Krick et al. 2016), read from
their files into arrays; :mod:`eclipsebench.decorrelate.pmap` and
:mod:`eclipsebench.decorrelate.kernel` work on the arrays and never see a path.

* a **calibration-star table**: photometry of a separate, constant star whose
  centroid wandered over the sweet-spot pixel (the simulator writes one to
  ``SIMDIR/calibration/pmap_calibration.fits`` with columns ``x``, ``y``,
  ``noise_pixels``, ``flux``, ``flux_err``): :class:`CalibrationSet`;
* the **gridded warm pmap** of the Spitzer Science Center (``pmap_ch2_*.fits``
  with ``xgrid_``, ``ygrid_``, ``occu_`` and ``psigma_`` companions, 500x500
  cells over pixel (15, 15)): :class:`GriddedPmap`.

Coordinates: the IRSA code defines the centroid so that the centre of the
bottom-left pixel is (0.0, 0.0), and its ``xgrid``/``ygrid`` run from 14.501
to 15.499: the same 0-based convention as this package (pixel (15, 15)
spans 14.5..15.5), so no offset is applied. ``xgrid`` varies along the FITS
NAXIS1 axis (numpy axis 1) and ``ygrid`` along NAXIS2 (numpy axis 0), i.e. the
map is indexed ``gain[iy, ix]`` like an image.

Nothing here has a default path: the user passes one, or the photometry
table's provenance (``SIMDIR``) points to a simulation folder that has a
calibration table.

Map version by date. The SSC released its warm maps in versions named by
their date (``..._YYMMDD.fits``: channel 2 ``120124``, then ``120827``, which
became the correction code's channel-2 default from 2012-08 on). The code
itself applies the one map it ships and has no date rule; what it "would
pick" for an observation is the default in force at the observation's date.
Given a folder that holds several versions (for example
``../shared/data/irac/`` with ``pmap_ch2/`` and ``pmap_ch2_120827/``),
:func:`pick_pmap_version` takes, among the maps of the data's channel, the
latest version dated on or before the observation (the earliest when the
observation predates them all). The real epoch 1 of the paper (2012-11-09)
gets ``120827``.
"""

from __future__ import annotations

import datetime
import os
import re
import warnings
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import DataError, InputError
from ..limits import MAX_PMAP_FILE_BYTES
from .inputs import check_input_file

__all__ = ["CalibrationSet", "GriddedPmap", "load_calibration_table", "load_gridded_pmap",
           "load_pmap", "find_pmap_path", "CALIBRATION_RELPATH", "pmap_versions",
           "pick_pmap_version", "check_pmap_path", "pmap_files"]

#: Where a simulated challenge keeps its calibration-star table, relative to SIMDIR.
CALIBRATION_RELPATH = Path("calibration") / "pmap_calibration.fits"

_TABLE_COLUMNS = ("x", "y", "noise_pixels", "flux", "flux_err")
_GRID_PARTS = ("pmap", "xgrid", "ygrid", "occu", "psigma")


@dataclass(frozen=True)
class CalibrationSet:
    """Photometry of a calibration star (a "pmap data set"), one row per frame.

    Attributes
    ----------
    x, y : ndarray
        Centroids, 0-based pixel coordinates.
    noise_pixels : ndarray
        Noise pixels beta of each frame.
    flux, flux_err : ndarray
        Aperture flux and uncertainty, electrons.
    source : str
        The file it came from.
    """

    x: np.ndarray
    y: np.ndarray
    noise_pixels: np.ndarray
    flux: np.ndarray
    flux_err: np.ndarray
    source: str = ""

    def __len__(self) -> int:
        return len(self.x)


@dataclass(frozen=True)
class GriddedPmap:
    """A gain map sampled on a regular grid (the SSC warm pmap).

    Attributes
    ----------
    x_grid, y_grid : ndarray, shape (nx,), (ny,)
        Cell centres, 0-based pixel coordinates, increasing.
    gain : ndarray, shape (ny, nx)
        Relative gain (mean about 1), indexed ``gain[iy, ix]``.
    occupancy : ndarray, shape (ny, nx)
        Kernel-weighted number of calibration points behind each cell.
    gain_sigma : ndarray, shape (ny, nx)
        Uncertainty of the gain.
    source : str
        The pmap file it came from.
    """

    x_grid: np.ndarray
    y_grid: np.ndarray
    gain: np.ndarray
    occupancy: np.ndarray
    gain_sigma: np.ndarray
    source: str = ""


def _read_fits_quietly(path: Path):
    """Open a FITS file, turning astropy's header-trailer warnings into nothing fatal.

    The SSC pmap files end with a non-standard trailer after the data that
    astropy reports as an ``AstropyUserWarning``; only that category is
    suppressed, and only here.
    """

    # a regular file within the stated size: not a device (/dev/zero) nor a FIFO
    check_input_file(path, "pixel-map FITS file", MAX_PMAP_FILE_BYTES)
    try:
        from astropy.io import fits  # about 0.02-0.2 s: not for a reduce of a CSV
        from astropy.utils.exceptions import AstropyUserWarning

        with warnings.catch_warnings():
            warnings.simplefilter("ignore", AstropyUserWarning)
            with fits.open(path, memmap=False) as hdul:
                hdul.verify("silentfix")
                return [(h.header.copy(), None if h.data is None else np.array(h.data))
                        for h in hdul]
    except OSError as exc:
        raise DataError(path, f"not a readable FITS file ({exc})") from None


def load_calibration_table(path: str | os.PathLike) -> CalibrationSet:
    """Read a calibration-star table (FITS binary table with x, y, noise_pixels, flux, flux_err).

    Rows with a non-finite value in any column are dropped.

    Raises
    ------
    DataError
        The file is missing, unreadable, has no table, lacks a column, or has
        fewer than 2 usable rows.
    """
    p = Path(path)
    if not p.is_file():
        raise DataError(p, "calibration table not found")
    hdus = _read_fits_quietly(p)
    table = next((d for _, d in hdus if d is not None and getattr(d, "dtype", None) is not None
                  and d.dtype.names), None)
    if table is None:
        raise DataError(p, "no binary table with the calibration columns "
                           f"{', '.join(_TABLE_COLUMNS)}")
    names = {n.lower(): n for n in table.dtype.names}
    missing = [c for c in _TABLE_COLUMNS if c not in names]
    if missing:
        raise DataError(p, f"calibration table lacks the column(s) {', '.join(missing)}")
    cols = {c: np.asarray(table[names[c]], dtype=float).ravel() for c in _TABLE_COLUMNS}
    good = np.ones(len(cols["x"]), bool)
    for v in cols.values():
        good &= np.isfinite(v)
    good &= cols["flux"] > 0
    if good.sum() < 2:
        raise DataError(p, "calibration table has fewer than 2 rows with finite values")
    return CalibrationSet(**{c: v[good] for c, v in cols.items()}, source=str(p))


def _grid_files(path: Path) -> dict[str, Path]:
    """The five files of a gridded pmap, given its folder or its ``pmap_`` file."""
    if path.is_dir():
        pm = sorted(path.glob("pmap_*.fits"))
        if len(pm) != 1:
            raise DataError(path, f"expected exactly one pmap_*.fits file, found {len(pm)}")
        path = pm[0]
    name = path.name
    if not name.startswith("pmap_"):
        raise DataError(path, "a gridded pmap file name must start with 'pmap_'")
    suffix = name[len("pmap_"):]
    files = {part: path.with_name(f"{part}_{suffix}") for part in _GRID_PARTS}
    missing = [str(f.name) for f in files.values() if not f.is_file()]
    if missing:
        raise DataError(path, f"gridded pmap companion file(s) missing: {', '.join(missing)}")
    return files


def pmap_files(path: str | os.PathLike) -> list[Path]:
    """The files a map at ``path`` is read from: a gridded map's five, else the file itself.

    ``path`` is what :func:`find_pmap_path` returned (a map version already
    picked); the run folder records their content (:mod:`eclipsebench.io.digest`).
    """
    p = Path(path)
    try:
        return sorted(_grid_files(p).values())
    except DataError:
        if p.is_dir():
            raise
        return [p]   # a calibration-star table (or a file load_pmap will refuse)


def load_gridded_pmap(path: str | os.PathLike) -> GriddedPmap:
    """Read the SSC gridded pmap (pmap_, xgrid_, ygrid_, occu_, psigma_ files).

    Parameters
    ----------
    path : path
        The folder holding the five files, or the ``pmap_*.fits`` file itself.

    Raises
    ------
    DataError
        A file is missing, unreadable, or the grids are not regular and consistent.
    """
    files = _grid_files(Path(path))
    arrays = {}
    for part, f in files.items():
        hdus = _read_fits_quietly(f)
        data = hdus[0][1]
        if data is None or data.ndim != 2:
            raise DataError(f, "expected a 2-D image in the primary HDU")
        arrays[part] = np.asarray(data, dtype=float)
    shape = arrays["pmap"].shape
    for part, a in arrays.items():
        if a.shape != shape:
            raise DataError(files[part], f"image shape {a.shape} differs from the pmap's {shape}")
    xg, yg = arrays["xgrid"], arrays["ygrid"]
    x_grid, y_grid = xg[0, :], yg[:, 0]
    if not (np.allclose(xg, x_grid[None, :], atol=1e-6) and np.allclose(yg, y_grid[:, None], atol=1e-6)):
        raise DataError(files["xgrid"], "xgrid/ygrid do not form a regular grid "
                                        "(x along axis 1, y along axis 0)")
    for g, part in ((x_grid, "xgrid"), (y_grid, "ygrid")):
        step = np.diff(g)
        if len(g) < 2 or np.any(step <= 0) or not np.allclose(step, step[0], rtol=1e-4):
            raise DataError(files[part], "grid coordinates must increase in equal steps")
    if not np.all(np.isfinite(arrays["pmap"])):
        raise DataError(files["pmap"], "gain map has non-finite cells")
    return GriddedPmap(x_grid=x_grid, y_grid=y_grid, gain=arrays["pmap"],
                       occupancy=arrays["occu"], gain_sigma=arrays["psigma"],
                       source=str(files["pmap"]))


def check_pmap_path(path: str | os.PathLike) -> Path:
    """``path`` if it is a folder or a regular file within ``MAX_PMAP_FILE_BYTES``.

    The check of ``--pmap`` before any work: a missing path, a device
    (``/dev/zero``) or a FIFO is one line naming it. Files in a folder are
    checked the same way when they are read.

    Raises
    ------
    InputError
        One line naming the path.
    """
    p = Path(path)
    if not p.exists():
        raise InputError(f"pmap {p}: no such file or folder")
    if not p.is_dir():
        check_input_file(p, "pixel-map FITS file", MAX_PMAP_FILE_BYTES)
    return p


def load_pmap(path: str | os.PathLike) -> CalibrationSet | GriddedPmap:
    """Load either kind of pixel map from ``path``, recognised by its content.

    A folder is read as the gridded SSC map (its single ``pmap_*.fits`` and
    companions); a file holding a binary table as a calibration-star table; a
    file whose primary HDU is a 2-D image and whose name starts with
    ``pmap_`` as the gridded map.
    """
    p = check_pmap_path(path)
    if p.is_dir():
        return load_gridded_pmap(p)
    hdus = _read_fits_quietly(p)
    if any(d is not None and getattr(d, "dtype", None) is not None and d.dtype.names
           for _, d in hdus):
        return load_calibration_table(p)
    if p.name.startswith("pmap_") and hdus[0][1] is not None and hdus[0][1].ndim == 2:
        return load_gridded_pmap(p)
    raise DataError(p, "neither a calibration-star table nor a gridded pmap_*.fits image")


_VERSION = re.compile(r"^pmap_ch(\d)_.*_(\d{6})\.fits$")
# BMJD of 2000-01-01 00:00 (MJD 51544).
_MJD_2000 = 51544.0


def pmap_versions(folder: str | os.PathLike, channel: int) -> list[tuple[datetime.date, Path]]:
    """The gridded maps of ``channel`` in ``folder`` and its subfolders, by version date.

    A map is a ``pmap_ch<N>_..._<YYMMDD>.fits`` file (the SSC's naming); the
    version date is its last six digits.

    Examples
    --------
    >>> pmap_versions("no/such/folder", 2)
    []
    """
    root = Path(folder)
    found = []
    for f in sorted(root.glob("pmap_*.fits")) + sorted(root.glob("*/pmap_*.fits")):
        m = _VERSION.match(f.name)
        if m is None or int(m.group(1)) != int(channel):
            continue
        yymmdd = m.group(2)
        try:
            date = datetime.date(2000 + int(yymmdd[:2]), int(yymmdd[2:4]), int(yymmdd[4:]))
        except ValueError:
            continue
        found.append((date, f))
    return sorted(found)


def pick_pmap_version(versions: list[tuple[datetime.date, Path]], time_bmjd: float) -> Path:
    """The map in force at ``time_bmjd``: the latest version dated on or before it.

    An observation older than every version gets the earliest one.

    Examples
    --------
    >>> v = [(datetime.date(2012, 1, 24), Path("a")), (datetime.date(2012, 8, 27), Path("b"))]
    >>> str(pick_pmap_version(v, 56240.7)), str(pick_pmap_version(v, 56000.0))
    ('b', 'a')
    >>> str(pick_pmap_version(v, 55000.0))
    'a'
    """
    if not versions:
        raise InputError("pmap: no map versions to choose from")
    day = datetime.date(2000, 1, 1) + datetime.timedelta(days=float(time_bmjd) - _MJD_2000)
    before = [path for date, path in versions if date <= day]
    return before[-1] if before else versions[0][1]


def find_pmap_path(option: str | os.PathLike | None, meta: Mapping[str, Any],
                   time_bmjd: float | None = None) -> Path:
    """The pixel-map path for KR/Pmap: the option, else ``SIMDIR/calibration/...``.

    A folder given as the option that holds more than one gridded map of the
    data's channel (``meta["CHANNEL"]``, default 2), directly or one level
    down, is a library of map versions: the one in force at the observation's
    date (``time_bmjd``, the first frame) is taken (:func:`pick_pmap_version`).

    Parameters
    ----------
    option : path or None
        The caller's ``pmap`` argument (``--pmap PATH`` on the command line).
    meta : mapping
        The photometry table's provenance; ``meta["SIMDIR"]`` is the simulation
        folder when the data are simulated.
    time_bmjd : float, optional
        The observation's time, to pick a map version by date.

    Raises
    ------
    InputError
        Neither the option nor a calibration table under ``SIMDIR`` exists.
    """
    if option is not None and str(option) != "":
        p = Path(option)
        if not p.exists():
            raise InputError(f"pmap {p}: no such file or folder")
        if p.is_dir():
            channel = int(meta.get("CHANNEL", meta.get("channel", 2)) or 2)
            versions = pmap_versions(p, channel)
            if len(versions) > 1 or (versions and not list(p.glob("pmap_*.fits"))):
                if time_bmjd is None:
                    raise InputError(f"pmap {p}: holds {len(versions)} map versions of channel "
                                     f"{channel}; the observation date is needed to pick one")
                return pick_pmap_version(versions, time_bmjd)
        return p
    simdir = meta.get("SIMDIR") or meta.get("simdir")
    if simdir:
        p = Path(str(simdir)) / CALIBRATION_RELPATH
        if p.is_file():
            return p
        raise InputError(f"method 'kr-pmap': no pmap given and {p} (from the table's SIMDIR) "
                         "does not exist")
    raise InputError("method 'kr-pmap': needs a pmap (a calibration-star table or the "
                     "gridded pmap folder); the table names no simulation folder (SIMDIR)")
