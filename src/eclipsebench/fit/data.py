"""A photometry table (one epoch) turned into the arrays a method fits.

Only good frames are kept (``flag == 0`` and finite time, flux, error and
centroid); frames are put in time order. The aperture is the table's default
``flux``/``flux_err`` pair (r = 2.25 px) unless ``radius_px`` picks one of the
``flux_r<R>`` columns (``flux_r2p50`` for 2.5 px).

Photometry from other pipelines (``docs/photometry.md``) needs only
``time_bmjd, flux, flux_err, x, y``; :func:`standardise_table` maps another
table's column names (``columns``), its time column and time format, and its
pixel columns ``p0..p8`` (or ``p0..p24``) to the names used here.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from typing import Any

import numpy as np
from astropy.table import Table
from astropy.time import Time

from ..astro.timescales import TimeSpec, to_bmjd_tdb
from ..decorrelate.base import EpochData
from ..errors import InputError
from ..photometry.table import COLUMN_UNITS
from ..photometry.table import REQUIRED_COLUMNS as CONTRACT_COLUMNS
from .names import TIME_FORMATS, TIME_SCALES

__all__ = ["epoch_data_from_table", "aperture_column", "standardise_table", "median_cadence_s",
           "check_columns",
           "REQUIRED_COLUMNS", "OPTIONAL_COLUMNS", "TIME_FORMATS"]

#: Columns every method needs.
REQUIRED_COLUMNS = ("time_bmjd", "flux", "flux_err", "x", "y")
#: Columns some methods or rules use; a table may lack them (``flag`` absent: every frame good).
OPTIONAL_COLUMNS = ("noise_pixels", "flag", "aorkey", "background", "width_x", "width_y",
                    "stamp3", "stamp5")
#: Values below this are modified (MJD-like) dates, above it full Julian dates.
_JD_THRESHOLD_D = 1.0e6
_PIXEL_COLUMN = re.compile(r"^p(\d+)$")
_APERTURE_COLUMN = re.compile(r"^flux(_err)?_r\d+p\d\d$")
_ARGUMENTS = {"columns": "columns", "time_column": "time_column", "time_format": "time_format",
              "time_scale": "time_scale", "time_at": "time_at", "observer": "observer",
              "coordinates": "system=... with ra_deg and dec_deg"}


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


def median_cadence_s(time_bmjd: np.ndarray) -> float:
    """The median time step between consecutive rows in time order (s), to the microsecond.

    Non-finite times are ignored; NaN below two rows. A table of 2 s frames
    gives 2; one row per 64-frame cube of 2 s frames about 128 plus the gap
    between cubes.

    Examples
    --------
    >>> median_cadence_s(57000.0 + np.arange(5) * 128.0 / 86400.0)
    128.0
    """
    t = np.asarray(getattr(time_bmjd, "value", time_bmjd), dtype=float)
    t = np.sort(t[np.isfinite(t)])
    if len(t) < 2:
        return float("nan")
    return float(np.round(np.median(np.diff(t)) * 86400.0, 6))


def _known_name(name: str) -> bool:
    return (name in REQUIRED_COLUMNS or name in OPTIONAL_COLUMNS or name in CONTRACT_COLUMNS
            or name in COLUMN_UNITS or bool(_PIXEL_COLUMN.match(name))
            or bool(_APERTURE_COLUMN.match(name)))


def _names_list(table) -> str:
    names = list(table.colnames)
    return ", ".join(names[:25]) + (f", ... ({len(names)} columns)" if len(names) > 25 else "")


def _time_values(col, label: str, fmt: str, fmt_label: str) -> tuple[np.ndarray, str | None]:
    """The numbers of a time column in ``fmt`` (days), and an astropy Time column's scale.

    An astropy ``Time`` column gives its MJD (``fmt`` then says only whether it
    is barycentric: ``bmjd``/``bjd`` or ``mjd``/``jd``) and its scale.
    """
    if isinstance(col, Time):
        return np.asarray(col.mjd, dtype=float) + TIME_FORMATS[fmt][0], str(col.scale)
    try:
        values = np.asarray(getattr(col, "value", col), dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{label}: not numeric") from None
    finite = values[np.isfinite(values)]
    if finite.size:
        typical = float(np.median(finite))
        is_jd = typical > _JD_THRESHOLD_D
        if is_jd and fmt in ("bmjd", "mjd"):
            raise InputError(f"{fmt_label} {fmt!r}: the times ({typical:.5f}) look like full "
                             "Julian dates; use 'bjd' (or 'jd')")
        if not is_jd and fmt in ("bjd", "jd"):
            raise InputError(f"{fmt_label} {fmt!r}: the times ({typical:.5f}) are not full "
                             "Julian dates; use 'bmjd' (or 'mjd')")
    return values, None


def _table_scale(meta: Mapping[str, Any], scale_label: str) -> str | None:
    """The time scale a table's metadata name (``TIMESYS``), checked; None when absent."""
    value = (meta or {}).get("TIMESYS", (meta or {}).get("timesys"))
    if value is None:
        return None
    scale = str(value).strip().lower()
    if scale not in TIME_SCALES:
        raise InputError(f"the table's TIMESYS {value!r}: unknown time scale (expected one of "
                         f"{', '.join(TIME_SCALES)}; give {scale_label})")
    return scale


