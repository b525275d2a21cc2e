"""A photometry table (one epoch) turned into the arrays a method fits.

Only good frames are kept (``flag == 0`` and finite time, flux, error and
centroid); frames are put in time order. The aperture is the table's default
``flux``/``flux_err`` pair (r = 2.25 px) unless ``radius_px`` picks one of the
``flux_r<R>`` columns (``flux_r2p50`` for 2.5 px).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..decorrelate.base import EpochData
from ..errors import InputError

__all__ = ["epoch_data_from_table", "aperture_column", "REQUIRED_COLUMNS"]

#: Columns every method needs.
REQUIRED_COLUMNS = ("time_bmjd", "flux", "flux_err", "x", "y", "flag")


def aperture_column(radius_px: float) -> str:
    """The name of the flux column of an aperture of ``radius_px`` pixels.

    Examples
    --------
    >>> aperture_column(2.25)
    'flux_r2p25'
    >>> aperture_column(3)
    'flux_r3p00'
    """
    return "flux_r" + f"{float(radius_px):.2f}".replace(".", "p")


def _column(table, name: str) -> np.ndarray:
    col = table[name]
    return np.asarray(getattr(col, "value", col))


def _source(table) -> str:
    meta = getattr(table, "meta", {}) or {}
    return str(meta.get("FILENAME", meta.get("filename", "the photometry table")))


def epoch_data_from_table(table, *, radius_px: float | None = None,
                          stamp: str = "stamp3") -> EpochData:
    """The good frames of one photometry table as an :class:`EpochData`.

    Parameters
    ----------
    table : astropy.table.Table
        One epoch (columns of ``docs/contracts.md``: ``time_bmjd, aorkey, x, y,
        noise_pixels, flux, flux_err, flag, stamp3, stamp5, ...``).
    radius_px : float or None
        Aperture radius; None uses the table's default ``flux``/``flux_err``.
        Another radius uses ``flux_r<R>``; its error is ``flux_err_r<R>`` when
        the table has it, otherwise ``flux_err`` scaled by the ratio of the
        frame-to-frame scatters of the two apertures (a data-driven estimate).
    stamp : {"stamp3", "stamp5", "none"}
        Pixel stamps for pixel-level methods (PLD, ICA); "none" leaves them out.
        A table without the stamp column gives ``pixels=None`` (methods that
        need pixels then refuse with a message naming the column).

    Returns
    -------
    EpochData
        Time-ordered good frames; ``meta`` holds the table metadata plus
        ``n_frames_table``, ``n_frames_flagged`` and ``n_frames_nonfinite``.

    Raises
    ------
    InputError
        When required columns are missing (all of them named), when every
        frame is flagged, or when ``stamp`` / ``radius_px`` name nothing usable.
    """
    src = _source(table)
    names = set(table.colnames)
    flux_name, err_name = "flux", "flux_err"
    if radius_px is not None:
        flux_name = aperture_column(radius_px)
        err_name = flux_name.replace("flux_", "flux_err_")
    required = [c for c in REQUIRED_COLUMNS if c not in ("flux", "flux_err")] + ["flux", "flux_err"]
    if radius_px is not None:
        required.append(flux_name)
    missing = [c for c in required if c not in names]
    if missing:
        raise InputError(f"{src}: missing column(s) {', '.join(missing)} "
                         f"(a photometry table needs {', '.join(required)})")
    if stamp not in ("stamp3", "stamp5", "none"):
        raise InputError(f"stamp {stamp!r}: expected 'stamp3', 'stamp5' or 'none'")

    n_table = len(table)
    flag = _column(table, "flag")
    good = flag == 0
    n_flagged = int(np.count_nonzero(~good))
    if not np.any(good):
        raise InputError(f"{src}: all {n_table} frames are flagged (flag != 0); nothing to fit")

    time = _column(table, "time_bmjd").astype(float)
    flux = _column(table, flux_name).astype(float)
    base_err = _column(table, "flux_err").astype(float)
    x = _column(table, "x").astype(float)
    y = _column(table, "y").astype(float)
    finite = np.isfinite(time) & np.isfinite(flux) & np.isfinite(base_err) & (base_err > 0) \
        & np.isfinite(x) & np.isfinite(y)
    if "noise_pixels" in names:
        finite &= np.isfinite(_column(table, "noise_pixels").astype(float))
    pixels = None
    if stamp != "none" and stamp in names:
        cube = np.asarray(_column(table, stamp), dtype=float)
        pixels = cube.reshape(len(cube), -1)
        finite &= np.all(np.isfinite(pixels), axis=1)
    keep = good & finite
    n_nonfinite = int(np.count_nonzero(good & ~finite))
    if not np.any(keep):
        raise InputError(f"{src}: no unflagged frame has finite time, flux, flux_err > 0, "
                         "centroid" + (f" and {stamp} pixels" if pixels is not None else ""))

    if radius_px is None:
        flux_err = base_err
    elif err_name in names:
        flux_err = _column(table, err_name).astype(float)
    else:
        flux_err = base_err * _scatter_ratio(flux[keep], _column(table, "flux").astype(float)[keep])

    order = np.argsort(time[keep], kind="stable")
    index = np.flatnonzero(keep)[order]

    def pick(a):
        return None if a is None else np.ascontiguousarray(np.asarray(a)[index])

    noise_pixels = _column(table, "noise_pixels").astype(float) if "noise_pixels" in names else None
    aorkey = _column(table, "aorkey") if "aorkey" in names else None

    meta: dict[str, Any] = {str(k): v for k, v in (getattr(table, "meta", {}) or {}).items()}
    meta.update(n_frames_table=n_table, n_frames_flagged=n_flagged,
                n_frames_nonfinite=n_nonfinite, flux_column=flux_name)
    return EpochData(time_bmjd=pick(time), flux=pick(flux), flux_err=pick(flux_err),
                     x=pick(x), y=pick(y), noise_pixels=pick(noise_pixels), pixels=pick(pixels),
                     aorkey=pick(aorkey), meta=meta)


def _scatter_ratio(flux_other: np.ndarray, flux_default: np.ndarray) -> float:
    """Ratio of the frame-to-frame scatters (MAD of first differences) of two apertures."""
    def scatter(f):
        d = np.diff(f)
        return float(np.median(np.abs(d - np.median(d))))
    s0 = scatter(flux_default)
    if len(flux_default) < 3 or s0 <= 0:
        return 1.0
    return scatter(flux_other) / s0
