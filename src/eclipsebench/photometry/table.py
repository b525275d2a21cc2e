"""The per-epoch photometry table: build, write (FITS, atomically), read.

Columns and metadata are the contract of ``docs/contracts.md``. JSON-valued
metadata (``INPUTS``, ``OPTIONS``, ``AORKEYS``, ``FLAGBITS``, ``FLAGCNT``) are
stored as JSON strings in the FITS header and decoded by
:func:`read_photometry`.

Files the astropy way: ``Table.read`` of a written table emits no warning.
Every ``TUNITn`` is a FITS-standard string; FITS has no electron (FITS 4.0,
Table 4), so electrons are written as the standard count ``ct`` (``count``,
``count pix-2``) and the header card ``CTUNIT = 'electron'`` says what is
counted: :func:`read_photometry` gives them back as ``u.electron``, a plain
``Table.read`` as ``u.ct``. Each column has its description in ``TCOMMn``, and the header has ``TIMESYS = 'TDB'``,
``MJDREF = 0``, ``TIMEUNIT = 'd'`` for ``time_bmjd``.

The bytes are a function of the data and the configuration (issue 28):
``CHECKSUM``/``DATASUM`` carry a fixed comment instead of the write time, and
the provenance folders ``INROOT`` and ``SIMDIR`` are written relative to the
table's own folder (``PATHREL`` lists them) and read back as absolute paths,
so two runs of the same input into different run folders write identical files.

FITS header values must be printable ASCII, but provenance paths (``INROOT``,
``SIMDIR``) may hold spaces and any letters. A string value that is not
printable ASCII is stored JSON-escaped (``"/data/\u00fc"``, quotes included)
and its key listed in the JSON list ``ESCAPED``; :func:`read_photometry`
decodes it back.

:func:`read_table` reads any table the reducer accepts: this package's FITS
tables, and FITS, ECSV or CSV tables from other pipelines (no column is
required at read time; ``docs/photometry.md``, "Photometry from other pipelines").
"""

from __future__ import annotations

import json
import os
import re
import textwrap
import warnings
from pathlib import Path

import astropy.units as u
import numpy as np
import yaml
from astropy.io import fits
from astropy.table import Table

from .. import __version__
from ..errors import DataError, InputError
from ..io.atomic import atomic_path
from ..limits import MAX_FRAMES_PER_EPOCH, MAX_TABLE_HEADER_BYTES, size_problem

__all__ = ["REQUIRED_COLUMNS", "COLUMN_UNITS", "JSON_KEYS", "make_table", "write_photometry",
           "read_photometry", "read_table", "table_format", "column_description", "fits_unit",
           "count_text_rows", "check_text_table"]

REQUIRED_COLUMNS = ("time_bmjd", "aorkey", "expid", "frame", "x", "y", "x_gauss", "y_gauss",
                    "noise_pixels", "width_x", "width_y", "background", "flux", "flux_err",
                    "stamp3", "stamp5", "flag")
JSON_KEYS = ("INPUTS", "OPTIONS", "AORKEYS", "FLAGBITS", "FLAGCNT")
ESCAPED_KEY = "ESCAPED"
_PRINTABLE_ASCII = re.compile(r"^[\x20-\x7e]*$")

_STRUCTURAL = re.compile(r"^(XTENSION|BITPIX|NAXIS\d*|PCOUNT|GCOUNT|TFIELDS|EXTNAME|CHECKSUM|"
                         r"DATASUM|COMMENT|HISTORY|CTUNIT|PATHREL|"
                         r"T(TYPE|FORM|UNIT|DIM|NULL|SCAL|ZERO|DISP|COMM)\d+)$")
#: Provenance folders written relative to the table's folder (byte-reproducible tables).
_PATH_KEYS = ("INROOT", "SIMDIR")
#: The comment of CHECKSUM/DATASUM (astropy's default is the write time).
_CHECKSUM_NOTE = "eclipsebench photometry table"
_PIX = u.pix
_E = u.electron
COLUMN_UNITS = {
    "time_bmjd": u.day, "x": _PIX, "y": _PIX, "x_col": _PIX, "y_col": _PIX, "x_gauss": _PIX,
    "y_gauss": _PIX, "x_gfix": _PIX, "y_gfix": _PIX, "x_lsq": _PIX, "y_lsq": _PIX,
    "width_x": _PIX, "width_y": _PIX, "gauss_fixed_width": _PIX, "noise_pixels": _PIX**2,
    "background": _E / _PIX**2, "background_mean": _E / _PIX**2,
    "background_median": _E / _PIX**2, "background_sigma": _E / _PIX**2,
    "flux": _E, "flux_err": _E, "flux_raw": _E, "aperture_area": _PIX**2,
    "stamp3": _E, "stamp5": _E,
}
_ORDER = ("time_bmjd", "aorkey", "expid", "dce", "frame", "x", "y", "x_col", "y_col", "x_gauss",
          "y_gauss", "x_gfix", "y_gfix", "x_lsq", "y_lsq", "noise_pixels", "width_x", "width_y",
          "background", "flux", "flux_err", "flag")