#: Lower-case column names of other pipelines, by the package's name they likely hold.
_LIKELY_NAMES = {
    "time_bmjd": ("bmjd", "bjd", "bjd_tdb", "bmjd_tdb", "time", "mjd", "jd", "t"),
    "flux": ("flux", "f", "phot", "aper_flux", "flux_aper"),
    "flux_err": ("flux_err", "fluxerr", "flux_error", "err", "error", "sigma", "eflux"),
    "x": ("x", "xc", "xcen", "x_cen", "xpos", "x_centroid", "centroid_x"),
    "y": ("y", "yc", "ycen", "y_cen", "ypos", "y_centroid", "centroid_y"),
}


def check_columns(table, source: str, *, radius_px: float | None = None,
                  labels: Mapping[str, str] | None = None) -> None:
    """Refuse a table without the columns a fit needs, saying how to map them.

    Another pipeline's table names its columns its own way: the message names
    the missing ones, the table's columns, and how to map them (``labels``:
    the command line's ``--columns``, ``--time-column``, ``--time-format``,
    the API's keywords by default), with the likely candidates filled in.
    ``reduce`` and ``trust`` both call it.

    Raises
    ------
    InputError
        One line naming the table, the missing columns and the options.

    Examples
    --------
    >>> check_columns(Table({"BJD": [1.0], "F": [1.0], "xc": [1.0], "yc": [1.0]}), "lc.csv")
    Traceback (most recent call last):
    ...
    eclipsebench.errors.InputError: lc.csv: missing column(s) time_bmjd, flux, flux_err, x, y (the table has BJD, F, xc, yc); map them with columns flux=F,flux_err=NAME,x=xc,y=yc and time_column BJD time_format bjd (one of bmjd, bjd, mjd, jd), or make a complete table from the BCDs with 'eclipsebench photometry'
    """
    labels = {**_ARGUMENTS, **dict(labels or {})}
    needed = [c for c in ("time_bmjd", "flux", "flux_err", "x", "y")
              if not (c == "flux" and radius_px is not None)]
    missing = [c for c in needed if c not in table.colnames]
    if not missing:
        return
    by_lower = {name.lower(): name for name in table.colnames}
    maps, time_hint = [], ""
    for name in missing:
        found = next((by_lower[c] for c in _LIKELY_NAMES[name] if c in by_lower), None)
        if name == "time_bmjd":
            fmt = "bjd" if found and "jd" in found.lower() and "mjd" not in found.lower() \
                else "bmjd"
            time_hint = (f" and {labels['time_column']} {found} {labels['time_format']} {fmt} "
                         f"(one of {', '.join(TIME_FORMATS)})" if found else
                         f" and {labels['time_column']} NAME {labels['time_format']} "
                         f"{'|'.join(TIME_FORMATS)}")
        else:
            maps.append(f"{name}={found or 'NAME'}")
    how = (f"map them with {labels['columns']} {','.join(maps)}" if maps else "map it") \
        + time_hint
    shown = ", ".join(table.colnames[:12]) + (" ..." if len(table.colnames) > 12 else "")
    raise InputError(f"{source}: missing column(s) {', '.join(missing)} (the table has "
                     f"{shown}); {how}, or make a complete table from the BCDs with "
                     "'eclipsebench photometry'")


