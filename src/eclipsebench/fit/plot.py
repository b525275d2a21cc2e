"""A figure of one reduced epoch: the binned decorrelated light curve and the model."""

from __future__ import annotations

import os

import numpy as np

from ..io.atomic import atomic_path

__all__ = ["bin_series", "plot_reduced_lightcurve"]


def bin_series(time: np.ndarray, values: np.ndarray, width_d: float):
    """Mean time, mean value and standard error of the mean in consecutive time bins.

    Bins with a single point get a NaN error.
    """
    time = np.asarray(time, dtype=float)
    values = np.asarray(values, dtype=float)
    index = np.floor((time - time.min()) / width_d).astype(int)
    _, inverse, counts = np.unique(index, return_inverse=True, return_counts=True)
    t = np.bincount(inverse, time) / counts
    m = np.bincount(inverse, values) / counts
    sq = np.bincount(inverse, values**2) / counts
    var = np.clip(sq - m**2, 0.0, None) * counts / np.maximum(counts - 1, 1)
    err = np.where(counts > 1, np.sqrt(var / counts), np.nan)
    return t, m, err


def plot_reduced_lightcurve(result, path: str | os.PathLike, *, bin_minutes: float = 5.0) -> None:
    """Write a PNG of ``result`` (an EpochResult): binned decorrelated flux, model, residuals."""
    # matplotlib (about 0.5 s to import) only when a plot is asked for.
    import matplotlib
    matplotlib.use("Agg")
    from matplotlib.figure import Figure


    lc = result.lightcurve
    t0 = result.t_ecl_bmjd
    hours = (lc["time_bmjd"] - t0) * 24.0
    width_h = bin_minutes / 60.0
    tb, fb, eb = bin_series(hours, lc["flux_corrected"], width_h)
    _, rb, rbe = bin_series(hours, lc["residual"], width_h)
    order = np.argsort(hours)
    fig = Figure(figsize=(7.0, 5.5), dpi=110)
    ax, axr = fig.subplots(2, 1, sharex=True, gridspec_kw={"height_ratios": [3, 1]})
    ax.errorbar(tb, (fb - 1) * 1e6, yerr=eb * 1e6, fmt="o", ms=3, color="0.3", lw=0.8,
                label=f"decorrelated, {bin_minutes:g}-min bins")
    ax.plot(hours[order], (lc["astro_model"][order] - 1) * 1e6, color="C3", lw=1.5,
            label=f"model ({result.phase} phase)")
    ax.set_ylabel("relative flux - 1 (ppm)")
    ax.set_title(f"{result.method}, epoch {result.epoch}: depth {result.depth_ppm:.0f} "
                 f"+- {result.depth_err_ppm:.0f} ppm")
    ax.legend(loc="best", fontsize=8)
    axr.errorbar(tb, rb * 1e6, yerr=rbe * 1e6, fmt="o", ms=3, color="0.3", lw=0.8)
    axr.axhline(0.0, color="C3", lw=1)
    axr.set_xlabel(f"hours from mid-eclipse ({t0:.5f} BMJD_TDB)")
    axr.set_ylabel("residual (ppm)")
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", metadata={"Software": None})
