"""The paper profile (issue 15): every method has its team's entry, and reduce applies it."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import eclipsebench as eb
from eclipsebench.config.reduce import ReduceSection
from eclipsebench.decorrelate.base import _PAPER_ORDER
from eclipsebench.errors import InputError
from eclipsebench.fit import profiles
from eclipsebench.fit.reduce import reduce_epoch, resolve_profile

DOCS = Path(__file__).resolve().parents[2] / "docs" / "methods.md"


@pytest.mark.parametrize("method", eb.methods())
def test_every_built_in_method_has_a_paper_profile(method):
    entry = profiles.paper_profile(method)
    assert entry.phases and entry.ramps and entry.reported_error
    for cell in ("centroid", "phase", "ramp", "fit", "error"):
        assert entry.why.get(cell), f"{method}: no justification for the {cell} cell"


def test_the_paper_seven_cite_appendix_b():
    for method in _PAPER_ORDER:
        why = profiles.paper_profile(method).why
        assert any("App. B" in v for v in why.values()), method


def test_docs_hold_the_generated_table():
    assert profiles.profile_markdown() in DOCS.read_text(encoding="utf-8")


def test_a_method_without_an_entry_runs_as_controlled(polygain):
    """A method whose record has no team's pipeline (a plugin) runs in both profiles."""
    options = ReduceSection(profile="paper")
    assert resolve_profile(polygain.name, options) == (replace(options, profile="controlled"),
                                                       None)
    assert profiles.paper_profile(polygain.name) is None
    with pytest.raises(InputError, match="profile 'team'"):
        resolve_profile("pld", profile="team")


def test_centroid_columns_and_the_fixed_width_fallback():
    cols = ["x", "y", "x_col", "y_col", "x_gauss", "y_gauss", "x_gfix", "y_gfix"]
    assert profiles.centroid_columns(cols, "gauss-fixed") == (("x_gfix", "y_gfix"), "")
    assert profiles.centroid_columns(cols[:6], "gauss-fixed")[0] == ("x_gauss", "y_gauss")
    with pytest.raises(InputError, match="gauss centroid columns"):
        profiles.centroid_columns(["x", "y"], "gauss")


def test_paper_profile_takes_the_team_choices(polygain, xo3_epoch, monkeypatch):
    """Phase and ramp by BIC among the team's candidates, its centroid, its error rule."""
    monkeypatch.setattr(polygain, "record", replace(polygain.record, paper=profiles.PaperProfile(
        team="test", centroid="gauss", phases=("flat", "quadratic"), ramps=("none",),
        eclipse_shape="physical", sampler="leastsq", reported_error=("jacobian",),
        fit="least squares")))
    table = xo3_epoch["table"](noise=3e-4)
    # the Gaussian centroid differs from x/y: the paper profile must regress on it
    table["x_gauss"] = table["x"] + 1e-3
    res = reduce_epoch(table, polygain.name, profile="paper")
    assert res.profile == "paper" and res.phase == "quadratic"   # the truth is curved
    assert set(res.profile_detail["bic"]) == {"flat/none", "quadratic/none"}
    assert res.profile_detail["bic"]["quadratic/none"] < res.profile_detail["bic"]["flat/none"]
    assert res.profile_detail["centroid"] == "x_gauss/y_gauss"
    assert res.depth_err_method == "jacobian"
    assert res.depth_err_ppm == pytest.approx(res.depth_err_jacobian_ppm)
    assert res.depth_err_prayer_bead_ppm is None   # not reported by the team: not computed
    ctrl = reduce_epoch(table, polygain.name, options=ReduceSection(phase="flat"))
    assert ctrl.profile == "controlled" and ctrl.phase == "flat"
    assert ctrl.depth_err_method == "mcmc" and ctrl.sampler == "mcmc"   # the shared rule
    assert np.isfinite(res.to_dict()["profile_detail"]["bic"]["flat/none"])


def test_the_controlled_profile_gives_every_method_one_eclipse_shape(kit, xo3_epoch):
    """SP(K2)'s team box is the paper profile's; controlled, it fits the shared shape.

    The box alone costs about 130 ppm on XO-3b (docs/fitting.md). On this
    noiseless epoch the same blind detrend gives 1789 ppm with the shared shape
    and 1646 ppm with the box, which the controlled profile used to take.
    """
    table = xo3_epoch["table"](noise=0.0, systematics=False)
    fast = ReduceSection(sampler="leastsq", prayer_bead_shifts=0)
    ctrl = reduce_epoch(table, "segpoly", options=fast)
    box = reduce_epoch(table, "segpoly", options=replace(fast, eclipse_shape="box"))
    paper = reduce_epoch(table, "segpoly", profile="paper")
    assert (ctrl.eclipse_shape, box.eclipse_shape, paper.eclipse_shape) == (
        "physical", "box", "box")
    assert ctrl.depth_ppm - box.depth_ppm > 100.0
    assert ctrl.depth_ppm < 1e6 * kit.TRUE_DEPTH   # the blind detrend's own loss


def test_prayer_bead_all_cycles_every_stride(kit, polygain, xo3_epoch):
    """Issue 15 point 2: every cyclic shift (in steps of the stride), each refitted fully."""
    from eclipsebench.fit.leastsq import fit_leastsq, prayer_bead
    from eclipsebench.fit.reduce import prepare_epoch

    prep = prepare_epoch(xo3_epoch["table"](noise=3e-4), polygain.name)
    model = prep.astro_model(ReduceSection(phase="flat"))
    fit = fit_leastsq(prep.systematics, model,
                      model.initial(depth=1e-3, t_event_bmjd=prep.t_event_predicted_bmjd))
    n = prep.n_frames
    beads = prayer_bead(prep.systematics, model, fit, n_shifts=None, stride=n // 10,
                        max_nfev=None)
    assert beads.shape == (n // (n // 10), len(fit.theta))     # the fit and 9 shifts
    assert np.all(np.isfinite(beads)) and np.ptp(beads[:, 0]) > 0
    res = reduce_epoch(xo3_epoch["table"](noise=3e-4), polygain.name,
                       options=ReduceSection(phase="flat", prayer_bead_mode="all",
                                             prayer_bead_stride=n // 5, sampler="leastsq"))
    assert res.depth_err_prayer_bead_ppm > 0