_DTYPES = {"aorkey": np.int64, "expid": np.int32, "dce": np.int32, "frame": np.int32,
           "flag": np.int32, "peak_x": np.int16, "peak_y": np.int16, "stamp_x": np.int16,
           "stamp_y": np.int16, "background_npix": np.int16}


#: What each column holds (TCOMMn); :func:`column_description` adds the patterned ones.
_DESCRIPTIONS = {
    "time_bmjd": "mid-exposure time, BMJD (TDB, barycentric)",
    "aorkey": "Spitzer AOR key", "expid": "exposure number in the AOR",
    "dce": "DCE number", "frame": "frame index in its subarray cube",
    "x": "star column (0-based, the chosen centroid)",
    "y": "star row (0-based, the chosen centroid)",
    "x_col": "centre-of-light column", "y_col": "centre-of-light row",
    "x_gauss": "Gaussian-fit column", "y_gauss": "Gaussian-fit row",
    "x_gfix": "fixed-width Gaussian column", "y_gfix": "fixed-width Gaussian row",
    "x_lsq": "asymmetric Gaussian column", "y_lsq": "asymmetric Gaussian row",
    "peak_x": "column of the brightest pixel", "peak_y": "row of the brightest pixel",
    "stamp_x": "column of the pixel stamps' centre", "stamp_y": "row of the pixel stamps' centre",
    "width_x": "Gaussian-fit sigma along columns", "width_y": "Gaussian-fit sigma along rows",
    "gauss_fixed_width": "sigma of the fixed-width Gaussian fit",
    "gauss_ok": "1 if the Gaussian fit converged", "gfix_ok": "1 if the fixed fit converged",
    "lsq_ok": "1 if the asymmetric fit converged",
    "noise_pixels": "noise pixels (sum I)^2 / sum I^2",
    "background": "background per pixel (the chosen estimator)",
    "background_mean": "annulus background, clipped mean",
    "background_median": "annulus background, median",
    "background_sigma": "annulus background, standard deviation",
    "background_npix": "annulus pixels used for the background",
    "flux": "aperture flux minus background (electrons)",
    "flux_err": "uncertainty of flux (electrons)",
    "flux_raw": "aperture sum before background (electrons)",
    "aperture_area": "aperture area (pixels, partial pixels exact)",
    "stamp3": "3x3 pixels about the stamp centre (electrons)",
    "stamp5": "5x5 pixels about the stamp centre (electrons)",
    "flag": "bit mask, 0 = good (FLAGBITS lists the bits)",
}


def column_description(name: str) -> str:
    """The description of a photometry column (TCOMMn), or "" for one unknown here.

    Examples
    --------
    >>> column_description("flux_r2p25")
    'aperture flux minus background, aperture r2p25 (electrons)'
    """
    if name in _DESCRIPTIONS:
        return _DESCRIPTIONS[name]
    if name.startswith("flux_err_"):
        return f"uncertainty of flux_{name[9:]} (electrons)"
    if name.startswith("flux_"):
        return f"aperture flux minus background, aperture {name[5:]} (electrons)"
    if name.startswith("radius_"):
        return f"radius of the variable aperture {name[7:]}"
    return ""


def fits_unit(unit) -> str:
    """``unit`` as a FITS-standard ``TUNITn`` string, electrons written as counts (``ct``).

    Examples
    --------
    >>> fits_unit(u.electron / u.pix**2), fits_unit(u.day)
    ('count pix-2', 'd')
    """
    unit = u.Unit(unit)
    bases = [u.ct if b == _E else b for b in unit.bases]
    return u.CompositeUnit(unit.scale, bases, unit.powers).to_string("fits")


