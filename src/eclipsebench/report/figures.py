"""The paper's figures as matplotlib :class:`~matplotlib.figure.Figure` objects.

Each function takes arrays (or the statistics dict) and returns a Figure; it
never touches files or the screen. :func:`save_figure` writes a Figure as PNG
and PDF atomically. Figures are built with the object-oriented API on the Agg
canvas (no pyplot, no display, no global state).
"""

from __future__ import annotations

import math
import textwrap
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
from matplotlib import colormaps
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from ..io.atomic import atomic_path
from ..stats.ensemble import GAUSS_1SIGMA, GAUSS_2SIGMA, pairwise_differences

__all__ = ["new_figure", "save_figure", "bin_mean", "centroid_clouds", "photometry_vs_phase",
           "decorrelated_lightcurves", "depths_per_epoch", "visit_differences",
           "method_differences", "repeatability_vs_reliability", "accuracy_vs_reliability",
           "accuracy_ratio_vs_bias", "coverage_per_method", "normalised_residual_histograms",
           "fit_inverse", "fit_line", "PAGE_WIDTH_IN", "LIGHTCURVE_POINTS"]

#: The report page's width (1100 px at the 120 dpi of :func:`save_figure`): no figure is
#: drawn wider, so none is shrunk in the browser.
PAGE_WIDTH_IN = 9.1
#: Points per decorrelated light curve, whatever its cadence (frames or a method's bins).
LIGHTCURVE_POINTS = 150


def _finish_grid(fig: Figure, axes, n_used: int, title: str, xlabel: str | None = None,
                 ylabel: str | None = None) -> Figure:
    """Hide the unused panels of a grid, label the shared axes, set the title."""
    for ax in axes[n_used:]:
        ax.set_visible(False)
    if xlabel:
        fig.supxlabel(xlabel, fontsize=8)
    if ylabel:
        fig.supylabel(ylabel, fontsize=8)
    # a grid narrower than its title (one or two methods) wraps the title, not clips it
    width_in = fig.get_size_inches()[0]
    fig.suptitle(textwrap.fill(title, max(20, int(width_in * 7.5))))
    return fig


#: Epochs named in legends and labels; a Monte Carlo's hundreds would hide the data.
MAX_LEGEND_EPOCHS = 20


def new_figure(width: float, height: float) -> Figure:
    """An empty Figure of ``width`` x ``height`` inches on its own Agg canvas (constrained
    layout): no pyplot, no backend chosen, nothing process-wide."""
    fig = Figure(figsize=(width, height), layout="constrained")
    FigureCanvasAgg(fig)
    return fig


_figure = new_figure


def _colors(n: int):
    cmap = colormaps["tab10" if n <= 10 else "turbo"]
    return [cmap(i if n <= 10 else i / max(n - 1, 1)) for i in range(n)]


def save_figure(fig: Figure, dest_stem: str | Path, *, dpi: int = 120) -> list[Path]:
    """Write ``dest_stem.png`` and ``dest_stem.pdf`` atomically (no timestamps).

    The layout is computed once, for the PNG; the PDF keeps its positions (the
    constrained layout of a figure of many panels costs as much as drawing it),
    and so does ``fig`` afterwards: its layout engine is set to none.
    """
    stem = Path(dest_stem)
    out = []
    for fmt, meta in (("png", {"Software": None}), ("pdf", {"CreationDate": None, "Creator": None,
                                                          "Producer": None})):
        path = stem.with_suffix(f".{fmt}")
        with atomic_path(path) as tmp:
            fig.savefig(tmp, format=fmt, dpi=dpi, metadata=meta)
        fig.set_layout_engine("none")
        out.append(path)
    return out


