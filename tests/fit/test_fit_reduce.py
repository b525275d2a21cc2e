"""reduce_epoch, select_phase_model and reduce_joint on synthetic XO-3b epochs."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from eclipsebench.config.reduce import ReduceSection
from eclipsebench.errors import InputError
from eclipsebench.fit.reduce import (
    reduce_epoch,
    reduce_joint,
    resolve_method_options,
    select_phase_model,
)

CONTRACT_KEYS = {"method", "epoch", "depth_ppm", "depth_err_ppm", "t_ecl_bmjd", "t_ecl_err_d",
                 "bic", "aic", "rms_ppm", "beta_red", "n_frames", "phase", "sampler", "chi2_red",
                 "c1_per_day", "c2_per_day2", "converged", "depth_err_method"}
FAST = ReduceSection(prayer_bead_shifts=4, sampler="leastsq")


def test_noiseless_epoch_gives_the_injected_depth_exactly(kit, polygain, xo3_epoch):
    res = reduce_epoch(xo3_epoch["table"](noise=0.0), polygain.name,
                       options=ReduceSection(prayer_bead_shifts=0), system=xo3_epoch["system"])
    assert res.depth_ppm == pytest.approx(kit.TRUE_DEPTH * 1e6, abs=0.5)
    assert res.t_event_bmjd == pytest.approx(xo3_epoch["t_true"], abs=2e-6)
    assert res.params["c2_per_day2"] == pytest.approx(kit.TRUE_C2, rel=1e-3)


def test_default_reports_the_least_squares_depth_with_the_posterior_width(kit, polygain,
                                                                        xo3_epoch):
    """Issue 14 point 3: ``sampler = "auto"`` samples an eclipse; the controlled profile
    reports the least-squares depth and the posterior's 16-84 % half-width, with the
    red-noise factor in the likelihood's flux errors."""
    table = xo3_epoch["table"](seed=5)[::2]
    res = reduce_epoch(table, polygain.name, options=ReduceSection(prayer_bead_shifts=0))
    lsq = reduce_epoch(table, polygain.name,
                       options=ReduceSection(prayer_bead_shifts=0, sampler="leastsq"))
    d = res.to_dict()
    assert d["sampler"] == "mcmc" and d["depth_err_method"] == "mcmc"
    assert res.depth_ppm == pytest.approx(lsq.depth_ppm, abs=1e-9)
    lo, hi = d["depth_err_lo_ppm"], d["depth_err_hi_ppm"]
    assert res.depth_err_ppm == pytest.approx(0.5 * (lo + hi))
    assert d["mcmc_converged"] and d["mcmc_n_over_tau"] >= 50
    assert d["mcmc_noise_scale"] == pytest.approx(np.sqrt(res.chi2_red) * max(1.0, res.beta_red))
    # the posterior's width is the Jacobian error times the same red-noise factor, to sampling
    assert res.depth_err_ppm == pytest.approx(lsq.depth_err_jacobian_ppm * max(1.0, res.beta_red),
                                              rel=0.15)
    assert res.chain is not None and res.chain["samples"].shape[1] == len(res.params)
    # the bead is not computed beside the posterior this rule reports; "largest" brings it back
    assert reduce_epoch(table, polygain.name,
                        options=ReduceSection(prayer_bead_shifts=4)).depth_err_prayer_bead_ppm is None
    largest = reduce_epoch(table, polygain.name,
                           options=ReduceSection(prayer_bead_shifts=4, error_rule="largest"))
    assert largest.depth_err_prayer_bead_ppm > 0 and largest.depth_err_mcmc_ppm > 0


