"""A campaign's report (issue 38): ``DIR/report/index.html`` of many real observations.

:func:`build_campaign_report` takes the campaign's summary (``summary.json``), each
epoch's decorrelated light curves and, where twins ran, each epoch's trust answer, and
writes the page with :mod:`eclipsebench.report.page` and the run report's figures
(:func:`eclipsebench.report.build.result_figures`: the paper's Figures 7 (depths per
epoch per method with the weighted means), 10 and 12 (mean/difference between epochs
and between methods) and 14 (R against r with the photon limit, where the photometry
gives one)), per profile and channel; each epoch's light curves with
:func:`eclipsebench.report.figures.decorrelated_lightcurves`, in hours from the
event. Figures are object-oriented matplotlib on their own canvas: building the page
sets no backend and imports no pyplot.
"""

from __future__ import annotations

import html
import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from astropy.table import Table

from ..io.atomic import write_text
from ..stats.compare import group_by_method
from . import figures as F
from .build import result_figures, with_units
from .page import figure_html, html_table, notes_html, page_folder, page_html
from .tables import anova_lines, display_rows

__all__ = ["build_campaign_report", "draw_epoch_lightcurves", "trust_rows", "TRUST_COLUMNS"]

#: An epoch's trust table: ``(trust.json key, heading)``, depths and errors in ppm.
TRUST_COLUMNS = (("depth_ppm", "depth (ppm)"), ("honest_err_ppm", "honest err (ppm)"),
                 ("depth_err_ppm", "reported err (ppm)"), ("bias_ppm", "twin bias (ppm)"),
                 ("rmse_ppm", "twin RMSE (ppm)"), ("z_rms", "z_rms"),
                 ("coverage_1sigma", "1-sigma coverage"))


def _cell(value: Any) -> str:
    if isinstance(value, bool) or value is None:
        return "n/a" if value is None else str(value)
    if isinstance(value, (int, float)):
        return "n/a" if not np.isfinite(value) else (f"{value:.2f}" if abs(value) < 10
                                                    else f"{value:.1f}")
    return str(value)


def trust_rows(answer: Mapping[str, Any]) -> tuple[list[list[str]], list[int]]:
    """An epoch's trust answer (``trust.json``) as table rows (headings first) and the
    index of the recommended method's row (highlighted), if any.

    Examples
    --------
    >>> rows, chosen = trust_rows({"recommended": "b", "methods": {
    ...     "a": {"depth_ppm": 1800.0, "honest_err_ppm": 90.0},
    ...     "b": {"depth_ppm": 1850.0, "honest_err_ppm": 70.0}}})
    >>> rows[2][:3], chosen
    (['b (recommended)', '1850.0', '70.0'], [1])
    """
    best = answer.get("recommended")
    rows = [["method", *(h for _, h in TRUST_COLUMNS)]]
    chosen = []
    for k, (m, s) in enumerate(sorted((answer.get("methods") or {}).items())):
        rows.append([m + (" (recommended)" if m == best else ""),
                     *(_cell(s.get(key)) for key, _ in TRUST_COLUMNS)])
        if m == best:
            chosen.append(k)
    return rows, chosen


def _group_figures(root: Path, profile: str, group: str, entry: Mapping[str, Any]
                   ) -> tuple[list[tuple[str, str, list[Path]]], list[str]]:
    """The run report's figures of one profile and channel, in their own folder."""
    if not entry.get("methods"):
        return [], [f"{group}, {profile}: no method has depths in 2 or more epochs"]
    depths = Table(rows=[(d["method"], d["epoch"], d["depth_ppm"], d["error_ppm"])
                         for d in entry["depths"]],
                   names=("method", "epoch", "depth_ppm", "error_ppm"))
    pl = entry.get("photon_limit") or {}
    stats = {**entry, "sigma_phot_ppm": pl.get("sigma_phot_ppm")}
    names = list(entry["methods"])
    depths = depths[np.isin(np.asarray(depths["method"]), names)]
    folder = root / f"{profile}_{group}"
    folder.mkdir(parents=True, exist_ok=True)
    items, skipped = result_figures(folder, stats, group_by_method(depths, names),
                                    f"{group}, {profile}", truth_ppm=None, lightcurves=None,
                                    lightcurve_epoch=None, truth_curve=None)
    skipped = [s for s in skipped if not s.startswith("decorrelated light curves")
               and not s.startswith("coverage and") and not s.startswith("accuracy figures")]
    return ([(f"{profile}_{group}_{n}", c, f) for n, c, f in items],
            [f"{group}, {profile}: {s}" for s in skipped])


def _stats_html(title: str, entry: Mapping[str, Any]) -> list[str]:
    rows = display_rows(dict(entry), pm=" ± ", minus="−", interval="{f} +{up}/−{down}")
    parts = [f"<h3>{html.escape(title)}</h3>", html_table([with_units(rows[0]), *rows[1:]])]
    parts += [f"<p>{html.escape(line)}</p>" for line in anova_lines(dict(entry))]
    combined = entry.get("combined")
    if combined:
        parts.append("<p>" + html.escape(
            f"Combined over methods: {combined['depth_ppm']:.1f} ± {combined['error_ppm']:.1f} "
            f"ppm (statistical {combined['sigma_stat_ppm']:.1f}, the methods' spread "
            f"{combined['sigma_sys_ppm']:.1f}; {combined['formula']})") + "</p>")
    return parts