def _unit_from_fits(text: str, counts_are: str | None):
    """A TUNITn read back: FITS first (counts as electrons when CTUNIT says so), else generic."""
    unit = u.Unit(text, format="fits", parse_strict="silent")
    if isinstance(unit, u.UnrecognizedUnit):  # a table written before TUNITn was FITS-standard
        return u.Unit(text, format="generic", parse_strict="silent")
    if counts_are == "electron":
        bases = [_E if b == u.ct else b for b in unit.bases]
        unit = u.CompositeUnit(unit.scale, bases, unit.powers)
    return unit


def _unit_for(name: str):
    if name in COLUMN_UNITS:
        return COLUMN_UNITS[name]
    if name.startswith("flux_"):
        return _E
    if name.startswith("radius_"):
        return _PIX
    return None


def make_table(columns: dict[str, np.ndarray], meta: dict) -> Table:
    """An astropy Table with the package's column order, dtypes and units.

    ``meta`` values that are lists or dicts are kept as Python objects here
    and encoded as JSON by :func:`write_photometry`.
    """
    names = [c for c in _ORDER if c in columns] + sorted(c for c in columns if c not in _ORDER)
    table = Table()
    for name in names:
        values = np.asarray(columns[name])
        if name in _DTYPES:
            if values.dtype.kind == "f":  # e.g. no pixel index for an all-NaN frame
                values = np.where(np.isfinite(values), values, -1)
            values = values.astype(_DTYPES[name])
        elif values.dtype == bool:
            values = values.astype(np.int16)
        unit = _unit_for(name)
        table[name] = values if unit is None else u.Quantity(values, unit).value
        if unit is not None:
            table[name].unit = unit
        table[name].description = column_description(name) or None
    table.meta.update(meta)
    return table


def _header_cards(meta: dict) -> list[tuple[str, object]]:
    cards = []
    escaped = []
    for key, value in meta.items():
        key = str(key).upper()
        if key == ESCAPED_KEY:
            continue
        if key in JSON_KEYS or isinstance(value, (list, tuple, dict)):
            value = _bounded_json(key, value)  # ASCII: non-ASCII escaped
        elif isinstance(value, np.generic):
            value = value.item()
        elif value is None:
            continue
        elif isinstance(value, str) and not _PRINTABLE_ASCII.match(value):
            value = json.dumps(value)
            escaped.append(key)
        cards.append((key if len(key) <= 8 else f"HIERARCH {key}", value))
    if escaped:
        cards.append((f"HIERARCH {ESCAPED_KEY}", json.dumps(escaped)))
    return cards


def _bounded_json(key: str, value: object) -> str:
    """``value`` as JSON, refused in one line once it passes ``MAX_TABLE_HEADER_BYTES``.

    Encoded piece by piece, so metadata that share references (a YAML alias
    bomb read by another reader) are never expanded in memory past the limit.
    """
    encoder = json.JSONEncoder(sort_keys=True, default=str)
    parts, size = [], 0
    for part in encoder.iterencode(value):
        size += len(part)
        if size > MAX_TABLE_HEADER_BYTES:
            raise InputError(f"metadata {key}: its JSON is above the limit of "
                             f"{MAX_TABLE_HEADER_BYTES} characters of a table header "
                             "(eclipsebench.limits)")
        parts.append(part)
    return "".join(parts)


def _relative_paths(meta: dict, folder: Path) -> tuple[dict, list[str]]:
    """``meta`` with the provenance folders relative to ``folder``; the keys made relative."""
    meta, done = dict(meta), []
    for key in _PATH_KEYS:
        value = meta.get(key)
        if isinstance(value, str) and os.path.isabs(value):
            try:
                meta[key] = Path(os.path.relpath(value, folder)).as_posix()
            except ValueError:   # another drive (Windows): kept absolute
                continue
            done.append(key)
    return meta, done


