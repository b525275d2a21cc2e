"""The report reads at 1400 px (issue 29): profile in every title, a symbol legend with units,
no overlapping text in the scatter plots, no figure wider than the page, light curves binned
alike, the photon limit explained."""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np
import pytest
from astropy.table import Table
from matplotlib.text import Text

from eclipsebench.report import figures as F
from eclipsebench.report.build import SYMBOLS, build_report
from eclipsebench.report.challenge import _analytic_note
from eclipsebench.stats.summary import summarize

#: The twelve built-in methods: their r cluster, as in a real run.
METHODS = ("bliss", "gp", "ica", "kr-data", "kr-pmap", "pld", "pld-aper", "poly2", "poly3",
           "poly4", "poly5", "segpoly")
TRUTH = 1875.0


def depth_table(n_epochs=4):
    rng = np.random.default_rng(11)
    rows = [(m, e, TRUTH - 40 + rng.normal(0, 60 + 2 * k), 70.0)
            for k, m in enumerate(METHODS) for e in range(1, n_epochs + 1)]
    return Table(rows=rows, names=["method", "epoch", "depth_ppm", "error_ppm"])


@pytest.fixture(scope="module")
def summary():
    return summarize(depth_table(), sigma_phot_ppm=66.0, truth_ppm=TRUTH, n_bootstrap=0)


def _texts(fig):
    """The visible texts of a drawn figure but its tick labels, with their boxes in pixels.

    (Tick labels are matplotlib's to place; at the corner of two axes they may touch.)
    """
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    ticks = {id(t) for ax in fig.axes for t in (*ax.get_xticklabels(), *ax.get_yticklabels())}
    return [(t.get_text(), t.get_window_extent(renderer)) for t in fig.findobj(Text)
            if t.get_visible() and t.get_text().strip() and id(t) not in ticks]


def _overlaps(fig) -> list[tuple[str, str]]:
    return [(a, b) for (a, box_a), (b, box_b) in itertools.combinations(_texts(fig), 2)
            if box_a.overlaps(box_b)]


@pytest.mark.parametrize("draw", [
    lambda s: F.repeatability_vs_reliability(s, 66.0),
    F.accuracy_vs_reliability,
    F.accuracy_ratio_vs_bias,
])
def test_scatter_plots_of_twelve_methods_have_no_overlapping_text(summary, draw):
    fig = draw(summary)
    assert _overlaps(fig) == []
    names = [t for t, _ in _texts(fig)]
    assert all(any(n.startswith(m + ":") for n in names) for m in METHODS)  # the key names each


def test_the_old_labels_beside_the_points_did_overlap(summary):
    """The check above can fail: names written at clustered points collide."""
    fig = F.repeatability_vs_reliability(summary, 66.0)
    ax = fig.axes[0]
    for line in ax.get_lines()[:len(METHODS)]:
        x, y = line.get_data()
        ax.annotate(line.get_label().split(":")[0], (x[0], y[0]), fontsize=7, xytext=(3, 3),
                    textcoords="offset points")
    assert _overlaps(fig)


def test_depth_legend_is_beside_the_axes(summary):
    t = depth_table()
    groups = {m: (t["epoch"][t["method"] == m], t["depth_ppm"][t["method"] == m],
                  t["error_ppm"][t["method"] == m]) for m in METHODS}
    fig = F.depths_per_epoch(groups, summary, truth_ppm=TRUTH)
    fig.canvas.draw()
    (legend,) = fig.legends
    renderer = fig.canvas.get_renderer()
    assert not legend.get_window_extent(renderer).overlaps(fig.axes[0].get_window_extent(renderer))


def test_sixty_six_method_pairs_fit_the_page_width(summary):
    t = depth_table()
    groups = {m: (t["epoch"][t["method"] == m], t["depth_ppm"][t["method"] == m])
              for m in METHODS}
    fig = F.method_differences(groups, summary["ttest"]["p"])
    assert len([ax for ax in fig.axes if ax.get_visible()]) == 66
    assert fig.get_size_inches()[0] <= F.PAGE_WIDTH_IN + 1e-9
    assert F.visit_differences(groups, summary).get_size_inches()[0] <= F.PAGE_WIDTH_IN + 1e-9


def test_light_curves_of_frames_and_of_bins_are_binned_to_as_many_points():
    curves = {}
    for name, n in (("bliss", 14_600), ("gp", 1_005)):
        phase = np.linspace(-0.39, -0.27, n)
        curves[name] = {"phase": phase, "flux_corrected": np.ones(n), "astro_model": np.ones(n)}
    fig = F.decorrelated_lightcurves(curves)
    points = [len(ax.get_lines()[0].get_xdata()) for ax in fig.axes]
    assert all(abs(p - F.LIGHTCURVE_POINTS) <= 10 for p in points), points


def test_the_page_names_the_figures_profile_and_explains_the_symbols(summary, tmp_path):
    # the page's text alone: no figure drawn (test_report_build draws them)
    index = build_report(tmp_path, summary=summary, depths=depth_table(), truth_ppm=TRUTH,
                         profile="paper", drawn=([], []))
    text = index.read_text()
    assert "<h2>Figures (paper profile)</h2>" in text
    assert "D_mean (ppm)" in text and "R (ppm)" in text and "sigma_orig (ppm)" in text
    for symbol, unit, _ in SYMBOLS:
        assert f"<td>{symbol}</td><td>{unit or '-'}</td>" in text


def test_figure_titles_carry_the_profile(summary, tmp_path, monkeypatch):
    titles = []
    def spy(fig, stem, **kwargs):
        titles.append(" ".join(t.get_text() for t in fig.findobj(Text)
                               if t.get_text().startswith(("Eclipse", "Repeat", "Accuracy",
                                                           "a/r", "Coverage", "Normalised",
                                                           "Methods", "Decorrelated"))))
        return [Path(stem).with_suffix(".png")]   # the titles are drawn; no file is needed

    monkeypatch.setattr(F, "save_figure", spy)
    build_report(tmp_path, summary=summary, depths=depth_table(), truth_ppm=TRUTH)
    assert len(titles) == 8
    assert all("(controlled profile)" in t for t in titles), titles


def test_the_analytic_photon_limit_says_why_it_is_not_the_readmes():
    summary = {"sigma_phot_ppm_analytic": 70.85,
               "photon_limit": {"analytic": {"snr_single": 254.2, "frames": 15357.0,
                                             "f_in": 0.2794, "depth_ppm": 1875.0}}}
    note = _analytic_note(summary)
    assert note.startswith("70.8 ppm")
    assert "64.5 ppm" in note and "S/N 254" in note and "f_in = 0.279" in note
    assert _analytic_note({"sigma_phot_ppm_analytic": None}) == "n/a"
