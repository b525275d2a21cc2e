"""Assemble the report folder: tables, figures (PNG + PDF) and ``index.html``.

:func:`build_report` takes arrays and tables (never stage folders) and a
destination, so the runner, a notebook or a test can call it alike. Figures
whose inputs are absent (no photometry, no truth, no photon limit) are
skipped and the page says so.
"""

from __future__ import annotations

import html
import json
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from ..io.atomic import write_text
from ..stats.compare import group_by_method
from ..stats.ensemble import normalised_residuals
from . import figures as F
from .page import figure_html, html_table, notes_html, page_folder, page_html, relative
from .paper_tables import COMPARED_KEYS, TABLE4, comparison_rows
from .tables import anova_lines, display_rows, write_tables

__all__ = ["build_report", "draw_planned", "plan_photometry_figures", "plan_result_figures",
           "render_index", "result_figures", "with_units"]

#: Centroids drawn over all epochs (4000 per epoch for ten; a PDF of 400,000 is 8 MB).
CENTROID_POINTS = 40_000


def build_report(dest: str | Path, *, summary: Mapping, depths, truth_ppm: float | None = None,
                 photometry: Mapping[object, Mapping[str, np.ndarray]] | None = None,
                 lightcurves: Mapping[str, Mapping[str, np.ndarray]] | None = None,
                 lightcurve_epoch: object | None = None,
                 truth_curve: tuple[np.ndarray, np.ndarray] | None = None,
                 gain_map: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
                 title: str = "eclipsebench report", notes: Mapping[str, object] | None = None,
                 profile: str | None = None,
                 drawn: tuple[list[Item], list[str]] | None = None) -> Path:
    """Write the whole report to ``dest`` and return the path of ``index.html``.

    Parameters
    ----------
    dest : path
        The report folder (created).
    summary : mapping
        The statistics dict (:func:`eclipsebench.stats.summary.summarize`).
    depths : astropy Table or mapping of columns
        ``method``, ``epoch``, ``depth_ppm``, ``error_ppm``.
    truth_ppm : float, optional
        The input depth (simulations).
    photometry : mapping, optional
        ``{epoch: {"phase", "x", "y", "noise_pixels", "background", "flux"}}``
        for the centroid and photometry figures.
    lightcurves : mapping, optional
        ``{method: {"phase", "flux_corrected", "astro_model"}}`` of one epoch.
    lightcurve_epoch : optional
        Which epoch ``lightcurves`` shows (for the caption).
    truth_curve : tuple, optional
        ``(phase, L)`` of the input light curve of that epoch.
    gain_map : tuple, optional
        ``(x, y, gain)`` behind the centroid clouds.
    title : str
        Page title.
    notes : mapping, optional
        Extra ``name: value`` lines shown at the top of the page (seed, photon
        limits, wall time...).
    profile : str, optional
        The profile whose depths and statistics the figures show, named in
        each figure's title (default: ``summary["profile"]``).
    drawn : tuple, optional
        ``(figures, not drawn)`` already written into ``dest`` (a run draws its figures in
        tasks of their own, :func:`draw_planned`): the page shows them and draws none.

    Returns
    -------
    Path
        ``dest/index.html``.
    """
    root = page_folder(dest)
    table_files = []
    for name, stats in (summary.get("profiles") or {"controlled": summary}).items():
        stem = "eclipse_depth_stats" + ("" if name == "controlled" else f"_{name}")
        table_files += write_tables(stats, root, stem=stem, caption=f"{title} ({name} profile)")
    profile = profile or summary.get("profile") or "controlled"
    if drawn is None:
        planned, skipped = plan_photometry_figures(photometry, gain_map)
        more, not_drawn = plan_result_figures(
            summary, group_by_method(depths, list(summary["methods"])), profile,
            truth_ppm=truth_ppm, lightcurves=lightcurves, lightcurve_epoch=lightcurve_epoch,
            truth_curve=truth_curve)
        drawn = draw_planned(root, planned + more), skipped + not_drawn
    summary_path = write_text(root / "statistics.json",
                              json.dumps(_plain(summary), indent=2, sort_keys=True) + "\n")
    page = render_index(title=title, summary=summary, figures=drawn[0],
                        tables=[*table_files, summary_path], skipped=drawn[1],
                        root=root, notes=notes or {}, profile=profile)
    return write_text(root / "index.html", page)


