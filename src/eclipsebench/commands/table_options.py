"""How to read another pipeline's table: the options ``reduce``, ``trust`` and ``campaign`` share.

``--columns``, ``--time-column``, ``--time-format``, ``--time-scale``,
``--time-at`` and ``--observer`` are read back as the keywords of
:func:`eclipsebench.reduce` (``columns``, ``time_column``, ... :func:`table_keywords`);
:data:`TABLE_LABELS` is how the library's one-line errors then name them.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from ..errors import InputError
from ..fit.names import TIME_AT, TIME_FORMATS, TIME_SCALES

__all__ = ["TABLE_LABELS", "add_table_options", "column_map", "time_options", "table_keywords",
           "table_paths"]

#: How errors about the table's names, its time format and its planet name the options.
TABLE_LABELS = {"columns": "--columns", "time_column": "--time-column",
                "time_format": "--time-format", "time_scale": "--time-scale",
                "time_at": "--time-at", "observer": "--observer",
                "coordinates": "--planet ra_deg=DEG --planet dec_deg=DEG, or --system",
                "system": "--system NAME", "method": "--method", "pmap": "--pmap PATH"}


def add_table_options(p: argparse.ArgumentParser, columns_help: str) -> None:
    """How to read another pipeline's table (reduce, trust, campaign): ``--columns``,
    ``--time-column``, ``--time-format``, ``--time-scale``, ``--time-at``, ``--observer``."""
    p.add_argument("--columns", dest="columns", action="append", default=[],
                   metavar="NEW=OLD,...", help=columns_help)
    p.add_argument("--time-column", metavar="NAME", default=None,
                   help="the table's time column (default: time_bmjd)")
    p.add_argument("--time-format", choices=tuple(TIME_FORMATS), default=None,
                   help="format of the time column: bmjd (default, BJD - 2400000.5) or bjd, "
                        "barycentric; mjd or jd, at the observer, converted to BMJD_TDB with "
                        "the planet's ra_deg/dec_deg and --observer (docs/photometry.md)")
    p.add_argument("--time-scale", choices=TIME_SCALES, default=None,
                   help="time scale of the time column (default: the table's TIMESYS, else "
                        "tdb for bmjd/bjd; required for mjd/jd)")
    p.add_argument("--time-at", choices=TIME_AT, default=None,
                   help="where in its frame each time stamp lies (default mid; start/end "
                        "move it by half the frame time, the median cadence)")
    p.add_argument("--observer", metavar="X,Y,Z,MJD|geocentre", default=None,
                   help="where mjd/jd times were taken: for Spitzer SPTZR_X,SPTZR_Y,SPTZR_Z,"
                        "MJD_OBS of a BCD header of the observation (km, UTC MJD); geocentre "
                        "(for Spitzer wrong by minutes)")


def column_map(items: list[str]) -> dict[str, str]:
    """``--columns NEW=OLD,...`` (repeatable) as ``{NEW: OLD}``."""
    out: dict[str, str] = {}
    for item in items:
        for pair in item.split(","):
            new, sep, old = (part.strip() for part in pair.partition("="))
            if not sep or not new or not old:
                raise InputError(f"--columns {pair.strip()!r}: expected NEW=OLD (the package's "
                                 "name = the table's)")
            if out.get(new, old) != old:
                raise InputError(f"--columns: {new} is mapped twice ({out[new]}, {old})")
            out[new] = old
    return out


def time_options(args: argparse.Namespace) -> dict:
    """``--time-scale``, ``--time-at`` and ``--observer`` as ``standardise_table``'s keywords."""
    return {k: v for k, v in (("time_scale", args.time_scale), ("time_at", args.time_at),
                              ("observer", args.observer)) if v is not None}


def table_keywords(args: argparse.Namespace) -> dict:
    """Every table option as :func:`eclipsebench.reduce`'s keywords (``columns``, ...)."""
    return {"columns": column_map(args.columns), "time_column": args.time_column,
            "time_format": args.time_format, **time_options(args)}


TABLE_SUFFIXES = (".fits", ".fit", ".ecsv", ".csv")


def table_paths(items: list[str]) -> list[Path]:
    """The tables named, a folder's tables (sorted by name), each checked to exist."""
    paths: list[Path] = []
    for item in items:
        p = Path(item)
        if p.is_dir():
            found = sorted(q for q in p.iterdir() if q.is_file()
                           and q.suffix.lower() in TABLE_SUFFIXES and ".lc." not in q.name)
            if not found:
                raise InputError(f"{p}: no photometry tables (.fits, .ecsv, .csv) in this folder")
            paths += found
        elif p.is_file():
            paths.append(p)
        else:
            raise InputError(f"{p}: no such photometry table")
    if len(set(paths)) != len(paths):
        raise InputError("TABLE: a table is given twice")
    return paths
