"""Issue 38, item 3: the trust page on report/'s toolkit, TrustResult's face, stdout's units.

The answer is made by the real scoring path (``trust.report.trust_summary``)
from twins drawn here with known properties: a calibrated method, one whose
errors are half its scatter, one whose real residuals are redder than every
twin's, and a method skipped; ten twins, too few to rank them.
"""

from __future__ import annotations

import ast
import json
from pathlib import Path

import numpy as np
import pytest
from astropy.table import Table
from matplotlib.figure import Figure

import eclipsebench
from eclipsebench.commands.trust import format_text
from eclipsebench.trust.report import trust_summary
from eclipsebench.trust.result import TrustResult

from ..conftest import page_built_in_an_svg_process

T_EVENT = 56241.95944   # the twins' mid-eclipse (BMJD_TDB), as real epoch 1's
DEPTH = 1800.0
N_TWINS = 10
TRUST = Path(eclipsebench.__file__).parent / "trust"


def _answer() -> tuple[dict, dict]:
    rng = np.random.default_rng(38)
    spec = {"calibrated": (150.0, 150.0, 1.0), "optimistic": (150.0, 75.0, 1.0),
            "red": (150.0, 150.0, 3.0)}   # (scatter, reported error, real beta_red)
    real, twins = {}, {}
    for m, (sd, err, beta) in spec.items():
        d = DEPTH + sd * rng.standard_normal(N_TWINS)
        e = np.full(N_TWINS, err)
        twins[m] = (list(d), list(e), list(1.0 + 0.05 * rng.standard_normal(N_TWINS)),
                    list(range(1, N_TWINS + 1)), list(T_EVENT + 1e-3 * rng.standard_normal(
                        N_TWINS)), [1.5e-3] * N_TWINS)
        real[m] = {"depth_ppm": DEPTH + 40.0, "depth_err_ppm": err, "beta_red": beta,
                   "t_ecl_bmjd": T_EVENT + 1e-4, "t_ecl_err_d": 1.5e-3}
    settings = {"seed": 7, "reduce": {"event": "eclipse", "profile": "controlled",
                                      "sampler": "leastsq"},
                "n_twins": N_TWINS, "system": "XO-3b", "table": "real1/epoch_01.fits"}
    recipe = {"depth_ppm": DEPTH, "t_event_bmjd": T_EVENT, "event": "eclipse",
              "from_method": "calibrated", "motion_rms_px": 0.17, "motion_peak_px": 0.75,
              "gain_model": "the simulator's", "calibration": {"noise_pixels_real": 3.98}}
    summary = trust_summary(settings, recipe, real, twins,
                            {"kr-pmap": "no pixel map (give --pmap)"}, {})
    return json.loads(json.dumps(summary)), twins   # as trust.json holds it


def _table(seed: int) -> Table:
    n = 3000
    rng = np.random.default_rng(seed)
    t = T_EVENT + np.linspace(-0.2, 0.15, n)
    return Table({"time_bmjd": t, "flag": np.zeros(n, int), "flux": 6e4 + 200 * rng.random(n),
                  "x": 15.2 + 0.01 * rng.standard_normal(n),
                  "y": 15.0 + 0.01 * rng.standard_normal(n),
                  "noise_pixels": 3.98 + 0.02 * rng.standard_normal(n)})


def _curves(summary: dict) -> dict:
    hours = np.linspace(-4.8, 3.6, 3000)
    inside = np.abs(hours) < 1.2
    return {m: {"hours": hours, "astro_model": 1.0 + np.where(inside, 0.0, s["depth_ppm"] * 1e-6),
                "flux_corrected": 1.0 + np.where(inside, 0.0, s["depth_ppm"] * 1e-6)
                + 1e-3 * np.sin(np.arange(hours.size))}
            for m, s in summary["methods"].items()}


@pytest.fixture(scope="module")
def answer():
    return _answer()