def _stamp_from_pixel_columns(table, labels: Mapping[str, str]) -> dict[str, np.ndarray]:
    """``stamp3`` (and ``stamp5``) from flat pixel columns ``p0..p8`` (or ``p0..p24``).

    Row-major: ``p<3 * row + col>`` with the row along y. A 5 x 5 stamp also
    gives its central 3 x 3 as ``stamp3`` (the package's stamps are co-centred).
    """
    found = {int(m.group(1)): name for name in table.colnames
             if (m := _PIXEL_COLUMN.match(name))}
    if not found:
        return {}
    out = {}
    for size in (5, 3):
        if set(found) == set(range(size * size)):
            cube = np.column_stack([np.asarray(getattr(table[found[k]], "value", table[found[k]]),
                                               dtype=float) for k in range(size * size)])
            out[f"stamp{size}"] = cube.reshape(len(table), size, size)
            if size == 5:
                out["stamp3"] = out["stamp5"][:, 1:4, 1:4].copy()
            return out
    raise InputError(f"{labels['columns']}: pixel columns must be p0..p8 (3 x 3) or p0..p24 "
                     f"(5 x 5); the table has {', '.join(found[k] for k in sorted(found))}")


def _checked_stamp(col, name: str, size: int, n: int) -> np.ndarray:
    cube = np.asarray(getattr(col, "value", col), dtype=float)
    if cube.size != n * size * size:
        raise InputError(f"column '{name}': expected {size} x {size} pixels per row, got "
                         f"shape {cube.shape}")
    return cube.reshape(n, size, size)


def _column_mapping(table, columns: Mapping[str, str] | None, time_column: str | None,
                    labels: Mapping[str, str]) -> dict[str, str]:
    """The package's column name -> the table's, checked (``columns`` and ``time_column``)."""
    mapping = dict(columns or {})
    for new, old in mapping.items():
        if not isinstance(new, str) or not isinstance(old, str) or not new or not old:
            raise InputError(f"{labels['columns']}: expected names NEW=OLD, got {new!r}={old!r}")
        if not _known_name(new):
            raise InputError(f"{labels['columns']}: unknown column name {new!r} (known: "
                             f"{', '.join(REQUIRED_COLUMNS + OPTIONAL_COLUMNS)}, flux_r<R>, "
                             "p0..p24)")
        if old not in table.colnames:
            raise InputError(f"{labels['columns']}: {new}={old}: the table has no column "
                             f"{old!r} (it has {_names_list(table)})")
    if time_column is not None:
        if not isinstance(time_column, str) or not time_column:
            raise InputError(f"{labels['time_column']}: expected a column name")
        if mapping.get("time_bmjd", time_column) != time_column:
            raise InputError(f"{labels['time_column']} {time_column!r} and "
                             f"{labels['columns']} time_bmjd={mapping['time_bmjd']} disagree")
        if time_column not in table.colnames:
            raise InputError(f"{labels['time_column']}: the table has no column "
                             f"{time_column!r} (it has {_names_list(table)})")
        mapping["time_bmjd"] = time_column
    return mapping


