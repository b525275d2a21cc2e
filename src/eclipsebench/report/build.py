"""Assemble the report folder: tables, figures (PNG + PDF) and ``index.html``.

:func:`build_report` takes arrays and tables (never stage folders) and a
destination, so the runner, a notebook or a test can call it alike. Figures
whose inputs are absent (no photometry, no truth, no photon limit) are
skipped and the page says so.
"""

from __future__ import annotations

import html
import json
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from ..io.atomic import write_text
from ..stats.compare import group_by_method
from ..stats.ensemble import normalised_residuals
from . import figures as F
from .paper_tables import COMPARED_KEYS, TABLE4, comparison_rows
from .tables import anova_lines, display_rows, write_tables

__all__ = ["build_report", "render_index"]

#: Centroids drawn over all epochs (4000 per epoch for ten; a PDF of 400,000 is 8 MB).
CENTROID_POINTS = 40_000


def _rel(path: Path, root: Path) -> str:
    return path.relative_to(root).as_posix()


def build_report(dest: str | Path, *, summary: Mapping, depths, truth_ppm: float | None = None,
                 photometry: Mapping[object, Mapping[str, np.ndarray]] | None = None,
                 lightcurves: Mapping[str, Mapping[str, np.ndarray]] | None = None,
                 lightcurve_epoch: object | None = None,
                 truth_curve: tuple[np.ndarray, np.ndarray] | None = None,
                 gain_map: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
                 title: str = "eclipsebench report", notes: Mapping[str, object] | None = None
                 ) -> Path:
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
    """
    root = Path(dest)
    root.mkdir(parents=True, exist_ok=True)
    groups = group_by_method(depths, list(summary["methods"]))
    table_files = []
    for name, stats in (summary.get("profiles") or {"controlled": summary}).items():
        stem = "eclipse_depth_stats" + ("" if name == "controlled" else f"_{name}")
        table_files += write_tables(stats, root, stem=stem, caption=f"{title} ({name} profile)")
    sigma_phot = summary.get("sigma_phot_ppm")
    items: list[tuple[str, str, list[Path]]] = []
    skipped: list[str] = []

    def add(name: str, caption: str, fig) -> None:
        items.append((name, caption, F.save_figure(fig, root / name)))

    if photometry:
        add("centroids", "Centroid positions per epoch (center of light)"
            + (" over the intra-pixel gain map." if gain_map is not None else "."),
            F.centroid_clouds({e: (p["x"], p["y"]) for e, p in photometry.items()},
                              gain_map=gain_map,
                              max_points=max(400, CENTROID_POINTS // len(photometry))))
        add("photometry_phase", "x and y centroids, noise pixels, background and aperture flux "
            "(normalised to the mean of all epochs) against orbital phase, binned 63 frames.",
            F.photometry_vs_phase(photometry))
    else:
        skipped.append("centroid clouds and photometry vs phase (no photometry given)")
    if lightcurves:
        add("lightcurves", f"Decorrelated light curves of epoch {lightcurve_epoch}, binned 64x; "
            "red: the fitted model" + ("; blue: the input light curve." if truth_curve is not None
                                        else "."),
            F.decorrelated_lightcurves(lightcurves, truth=truth_curve))
    else:
        skipped.append("decorrelated light curves (none given)")
    add("depths", "Eclipse depths per epoch and method (reported 1-sigma errors); right: weighted "
        "means with sigma_tot = f_dis sigma_orig; red: grand mean +- its error"
        + ("; blue: the input depth." if truth_ppm is not None else "."),
        F.depths_per_epoch({m: (g.epoch, g.depth_ppm, g.error_ppm) for m, g in groups.items()},
                           summary, truth_ppm=truth_ppm))
    add("visit_differences", "Mean/difference plots between visits: every ordered pair of epochs; "
        "dashed: +-R (the repeatability).",
        F.visit_differences({m: (g.epoch, g.depth_ppm) for m, g in groups.items()}, summary))
    if len(groups) >= 2:
        add("method_differences", "Mean/difference plots between methods per common epoch; dashed: "
            "mean difference +- SD; corner: unpaired t-test p (red if < 0.05).",
            F.method_differences({m: (g.epoch, g.depth_ppm) for m, g in groups.items()},
                                 summary["ttest"]["p"]))
    else:
        skipped.append("method differences (one method)")
    if sigma_phot is not None:
        add("repeatability_reliability", "Repeatability R against reliability r; solid: "
            "R = sqrt(2) sigma_phot / r; dashed: least-squares fit R = k / r.",
            F.repeatability_vs_reliability(summary, sigma_phot))
        if truth_ppm is not None:
            add("accuracy_reliability", "Accuracy a against reliability r; dotted: a = r; dashed: "
                "linear fit.", F.accuracy_vs_reliability(summary))
            add("accuracy_ratio_bias", "a / r against the mean absolute bias; dashed: linear fit.",
                F.accuracy_ratio_vs_bias(summary))
        else:
            skipped.append("accuracy figures (no truth)")
    else:
        skipped.append("repeatability/reliability and accuracy figures (no photon limit)")
    if truth_ppm is not None:
        add("coverage", "Fraction of epochs whose reported 1-sigma (blue) and 2-sigma (red) errors "
            "cover the input depth, with exact binomial 68% intervals; dashed: 68.3% and 95.4%, "
            "the coverage of honest Gaussian errors.", F.coverage_per_method(summary))
        add("normalised_residuals", "Normalised residuals (D - truth) / sigma per epoch with the "
            "reported sigma: all methods pooled, then per method, against the unit Gaussian "
            "(black); values beyond +-4 are counted in the outer bins.",
            F.normalised_residual_histograms(
                {m: normalised_residuals(g.depth_ppm, g.error_ppm, truth_ppm)
                 for m, g in groups.items()}))
    else:
        skipped.append("coverage and normalised residuals (no truth)")
    summary_path = write_text(root / "statistics.json",
                              json.dumps(_plain(summary), indent=2, sort_keys=True) + "\n")
    page = render_index(title=title, summary=summary, figures=items,
                        tables=[*table_files, summary_path], skipped=skipped, root=root,
                        notes=notes or {})
    return write_text(root / "index.html", page)


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


def _html_table(rows: list[list[str]]) -> str:
    esc = html.escape
    thead = "".join(f"<th>{esc(str(c))}</th>" for c in rows[0])
    tbody = "\n".join("<tr>" + "".join(f"<td>{esc(str(c))}</td>" for c in r) + "</tr>"
                      for r in rows[1:])
    return f"<table><thead><tr>{thead}</tr></thead><tbody>\n{tbody}\n</tbody></table>"


def render_index(*, title: str, summary: Mapping, figures: list[tuple[str, str, list[Path]]],
                 tables: list[Path], skipped: list[str], root: Path,
                 notes: Mapping[str, object]) -> str:
    """The HTML page: the statistics table, links to the table files, every figure.

    All links are relative to ``root`` so the folder can be moved or opened
    offline; no scripts, no external resources.
    """
    esc = html.escape
    parts = [
        "<!DOCTYPE html>", '<html lang="en">', "<head>", '<meta charset="utf-8">',
        f"<title>{esc(title)}</title>",
        "<style>body{font-family:sans-serif;max-width:1100px;margin:auto;padding:1em}"
        "table{border-collapse:collapse;font-size:90%}td,th{border:1px solid #bbb;"
        "padding:2px 6px;text-align:right}td:first-child{text-align:left}"
        "figure{margin:1.5em 0}img{max-width:100%;border:1px solid #ddd}</style>",
        "</head>", "<body>", f"<h1>{esc(title)}</h1>",
    ]
    if notes:
        parts.append("<ul>" + "".join(f"<li><b>{esc(str(k))}</b>: {esc(str(v))}</li>"
                                      for k, v in notes.items()) + "</ul>")
    profiles = summary.get("profiles") or {summary.get("profile", "controlled"): summary}
    for name, stats in profiles.items():
        parts += [f"<h2>Eclipse depth statistics: {esc(name)} profile</h2>",
                  f"<p>{esc(_PROFILE_WORDS.get(name, ''))}</p>",
                  _html_table(display_rows(stats, pm=" ± ", minus="−",
                                           interval="{f} +{up}/−{down}"))]
        parts += [f"<p>{esc(line)}</p>" for line in anova_lines(stats)]
        if summary.get("truth_ppm") is not None:
            rows = comparison_rows(stats, TABLE4)
            head = ["method", "paper"] + [f"{k} {w}" for k in COMPARED_KEYS
                                          for w in ("ours", "Table 4")]
            parts += [f"<p>The {esc(name)} profile beside the paper's Table 4 (the simulated "
                      "2015 challenge; for comparison only).</p>", _html_table([head, *rows])]
    parts.append("<p>Tables: " + ", ".join(f'<a href="{esc(_rel(p, root))}">{esc(p.name)}</a>'
                                            for p in tables) + "</p>")
    parts.append("<h2>Figures</h2>")
    for name, caption, files in figures:
        png = next(p for p in files if p.suffix == ".png")
        pdf = [p for p in files if p.suffix == ".pdf"]
        link = f' (<a href="{esc(_rel(pdf[0], root))}">PDF</a>)' if pdf else ""
        parts.append(f'<figure id="{esc(name)}"><img src="{esc(_rel(png, root))}" '
                     f'alt="{esc(name)}"><figcaption>{esc(caption)}{link}</figcaption></figure>')
    if skipped:
        parts.append("<p>Not drawn: " + "; ".join(esc(s) for s in skipped) + ".</p>")
    parts += ["</body>", "</html>", ""]
    return "\n".join(parts)