def bin_mean(values, size: int) -> np.ndarray:
    """Means of consecutive groups of ``size`` values (a last partial group is dropped)."""
    v = np.asarray(values, dtype=float)
    n = (v.size // size) * size
    if n == 0:
        return v[:0]
    return v[:n].reshape(-1, size).mean(axis=1)


def fit_inverse(r, R) -> float:
    """Least-squares ``k`` of ``R = k / r`` (the paper's dashed curves, Figs. 14-15)."""
    u = 1.0 / np.asarray(r, dtype=float)
    R = np.asarray(R, dtype=float)
    return float(np.sum(u * R) / np.sum(u * u))


def fit_line(x, y) -> tuple[float, float]:
    """Least-squares slope and intercept of ``y = slope x + intercept``."""
    slope, intercept = np.polyfit(np.asarray(x, float), np.asarray(y, float), 1)
    return float(slope), float(intercept)


def centroid_clouds(centroids: Mapping[object, tuple[np.ndarray, np.ndarray]], *,
                    gain_map: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
                    max_points: int = 4000, title: str = "Centroids") -> Figure:
    """Centroid positions per epoch over the intra-pixel gain map (Figs. 1-2).

    Parameters
    ----------
    centroids : mapping
        ``{epoch: (x, y)}``, 0-based pixel coordinates.
    gain_map : tuple, optional
        ``(x, y, gain)`` with ``gain[j, i]`` at ``(x[i], y[j])``, shown as a
        grey scale with contours.
    max_points : int
        Points drawn per epoch (evenly thinned).
    """
    fig = _figure(6.0, 5.4)
    ax = fig.add_subplot()
    if gain_map is not None:
        gx, gy, gain = (np.asarray(a, dtype=float) for a in gain_map)
        mesh = ax.pcolormesh(gx, gy, gain, cmap="Greys_r", shading="auto")
        ax.contour(gx, gy, gain, levels=8, colors="k", linewidths=0.4)
        fig.colorbar(mesh, ax=ax, label="relative gain")
    for color, (epoch, (x, y)) in zip(_colors(len(centroids)), centroids.items(), strict=True):
        x, y = np.asarray(x, float), np.asarray(y, float)
        step = max(1, x.size // max_points)
        ax.plot(x[::step], y[::step], ".", ms=1.0, color=color, label=f"{epoch}", alpha=0.6)
    ax.set_xlabel("x (pixel, 0-based)")
    ax.set_ylabel("y (pixel, 0-based)")
    ax.set_title(title)
    ax.set_aspect("equal", adjustable="datalim")
    if len(centroids) <= MAX_LEGEND_EPOCHS:
        ax.legend(title="epoch", fontsize=6, markerscale=8, loc="upper right", ncols=2)
    return fig


def photometry_vs_phase(epochs: Mapping[object, Mapping[str, np.ndarray]], *, bin_size: int = 63,
                        title: str = "Photometry vs phase") -> Figure:
    """x, y, noise pixels, background and flux versus orbital phase (Figs. 3-4).

    Parameters
    ----------
    epochs : mapping
        ``{epoch: {"phase", "x", "y", "noise_pixels", "background", "flux"}}``.
        Background and flux are normalised to their means over all epochs.
    bin_size : int
        Frames averaged per point (63: one subarray cube without its first frame).
    """
    panels = (("x", "x (px)", False), ("y", "y (px)", False),
              ("noise_pixels", "noise pixels", False), ("background", "background (norm.)", True),
              ("flux", "flux (norm.)", True))
    norms = {}
    for key, _, normalise in panels:
        if normalise:
            allv = np.concatenate([np.asarray(e[key], float) for e in epochs.values()])
            norms[key] = float(np.nanmean(allv)) or 1.0
    fig = _figure(7.0, 9.0)
    axes = fig.subplots(len(panels), 1, sharex=True)
    for color, (epoch, data) in zip(_colors(len(epochs)), epochs.items(), strict=True):
        phase = bin_mean(data["phase"], bin_size)
        for ax, (key, _, _) in zip(axes, panels, strict=True):
            v = bin_mean(data[key], bin_size) / norms.get(key, 1.0)
            ax.plot(phase, v, ".", ms=2, color=color, label=str(epoch))
    for ax, (_, label, _) in zip(axes, panels, strict=True):
        ax.set_ylabel(label, fontsize=8)
    axes[-1].set_xlabel("orbital phase (since transit)")
    axes[0].set_title(title)
    if len(epochs) <= MAX_LEGEND_EPOCHS:
        axes[0].legend(title="epoch", fontsize=6, ncols=5, markerscale=3)
    return fig


def decorrelated_lightcurves(curves: Mapping[str, Mapping[str, np.ndarray]], *,
                             truth: tuple[np.ndarray, np.ndarray] | None = None,
                             points: int = LIGHTCURVE_POINTS,
                             title: str = "Decorrelated light curves", x: str = "phase",
                             xlabel: str = "orbital phase", highlight: str | None = None,
                             notes: Mapping[str, str] | None = None) -> Figure:
    """One panel per method: the decorrelated flux binned and the fitted model (Figs. 5-6).

    Parameters
    ----------
    curves : mapping
        ``{method: {x, "flux_corrected", "astro_model"}}``.
    truth : tuple, optional
        ``(x, L)``: the input light curve, drawn as a blue line.
    points : int
        Binned points per panel: each curve is binned by its own factor, so a
        method whose light curve holds its bins (GP, SPCA) shows as many
        points as one that holds every frame.
    title : str
        The figure's title.
    x, xlabel : str
        The curves' key of the horizontal axis and its label (a trust page
        draws hours from mid-eclipse).
    highlight : str, optional
        A method whose panel is framed and its fit drawn thicker (the
        recommended one).
    notes : mapping, optional
        ``{method: text}`` added to a panel's label (its depth).
    """
    n = max(len(curves), 1)
    fig = _figure(7.0, 1.6 * n + 0.8)
    axes = np.atleast_1d(fig.subplots(n, 1, sharex=True, sharey=True, squeeze=False)[:, 0])
    for ax, (method, c) in zip(axes, curves.items(), strict=False):
        chosen = method == highlight
        size = max(1, round(len(c[x]) / points))
        ax.plot(bin_mean(c[x], size), bin_mean(c["flux_corrected"], size), ".",
                ms=2, color="0.3", label=f"data, binned {size}x")
        ax.plot(c[x], c["astro_model"], "-", color="tab:red", lw=2 if chosen else 1, label="fit")
        if truth is not None:
            ax.plot(truth[0], truth[1], "-", color="tab:blue", lw=1, label="input")
        extra = (notes or {}).get(method)
        ax.text(0.01, 0.05, f"{method}{' (recommended)' if chosen else ''}"
                + (f": {extra}" if extra else f" ({len(c[x])} rows, binned {size}x)"),
                transform=ax.transAxes, fontsize=8, fontweight="bold" if chosen else "normal")
        if chosen:
            for side in ax.spines.values():
                side.set_edgecolor("goldenrod")
                side.set_linewidth(2.5)
        ax.set_ylabel("rel. flux", fontsize=8)
        ax.ticklabel_format(axis="y", useOffset=False)   # 1.002, not "+1" and 0.002
    axes[0].legend(fontsize=7, loc="upper right", ncols=3)
    axes[-1].set_xlabel(xlabel)
    axes[0].set_title(title)
    return fig


def depths_per_epoch(groups: Mapping[str, tuple[np.ndarray, np.ndarray, np.ndarray]],
                     summary: Mapping, *, truth_ppm: float | None = None,
                     title: str = "Eclipse depths") -> Figure:
    """Depths per epoch for every method and the weighted means (Figs. 7-8).

    Parameters
    ----------
    groups : mapping
        ``{method: (epoch, depth_ppm, error_ppm)}``.
    summary : mapping
        The statistics dict (``methods[m]["D_mean"]``, ``["sigma_tot"]``).
    truth_ppm : float, optional
        The input depth, drawn as a blue line.
    """
    fig = _figure(PAGE_WIDTH_IN, 4.5)
    ax = fig.add_subplot()
    names = list(groups)
    width = 0.7 / max(len(names), 1)
    epochs = sorted({int(e) for g in groups.values() for e in g[0]})
    right = (max(epochs) if epochs else 0) + 1.5
    means = []
    for k, (color, name) in enumerate(zip(_colors(len(names)), names, strict=True)):
        ep, d, e = (np.asarray(a, float) for a in groups[name])
        off = (k - (len(names) - 1) / 2) * width
        ax.errorbar(ep + off, d, yerr=e, fmt="o", ms=3, color=color, label=name, lw=0.8)
        s = summary["methods"].get(name)
        if s is not None:
            ax.errorbar(right + 0.5 + k * 0.3, s["D_mean"], yerr=s["sigma_tot"], fmt="s", ms=4,
                        color=color, lw=1.2)
            means.append((s["D_mean"], s["sigma_tot"]))
    ax.axvline(right, color="0.6")
    if means:
        grand = float(np.mean([m for m, _ in means]))
        err = float(np.sqrt(np.sum([s**2 for _, s in means])) / len(means))
        for v in (grand - err, grand, grand + err):
            ax.axhline(v, color="tab:red", lw=0.8, ls="-" if v == grand else "--")
    if truth_ppm is not None:
        ax.axhline(truth_ppm, color="tab:blue", lw=1.2, label=f"input {truth_ppm:.0f} ppm")
    every = max(1, math.ceil(len(epochs) / 25))  # a Monte Carlo's hundreds of epochs
    ticks = epochs[::every]
    ax.set_xticks(ticks + [right + 0.5 + 0.15 * (len(names) - 1)],
                  [str(e) for e in ticks] + ["mean"])
    ax.set_xlabel("epoch")
    ax.set_ylabel("eclipse depth (ppm)")
    ax.set_title(title)
    # beside the axes, never over an error bar
    fig.legend(*ax.get_legend_handles_labels(), loc="outside right upper", fontsize=7)
    return fig


def _grid(n: int) -> tuple[int, int]:
    cols = min(n, 4)
    return math.ceil(n / cols), cols


def _grid_size(rows: int, cols: int, panel_width: float, panel_height: float
               ) -> tuple[float, float]:
    """A grid figure's size: panels shrunk together so the width fits the page."""
    scale = min(1.0, PAGE_WIDTH_IN / (panel_width * cols))
    return panel_width * cols * scale, panel_height * rows * scale


def visit_differences(groups: Mapping[str, tuple[np.ndarray, np.ndarray]], summary: Mapping, *,
                      title: str = "Repeated visits: mean/difference") -> Figure:
    """Mean/difference plots between visits, one panel per method (Figs. 10-11).

    Every ordered pair of epochs (i, j), i != j: ``(D_i + D_j) / 2`` against
    ``D_i - D_j``, labelled "i-j", with dashed lines at +-R.

    Parameters
    ----------
    groups : mapping
        ``{method: (epoch, depth_ppm)}``.
    """
    rows, cols = _grid(max(len(groups), 1))
    fig = _figure(*_grid_size(rows, cols, 3.2, 2.8))
    axes = np.atleast_1d(fig.subplots(rows, cols, squeeze=False).ravel())
    for ax, (name, (ep, d)) in zip(axes, groups.items(), strict=False):
        d = np.asarray(d, float)
        ep = np.asarray(ep)
        n = d.size
        ii, jj = np.nonzero(~np.eye(n, dtype=bool))
        mean = (d[ii] + d[jj]) / 2.0
        diff = pairwise_differences(d)
        ax.plot(mean, diff, ".", ms=3)
        if n <= 12:
            for x, y, a, b in zip(mean, diff, ep[ii], ep[jj], strict=True):
                ax.annotate(f"{a}-{b}", (x, y), fontsize=4, alpha=0.7)
        R = summary["methods"][name]["R"]
        ax.axhline(0.0, color="0.6", lw=0.8)
        for v in (-R, R):
            ax.axhline(v, color="k", ls="--", lw=0.8)
        ax.text(0.02, 0.03, f"SD = {R:.0f} ppm", transform=ax.transAxes, fontsize=7)
        ax.set_title(name, fontsize=9)
        ax.set_xlabel("mean depth (ppm)", fontsize=7)
        ax.set_ylabel("D1 - D2 (ppm)", fontsize=7)
    return _finish_grid(fig, axes, len(groups), title)


def method_differences(groups: Mapping[str, tuple[np.ndarray, np.ndarray]], ttest_p: Mapping, *,
                       title: str = "Methods: mean/difference") -> Figure:
    """Mean/difference plots between every pair of methods (Figs. 16-17).

    Per pair (a, b) and common epoch: ``(D_a + D_b) / 2`` against
    ``D_a - D_b`` labelled by epoch; dashed lines at the mean difference and
    +-1 SD; the unpaired t-test p value in the corner.
    """
    names = list(groups)
    pairs = [(a, b) for i, a in enumerate(names) for b in names[i + 1:]]
    rows, cols = _grid(max(len(pairs), 1))
    fig = _figure(*_grid_size(rows, cols, 3.0, 2.6))
    axes = np.atleast_1d(fig.subplots(rows, cols, squeeze=False).ravel())
    for ax, (a, b) in zip(axes, pairs, strict=False):
        ea, da = (np.asarray(v) for v in groups[a])
        eb, db = (np.asarray(v) for v in groups[b])
        common, ia, ib = np.intersect1d(ea, eb, return_indices=True)
        mean = (da[ia] + db[ib]) / 2.0
        diff = da[ia].astype(float) - db[ib]
        ax.plot(mean, diff, ".", ms=4)
        if common.size <= MAX_LEGEND_EPOCHS:
            for x, y, e in zip(mean, diff, common, strict=True):
                ax.annotate(str(e), (x, y), fontsize=5)
        ax.axhline(0.0, color="0.6", lw=0.8)
        if diff.size >= 2:
            m, s = float(diff.mean()), float(diff.std(ddof=1))
            for v in (m - s, m, m + s):
                ax.axhline(v, color="k", ls="--", lw=0.8)
            ax.text(0.02, 0.03, f"{m:.0f} ± {s:.0f}", transform=ax.transAxes, fontsize=7)
        p = ttest_p.get(a, {}).get(b)
        if p is not None:
            ax.text(0.98, 0.03, f"p = {p:.2f}", transform=ax.transAxes, fontsize=7, ha="right",
                    color="tab:red" if p < 0.05 else "k")
        ax.set_title(f"{a} - {b}", fontsize=8)
        ax.tick_params(labelsize=6)
        ax.ticklabel_format(axis="x", useOffset=False)  # no "+1.832e3" under a small panel
    return _finish_grid(fig, axes, len(pairs), title, "mean depth (ppm)", "difference (ppm)")


def _method_points(summary: Mapping, keys: Sequence[str]):
    names: list[str] = []
    cols: list[list[float]] = [[] for _ in keys]
    for name, s in summary["methods"].items():
        vals = [s.get(k) for k in keys]
        if all(v is not None and np.isfinite(v) for v in vals):
            names.append(name)
            for c, v in zip(cols, vals, strict=True):
                c.append(float(v))
    return names, [np.asarray(c) for c in cols]


_MARKERS = ("o", "s", "^", "D", "v", "P", "X", "*", "<", ">", "h", "p")


def _method_scatter(fig: Figure, ax, names: Sequence[str], x, y, values: str) -> None:
    """One marker per method and a key beside the axes naming each with its values.

    Labels next to the points overlap where methods cluster (twelve methods
    with similar r); the key cannot. ``values`` formats a key entry from
    ``x`` and ``y``, e.g. ``"r = {x:.2f}, R = {y:.0f} ppm"``.
    """
    cmap = colormaps["tab10" if len(names) <= 10 else "tab20"]
    colors = [cmap(i % cmap.N) for i in range(len(names))]
    handles = []
    for k, (name, a, b) in enumerate(zip(names, x, y, strict=True)):
        (h,) = ax.plot([a], [b], _MARKERS[k % len(_MARKERS)], ms=6, color=colors[k],
                       markeredgecolor="k", markeredgewidth=0.4,
                       label=f"{name}: {values.format(x=a, y=b)}")
        handles.append(h)
    if handles:
        fig.legend(handles=handles, loc="outside right upper", fontsize=7, title="method",
                   title_fontsize=7)


def _log_when_spread(ax, r: np.ndarray) -> bool:
    """A log r axis when the reliabilities span more than a decade (a few epochs' outliers)."""
    spread = r.size >= 2 and r.min() > 0 and r.max() / r.min() > 10.0
    if spread:
        ax.set_xscale("log")
    return bool(spread)


def repeatability_vs_reliability(summary: Mapping, sigma_phot_ppm: float, *,
                                 title: str = "Repeatability vs reliability") -> Figure:
    """R against r with ``R = sqrt(2) sigma_phot / r`` and the fit ``R = k / r`` (Figs. 12-13)."""
    names, (r, R) = _method_points(summary, ("r", "R"))
    fig = _figure(7.5, 4.2)
    ax = fig.add_subplot()
    _method_scatter(fig, ax, names, r, R, "r = {x:.2f}, R = {y:.0f} ppm")
    if r.size:
        log = _log_when_spread(ax, r)
        grid = (np.geomspace(0.8 * r.min(), 1.2 * r.max(), 200) if log
                else np.linspace(0.8 * r.min(), min(1.2 * r.max(), 1.5), 200))
        ax.plot(grid, math.sqrt(2) * sigma_phot_ppm / grid, "-", color="k",
                label=f"R = √2 σ_phot / r = {math.sqrt(2) * sigma_phot_ppm:.1f} / r")
        k = fit_inverse(r, R)
        ax.plot(grid, k / grid, "--", color="tab:red", label=f"fit R = {k:.1f} / r")
        ax.legend(handles=ax.get_lines()[len(names):], fontsize=7)
    ax.set_xlabel("reliability r" + (" (log scale)" if ax.get_xscale() == "log" else ""))
    ax.set_ylabel("repeatability R (ppm)")
    ax.set_title(title)
    return fig


def accuracy_vs_reliability(summary: Mapping, *, title: str = "Accuracy vs reliability") -> Figure:
    """a against r with the line a = r and a linear fit (Fig. 19)."""
    names, (r, a) = _method_points(summary, ("r", "a"))
    fig = _figure(7.5, 4.2)
    ax = fig.add_subplot()
    _method_scatter(fig, ax, names, r, a, "r = {x:.2f}, a = {y:.2f}")
    if r.size:
        top = float(max(r.max(), a.max()) * 1.15)
        grid = (np.geomspace(0.8 * r.min(), top, 200) if _log_when_spread(ax, r)
                else np.linspace(0.0, top, 200))
        ax.plot(grid, grid, ":", color="0.5", label="a = r")
        if r.size >= 2 and np.ptp(r) > 0:
            slope, icpt = fit_line(r, a)
            ax.plot(grid, slope * grid + icpt, "--", color="tab:red",
                    label=f"fit a = {slope:.2f} r {icpt:+.2f}")
        ax.set_ylim(0.0, 1.3 * float(a.max()) if a.max() > 0 else 1.0)  # the points, not a = r
        ax.legend(handles=ax.get_lines()[len(names):], fontsize=7)
    ax.set_xlabel("reliability r" + (" (log scale)" if ax.get_xscale() == "log" else ""))
    ax.set_ylabel("accuracy a")
    ax.set_title(title)
    return fig


def accuracy_ratio_vs_bias(summary: Mapping, *, title: str = "a/r vs |bias|") -> Figure:
    """a/r against the mean absolute bias with a linear fit (Fig. 20)."""
    names, (r, a, bias) = _method_points(summary, ("r", "a", "bias"))
    fig = _figure(7.5, 4.2)
    ax = fig.add_subplot()
    ratio, absb = a / r if r.size else r, np.abs(bias)
    _method_scatter(fig, ax, names, absb, ratio, "|bias| = {x:.0f} ppm, a/r = {y:.2f}")
    if r.size >= 2 and np.ptp(absb) > 0:
        slope, icpt = fit_line(absb, ratio)
        grid = np.array([0.0, absb.max() * 1.1])
        ax.plot(grid, slope * grid + icpt, "--", color="tab:red",
                label=f"fit a/r = {icpt:.2f} {slope:+.4f} |B|")
        ax.legend(handles=ax.get_lines()[len(names):], fontsize=7)
    ax.set_xlabel("|mean bias| (ppm)")
    ax.set_ylabel("a / r")
    ax.set_title(title)
    return fig


def coverage_per_method(summary: Mapping, *, title: str = "Coverage of the truth") -> Figure:
    """1- and 2-sigma coverage per method with 68% binomial intervals, against 68% and 95%.

    Parameters
    ----------
    summary : mapping
        The statistics dict: ``methods[m]["coverage"]``, ``["coverage_lo"]``,
        ``["coverage_hi"]`` and the same for ``coverage_2sigma``; methods
        without them (no truth) are left out.
    """
    rows = [(name, s) for name, s in summary["methods"].items()
            if s.get("coverage") is not None and s.get("coverage_2sigma") is not None]
    fig = _figure(max(5.0, 0.55 * len(rows) + 2.5), 4.0)
    ax = fig.add_subplot()
    x = np.arange(len(rows))
    for key, level, color, dx, label in (("coverage", GAUSS_1SIGMA, "tab:blue", -0.12, "1 sigma"),
                                         ("coverage_2sigma", GAUSS_2SIGMA, "tab:red", 0.12,
                                          "2 sigma")):
        c = np.array([s[key] for _, s in rows], float)
        lo = np.array([s[f"{key}_lo"] for _, s in rows], float)
        hi = np.array([s[f"{key}_hi"] for _, s in rows], float)
        ax.errorbar(x + dx, c, yerr=[c - lo, hi - c], fmt="o", ms=4, color=color, lw=1,
                    capsize=2, label=f"within {label}")
        ax.axhline(level, color=color, ls="--", lw=0.8)
        ax.text(1.0, level, f" {100 * level:.1f}%", transform=ax.get_yaxis_transform(),
                color=color, fontsize=7, va="center")
    n = sorted({int(s["N"]) for _, s in rows})
    ax.set_xticks(x, [name for name, _ in rows], rotation=45, ha="right", fontsize=8)
    ax.set_xlim(-0.6, max(len(rows), 1) - 0.4)
    ax.set_ylim(0.0, 1.04)
    ax.set_ylabel("fraction of epochs covering the truth")
    ax.set_title(title + (f", N = {n[0]} epochs" if len(n) == 1 else ""))
    ax.legend(fontsize=7, loc="lower left")
    return fig


def normalised_residual_histograms(residuals: Mapping[str, np.ndarray], *, limit: float = 4.0,
                                   bin_width: float = 0.5,
                                   title: str = "Normalised residuals (D - truth) / sigma",
                                   counted: str = "epochs", xlabel: str = "(D - truth) / sigma"
                                   ) -> Figure:
    """Histograms of ``z = (D_i - truth) / sigma_i`` against the unit Gaussian.

    The first panel pools every method; then one panel per method. Each is
    a density (area 1) with the unit Gaussian density drawn over it; values
    beyond ``+-limit`` are counted in the outermost bins. The corner gives
    the number of epochs (``counted``: what a value is, twins on a trust
    page) and the RMS of z (1 for honest errors). Every panel has the same
    scales, so the panels compare at a glance.

    Parameters
    ----------
    residuals : mapping
        ``{method: z}``.
    limit, bin_width : float
        Histogram range ``[-limit, limit]`` and bin width.
    """
    panels = {"all methods": np.concatenate([np.asarray(z, float) for z in residuals.values()])
              if residuals else np.zeros(0)}
    panels.update({m: np.asarray(z, float) for m, z in residuals.items()})
    rows, cols = _grid(len(panels))
    fig = _figure(*_grid_size(rows, cols, 2.9, 2.4))
    axes = np.atleast_1d(fig.subplots(rows, cols, squeeze=False, sharex=True, sharey=True)
                         .ravel())
    edges = np.arange(-limit, limit + bin_width / 2, bin_width)
    grid = np.linspace(-limit, limit, 201)
    gauss = np.exp(-0.5 * grid**2) / math.sqrt(2.0 * math.pi)
    for ax, (name, z) in zip(axes, panels.items(), strict=False):
        if z.size:
            ax.hist(np.clip(z, -limit + 1e-9, limit - 1e-9), bins=edges, density=True,
                    color="0.55" if name == "all methods" else "tab:blue", alpha=0.8)
        ax.plot(grid, gauss, "-", color="k", lw=1)
        rms = float(np.sqrt(np.mean(z**2))) if z.size else float("nan")
        ax.text(0.02, 0.97, f"N = {z.size} {counted}\nrms = {rms:.2f}", transform=ax.transAxes,
                fontsize=7, va="top")
        ax.set_title(name, fontsize=9)
        ax.tick_params(labelsize=7)
    return _finish_grid(fig, axes, len(panels), title, xlabel, "density")