def standardise_table(table, *, columns: Mapping[str, str] | None = None,
                      time_column: str | None = None, time_format: str | None = None,
                      time_scale: str | None = None, time_at: str | None = None,
                      observer: Any = None, frame_time_s: float | None = None,
                      target: Any = None, labels: Mapping[str, str] | None = None) -> Table:
    """A table with the package's column names, time in BMJD_TDB and stamps as cubes.

    Parameters
    ----------
    table : astropy.table.Table
        Any photometry table: this package's, or another pipeline's.
    columns : Mapping, optional
        The package's column name -> the table's (``{"flux": "FLUX"}``). Names
        are those of ``docs/photometry.md``; an unknown name is refused.
    time_column : str, optional
        The table's time column (default ``time_bmjd``, or ``columns["time_bmjd"]``).
    time_format : {"bmjd", "bjd", "mjd", "jd"}, optional
        The time column's format (default ``"bmjd"``): "bjd"/"bmjd" are
        barycentric, "jd"/"mjd" taken at the observer (then ``time_scale``,
        ``observer`` and ``target``'s coordinates are needed). Times whose
        size does not fit the format (a JD given as "bmjd") are refused.
    time_scale : {"utc", "tt", "tdb"}, optional
        The times' scale (default: an astropy Time column's, else the table's
        ``TIMESYS``, else TDB for barycentric formats).
    time_at : {"start", "mid", "end"}, optional
        Where in its frame each stamp lies (default ``"mid"``).
    observer : "geocentre" or (x_km, y_km, z_km, mjd_utc), optional
        Where times at the observer were taken
        (:func:`eclipsebench.astro.timescales.parse_observer`).
    frame_time_s : float, optional
        The frame time for ``time_at`` start or end (default: the median cadence).
    target : PlanetSystem, optional
        Its ``ra_deg``/``dec_deg`` direct the barycentric correction.
    labels : Mapping, optional
        How errors name ``columns``, ``time_column``, ``time_format``,
        ``time_scale``, ``time_at`` and ``observer`` (the command line
        passes ``--columns`` ...).

    Returns
    -------
    astropy.table.Table
        A new table (the input is not changed); the default arguments on a
        table of this package give the same columns. A conversion of the
        times is recorded in ``meta["TIMECONV"]`` (one line, for the result)
        and ``meta["TIMESRC"]``.

    Raises
    ------
    InputError
        An unknown name, a column the table lacks, a time format that does
        not fit the times, an incomplete set of pixel columns.

    Examples
    --------
    >>> t = Table({"BJD": [2457000.5, 2457000.75], "F": [1.0, 1.1]})
    >>> s = standardise_table(t, columns={"flux": "F"}, time_column="BJD", time_format="bjd")
    >>> s["time_bmjd"].tolist(), s["flux"].tolist()
    ([57000.0, 57000.25], [1.0, 1.1])
    """
    labels = {**_ARGUMENTS, **dict(labels or {})}
    mapping = _column_mapping(table, columns, time_column, labels)
    fmt = "bmjd" if time_format is None else time_format
    if fmt not in TIME_FORMATS:
        raise InputError(f"{labels['time_format']}: {fmt!r} is not one of "
                         f"{', '.join(TIME_FORMATS)}")

    out = table.copy(copy_data=False)
    out.meta = dict(table.meta or {})
    for new, old in mapping.items():
        if new != old:
            col = table[old].copy()
            if new in out.colnames:
                out.replace_column(new, col)
            else:
                out[new] = col
    if "time_bmjd" in out.colnames:
        source = mapping.get("time_bmjd", "time_bmjd")
        col = out["time_bmjd"]
        values, column_scale = _time_values(col, f"time column {source!r}", fmt,
                                            labels["time_format"])
        if time_scale is not None and column_scale not in (None, time_scale):
            raise InputError(f"{labels['time_scale']} {time_scale}: the time column "
                             f"{source!r} is an astropy Time in scale {column_scale!r}")
        scale = time_scale or column_scale or _table_scale(out.meta, labels["time_scale"])
        spec = TimeSpec(fmt, scale, time_at or "mid", observer, frame_time_s).check(labels)
        if spec.is_plain():
            needs = isinstance(col, Time) or col.dtype.kind != "f"
            if needs:
                out.replace_column("time_bmjd", values)
            if needs or source != "time_bmjd":
                out.meta["TIMESRC"] = f"{source} (BMJD_TDB)"
        else:
            ra, dec = getattr(target, "ra_deg", None), getattr(target, "dec_deg", None)
            converted, how = to_bmjd_tdb(values, spec, ra_deg=ra, dec_deg=dec, label=f"time column {source!r}",
                                         coords_hint=labels["coordinates"])
            out.replace_column("time_bmjd", converted)
            out.meta["TIMESRC"] = f"{source} ({how['text']})"
            out.meta["TIMECONV"] = f"{source}: {how['text']}"
    elif any(v is not None for v in (time_format, time_scale, time_at, observer)):
        raise InputError(f"{labels['time_format']}: the table has no time column "
                         f"'time_bmjd' (give {labels['time_column']})")
    n = len(out)
    for name, size in (("stamp3", 3), ("stamp5", 5)):
        if name in out.colnames:
            out.replace_column(name, _checked_stamp(out[name], name, size, n))
    if "stamp3" not in out.colnames:
        stamps = _stamp_from_pixel_columns(out, labels)
        if "stamp5" in out.colnames and not stamps:
            stamps = {"stamp3": np.asarray(out["stamp5"])[:, 1:4, 1:4].copy()}
        for name, cube in stamps.items():
            if name not in out.colnames:
                out[name] = cube
    return out


