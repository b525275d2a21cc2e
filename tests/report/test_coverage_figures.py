"""The coverage figure and the normalised-residual histograms of the report."""

from __future__ import annotations

import math

import numpy as np
import pytest
from astropy.table import Table

from eclipsebench.report.build import build_report
from eclipsebench.report.figures import coverage_per_method, normalised_residual_histograms
from eclipsebench.report.tables import stats_table
from eclipsebench.stats.ensemble import GAUSS_1SIGMA, GAUSS_2SIGMA
from eclipsebench.stats.summary import summarize

TRUTH = 1875.0


def depth_table(n_epochs=40, scales=(1.0, 2.0)):
    """Two methods with Gaussian residuals; the second's errors are too small by 2x."""
    rng = np.random.default_rng(3)
    rows = []
    for name, scale in zip(("honest", "optimistic"), scales, strict=True):
        for e in range(1, n_epochs + 1):
            rows.append((name, e, TRUTH + scale * 100.0 * rng.standard_normal(), 100.0))
    return Table(rows=rows, names=["method", "epoch", "depth_ppm", "error_ppm"])


@pytest.fixture(scope="module")
def summary():
    return summarize(depth_table(), truth_ppm=TRUTH, n_bootstrap=0)


def test_coverage_figure_draws_each_method_with_its_interval(summary):
    fig = coverage_per_method(summary)
    ax = fig.axes[0]
    assert [t.get_text() for t in ax.get_xticklabels()] == ["honest", "optimistic"]
    levels = sorted(round(line.get_ydata()[0], 4) for line in ax.lines
                    if len(line.get_ydata()) == 2 and line.get_ydata()[0] == line.get_ydata()[1])
    assert levels == [round(GAUSS_1SIGMA, 4), round(GAUSS_2SIGMA, 4)]
    points = {c.get_label(): c for c in ax.containers}
    one = points["within 1 sigma"]
    y = one.lines[0].get_ydata()
    assert y.tolist() == [summary["methods"][m]["coverage"] for m in ("honest", "optimistic")]
    # the error bar spans exactly the summary's interval
    seg = one.lines[2][0].get_segments()[0]
    s = summary["methods"]["honest"]
    assert seg[:, 1].tolist() == pytest.approx([s["coverage_lo"], s["coverage_hi"]])


def test_residual_histograms_are_densities_against_a_unit_gaussian(summary):
    rng = np.random.default_rng(8)
    z = {"a": rng.standard_normal(500), "b": np.array([0.1, -0.2, 9.0])}
    fig = normalised_residual_histograms(z)
    visible = [ax for ax in fig.axes if ax.get_visible()]
    assert [ax.get_title() for ax in visible] == ["all methods", "a", "b"]
    for ax in visible:
        area = sum(p.get_width() * p.get_height() for p in ax.patches)
        assert area == pytest.approx(1.0)  # the 9-sigma value is kept in the last bin
        x, g = ax.lines[0].get_data()
        assert g.max() == pytest.approx(1 / math.sqrt(2 * math.pi), rel=1e-4)
    text = visible[2].texts[0].get_text()
    assert "N = 3" in text and f"{math.sqrt((0.01 + 0.04 + 81) / 3):.2f}" in text


def test_report_has_both_figures_and_the_table_the_columns(summary, tmp_path):
    t = depth_table()
    index = build_report(tmp_path, summary=summary, depths=t, truth_ppm=TRUTH)
    text = index.read_text()
    for name in ("coverage", "normalised_residuals"):
        assert f'src="{name}.png"' in text
        assert (tmp_path / f"{name}.pdf").stat().st_size > 0
    table = stats_table(summary)
    for col in ("coverage", "coverage_lo", "coverage_hi", "coverage_2sigma", "coverage_2sigma_lo",
                "coverage_2sigma_hi", "z_rms"):
        assert col in table.colnames
    # the optimistic method's errors are 2x too small: z_rms near 2, coverage well below 68%
    opt = summary["methods"]["optimistic"]
    assert 1.6 < opt["z_rms"] < 2.4 and opt["coverage_hi"] < GAUSS_1SIGMA


def test_without_truth_the_figures_are_skipped(tmp_path):
    t = depth_table(n_epochs=5)
    index = build_report(tmp_path, summary=summarize(t, n_bootstrap=0), depths=t)
    assert "coverage and normalised residuals (no truth)" in index.read_text()
    assert not (tmp_path / "coverage.png").exists()
