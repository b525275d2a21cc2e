"""The trust run's page and figures, on :mod:`eclipsebench.report`'s toolkit.

The page (``report/index.html`` of a trust folder) is built with
:mod:`eclipsebench.report.page` and its figures with the object-oriented
matplotlib API (:func:`eclipsebench.report.figures.new_figure`: a bare
``Figure`` on its own Agg canvas; no pyplot, no backend chosen, nothing
process-wide), the same as a run's report. It shows, top to bottom: the
line to quote and how far the ranking goes, the cautions, the per-method
table (the recommended method highlighted), the version, command line and
seed, then the real decorrelated light curve with each method's fit, the
twins' depths against the injected one, their z-scores on one scale, and
the real observation beside one twin; times in hours from mid-eclipse.

:func:`write_page` is called by the score task with what it has in memory;
:func:`write_page_of_folder` draws the page of an existing trust folder
again (a folder made by an older version included).
"""

from __future__ import annotations

import html
import json
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from astropy.table import Table
from matplotlib.figure import Figure

from .. import __version__
from ..astro.events import event_for
from ..fit.result.plot import literal_text
from ..photometry.binning import bin_indices, bin_values
from ..photometry.table import read_table
from ..report import figures as F
from ..report.page import figure_html, html_table, notes_html, page_folder, page_html
from .collect import collect
from .layout import TrustLayout
from .rows import (
    DEPTH_COLUMNS,
    PHASE_HEAD,
    TIME_COLUMNS,
    cautions,
    method_rows,
    phase_rows,
    phase_units,
)
from .score import DISTINGUISHABLE_AT, RECOMMEND_DRAWS

__all__ = ["write_page", "write_page_of_folder", "load_twins", "real_curves", "twin_depths_figure",
           "real_lightcurves_figure", "z_score_figure", "resemblance_figure", "hours_label"]

#: Colours of the figures: the real observation, the twins, the recommended method.
REAL_COLOR, TWIN_COLOR, CHOSEN_COLOR = "tab:red", "tab:blue", "goldenrod"


def _event(summary: Mapping[str, Any]) -> str:
    return event_for((summary.get("twins") or {}).get("event")).mid_label


def hours_label(summary: Mapping[str, Any]) -> str:
    """The time axis's label: hours from the twins' mid-event time, which it names."""
    t0 = (summary.get("twins") or {}).get("t_event_bmjd")
    return (f"hours from {_event(summary)}" + (f" (BMJD_TDB {t0:.5f})" if t0 is not None
                                                 else ""))


def _hours(time_bmjd, summary: Mapping[str, Any]) -> np.ndarray:
    t0 = (summary.get("twins") or {}).get("t_event_bmjd")
    time_bmjd = np.asarray(time_bmjd, float)
    return (time_bmjd - (float(t0) if t0 is not None else float(np.median(time_bmjd)))) * 24.0


