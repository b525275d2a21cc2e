"""Bin per-frame columns in time: every N frames or fixed time widths, weighted means.

:func:`bin_indices` decides which frames share a bin; :func:`bin_values`
averages any column with weights; :func:`bin_table` does both for a
photometry table (good frames only, inverse-variance weights from
``flux_err``).
"""

from __future__ import annotations

import numpy as np
from astropy.table import Table

__all__ = ["bin_indices", "bin_values", "bin_table"]

#: integer labels that a mean would turn into nonsense
_IDENTIFIERS = ("flag", "aorkey", "expid", "dce", "frame", "peak_x", "peak_y", "stamp_x",
                "stamp_y", "background_npix")


def bin_indices(time_bmjd: np.ndarray, *, n_frames: int | None = None,
                width_days: float | None = None) -> np.ndarray:
    """Bin number of each sample (0, 1, ...; consecutive, no empty bins).

    Exactly one of ``n_frames`` (consecutive groups of that many samples; the
    last one may be shorter) or ``width_days`` (bins of that width starting at
    the first time; samples must be in time order) must be given.
    """
    t = np.asarray(time_bmjd, dtype=float)
    if (n_frames is None) == (width_days is None):
        raise ValueError("give exactly one of n_frames or width_days")
    if n_frames is not None:
        if int(n_frames) < 1:
            raise ValueError(f"n_frames: expected an integer >= 1, got {n_frames}")
        return np.arange(t.size) // int(n_frames)
    if width_days is None or not width_days > 0:
        raise ValueError(f"width_days: expected a positive number, got {width_days}")
    if t.size and np.any(np.diff(t) < 0):
        raise ValueError("time_bmjd: expected samples in time order")
    raw = np.floor((t - (t[0] if t.size else 0.0)) / width_days).astype(np.int64)
    _, dense = np.unique(raw, return_inverse=True)
    return dense.reshape(t.shape)


def bin_values(values: np.ndarray, bins: np.ndarray, weights: np.ndarray | None = None):
    """Weighted mean of ``values`` (n, ...) in each bin; returns (means, sum of weights).

    Examples
    --------
    >>> bin_values(np.array([1.0, 3.0, 5.0]), np.array([0, 0, 1]))[0]
    array([2., 5.])
    """
    values = np.asarray(values, dtype=float)
    bins = np.asarray(bins)
    nb = int(bins.max()) + 1 if bins.size else 0
    w = np.ones(bins.shape) if weights is None else np.asarray(weights, dtype=float)
    wsum = np.bincount(bins, weights=w, minlength=nb)
    shaped = w.reshape(w.shape + (1,) * (values.ndim - 1))
    acc = np.zeros((nb,) + values.shape[1:])
    np.add.at(acc, bins, values * shaped)
    with np.errstate(invalid="ignore", divide="ignore"):
        means = acc / wsum.reshape((nb,) + (1,) * (values.ndim - 1))
    return means, wsum


def bin_table(table: Table, *, n_frames: int | None = None, width_days: float | None = None,
              columns: list[str] | None = None, weighted: bool = True,
              good_only: bool = True) -> Table:
    """Bin a photometry table: weighted means of every numeric column.

    Parameters
    ----------
    table : Table
        A photometry table (``time_bmjd``, ``flux``, ``flux_err``, ``flag``, ...).
    n_frames, width_days : int or float
        Bin every ``n_frames`` good frames, or by ``width_days`` of time.
    columns : list of str, optional
        Columns to bin (default: every numeric column but the integer labels
        ``flag``, ``aorkey``, ``expid``, ``dce``, ``frame`` and pixel indices).
    weighted : bool
        Inverse-variance weights ``1 / flux_err^2`` (else equal weights).
    good_only : bool
        Use only frames with ``flag == 0``.

    Returns
    -------
    Table
        One row per bin with the weighted means, ``n_frames`` per bin, and
        ``flux_err = 1 / sqrt(sum 1/flux_err^2)`` (weighted) or
        ``sqrt(sum flux_err^2) / n`` (unweighted).
    """
    rows = np.asarray(table["flag"]) == 0 if good_only and "flag" in table.colnames else \
        np.ones(len(table), dtype=bool)
    sub = table[rows]
    order = np.argsort(np.asarray(sub["time_bmjd"]), kind="stable")
    sub = sub[order]
    bins = bin_indices(np.asarray(sub["time_bmjd"]), n_frames=n_frames, width_days=width_days)
    err = np.asarray(sub["flux_err"], dtype=float) if "flux_err" in sub.colnames else None
    w = 1.0 / err**2 if (weighted and err is not None) else np.ones(len(sub))
    names = columns if columns is not None else [
        c for c in sub.colnames if c not in _IDENTIFIERS and np.issubdtype(sub[c].dtype, np.number)]
    out = Table()
    for name in names:
        means, wsum = bin_values(np.asarray(sub[name], dtype=float), bins, w)
        out[name] = means
        if sub[name].unit is not None:
            out[name].unit = sub[name].unit
    counts = np.bincount(bins) if bins.size else np.zeros(0, int)
    out["n_frames"] = counts
    if err is not None:
        if weighted:
            out["flux_err"] = 1.0 / np.sqrt(np.bincount(bins, weights=1.0 / err**2))
        else:
            out["flux_err"] = np.sqrt(np.bincount(bins, weights=err**2)) / counts
        out["flux_err"].unit = sub["flux_err"].unit
    out.meta.update(table.meta)
    out.meta["BINNING"] = {"n_frames": n_frames, "width_days": width_days, "weighted": weighted}
    return out