def test_the_answer_drawn_here_has_each_caution(answer):
    summary, _ = answer
    assert summary["methods"]["red"]["redder_than_twins"]
    assert not summary["ranking"]["resolved"] and summary["skipped"] == {
        "kr-pmap": "no pixel map (give --pmap)"}


def test_building_the_page_keeps_the_backend_and_never_imports_pyplot(answer, tmp_path):
    """In a fresh process whose backend is svg: the page is written and the backend is still
    svg, pyplot never imported (the old page switched the process to Agg through pyplot)."""
    summary, twins = answer
    (tmp_path / "answer.json").write_text(json.dumps({"summary": summary, "twins": twins}))
    page = page_built_in_an_svg_process(f"""
import json
import numpy as np
sys.path.insert(0, {str(Path(__file__).parent.parent.parent)!r})
from tests.trust.test_page import _curves, _table
from eclipsebench.trust.page import write_page
data = json.load(open({str(tmp_path / "answer.json")!r}))
page = write_page({str(tmp_path / "report")!r}, data["summary"], twins=data["twins"],
                  curves=_curves(data["summary"]), real_table=_table(1), twin_table=_table(2),
                  command="eclipsebench trust x.fits --out y")
""")
    assert Path(page).is_file()


def test_trust_imports_no_pyplot_and_switches_no_backend():
    for path in sorted(TRUST.glob("*.py")):
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom):
                names = [f"{node.module}.{a.name}" for a in node.names]
            elif isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute):
                assert node.func.attr != "use" or not (
                    isinstance(node.func.value, ast.Name) and node.func.value.id == "matplotlib"
                ), f"{path.name}: matplotlib.use"
                continue
            else:
                continue
            assert not any("pyplot" in n for n in names), (path.name, names)


def test_the_page_shows_the_answer_its_cautions_and_where_it_came_from(answer, tmp_path):
    from eclipsebench.trust.page import write_page

    summary, twins = answer
    page = write_page(tmp_path, summary, twins=twins, curves=_curves(summary),
                      real_table=_table(1), twin_table=_table(2),
                      command="eclipsebench trust real1/epoch_01.fits --out t --seed 7").read_text()
    assert f"<b>eclipsebench</b>: {eclipsebench.__version__}" in page
    assert "<b>command</b>: eclipsebench trust real1/epoch_01.fits --out t --seed 7" in page
    assert "<b>seed</b>: 7" in page
    assert summary["quote"]["text"] in page
    cautions = page.split("<div class='caution'>")[1].split("</div>")[0]
    assert "too few twins to rank" in cautions
    assert "red: the real residuals are redder" in cautions
    assert "kr-pmap skipped: no pixel map" in cautions
    # the per-method table with units, the recommended row highlighted
    assert "<th>depth (ppm)</th>" in page and "<th>1-sigma cov (%)</th>" in page
    best = summary["recommended"]
    assert best is not None and f'<tr class="chosen"><td>{best}</td>' in page
    for name in ("lightcurves", "depths", "z_scores", "twin"):
        assert f'src="{name}.png"' in page and (tmp_path / f"{name}.pdf").is_file()


def _drawn(fig: Figure) -> Figure:
    fig.canvas.draw()
    return fig


def test_the_figures_use_hours_from_mid_eclipse_and_label_every_axis(answer):
    from eclipsebench.trust.page import real_lightcurves_figure, resemblance_figure

    summary, _ = answer
    for fig in (_drawn(real_lightcurves_figure(summary, _curves(summary))),
                _drawn(resemblance_figure(summary, _table(1), _table(2)))):
        axes = [ax for ax in fig.axes if ax.get_visible()]
        assert axes[-1].get_xlabel().startswith("hours from mid-eclipse (BMJD_TDB 56241.95944")
        for ax in axes:
            assert ax.get_ylabel()
            assert ax.xaxis.get_offset_text().get_text() == ""   # no "+5.624e4"
            assert ax.yaxis.get_offset_text().get_text() == ""
        low, high = axes[-1].get_xlim()
        assert -6 < low < -4 and 3 < high < 5