def twin_depths_figure(summary: Mapping[str, Any],
                       twin_depths: Mapping[str, Sequence[float]] | None = None) -> Figure:
    """Per method: the twins' depths, the real depth with its honest (thick) and reported
    (thin) errors, the depth injected into the twins; the recommended method on a shaded band
    and the methods the twins cannot tell from it marked.

    Parameters
    ----------
    summary : mapping
        ``trust.json``'s content.
    twin_depths : mapping, optional
        ``{method: depths of its twins (ppm)}``; without it the twins are shown by their
        mean and SD (the injected depth plus the bias, +- the SD).
    """
    methods = list(summary.get("methods", {}))
    best = summary.get("recommended")
    near = set(summary.get("near_equals") or [])
    fig = F.new_figure(min(F.PAGE_WIDTH_IN, max(5.5, 1.1 * len(methods) + 3.0)), 4.2)
    ax = fig.add_subplot()
    jitter = np.random.default_rng(0)   # the points' spread on the page, not a result
    n = summary.get("n_twins")
    for i, m in enumerate(methods):
        s = summary["methods"][m]
        if m == best:
            ax.axvspan(i - 0.5, i + 0.5, color=CHOSEN_COLOR, alpha=0.18, lw=0,
                       label="recommended method")
        if twin_depths is not None and m in twin_depths:
            d = np.asarray(twin_depths[m], float)
            ax.plot(i - 0.12 + 0.12 * jitter.uniform(-1, 1, d.size), d, ".", ms=4, alpha=0.55,
                    color=TWIN_COLOR, label=f"twins ({n} per method): each one's depth"
                    if i == 0 else None)
        else:
            ax.errorbar(i - 0.12, summary["twin_depth_ppm"] + s["bias_ppm"], yerr=s["sd_ppm"],
                        fmt="o", ms=4, color=TWIN_COLOR, capsize=3,
                        label=f"twins ({n} per method): mean ± SD" if i == 0 else None)
        ax.errorbar(i + 0.22, s["depth_ppm"], yerr=s["honest_err_ppm"], fmt="none", lw=4,
                    color=REAL_COLOR, alpha=0.35,
                    label="real depth ± honest error" if i == 0 else None)
        ax.errorbar(i + 0.22, s["depth_ppm"], yerr=s["depth_err_ppm"], fmt="s", ms=5, lw=1.2,
                    capsize=3, color=REAL_COLOR,
                    label="real depth ± reported error" if i == 0 else None)
    ax.axhline(summary["twin_depth_ppm"], color="k", lw=1,
               label=f"depth injected in the twins ({summary['twin_depth_ppm']:.0f} ppm)")
    ax.set_xticks(range(len(methods)), [m + (" *" if m in near else "") for m in methods],
                  rotation=30, ha="right")
    for tick, m in zip(ax.get_xticklabels(), methods, strict=True):
        if m == best:
            tick.set_fontweight("bold")
    ax.set_xlim(-0.6, len(methods) - 0.4)
    ax.set_ylabel(f"{(summary.get('twins') or {}).get('event', 'eclipse')} depth (ppm)")
    ax.set_title(literal_text(f"{summary.get('system')}: the real depth and {n} twins per "
                              f"method ({summary.get('profile')} profile)"), fontsize=10)
    ax.set_xlabel("method (bold: recommended" + ("; *: the twins cannot tell it from the "
                                                 "recommended one)" if near else ")"),
                  fontsize=8)
    fig.legend(*ax.get_legend_handles_labels(), loc="outside right upper", fontsize=7)
    return fig


def real_lightcurves_figure(summary: Mapping[str, Any],
                            curves: Mapping[str, Mapping[str, np.ndarray]]) -> Figure:
    """The real decorrelated light curve of each method with its fit, hours from mid-eclipse
    (:func:`eclipsebench.report.figures.decorrelated_lightcurves`), the recommended framed."""
    methods = summary.get("methods", {})
    notes = {m: f"depth {methods[m]['depth_ppm']:.0f} ± {methods[m]['depth_err_ppm']:.0f} ppm "
                f"(honest {methods[m]['honest_err_ppm']:.0f})"
             for m in curves if m in methods}
    return F.decorrelated_lightcurves(
        curves, x="hours", xlabel=hours_label(summary), highlight=summary.get("recommended"),
        notes=notes, title=literal_text(f"{summary.get('system')}: the real observation "
                                        "decorrelated by each method, with its fit"))


def z_score_figure(summary: Mapping[str, Any], twins: Mapping[str, tuple]) -> Figure:
    """The twins' ``(D_i - D_injected) / sigma_i`` per method against the unit Gaussian, every
    panel on the same scales (:func:`eclipsebench.report.figures.normalised_residual_histograms`).
    """
    truth = float(summary["twin_depth_ppm"])
    z = {m: (np.asarray(t[0], float) - truth) / np.asarray(t[1], float) for m, t in twins.items()
         if m in summary.get("methods", {})}
    return F.normalised_residual_histograms(
        z, limit=5.0, counted="twins", xlabel="(D - injected depth) / reported error",
        title="The twins' z-scores (D - injected) / reported error; black: the unit Gaussian "
              "(honest errors)")


def _binned(time, values, width_d: float):
    """Mean time and median value of each ``width_d`` bin of at least 3 frames."""
    bins = bin_indices(time, width_days=width_d)
    centres, counts = bin_values(time, bins)
    order = np.argsort(bins, kind="stable")
    medians = np.array([np.median(v) for v in np.split(values[order], np.cumsum(
        counts.astype(int))[:-1])])
    keep = counts >= 3
    return centres[keep], medians[keep]