def _column(table, name: str) -> np.ndarray:
    col = table[name]
    return np.asarray(getattr(col, "value", col))


def _source(table) -> str:
    meta = getattr(table, "meta", {}) or {}
    return str(meta.get("FILENAME", meta.get("filename", "the photometry table")))


def _require_columns(src: str, names, flux_name: str | None) -> None:
    """InputError naming the required columns a table lacks (``flux_name``: another radius)."""
    required = [c for c in REQUIRED_COLUMNS if c not in ("flux", "flux_err")] + ["flux", "flux_err"]
    if flux_name is not None:
        required.append(flux_name)
    missing = [c for c in required if c not in names]
    if missing:
        raise InputError(f"{src}: missing column(s) {', '.join(missing)} "
                         f"(a photometry table needs {', '.join(required)})")


def _epoch_meta(table, stamp: str, flux_name: str, *, cadence_s: float, n_frames_table: int,
                n_frames_flagged: int, n_frames_nonfinite: int) -> dict[str, Any]:
    """The table's provenance plus the frame counts and the columns behind the epoch's data."""
    meta: dict[str, Any] = {str(k): v for k, v in (getattr(table, "meta", {}) or {}).items()}
    pixel_source = (f"{stamp} pixels (or {'p0..p8' if stamp == 'stamp3' else 'p0..p24'})"
                    if stamp != "none" else "stamp3 or stamp5 pixels ([reduce] stamp is 'none')")
    meta.update(n_frames_table=n_frames_table, n_frames_flagged=n_frames_flagged,
                n_frames_nonfinite=n_frames_nonfinite, flux_column=flux_name,
                cadence_s=cadence_s, table_columns={"pixels": pixel_source, "flux": flux_name})
    return meta


def epoch_data_from_table(table, *, radius_px: float | None = None,
                          stamp: str = "stamp3") -> EpochData:
    """The good frames of one photometry table as an :class:`EpochData`.

    Parameters
    ----------
    table : astropy.table.Table
        One epoch with the package's column names (:func:`standardise_table`):
        ``time_bmjd, flux, flux_err, x, y`` and, optionally, ``flag`` (absent:
        every frame is good), ``noise_pixels``, ``aorkey``, ``width_x``,
        ``width_y``, ``stamp3``, ``stamp5``, ``flux_r<R>``.
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
        ``n_frames_table``, ``n_frames_flagged``, ``n_frames_nonfinite``,
        ``cadence_s`` (median time step of the kept rows) and
        ``table_columns`` (the table column behind each array, for messages).
        ``width_x``/``width_y`` are not part of the finite-value cut: a method
        that uses them checks them.

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
    _require_columns(src, names, flux_name if radius_px is not None else None)
    if stamp not in ("stamp3", "stamp5", "none"):
        raise InputError(f"stamp {stamp!r}: expected 'stamp3', 'stamp5' or 'none'")

    n_table = len(table)
    flag = _column(table, "flag") if "flag" in names else np.zeros(n_table, dtype=np.int32)
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
    width_x = _column(table, "width_x").astype(float) if "width_x" in names else None
    width_y = _column(table, "width_y").astype(float) if "width_y" in names else None
    meta = _epoch_meta(table, stamp, flux_name, cadence_s=median_cadence_s(time[index]),
                       n_frames_table=n_table, n_frames_flagged=n_flagged,
                       n_frames_nonfinite=n_nonfinite)
    return EpochData(time_bmjd=pick(time), flux=pick(flux), flux_err=pick(flux_err),
                     x=pick(x), y=pick(y), noise_pixels=pick(noise_pixels), pixels=pick(pixels),
                     aorkey=pick(aorkey), meta=meta, width_x=pick(width_x),
                     width_y=pick(width_y))


def _scatter_ratio(flux_other: np.ndarray, flux_default: np.ndarray) -> float:
    """Ratio of the frame-to-frame scatters (MAD of first differences) of two apertures."""
    def scatter(f):
        d = np.diff(f)
        return float(np.median(np.abs(d - np.median(d))))
    s0 = scatter(flux_default)
    if len(flux_default) < 3 or s0 <= 0:
        return 1.0
    return scatter(flux_other) / s0
