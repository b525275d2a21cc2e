"""Figures of one reduced epoch: the binned decorrelated light curve with the model, and
the corner plot of its posterior.

:func:`lightcurve_figure` and :func:`corner_figure` return a matplotlib
``Figure`` (what ``EpochResult.plot()`` gives a notebook);
:func:`plot_reduced_lightcurve` and :func:`plot_corner` write them as PNG
(``reduce --plot``). matplotlib is imported only when a figure is made, and
no backend is chosen: the figures are bare ``Figure`` objects, so a
notebook's own backend is left alone.
"""

from __future__ import annotations

import os

import numpy as np

from ...io.atomic import atomic_path

__all__ = ["bin_series", "lightcurve_figure", "corner_figure", "plot_reduced_lightcurve",
           "plot_corner", "save_png", "literal_text"]


def literal_text(text: object) -> str:
    r"""``text`` as matplotlib draws it literally: every ``$`` escaped (no math text).

    Names from the user (a planet's, ``--planet name=XO-3$b``) are drawn with
    this wherever a figure shows them: an unescaped ``$`` starts matplotlib's
    math text, which fails on most names.

    Examples
    --------
    >>> literal_text("XO-3$b")
    'XO-3\\$b'
    """
    return str(text).replace("$", r"\$")


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


def save_png(fig, path: str | os.PathLike) -> None:
    """Write ``fig`` as a PNG atomically, with no software stamp (stable bytes)."""
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", metadata={"Software": None})


def lightcurve_figure(result, *, bin_minutes: float = 5.0):
    """A Figure of ``result`` (an EpochResult): binned decorrelated flux and model, residuals.

    Two axes sharing the time axis (hours from mid-eclipse): the light curve
    with the model above, the residuals below; the title names the method,
    epoch, profile and depth.
    """
    # matplotlib (about 0.5 s to import) only when a plot is asked for.
    from matplotlib.figure import Figure

    lc = result.lightcurve
    t0 = result.t_event_bmjd
    hours = (np.asarray(lc["time_bmjd"]) - t0) * 24.0
    width_h = bin_minutes / 60.0
    tb, fb, eb = bin_series(hours, lc["flux_corrected"], width_h)
    _, rb, rbe = bin_series(hours, lc["residual"], width_h)
    order = np.argsort(hours)
    fig = Figure(figsize=(7.0, 5.5), dpi=110)
    ax, axr = fig.subplots(2, 1, sharex=True, gridspec_kw={"height_ratios": [3, 1]})
    ax.errorbar(tb, (fb - 1) * 1e6, yerr=eb * 1e6, fmt="o", ms=3, color="0.3", lw=0.8,
                label=f"decorrelated, {bin_minutes:g}-min bins")
    ax.plot(hours[order], (np.asarray(lc["astro_model"])[order] - 1) * 1e6, color="C3", lw=1.5,
            label=f"model ({result.phase} phase)")
    ax.set_ylabel("relative flux - 1 (ppm)")
    ax.set_title(f"{result.method}, epoch {result.epoch} ({result.profile} profile): depth "
                 f"{result.depth_ppm:.0f} +- {result.depth_err_ppm:.0f} ppm")
    ax.legend(loc="best", fontsize=8)
    axr.errorbar(tb, rb * 1e6, yerr=rbe * 1e6, fmt="o", ms=3, color="0.3", lw=0.8)
    axr.axhline(0.0, color="C3", lw=1)
    axr.set_xlabel(f"hours from mid-eclipse ({t0:.5f} BMJD_TDB)")
    axr.set_ylabel("residual (ppm)")
    fig.tight_layout()
    return fig


def plot_reduced_lightcurve(result, path: str | os.PathLike, *, bin_minutes: float = 5.0) -> None:
    """Write a PNG of :func:`lightcurve_figure` of ``result``."""
    save_png(lightcurve_figure(result, bin_minutes=bin_minutes), path)


def _display(name: str, values: np.ndarray) -> tuple[str, np.ndarray]:
    """Axis label and values: the depth in ppm, the eclipse time in seconds from its median."""
    if name == "depth":
        return "depth (ppm)", values * 1e6
    if name == "t_ecl_bmjd":
        return "t_ecl - median (s)", (values - np.median(values)) * 86400.0
    return name, values


def corner_figure(names, samples: np.ndarray, *, bins: int = 30):
    """A corner-plot Figure of posterior ``samples`` (n, p): histograms and 2-D densities.

    Each diagonal panel is the marginal histogram with the 16th, 50th and
    84th percentiles dashed; below it, the 2-D histogram of each pair. The
    depth is shown in ppm and the eclipse time in seconds from its median.

    Examples
    --------
    >>> g = np.random.default_rng(0)
    >>> fig = corner_figure(["depth", "t_ecl_bmjd"], g.normal([1.8e-3, 5e4], [1e-4, 1e-3], (500, 2)))
    >>> len(fig.axes)
    4
    """
    from matplotlib.figure import Figure

    samples = np.asarray(samples, dtype=float)
    names = [str(n) for n in names]
    if samples.ndim != 2 or samples.shape[1] != len(names) or len(samples) < 2:
        raise ValueError(f"samples: expected (n >= 2, {len(names)}), got {samples.shape}")
    shown = [_display(n, samples[:, i]) for i, n in enumerate(names)]
    p = len(names)
    fig = Figure(figsize=(1.9 * p + 1, 1.9 * p + 1), dpi=100)
    axes = np.atleast_2d(fig.subplots(p, p, squeeze=False))
    for i in range(p):
        for j in range(p):
            ax = axes[i, j]
            if j > i:
                ax.set_axis_off()
                continue
            xi_label, xi = shown[j]
            if i == j:
                ax.hist(xi, bins=bins, color="0.4", histtype="step")
                for q in np.percentile(xi, [15.865525393145708, 50.0, 84.13447460685429]):
                    ax.axvline(q, color="C3", ls="--", lw=0.8)
                ax.set_yticks([])
            else:
                ax.hist2d(xi, shown[i][1], bins=bins, cmap="Greys")
            if i == p - 1:
                ax.set_xlabel(xi_label, fontsize=8)
            else:
                ax.set_xticklabels([])
            if j == 0 and i > 0:
                ax.set_ylabel(shown[i][0], fontsize=8)
            elif j > 0:
                ax.set_yticklabels([])
            ax.tick_params(labelsize=7)
    fig.tight_layout()
    return fig


def plot_corner(names, samples: np.ndarray, path: str | os.PathLike, *, bins: int = 30) -> None:
    """Write a PNG of :func:`corner_figure` of posterior ``samples``.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> g = np.random.default_rng(0)
    >>> out = pathlib.Path(tempfile.mkdtemp()) / "corner.png"
    >>> plot_corner(["depth", "t_ecl_bmjd"], g.normal([1.8e-3, 5e4], [1e-4, 1e-3], (500, 2)), out)
    >>> out.stat().st_size > 0
    True
    """
    save_png(corner_figure(names, samples, bins=bins), path)