def write_photometry(table: Table, path: str | os.PathLike) -> Path:
    """Write ``table`` as a FITS binary table, atomically (temporary file + rename).

    The bytes depend only on the data, the metadata and the folders' relative
    layout (module docstring); ``Table.read`` of the file emits no warning.
    """
    path = Path(path)
    plain = Table(table, meta={}, copy=False)
    units = {}
    for name in plain.colnames:
        if plain[name].unit is not None:
            units[name] = fits_unit(plain[name].unit)
            plain[name].unit = None
    hdu = fits.table_to_hdu(plain)
    hdu.name = "PHOTOMETRY"
    for k, name in enumerate(plain.colnames, start=1):
        if name in units:
            hdu.header[f"TUNIT{k}"] = units[name]
        text = table[name].description or column_description(name)
        if text:
            hdu.header[f"TCOMM{k}"] = text[:68]
    hdu.header["CTUNIT"] = ("electron", "what TUNITn 'count' counts")
    meta, relative = _relative_paths(dict(table.meta), path.resolve().parent)
    for key, value in _header_cards(meta):
        hdu.header[key] = value
    if relative:
        hdu.header["PATHREL"] = (json.dumps(relative), "keys relative to this file's folder")
    for key, value in (("TIMESYS", "TDB"), ("MJDREF", 0.0), ("TIMEUNIT", "d")):
        if key not in hdu.header:
            hdu.header[key] = value
    hdu.header["HIERARCH EB_VERSION"] = str(table.meta.get("EB_VERSION", __version__))
    primary = fits.PrimaryHDU()
    for h in (primary, hdu):   # a fixed comment: the checksums do not carry the write time
        h.add_checksum(when=_CHECKSUM_NOTE)
    with atomic_path(path) as tmp:
        fits.HDUList([primary, hdu]).writeto(tmp)
    return path


def read_photometry(path: str | os.PathLike) -> Table:
    """Read a photometry table written by :func:`write_photometry`.

    JSON metadata (``INPUTS``, ``OPTIONS``, ``AORKEYS``, ``FLAGBITS``,
    ``FLAGCNT``) come back as Python objects.

    Raises
    ------
    DataError
        Naming the file if it cannot be read or lacks a required column.
    """
    path = Path(path)
    if not path.is_file():
        raise DataError(path, "no such photometry table")
    table = _read_fits(path)
    missing = [c for c in REQUIRED_COLUMNS if c not in table.colnames]
    if missing:
        raise DataError(path, f"photometry table lacks columns {missing}")
    return table


_FITS_SUFFIXES = (".fits", ".fit", ".fts", ".fits.gz", ".fit.gz", ".fts.gz")


def table_format(path: str | os.PathLike) -> str:
    r"""``"fits"``, ``"ecsv"`` or ``"csv"``: how :func:`read_table` reads ``path``.

    FITS by its first card (``SIMPLE``) or a FITS suffix (also gzipped); ECSV
    by its ``# %ECSV`` first line; anything else is read as CSV.

    Examples
    --------
    >>> import tempfile, os
    >>> d = tempfile.mkdtemp()
    >>> with open(os.path.join(d, "a.txt"), "w") as f:
    ...     _ = f.write("time_bmjd,flux\n57000.0,1.0\n")
    >>> table_format(os.path.join(d, "a.txt"))
    'csv'
    """
    path = Path(path)
    with open(path, "rb") as fh:
        head = fh.read(16)
    if head.startswith(b"SIMPLE") or path.name.lower().endswith(_FITS_SUFFIXES):
        return "fits"
    if head.lstrip().startswith(b"# %ECSV") or path.suffix.lower() == ".ecsv":
        return "ecsv"
    return "csv"


def read_table(path: str | os.PathLike) -> Table:
    r"""Read a photometry table in FITS, ECSV or CSV, requiring no particular column.

    The reducer reads its input with this: a table written by
    :func:`write_photometry` comes back as :func:`read_photometry` gives it; a
    table from another pipeline keeps its own column names (the reducer maps
    them, :func:`eclipsebench.fit.data.standardise_table`). A FITS table is
    the ``PHOTOMETRY`` extension, else the first extension.

    Rows are counted before the table is read whole (FITS: ``NAXIS2``; CSV
    and ECSV: lines, streamed, :func:`count_text_rows`) and a table of more
    than ``MAX_FRAMES_PER_EPOCH`` rows is refused; an ECSV header is checked
    by :func:`check_text_table` (its size, its YAML aliases expanded) before
    it is parsed.

    Raises
    ------
    DataError
        Naming the file if it does not exist, cannot be read (a truncated FITS
        file included), has no rows or too many, or its ECSV metadata are
        too large, or would be through their YAML aliases.

    Examples
    --------
    >>> import tempfile, os
    >>> path = os.path.join(tempfile.mkdtemp(), "lc.csv")
    >>> with open(path, "w") as f:
    ...     _ = f.write("time_bmjd,flux,flux_err,x,y\n57000.0,1.0,0.01,15.0,15.1\n")
    >>> read_table(path).colnames
    ['time_bmjd', 'flux', 'flux_err', 'x', 'y']
    """
    path = Path(path)
    if not path.is_file():
        raise DataError(path, "no such photometry table")
    kind = table_format(path)
    if kind == "fits":
        table = _read_fits(path)
    else:
        check_text_table(path, kind)   # rows counted, ECSV metadata checked: before reading
        try:
            table = Table.read(path, format=f"ascii.{kind}")
        except Exception as exc:
            raise DataError(path, f"not a readable {kind.upper()} photometry table "
                            f"({type(exc).__name__}: {exc})") from None
        table.meta = {str(k): v for k, v in table.meta.items() if k != "comments"}
    if len(table) == 0:
        raise DataError(path, "the photometry table has no rows")
    return table