def test_the_recommended_method_is_highlighted_and_the_twins_are_in_the_legend(answer):
    from eclipsebench.trust.page import real_lightcurves_figure, twin_depths_figure

    summary, twins = answer
    best = summary["recommended"]
    fig = _drawn(twin_depths_figure(summary, {m: t[0] for m, t in twins.items()}))
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert f"twins ({N_TWINS} per method): each one's depth" in labels
    assert "recommended method" in labels and "real depth ± honest error" in labels
    ax = fig.axes[0]
    bold = [t.get_text() for t in ax.get_xticklabels() if t.get_fontweight() == "bold"]
    assert bold == [best]
    assert ax.get_ylabel() == "eclipse depth (ppm)"
    curves = real_lightcurves_figure(summary, _curves(summary))
    framed = [ax for ax in curves.axes if ax.spines["left"].get_linewidth() > 2]
    assert len(framed) == 1 and any(f"{best} (recommended)" in t.get_text()
                                    for t in framed[0].texts)


def test_the_z_score_panels_share_one_scale_and_are_labelled(answer):
    from eclipsebench.trust.page import z_score_figure

    summary, twins = answer
    fig = _drawn(z_score_figure(summary, twins))
    axes = [ax for ax in fig.axes if ax.get_visible()]
    assert [ax.get_title() for ax in axes] == ["all methods", *summary["methods"]]
    assert len({ax.get_ylim() for ax in axes}) == 1 and len({ax.get_xlim() for ax in axes}) == 1
    assert fig.get_supylabel() == "density"
    assert fig.get_supxlabel() == "(D - injected depth) / reported error"
    assert f"N = {N_TWINS} twins" in axes[1].texts[0].get_text()


def test_trust_result_plots_and_shows_its_table_and_cautions(answer, tmp_path):
    summary, _ = answer
    result = TrustResult(summary)
    fig = result.plot()
    assert isinstance(fig, Figure) and fig.axes[0].get_ylabel() == "eclipse depth (ppm)"
    # without its folder the twins are drawn as their mean and SD
    assert any("mean ± SD" in t.get_text() for t in _drawn(fig).legends[0].get_texts())
    text = repr(result)
    lines = text.splitlines()
    units = next(i for i, line in enumerate(lines) if line.split()[:2] == ["ppm", "ppm"])
    assert lines[units - 1].split()[:2] == ["method", "depth"]
    assert all(any(line.strip().startswith(m) for line in lines) for m in summary["methods"])
    assert "caution     too few twins to rank" in text
    assert "caution     red: the real residuals are redder" in text
    assert "caution     kr-pmap skipped" in text
    page = result._repr_html_()
    assert "<th>depth (ppm)</th>" in page and "redder" in page and "kr-pmap skipped" in page
    assert len(page) < 4096


def test_the_stdout_columns_carry_units(answer):
    summary, _ = answer
    lines = format_text(summary).splitlines()
    head = next(i for i, line in enumerate(lines) if line.startswith("method "))
    columns = lines[head].split("  ")
    assert [c.strip() for c in columns if c.strip()][:4] == ["method", "depth", "honest err",
                                                            "reported err"]
    assert lines[head + 1].split() == ["ppm"] * 7 + ["%"] * 3   # z_rms has none
    timed = next(i for i, line in enumerate(lines) if line.startswith("mid-time "))
    assert lines[timed + 1].split() == ["s"] * 6 + ["%"]
    assert any(line.startswith("caution       red: the real residuals") for line in lines)


def test_an_api_run_s_page_shows_the_call_with_the_arguments_given():
    from eclipsebench.api import _call_text, trust

    given = {"table": Path("real1/epoch_01.fits"), "out": "t1", "twins": 10,
             "methods": ["bliss"], "seed": 0, "config": object(),
             "reduce_options": {"sampler": "leastsq"}}
    assert _call_text("eb.trust", trust, given) == (
        "eb.trust('real1/epoch_01.fits', 't1', twins=10, methods=['bliss'], config=<object>, "
        "sampler='leastsq')")
