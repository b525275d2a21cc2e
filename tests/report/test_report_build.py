"""The report folder: tables in three formats, figures as PNG and PDF, an offline index.html."""

from __future__ import annotations

import re
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest
from astropy.table import Table

from eclipsebench.report.build import build_report
from eclipsebench.report.figures import fit_inverse, fit_line
from eclipsebench.stats.summary import summarize

METHODS = ("bliss", "pld", "gp")


def depth_table(n_epochs=6):
    rng = np.random.default_rng(4)
    rows = []
    for k, m in enumerate(METHODS):
        for e in range(1, n_epochs + 1):
            rows.append((m, e, 1875 + rng.normal(-30 * k, 120), 100 + 10 * k))
    return Table(rows=rows, names=["method", "epoch", "depth_ppm", "error_ppm"])


def photometry(n_epochs=3, n=630):
    rng = np.random.default_rng(5)
    out = {}
    for e in range(1, n_epochs + 1):
        phase = np.linspace(-0.45, -0.2, n)
        out[e] = {"phase": phase, "x": 15.1 + 0.05 * rng.standard_normal(n),
                  "y": 15.2 + 0.05 * rng.standard_normal(n),
                  "noise_pixels": 4.5 + 0.1 * rng.standard_normal(n),
                  "background": 4.0 + 0.1 * rng.standard_normal(n),
                  "flux": 73000 + 300 * rng.standard_normal(n)}
    return out


class _Refs(HTMLParser):
    def __init__(self):
        super().__init__()
        self.refs = []

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        for key in ("src", "href"):
            if key in a:
                self.refs.append((tag, a[key]))


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    dest = tmp_path_factory.mktemp("report")
    t = depth_table()
    s = summarize(t, sigma_phot_ppm=53.0, truth_ppm=1875.0, n_bootstrap=200)
    phase = np.linspace(-0.45, -0.2, 640)
    curves = {m: {"phase": phase, "flux_corrected": 1 + 1e-4 * np.sin(30 * phase),
                  "astro_model": np.ones_like(phase)} for m in METHODS}
    gx = np.linspace(14.5, 15.5, 21)
    gain = 1 - 0.02 * ((gx[None, :] - 15) ** 2 + (gx[:, None] - 15) ** 2)
    index = build_report(dest, summary=s, depths=t, truth_ppm=1875.0, photometry=photometry(),
                         lightcurves=curves, lightcurve_epoch=5,
                         truth_curve=(phase, np.ones_like(phase)), gain_map=(gx, gx, gain),
                         notes={"seed": 1})
    return dest, index


def test_every_referenced_file_exists_and_is_non_empty(report):
    dest, index = report
    parser = _Refs()
    parser.feed(index.read_text())
    images = [ref for tag, ref in parser.refs if tag == "img"]
    assert len(images) == 11  # every figure of the paper, coverage and residuals
    for _tag, ref in parser.refs:
        assert not re.match(r"^[a-z]+:", ref) and not ref.startswith("/"), ref  # offline
        path = dest / ref
        assert path.is_file() and path.stat().st_size > 0, ref
    for ref in images:
        assert (dest / ref).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        pdf = (dest / ref).with_suffix(".pdf")
        assert pdf.read_bytes()[:5] == b"%PDF-"


def test_tables_in_three_formats(report):
    dest, _ = report
    t = Table.read(dest / "eclipse_depth_stats.ecsv", format="ascii.ecsv")
    assert list(t["method"]) == [*METHODS, "Average"]
    assert t["R"].unit == "ppm"
    tex = (dest / "eclipse_depth_stats.tex").read_text()
    assert "\\begin{deluxetable*}" in tex and "\\tablehead" in tex
    md = (dest / "eclipse_depth_stats.md").read_text().splitlines()
    assert md[0].startswith("| Method") and len(md) == 2 + len(METHODS) + 1


def test_report_without_optional_inputs(tmp_path):
    t = depth_table()
    s = summarize(t, n_bootstrap=0)
    index = build_report(tmp_path, summary=s, depths=t)
    text = index.read_text()
    assert "Not drawn" in text
    assert len(list(tmp_path.glob("*.png"))) == 3  # depths, visit and method differences


def test_fits_used_in_the_figures():
    r = np.array([0.2, 0.4, 0.5])
    assert fit_inverse(r, 75.0 / r) == pytest.approx(75.0)
    assert fit_line([0, 1, 2], [1, 3, 5]) == pytest.approx((2.0, 1.0))


def test_png_is_deterministic(tmp_path):
    from eclipsebench.report.figures import repeatability_vs_reliability, save_figure
    s = summarize(depth_table(), sigma_phot_ppm=53.0, n_bootstrap=0)
    a = save_figure(repeatability_vs_reliability(s, 53.0), tmp_path / "a")
    b = save_figure(repeatability_vs_reliability(s, 53.0), tmp_path / "b")
    for x, y in zip(a, b, strict=True):
        assert Path(x).read_bytes() == Path(y).read_bytes()
