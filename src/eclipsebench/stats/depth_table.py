"""Read a depth table (CSV or ECSV) for the ensemble statistics."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
from astropy.table import Table

from ..errors import DataError
from ..photometry.table import check_text_table

__all__ = ["REQUIRED_COLUMNS", "read_depth_table", "check_depth_table"]

REQUIRED_COLUMNS = ("method", "epoch", "depth_ppm", "error_ppm")


def check_depth_table(table: Table, source: object = "depth table") -> Table:
    """Validate the columns and values of a depth table; return it.

    Raises
    ------
    DataError
        Missing columns, non-numeric or non-finite values, non-positive
        errors, repeated (method, epoch) pairs, or a method with fewer than
        two epochs; the message names ``source`` and the column.
    """
    missing = [c for c in REQUIRED_COLUMNS if c not in table.colnames]
    if missing:
        raise DataError(source, f"missing column(s) {', '.join(missing)} (expected "
                                f"{', '.join(REQUIRED_COLUMNS)}; found {', '.join(table.colnames)})")
    if len(table) == 0:
        raise DataError(source, "no rows")
    for col in ("epoch", "depth_ppm", "error_ppm"):
        column = table[col]
        mask = np.asarray(getattr(column, "mask", np.zeros(len(column), bool)), dtype=bool)
        try:
            values = np.asarray(np.where(mask, np.nan, np.asarray(column, dtype=float)))
        except (TypeError, ValueError):
            raise DataError(source, f"column '{col}': expected numbers") from None
        bad = ~np.isfinite(values)
        if bad.any():
            raise DataError(source, f"column '{col}': NaN or missing value in row "
                                    f"{int(np.flatnonzero(bad)[0]) + 1}")
        if col == "error_ppm" and np.any(values <= 0):
            raise DataError(source, f"column 'error_ppm': expected positive values (row "
                                    f"{int(np.flatnonzero(values <= 0)[0]) + 1})")
        if col == "epoch" and np.any(values != np.round(values)):
            raise DataError(source, "column 'epoch': expected integers")
    out = Table({"method": [str(m).strip() for m in table["method"]],
                 "epoch": np.asarray(table["epoch"], dtype=float).astype(int),
                 "depth_ppm": np.asarray(table["depth_ppm"], dtype=float),
                 "error_ppm": np.asarray(table["error_ppm"], dtype=float)},
                masked=False)
    seen = set()
    for m, e in zip(out["method"], out["epoch"], strict=True):
        if (m, int(e)) in seen:
            raise DataError(source, f"method '{m}' epoch {int(e)} appears more than once")
        seen.add((m, int(e)))
    names, counts = np.unique(np.asarray(out["method"]), return_counts=True)
    few = [f"{n} ({c})" for n, c in zip(names, counts, strict=True) if c < 2]
    if few:
        raise DataError(source, "expected at least 2 epochs per method; too few for "
                                + ", ".join(few))
    return out


def read_depth_table(path: str | os.PathLike[str]) -> Table:
    """Read ``path`` (ECSV when it ends in .ecsv, otherwise CSV) and validate it."""
    p = Path(path)
    if not p.is_file():
        raise DataError(p, "no such file (expected a CSV or ECSV depth table)")
    fmt = "ascii.ecsv" if p.suffix.lower() == ".ecsv" else "ascii.csv"
    check_text_table(p, fmt[6:])   # rows counted and ECSV metadata checked before reading
    try:
        table = Table.read(p, format=fmt)
    except Exception as exc:  # astropy raises many types for malformed text
        raise DataError(p, f"cannot read as {fmt[6:].upper()} ({type(exc).__name__}: {exc})") from None
    return check_depth_table(table, p)