def test_recovers_depth_within_its_error(kit, polygain, xo3_epoch):
    res = reduce_epoch(xo3_epoch["table"](), polygain.name, options=FAST)
    d = res.to_dict()
    assert CONTRACT_KEYS <= set(d)
    assert d["method"] == polygain.name and d["epoch"] == 3 and d["sampler"] == "leastsq"
    assert d["n_frames"] == len(xo3_epoch["time"])
    assert abs(res.depth_ppm - kit.TRUE_DEPTH * 1e6) < 3 * res.depth_err_ppm
    assert abs(res.t_event_bmjd - xo3_epoch["t_true"]) < 3 * res.t_event_err_d
    assert res.t_event_predicted_bmjd == pytest.approx(xo3_epoch["t_pred"])
    # the reported error is the largest available estimate
    jac_beta = res.depth_err_jacobian_ppm * max(1.0, res.beta_red)
    assert res.depth_err_ppm == pytest.approx(max(jac_beta, res.depth_err_prayer_bead_ppm))
    assert res.converged
    lc = res.lightcurve
    assert set(lc) == {"time_bmjd", "flux_corrected", "astro_model", "residual", "flux_err",
                       "systematics_model"}
    # decorrelated: the gain is gone, only the 1e-3 white noise remains
    assert np.std(lc["residual"]) == pytest.approx(1e-3, rel=0.1)
    assert np.allclose(lc["residual"], lc["flux_corrected"] - lc["astro_model"])


def test_bad_input_gives_one_clear_line(polygain, xo3_epoch):
    t = xo3_epoch["table"]()
    outside = t[t["time_bmjd"] < xo3_epoch["t_pred"] - 0.1]
    with pytest.raises(InputError, match="outside the time span") as err:
        reduce_epoch(outside, polygain.name)
    assert "\n" not in str(err.value)
    with pytest.raises(InputError, match="unknown method"):
        reduce_epoch(t, "no-such-method")
    flagged = t.copy()
    flagged["flag"][:] = 4
    with pytest.raises(InputError, match="all .* frames are flagged"):
        reduce_epoch(flagged, polygain.name)
    with pytest.raises(InputError, match="missing column"):
        reduce_epoch(t[["time_bmjd", "flux", "flux_err", "flag"]], polygain.name)


def test_phase_model_selection_reports_bic_and_aic(polygain, xo3_epoch):
    sel = select_phase_model(xo3_epoch["table"](noise=3e-4), polygain.name)
    rows = {r["phase"]: r for r in sel.rows}
    assert set(rows) == {"flat", "linear", "quadratic", "sinusoid"}
    n = len(xo3_epoch["time"])
    for r in rows.values():
        # BIC - AIC = k (ln n - 2) for the same maximum likelihood
        assert r["bic"] - r["aic"] == pytest.approx(r["k"] * (np.log(n) - 2))
    assert [rows[p]["k"] for p in ("flat", "linear", "quadratic")] == [8, 9, 10]
    assert sel.best_bic == min(rows, key=lambda p: rows[p]["bic"])
    assert sel.best_aic == min(rows, key=lambda p: rows[p]["aic"])
    # the truth is quadratic with a strong curvature: flat must lose
    assert rows["flat"]["bic"] > rows["quadratic"]["bic"]
    assert sel.best_bic in sel.bracket and sel.best_aic in sel.bracket


def test_joint_fit_has_one_depth(kit, polygain, xo3_epoch):
    tables = [xo3_epoch["table"](seed=11), xo3_epoch["table"](seed=12)]
    joint = reduce_joint(tables, polygain.name, options=ReduceSection(phase="quadratic"),
                         epochs=[1, 2])
    singles = [reduce_epoch(t, polygain.name, options=ReduceSection(phase="quadratic",
                                                                   prayer_bead_shifts=0))
               for t in tables]
    assert joint.epochs == (1, 2)
    assert abs(joint.depth_ppm - kit.TRUE_DEPTH * 1e6) < 3 * joint.depth_err_ppm
    # two epochs: the joint error is about 1/sqrt(2) of a single one
    ratio = joint.depth_err_jacobian_ppm / np.mean([s.depth_err_jacobian_ppm for s in singles])
    assert 0.6 < ratio < 0.8
    # the common depth lies between the two single-epoch depths' weighted range
    lo, hi = sorted(s.depth_ppm for s in singles)
    assert lo - 20 < joint.depth_ppm < hi + 20
    assert joint.k == 1 + 2 * (3 + 6)  # depth + per epoch (t_ecl, c1, c2, 6 gain terms)