def resemblance_figure(summary: Mapping[str, Any], real_table: Table, twin_table: Table
                       ) -> Figure:
    """The real observation beside twin 1: raw flux, centroids and noise pixels in 5-minute
    bins, hours from mid-eclipse."""
    fig = F.new_figure(8.0, 8.0)
    axes = fig.subplots(4, 1, sharex=True)
    columns = ("flux", "x", "y", "noise_pixels")
    for t, label, color in ((real_table, "real observation", "k"), (twin_table, "twin 1",
                                                                   TWIN_COLOR)):
        good = np.asarray(t["flag"]) == 0
        time = np.asarray(t["time_bmjd"], float)[good]
        for ax, col in zip(axes, columns, strict=True):
            if col not in t.colnames:   # another pipeline's table without noise pixels
                continue
            v = np.asarray(t[col], float)[good]
            tb, vb = _binned(time, v / np.median(v) if col == "flux" else v, 5.0 / 1440)
            ax.plot(_hours(tb, summary), vb, ".", ms=3, color=color, label=label)
    for ax, name in zip(axes, ("raw flux / median", "x (px)", "y (px)", "noise pixels"),
                        strict=True):
        ax.set_ylabel(name, fontsize=8)
        ax.ticklabel_format(axis="y", useOffset=False)
    axes[0].legend(fontsize=8)
    axes[-1].set_xlabel(hours_label(summary))
    axes[0].set_title("The real observation beside one twin (5-minute bins, good frames)")
    return fig


def load_twins(root: str | Path, summary: Mapping[str, Any]) -> dict[str, tuple]:
    """The twins' ``(depths, errors, ...)`` per scored method of a trust folder
    (:func:`eclipsebench.trust.collect.collect`)."""
    methods = [m for m in summary.get("methods", {})]
    _, twins, _, _ = collect(Path(root), methods, int(summary["n_twins"]),
                             (summary.get("twins") or {}).get("event") or "eclipse")
    return twins


def real_curves(layout: TrustLayout, summary: Mapping[str, Any]) -> dict[str, dict]:
    """The real decorrelated light curve of each scored method (``real/<method>.lc.ecsv``),
    time in hours from the twins' mid-event time."""
    curves = {}
    for m in summary.get("methods", {}):
        path = layout.real(m).with_suffix(".lc.ecsv")
        if path.is_file():
            lc = Table.read(path, format="ascii.ecsv")
            curves[m] = {"hours": _hours(lc["time_bmjd"], summary),
                         "flux_corrected": np.asarray(lc["flux_corrected"], float),
                         "astro_model": np.asarray(lc["astro_model"], float)}
    return curves


def _provenance_html(summary: Mapping[str, Any]) -> str:
    esc = html.escape
    parts = []
    if summary.get("source_table"):
        parts.append(f"<p>Another pipeline's table, {esc(summary['source_table'])}, completed "
                     f"for the twins as {esc(summary['table'])}. Inferred:</p><ul>"
                     + "".join(f"<li>{esc(k)}: {esc(str(v))}</li>"
                               for k, v in (summary.get("inferred") or {}).items()) + "</ul>")
    if summary.get("time_conversion"):
        parts.append(f"<p>Times: {esc(summary['time_conversion'])}.</p>")
    return "".join(parts)


def _noise_pixels_text(twins: Mapping[str, Any]) -> str:
    real = (twins.get("calibration") or {}).get("noise_pixels_real")
    bound = twins.get("motion_bound") or {}
    if real is None:
        return ("no noise pixels in the table: the motion within an exposure is the most whose "
                f"pilot twin is no redder than the real residuals, A_fbm "
                f"{float(twins.get('motion_peak_px') or 0.0):.3f} px"
                if bound.get("photometry_only") else "no noise pixels in the table: not calibrated")
    return (f"median noise pixels {real:.2f} real" + (
                f"; the noise pixels alone gave a peak of {bound['steps'][0]['motion_peak_px']:.3f}"
                " px, whose pilot twin was redder than the real residuals, so the motion is the "
                "most the real photometry allows" if bound.get("bounded") else ""))