#: A figure of the report: file stem, caption, files written.
Item = tuple[str, str, list[Path]]
#: A figure to draw: file stem, caption and the call that draws it.
Planned = tuple[str, str, Callable[[], Any]]


def draw_planned(root: Path, planned: list[Planned]) -> list[Item]:
    """Draw and save (PNG and PDF) each planned figure into ``root``, in order."""
    return [(name, caption, F.save_figure(draw(), root / name)) for name, caption, draw in planned]


def plan_photometry_figures(photometry, gain_map) -> tuple[list[Planned], list[str]]:
    """Centroids and photometry against phase: one photometry for every profile."""
    if not photometry:
        return [], ["centroid clouds and photometry vs phase (no photometry given)"]
    every = " (photometry: the same for every profile)"
    return [
        ("centroids", "Centroid positions per epoch (center of light)"
         + (" over the intra-pixel gain map." if gain_map is not None else "."),
         lambda: F.centroid_clouds({e: (p["x"], p["y"]) for e, p in photometry.items()},
                                   gain_map=gain_map, title="Centroids" + every,
                                   max_points=max(400, CENTROID_POINTS // len(photometry)))),
        ("photometry_phase", "x and y centroids, noise pixels, background and aperture flux "
         "(normalised to the mean of all epochs) against orbital phase, binned 63 frames.",
         lambda: F.photometry_vs_phase(photometry, title="Photometry vs phase" + every)),
    ], []


def result_figures(root: Path, summary: Mapping, groups: Mapping, profile: str, *,
                   truth_ppm, lightcurves, lightcurve_epoch, truth_curve
                   ) -> tuple[list[Item], list[str]]:
    """Draw the figures of one profile's depths and statistics (:func:`plan_result_figures`)
    into ``root``: ``(figures, not drawn)``."""
    planned, skipped = plan_result_figures(summary, groups, profile, truth_ppm=truth_ppm,
                                           lightcurves=lightcurves,
                                           lightcurve_epoch=lightcurve_epoch,
                                           truth_curve=truth_curve)
    return draw_planned(root, planned), skipped


def plan_result_figures(summary: Mapping, groups: Mapping, profile: str, *,
                        truth_ppm, lightcurves, lightcurve_epoch, truth_curve
                        ) -> tuple[list[Planned], list[str]]:
    """The figures of one profile's depths and statistics, each titled with the profile,
    planned (not drawn), and what cannot be drawn."""
    items: list[Planned] = []
    skipped: list[str] = []
    sigma_phot = summary.get("sigma_phot_ppm")

    def named(text: str) -> str:
        return f"{text} ({profile} profile)"

    def add(name: str, caption: str, draw: Callable[[], Any]) -> None:
        items.append((name, caption, draw))

    if lightcurves:
        add("lightcurves", f"Decorrelated light curves of epoch {lightcurve_epoch}, each binned "
            f"to about {F.LIGHTCURVE_POINTS} points (a method fitted on bins, as GP, has fewer "
            "rows, binned less); red: the fitted model"
            + ("; blue: the input light curve." if truth_curve is not None else "."),
            lambda: F.decorrelated_lightcurves(lightcurves, truth=truth_curve,
                                               title=named("Decorrelated light curves")))
    else:
        skipped.append("decorrelated light curves (none given)")
    add("depths", "Eclipse depths per epoch and method (reported 1-sigma errors); right: weighted "
        "means with sigma_tot = f_dis sigma_orig; red: grand mean +- its error"
        + ("; blue: the input depth." if truth_ppm is not None else "."),
        lambda: F.depths_per_epoch({m: (g.epoch, g.depth_ppm, g.error_ppm)
                                    for m, g in groups.items()},
                                   summary, truth_ppm=truth_ppm, title=named("Eclipse depths")))
    add("visit_differences", "Mean/difference plots between visits: every ordered pair of epochs; "
        "dashed: +-R (the repeatability).",
        lambda: F.visit_differences({m: (g.epoch, g.depth_ppm) for m, g in groups.items()},
                                    summary, title=named("Repeated visits: mean/difference")))
    if len(groups) >= 2:
        add("method_differences", "Mean/difference plots between methods per common epoch; dashed: "
            "mean difference +- SD; corner: unpaired t-test p (red if < 0.05).",
            lambda: F.method_differences({m: (g.epoch, g.depth_ppm) for m, g in groups.items()},
                                         summary["ttest"]["p"],
                                         title=named("Methods: mean/difference")))
    else:
        skipped.append("method differences (one method)")
    if sigma_phot is not None:
        add("repeatability_reliability", "Repeatability R against reliability r; solid: "
            "R = sqrt(2) sigma_phot / r; dashed: least-squares fit R = k / r.",
            lambda: F.repeatability_vs_reliability(summary, sigma_phot,
                                                   title=named("Repeatability vs reliability")))
        if truth_ppm is not None:
            add("accuracy_reliability", "Accuracy a against reliability r; dotted: a = r; dashed: "
                "linear fit.", lambda: F.accuracy_vs_reliability(
                    summary, title=named("Accuracy vs reliability")))
            add("accuracy_ratio_bias", "a / r against the mean absolute bias; dashed: linear fit.",
                lambda: F.accuracy_ratio_vs_bias(summary, title=named("a/r vs |bias|")))
        else:
            skipped.append("accuracy figures (no truth)")
    else:
        skipped.append("repeatability/reliability and accuracy figures (no photon limit)")
    if truth_ppm is not None:
        add("coverage", "Fraction of epochs whose reported 1-sigma (blue) and 2-sigma (red) errors "
            "cover the input depth; error bars: the exact binomial 68% interval of that "
            "fraction; dashed: 68.3% and 95.4%, the coverage of honest Gaussian errors.",
            lambda: F.coverage_per_method(summary, title=named("Coverage of the truth")))
        add("normalised_residuals", "Normalised residuals (D - truth) / sigma per epoch with the "
            "reported sigma: all methods pooled, then per method, against the unit Gaussian "
            "(black); values beyond +-4 are counted in the outer bins.",
            lambda: F.normalised_residual_histograms(
                {m: normalised_residuals(g.depth_ppm, g.error_ppm, truth_ppm)
                 for m, g in groups.items()},
                title=named("Normalised residuals (D - truth) / sigma")))
    else:
        skipped.append("coverage and normalised residuals (no truth)")
    return items, skipped


def _plain(obj):
    if isinstance(obj, Mapping):
        return {str(k): _plain(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_plain(v) for v in obj]
    if isinstance(obj, (np.floating, float)):
        return float(obj) if np.isfinite(obj) else None
    if isinstance(obj, np.integer):
        return int(obj)
    return obj


_PROFILE_WORDS = {
    "controlled": "Every method with the same astrophysical model, centroid, aperture and error "
                  "rule: the differences are the methods' own.",
    "paper": "Each method as its team ran it for the 2015 challenge (paper, Appendix B): its "
             "centroid, phase model, sampler and reported error (docs/methods.md).",
}


#: The table's symbols: (heading, unit, meaning), in the order of its columns (docs/scoring.md).
SYMBOLS = (
    ("D_mean", "ppm", "inverse-variance weighted mean depth over the epochs (Eq. weighted_mean)"),
    ("sigma_mean", "ppm", "mean of the reported 1-sigma errors"),
    ("SD", "ppm", "sample standard deviation of the depths (N - 1)"),
    ("sigma_orig", "ppm", "error of D_mean from the reported errors, 1 / sqrt(sum 1/sigma_i^2)"),
    ("f_dis", "", "dispersion factor max(1, sqrt(chi^2 / (N - 1))): how much the depths scatter "
                  "beyond their errors; +up/-down: its 68% interval, shown when above 1 "
                  "(Section 3.2)"),
    ("sigma_tot", "ppm", "f_dis sigma_orig: the error of D_mean"),
    ("R", "ppm", "repeatability: SD of the differences between every ordered pair of epochs "
                 "(Section 3.4.1)"),
    ("r", "", "reliability sigma_phot / SD: 1 when the depths scatter as photon noise alone "
              "(Section 3.4.2)"),
    ("Closest match", "ppm", "the other method whose per-epoch differences from this one are "
                             "smallest: its name, (mean +- SD of the differences)"),
    ("RMSE", "ppm", "root-mean-square of depth - true depth"),
    ("bias", "ppm", "mean of (depth - true depth), the plain mean (Section 3.4.3)"),
    ("a", "", "accuracy sigma_phot / RMSE (Section 3.4.3)"),
    ("sigma_phot", "ppm", "photon-noise limit of one epoch's depth (the notes at the top say "
                          "which)"),
)
_UNITS = {name: unit for name, unit, _ in SYMBOLS}


def _symbols_html() -> str:
    """The legend of the table's symbols with their units."""
    esc = html.escape
    rows = "".join(f"<tr><td>{esc(n)}</td><td>{esc(u or '-')}</td><td>{esc(m)}</td></tr>"
                   for n, u, m in SYMBOLS)
    return ("<p>Symbols (every depth-like column in ppm; r, a and f_dis are ratios):</p>"
            '<table class="symbols"><thead><tr><th>symbol</th><th>unit</th><th>meaning</th>'
            f"</tr></thead><tbody>{rows}</tbody></table>")


def with_units(head: list[str]) -> list[str]:
    """Table headings with their unit: ``D_mean (ppm)``."""
    units = [_UNITS.get(h, _UNITS.get(h.split(" ")[0], "")) for h in head]
    return [f"{h} ({u})" if u else h for h, u in zip(head, units, strict=True)]


def render_index(*, title: str, summary: Mapping, figures: list[tuple[str, str, list[Path]]],
                 tables: list[Path], skipped: list[str], root: Path,
                 notes: Mapping[str, object], profile: str | None = None) -> str:
    """The HTML page: the statistics table, links to the table files, every figure.

    Built from :mod:`eclipsebench.report.page` (all links relative to
    ``root``, no scripts, no external resources). ``profile`` is the profile
    the figures show (named in the Figures heading).
    """
    esc = html.escape
    parts = [notes_html(notes)] if notes else []
    profiles = summary.get("profiles") or {summary.get("profile", "controlled"): summary}
    for name, stats in profiles.items():
        rows = display_rows(stats, pm=" ± ", minus="−", interval="{f} +{up}/−{down}")
        parts += [f"<h2>Eclipse depth statistics: {esc(name)} profile</h2>",
                  f"<p>{esc(_PROFILE_WORDS.get(name, ''))}</p>",
                  html_table([with_units(rows[0]), *rows[1:]])]
        if name == next(iter(profiles)):
            parts.append(_symbols_html())
        parts += [f"<p>{esc(line)}</p>" for line in anova_lines(stats)]
        if summary.get("truth_ppm") is not None:
            rows = comparison_rows(stats, TABLE4)
            head = ["method", "paper"] + [f"{k} {w}" for k in COMPARED_KEYS
                                          for w in ("ours", "Table 4")]
            parts += [f"<p>The {esc(name)} profile beside the paper's Table 4 (the simulated "
                      "2015 challenge; for comparison only).</p>", html_table([head, *rows])]
    parts.append("<p>Tables: " + ", ".join(f'<a href="{esc(relative(p, root))}">{esc(p.name)}</a>'
                                            for p in tables) + "</p>")
    parts.append("<h2>Figures" + (f" ({esc(profile)} profile)" if profile else "") + "</h2>")
    parts += [figure_html(name, caption, files, root) for name, caption, files in figures]
    if skipped:
        parts.append("<p>Not drawn: " + "; ".join(esc(s) for s in skipped) + ".</p>")
    return page_html(title, parts)