def _rows_problem(n_rows: int) -> str:
    return f"{size_problem(n_rows, MAX_FRAMES_PER_EPOCH, 'rows')}; nothing was read"


def count_text_rows(path: str | os.PathLike) -> int:
    r"""The data rows of a CSV or ECSV file, counted by streaming it (never read whole).

    Lines that are blank or comments (``#``, the ECSV header) are not rows,
    nor is the first other line (the column names).

    Examples
    --------
    >>> import tempfile, os
    >>> path = os.path.join(tempfile.mkdtemp(), "lc.csv")
    >>> with open(path, "w") as f:
    ...     _ = f.write("# a comment\ntime_bmjd,flux\n57000.0,1.0\n\n57000.1,1.1")
    >>> count_text_rows(path)
    2
    """
    lines = skipped = 0
    last = b"\n"
    with open(path, "rb") as fh:
        while chunk := fh.read(1 << 22):
            joined = last + chunk   # a comment or blank line that starts at the chunk's edge
            lines += chunk.count(b"\n")
            skipped += (joined.count(b"\n#") + joined.count(b"\n\n")
                        + joined.count(b"\n\r\n"))
            last = chunk[-1:]
    if last != b"\n":
        lines += 1   # the last line has no newline
    return max(lines - skipped - 1, 0)


def check_text_table(path: str | os.PathLike, kind: str) -> None:
    """Refuse a CSV or ECSV table before it is parsed: too many rows, a header too large
    or that YAML aliases would make too large.

    ECSV metadata is YAML; an alias (``*name``) repeats an anchored node by
    reference, so a kilobyte of aliases can stand for gigabytes once written
    out (a "billion laughs"). The header is read up to ``MAX_TABLE_HEADER_BYTES``
    and, when it holds aliases, composed without building any value; a header
    whose expansion passes the same limit is refused.

    Parameters
    ----------
    path : path
        The table.
    kind : {"csv", "ecsv"}
        How it will be read (:func:`table_format`).

    Raises
    ------
    DataError
        One line naming the file.
    """
    path = Path(path)
    n_rows = count_text_rows(path)
    if n_rows > MAX_FRAMES_PER_EPOCH:
        raise DataError(path, _rows_problem(n_rows))
    if kind != "ecsv":
        return
    header, size = [], 0
    with open(path, "rb") as fh:
        while raw := fh.readline(MAX_TABLE_HEADER_BYTES + 1 - size):   # a bounded read
            line = raw.strip()
            if line and not line.startswith(b"#"):
                break
            size += len(raw)
            if size > MAX_TABLE_HEADER_BYTES:
                raise DataError(path, f"the ECSV header is above the limit of "
                                f"{MAX_TABLE_HEADER_BYTES} bytes (eclipsebench.limits)")
            text = line[1:].decode("utf-8", errors="replace")
            header.append(text[1:] if text.startswith(" ") else text)
    _check_yaml_expansion(path, [h for h in header if not h.startswith("%ECSV")])


def _expanded_chars(node, memo: dict[int, int], active: set[int]) -> int:
    """Characters of a composed YAML node once every alias in it is expanded (memoised: the
    cost is the number of distinct nodes, not the expansion)."""
    key = id(node)
    if key in memo:
        return memo[key]
    if key in active:
        raise ValueError("an alias refers to a node that holds it")
    active.add(key)
    if isinstance(node, yaml.ScalarNode):
        n = len(node.value) + 2
    elif isinstance(node, yaml.SequenceNode):
        n = 2 + sum(_expanded_chars(c, memo, active) for c in node.value)
    else:
        n = 2 + sum(_expanded_chars(k, memo, active) + _expanded_chars(v, memo, active)
                    for k, v in node.value)
    active.discard(key)
    memo[key] = n
    return n