def draw_epoch_lightcurves(root: Path, epoch: int,
                           curves: Mapping[str, Mapping[str, np.ndarray]], since: str
                           ) -> list[Path]:
    """Epoch ``epoch``'s decorrelated light curves (``{method: {"hours", "flux_corrected",
    "astro_model"}}``) as ``root/lightcurves/lightcurves_epoch_NN.{png,pdf}``, the hours
    counted from ``since``; no curves: nothing drawn (an empty list)."""
    if not curves:
        return []
    fig = F.decorrelated_lightcurves(curves, x="hours", xlabel=f"hours from {since}",
                                     title=f"Epoch {epoch}: decorrelated light curves")
    return F.save_figure(fig, Path(root) / "lightcurves" / f"lightcurves_epoch_{epoch:02d}")


def build_campaign_report(dest: str | os.PathLike[str], *, summary: Mapping[str, Any],
                          lightcurves: Mapping[int, Mapping[str, Mapping[str, np.ndarray]]],
                          event_names: Mapping[int, str] | None = None,
                          trust: Mapping[int, tuple[Mapping[str, Any], Path | None]]
                          | None = None,
                          notes: Mapping[str, object] | None = None,
                          drawn: Mapping[int, Sequence[Path]] | None = None) -> Path:
    """Write a campaign's report into ``dest`` and return the path of ``index.html``.

    Parameters
    ----------
    dest : path
        The report folder (created); ``index.html`` is written last.
    summary : mapping
        The campaign's ``summary.json``: ``profiles.<profile>.channels.<group>`` with
        ``methods``, ``depths``, ``ttest``, ``anova``, ``photon_limit``, ``combined``
        and, where twins ran, ``honest``; ``joint``; ``planet``.
    lightcurves : mapping
        ``{epoch: {method: {"hours", "flux_corrected", "astro_model"}}}``: each epoch's
        decorrelated light curves (``RESULT.lc.ecsv``), time in hours from the event.
    event_names : mapping, optional
        ``{epoch: what "hours" counts from}`` (default "mid-eclipse").
    trust : mapping, optional
        ``{epoch: (trust answer, path of that trust run's page or None)}`` where twins ran.
    notes : mapping, optional
        ``name: value`` lines at the top (seed, version, command line...).
    drawn : mapping, optional
        ``{epoch: files}`` of light-curve figures already drawn into ``dest``
        (:func:`draw_epoch_lightcurves`, by a campaign's task per epoch while other
        tasks ran; no files: none drawn); they are linked, not drawn again.

    Returns
    -------
    Path
        ``dest/index.html``.
    """
    root = page_folder(dest)
    esc = html.escape
    parts: list[str] = [notes_html(notes)] if notes else []
    figures: list[tuple[str, str, list[Path]]] = []
    skipped: list[str] = []
    for profile, p in (summary.get("profiles") or {}).items():
        for group, entry in (p.get("channels") or {}).items():
            if entry.get("methods"):
                parts += _stats_html(f"Eclipse depth statistics, {group}, {profile} profile "
                                     "(reported errors)", entry)
                if entry.get("honest", {}).get("methods"):
                    parts += _stats_html(f"The same with the twins' honest errors ({group}, "
                                         f"{profile} profile)", entry["honest"])
            items, more = _group_figures(root, profile, group, entry)
            figures += items
            skipped += more
    joint = summary.get("joint") or {}
    rows = [["channel", "method", "joint depth (ppm)", "error (ppm)"]]
    rows += [[g, m, _cell(j.get("depth_ppm")), _cell(j.get("depth_err_ppm"))]
             for g, by_m in joint.items() for m, j in by_m.items()]
    if len(rows) > 1:
        parts += ["<h3>Joint fits: one depth over every epoch of a channel</h3>",
                  html_table(rows)]
    parts.append("<h2>Figures</h2>")
    parts += [figure_html(n, c, f, root) for n, c, f in figures]
    parts.append("<h2>Each epoch's decorrelated light curves</h2>")
    for epoch in sorted(set(lightcurves) | set(drawn or {})):
        if drawn and epoch in drawn:
            files = list(drawn[epoch])
        else:
            files = draw_epoch_lightcurves(root, epoch, lightcurves[epoch],
                                           (event_names or {}).get(epoch, "mid-eclipse"))
        if not files:
            skipped.append(f"epoch {epoch}'s light curves (no method reduced it)")
            continue
        parts.append(figure_html(f"lightcurves_epoch_{epoch:02d}",
                                 f"Epoch {epoch}: each method's decorrelated flux, binned "
                                 f"to about {F.LIGHTCURVE_POINTS} points; red: its fitted "
                                 "model.", files, root))
    if trust:
        parts.append("<h2>Each epoch's digital twins (trust)</h2>")
        for epoch in sorted(trust):
            answer, page = trust[epoch]
            rows, chosen = trust_rows(answer)
            link = (f' (<a href="{esc(Path(os.path.relpath(page, root)).as_posix())}">its '
                    "trust page</a>)" if page is not None else "")
            parts += [f"<h3>Epoch {epoch}: {answer.get('n_twins')} twins{link}</h3>",
                      html_table(rows, chosen=chosen)]
    if skipped:
        parts.append("<p>Not drawn: " + "; ".join(esc(s) for s in skipped) + ".</p>")
    tables = sorted((root.parent / "tables").glob("table3_*.ecsv"))
    if tables:
        parts.append("<p>Tables: " + ", ".join(
            f'<a href="{esc(Path(os.path.relpath(t, root)).as_posix())}">{esc(t.name)}</a>'
            for t in tables) + "</p>")
    title = f"eclipsebench campaign: {summary.get('planet', '')}"
    return write_text(root / "index.html", page_html(title, parts))