def _table_html(summary: Mapping[str, Any], columns) -> str:
    head, units, rows = method_rows(summary, columns)
    chosen = [i for i, r in enumerate(rows) if r[0] == summary.get("recommended")]
    return html_table([[f"{h} ({u})" if u else h for h, u in zip(head, units, strict=True)],
                       *rows], chosen=chosen)


def _body(summary: Mapping[str, Any], figures: Sequence[tuple[str, str, list[Path]]],
          root: Path, command: str | None) -> list[str]:
    esc = html.escape
    tw = summary.get("twins") or {}
    near = summary.get("near_equals") or []
    ranking = summary.get("ranking") or {}
    freq = summary.get("recommended_frequency") or {}
    none = freq.get("none")
    parts = [f"<p style='font-size:130%'><b>Quote: {esc(summary['quote']['text'])}</b></p>"]
    if ranking.get("resolved"):   # else the first caution says how many twins it needs
        parts.append("<p>Ranking: " + esc(ranking.get("text", "")) + "</p>")
    warn = cautions(summary)
    if warn:
        parts.append("<div class='caution'><b>Cautions</b><ul>"
                     + "".join(f"<li>{esc(c)}</li>" for c in warn) + "</ul></div>")
    parts.append(notes_html({
        "eclipsebench": summary.get("eclipsebench_version") or __version__,
        "command": command or "not recorded (the page was drawn again from the folder)",
        "seed": summary.get("seed"), "table": summary.get("table"),
        "planet": summary.get("system"),
        "twins": f"{summary.get('n_twins')} with a {summary['twin_depth_ppm']:.1f} ppm "
                 f"{tw.get('event')} (the real depth of {tw.get('from_method')}), reduced like "
                 f"the real table ({summary.get('profile')} profile, sampler "
                 f"{summary.get('sampler')})"}))
    parts.append("<h2>Per method</h2>")
    parts.append(f"<p>Recommended (highlighted): <b>{esc(str(summary.get('recommended')))}</b> "
                 f"({esc(str(summary.get('recommended_because', '')))})."
                 + (f" The twins cannot tell {esc(', '.join(near))} from it (mean squared error "
                    f"within {DISTINGUISHABLE_AT:g} paired standard errors): any of these."
                    if near else "") + "</p>")
    parts.append(_table_html(summary, DEPTH_COLUMNS))
    parts.append(
        "<p>depth: the method's depth on the real observation; honest err: its reported "
        "error times max(1, z_rms), the error to quote; bias, SD, RMSE: the twins' depths "
        "minus the injected depth; z_rms: the rms of (D - injected) / reported error (1 for "
        "honest errors); coverage: the fraction of twins whose reported error covers the "
        f"injected depth (68 % and 95 % for honest errors); recommended in: how often each "
        f"method would be recommended over {RECOMMEND_DRAWS} bootstrap resamples of the twins"
        + (f" (none: {100 * none:.0f} %)" if none is not None else "")
        + f". Twins: motion within an exposure {tw.get('motion_rms_px', float('nan')):.3f} px "
        f"rms, the simulator's jitter with a peak of {tw.get('motion_peak_px', float('nan')):.3f}"
        f" px per 131-s block ({esc(_noise_pixels_text(tw))}); gain: "
        f"{esc(str(tw.get('gain_model')))}.</p>")
    parts.append(_provenance_html(summary))
    if any("t_rmse_s" in s for s in summary.get("methods", {}).values()):
        parts += [f"<h2>The {esc(_event(summary))} time</h2><p>Over the twins whose fit freed "
                  "it, in seconds against the injected time: the bias, scatter and coverage, "
                  "and an honest error on the real time (its reported error times max(1, "
                  "z_rms)).</p>", _table_html(summary, TIME_COLUMNS)]
    phase = phase_rows(summary)
    if phase:
        parts.append("<h2>The phase curve</h2><p>The twins' phase-curve semi-amplitude and peak "
                     "(hotspot) offset, east positive, of their harmonic fits against the "
                     "injected ones (harmonic_summary of the real fit's harmonics): bias, "
                     "scatter, coverage, and an honest error on the real value (its reported "
                     "error times max(1, z_rms); none where the fits give no error).</p>")
    for name, unit, rows in phase:
        chosen = [i for i, r in enumerate(rows) if r[0] == summary.get("recommended")]
        parts += [f"<h3>{esc(name.replace('_', ' '))} (injected "
                  f"{summary[f'twin_{name}_{unit}']:.1f} {esc(unit)})</h3>",
                  html_table([["method", *(f"{h} ({u})" if u else h for h, u in
                                           zip(PHASE_HEAD, phase_units(unit), strict=True))],
                              *rows], chosen=chosen)]
    like = summary.get("resemblance") or {}
    if like.get("real"):
        parts += ["<h2>The real observation and twin 1</h2>", html_table(
            [["good frames", "real", "twin 1"],
             *([k, f"{v:.4g}", f"{like['twin_001'][k]:.4g}"] for k, v in like["real"].items())])]
    parts.append("<h2>Figures</h2>")
    parts += [figure_html(name, caption, files, root) for name, caption, files in figures]
    return parts