def _check_yaml_expansion(path: Path, lines: list[str]) -> None:
    """A :class:`DataError` if the YAML ``lines`` would expand, through their aliases, past
    ``MAX_TABLE_HEADER_BYTES`` (or refer to themselves).

    The header is composed (a graph of nodes, an alias the node it names:
    nothing is copied) and its expanded size counted node by node. An alias
    as astropy writes one (the same list under two keys) passes.
    """
    text = textwrap.dedent("\n".join(lines))
    if "*" not in text:
        return   # no alias: the header's size is its expansion
    try:
        root = yaml.compose(text, Loader=yaml.SafeLoader)
        chars = 0 if root is None else _expanded_chars(root, {}, set())
    except yaml.YAMLError:
        return   # not YAML: astropy's reader says what is wrong
    except (ValueError, RecursionError) as exc:
        why = "nested too deeply" if isinstance(exc, RecursionError) else str(exc)
        raise DataError(path, f"the ECSV metadata cannot be expanded ({why}): refused") \
            from None
    if chars > MAX_TABLE_HEADER_BYTES:
        raise DataError(path, f"the ECSV metadata expand through YAML aliases to {chars} "
                        f"characters, above the limit of {MAX_TABLE_HEADER_BYTES} "
                        "(eclipsebench.limits): refused before reading")


def _read_fits(path: Path) -> Table:
    """The FITS table of ``path`` with units and decoded metadata (no column checks).

    The rows (``NAXIS2``) are checked from the header before the data are
    read; astropy's warnings on a broken file (a truncated one) become part of
    the one-line error.
    """
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            table, relative = _read_fits_table(path)
    except DataError:
        raise
    except Exception as exc:
        said = [str(w.message).splitlines()[0] for w in caught]
        why = [s for s in said if "truncated" in s] or [f"{type(exc).__name__}: {exc}", *said]
        raise DataError(path, f"not a readable photometry table ({'; '.join(why)})") from None
    broken = [w for w in caught if "truncated" in str(w.message)]
    if broken:
        raise DataError(path, "not a readable photometry table (" + str(broken[0].message)
                        .splitlines()[0] + ")")
    for w in caught:   # anything else astropy said, said as before
        warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    _decode_meta(table, path, relative)
    return table


def _read_fits_table(path: Path) -> tuple[Table, str | None]:
    with fits.open(path, memmap=False) as hdul:
        hdu = hdul["PHOTOMETRY"] if "PHOTOMETRY" in hdul else hdul[1]
        if not isinstance(hdu, (fits.BinTableHDU, fits.TableHDU)):
            raise TypeError(f"extension {hdu.name or 1} is not a table")
        header = hdu.header
        n_rows = header.get("NAXIS2", 0)
        if isinstance(n_rows, int) and n_rows > MAX_FRAMES_PER_EPOCH:   # before any data
            raise DataError(path, _rows_problem(n_rows))
        counts_are = header.get("CTUNIT")
        # a plain structured array: units and descriptions are set from the header below
        table = Table(np.array(hdu.data))
        for k in range(1, int(header.get("TFIELDS", 0)) + 1):
            name = header.get(f"TTYPE{k}")
            if name not in table.colnames:
                continue
            if f"TUNIT{k}" in header:
                table[name].unit = _unit_from_fits(str(header[f"TUNIT{k}"]), counts_are)
            if f"TCOMM{k}" in header:
                table[name].description = str(header[f"TCOMM{k}"])
        for key, value in header.items():
            if not _STRUCTURAL.match(key):
                table.meta[key] = value
        return table, header.get("PATHREL")


def _decode_meta(table: Table, path: Path, relative: str | None) -> None:
    """JSON and escaped values back to Python objects; relative folders back to absolute."""
    escaped = _json_list(table.meta.pop(ESCAPED_KEY, None))
    meta = {}
    for key, value in table.meta.items():
        if (key in JSON_KEYS or key in escaped) and isinstance(value, str):
            try:
                value = json.loads(value)
            except json.JSONDecodeError:
                pass
        meta[key] = value
    folder = path.resolve().parent
    for key in _json_list(relative):
        if isinstance(meta.get(key), str):
            meta[key] = os.path.normpath(folder / meta[key])
    table.meta.clear()
    table.meta.update(meta)


def _json_list(text) -> set:
    """The JSON list ``text`` as a set (empty when absent or unreadable)."""
    try:
        return set(json.loads(text)) if isinstance(text, str) else set()
    except (json.JSONDecodeError, TypeError):
        return set()