def test_method_hooks_extra_variance_and_hyperparameters(monkeypatch, polygain, xo3_epoch):
    from typing import ClassVar

    from eclipsebench.decorrelate import base

    calls = []

    class Hooked(polygain):
        name: ClassVar[str] = "test-polygain-hooked"

        def extra_depth_variance(self, astro, dastro_ddepth):
            # dastro/ddepth is the visible fraction (at the fitted eclipse time)
            assert np.mean(np.abs(dastro_ddepth - xo3_epoch["visible"][::2])) < 0.01
            assert dastro_ddepth.min() == pytest.approx(0, abs=1e-6)
            return (50e-6) ** 2

        def optimise_hyperparameters(self, astro):
            calls.append(float(np.mean(astro)))
            return {"converged": True}

    monkeypatch.setitem(base._REGISTRY, Hooked.name, Hooked)
    table = xo3_epoch["table"](seed=8)[::2]
    opts = ReduceSection(prayer_bead_shifts=0, sampler="leastsq")
    plain = reduce_epoch(table, polygain.name, options=opts)
    hooked = reduce_epoch(table, Hooked.name, options=opts)
    assert hooked.depth_err_separation_ppm == pytest.approx(50.0)
    assert hooked.depth_err_ppm == pytest.approx(np.hypot(plain.depth_err_ppm, 50.0))
    assert hooked.depth_err_method.endswith("+separation")
    # alternation: called at least once, stops when the solution no longer moves
    assert 1 <= len(calls) <= 5
    assert hooked.depth_ppm == pytest.approx(plain.depth_ppm, abs=1e-3)


def test_method_can_opt_out_of_the_prayer_bead(monkeypatch, polygain, xo3_epoch):
    from typing import ClassVar

    from eclipsebench.decorrelate import base
    from eclipsebench.decorrelate.record import FitterPolicy, MethodRecord

    class NoBead(polygain):
        name: ClassVar[str] = "test-polygain-nobead"
        record: ClassVar[MethodRecord] = MethodRecord(policy=FitterPolicy(use_prayer_bead=False))

    monkeypatch.setitem(base._REGISTRY, NoBead.name, NoBead)
    table = xo3_epoch["table"](seed=9)[::4]
    res = reduce_epoch(table, NoBead.name,
                       options=ReduceSection(prayer_bead_shifts=4, sampler="leastsq"))
    assert res.depth_err_prayer_bead_ppm is None
    assert res.depth_err_method == "jacobian_beta"
    with_bead = reduce_epoch(table, polygain.name,
                             options=ReduceSection(prayer_bead_shifts=4, sampler="leastsq"))
    assert with_bead.depth_err_prayer_bead_ppm > 0


def test_gp_hyperparameters_given_are_held_by_the_fit(xo3_epoch):
    """GP's option ``hyperparameters`` "skips the optimisation": the fitter's alternation of
    kernel and astrophysical fit leaves given values as they are (trust's twins rely on it)."""
    from eclipsebench.decorrelate.gp import HYPER_NAMES

    table = xo3_epoch["table"](seed=4, noise=1e-3)
    given = [-6.0, -2.0, -2.5, 1.0, 0.0]
    res = reduce_epoch(table, "gp", options=replace(ReduceSection(), sampler="leastsq",
                                                    prayer_bead_shifts=0),
                       method_options=resolve_method_options("gp", method_options={
                           "hyperparameters": given}))
    held = res.diagnostics["hyperparameters"]
    assert [held[n] for n in HYPER_NAMES] == given