def write_page(dest: str | Path, summary: Mapping[str, Any], *, twins: Mapping[str, tuple],
               curves: Mapping[str, Mapping[str, np.ndarray]], real_table: Table,
               twin_table: Table, command: str | None = None) -> Path:
    """Write the figures (PNG and PDF) and ``index.html`` of a trust answer into ``dest``.

    Parameters
    ----------
    dest : path
        The page's folder (created).
    summary : mapping
        The answer (``trust.json``'s content).
    twins : mapping
        ``{method: (depths, errors, ...)}`` of the twins (:func:`load_twins`).
    curves : mapping
        ``{method: {"hours", "flux_corrected", "astro_model"}}``: the real light curves.
    real_table, twin_table : Table
        The real photometry table and twin 1's.
    command : str, optional
        The command line (or API call) that made the answer, shown on the page.

    Returns
    -------
    Path
        ``dest/index.html``.
    """
    from ..io.atomic import write_text

    root = page_folder(dest)
    items: list[tuple[str, str, list[Path]]] = []
    event = (summary.get("twins") or {}).get("event", "eclipse")
    if curves:
        items.append(("lightcurves", f"The real observation decorrelated by each method, binned, "
                      f"with the method's fitted {event} model (red); the recommended method "
                      "framed. Time in hours from the twins' mid-event time.",
                      F.save_figure(real_lightcurves_figure(summary, curves),
                                    root / "lightcurves")))
    if summary.get("methods"):
        items.append(("depths", "Each twin's depth per method (blue) against the depth injected "
                      "into them (black); red: the real depth with its reported (bar) and honest "
                      "(band) error; shaded: the recommended method.",
                      F.save_figure(twin_depths_figure(summary, {m: t[0] for m, t in
                                                                 twins.items()}),
                                    root / "depths")))
        items.append(("z_scores", "Each method's twins' (D - injected) / reported error, all "
                      "methods pooled then per method, every panel on the same scales; an honest "
                      "error gives the unit Gaussian (black) and rms 1.",
                      F.save_figure(z_score_figure(summary, twins), root / "z_scores")))
    items.append(("twin", "The real observation (black) beside twin 1 (blue): raw flux, "
                  "centroids and noise pixels, so a reader can see the twin is faithful.",
                  F.save_figure(resemblance_figure(summary, real_table, twin_table),
                                root / "twin")))
    title = f"How far to trust the depth of {summary.get('system')}"
    return write_text(root / "index.html", page_html(title, _body(summary, items, root,
                                                                  command)))


def write_page_of_folder(folder: str | Path, dest: str | Path | None = None, *,
                         command: str | None = None) -> Path:
    """Draw the page of an existing trust folder again (into ``dest``, default its
    ``report/``) from its ``trust.json``, real light curves, twins and tables."""
    layout = TrustLayout(Path(folder))
    summary = json.loads(layout.result.read_text())
    return write_page(layout.report.parent if dest is None else dest, summary,
                      twins=load_twins(layout.root, summary),
                      curves=real_curves(layout, summary),
                      real_table=read_table(summary["table"]),
                      twin_table=read_table(layout.twin(1)), command=command)
