"""Least-squares joint fit, BIC/AIC, red-noise factor and prayer bead on a synthetic epoch."""

from __future__ import annotations

import numpy as np
import pytest

from eclipsebench.decorrelate import get_method
from eclipsebench.decorrelate.base import EpochData
from eclipsebench.fit.data import epoch_data_from_table
from eclipsebench.fit.leastsq import (
    _Problem,
    fit_leastsq,
    information_criteria,
    prayer_bead,
    red_noise_beta,
    rms_vs_bin_size,
)
from eclipsebench.fit.model import AstroModel


def test_information_criteria_by_hand():
    bic, aic = information_criteria(-1234.5, 7, 15000)
    assert bic == pytest.approx(2469.0 + 7 * 9.615805480084347)
    assert aic == pytest.approx(2469.0 + 14.0)


def test_rms_vs_bin_size_by_hand():
    r = np.array([1.0, -1.0, 2.0, 0.0, -2.0, 3.0, 1.0, 1.0])
    sizes, sigma, expected = rms_vs_bin_size(r, [2, 3, 5])
    assert sizes.tolist() == [2, 3]  # 5 leaves a single bin
    means = np.array([0.0, 1.0, 0.5, 1.0])
    assert sigma[0] == pytest.approx(np.sqrt(np.mean((means - means.mean()) ** 2)))
    assert expected[0] == pytest.approx(np.std(r) / np.sqrt(2) * np.sqrt(4 / 3))


def test_beta_is_one_on_white_noise_and_larger_on_red_noise():
    rng = np.random.default_rng(42)
    n = 20000
    time = 57000.0 + np.arange(n) * 2.0 / 86400
    # one draw scatters by ~10 % (22-66 bins per width); the mean of 40 draws by ~2 %
    betas = [red_noise_beta(rng.standard_normal(n), time) for _ in range(40)]
    assert abs(np.mean(betas) - 1.0) < 0.06
    assert 0.6 < min(betas) and max(betas) < 1.4
    # add a random walk smoothed over ~7 min: correlated on the 10-30 min scale
    white = rng.standard_normal(n)
    red = white + np.convolve(rng.standard_normal(n), np.ones(200) / 200 * 3.0, "same")
    assert red_noise_beta(red, time) > 1.5


@pytest.fixture
def fitted(kit, trapezoid_epoch):
    data = epoch_data_from_table(trapezoid_epoch["table"])
    sys = kit.PolyGain(data)
    model = AstroModel(data.time_bmjd, None, phase="quadratic", shape=trapezoid_epoch["shape"])
    theta0 = model.initial(depth=1e-3, t_event_bmjd=trapezoid_epoch["t_ecl"] - 0.004)
    return sys, model, fit_leastsq(sys, model, theta0)


def test_recovers_depth_and_time_within_errors(kit, trapezoid_epoch, fitted):
    sys, model, fit = fitted
    assert fit.success
    depth, err = fit.value("depth"), fit.error("depth")
    assert 20e-6 < err < 200e-6
    assert abs(depth - kit.TRUE_DEPTH) < 3 * err
    assert abs(fit.value("t_ecl_bmjd") - trapezoid_epoch["t_ecl"]) < 3 * fit.error("t_ecl_bmjd")
    assert abs(fit.value("c2_per_day2") - kit.TRUE_C2) < 3 * fit.error("c2_per_day2")
    assert fit.chi2_red == pytest.approx(1.0, abs=0.05)
    assert 1e3 * 0.9 < fit.rms_ppm < 1e3 * 1.1


def test_bic_and_aic_recomputed_from_the_residuals(fitted):
    sys, model, fit = fitted
    d = sys.data
    r = (d.flux - fit.model) / d.flux_err
    loglike = -0.5 * np.sum(r**2) - np.sum(np.log(d.flux_err)) - 0.5 * len(r) * np.log(2 * np.pi)
    k = 4 + 6  # depth, t_ecl, c1, c2 + six polynomial gain coefficients
    assert fit.k == k
    assert fit.bic == pytest.approx(-2 * loglike + k * np.log(len(r)), rel=1e-12)
    assert fit.aic == pytest.approx(-2 * loglike + 2 * k, rel=1e-12)


def test_jacobian_error_matches_the_scatter_of_noise_realisations(kit, trapezoid_epoch):
    """The Jacobian depth error is the spread of depths over independent noise draws."""
    depths, errors = [], []
    for seed in range(12):
        table = kit.make_epoch_table(t_ecl=trapezoid_epoch["t_ecl"], time=trapezoid_epoch["time"],
                                     visible=trapezoid_epoch["shape"].visible_fraction(
                                         trapezoid_epoch["t_ecl"]), seed=100 + seed)
        data = epoch_data_from_table(table)
        model = AstroModel(data.time_bmjd, None, phase="flat", shape=trapezoid_epoch["shape"])
        fit = fit_leastsq(kit.PolyGain(data), model,
                          model.initial(t_event_bmjd=trapezoid_epoch["t_ecl"]))
        depths.append(fit.value("depth"))
        errors.append(fit.error("depth"))
    # 12 draws: the sample sd is within ~ +-40 % of the true sigma at 2 sigma
    assert 0.6 < np.std(depths, ddof=1) / np.mean(errors) < 1.4


def test_prayer_bead_shapes_and_spread(fitted):
    sys, model, fit = fitted
    beads = prayer_bead(sys, model, fit, n_shifts=6)
    assert beads.shape == (7, len(fit.theta))
    assert np.array_equal(beads[0], fit.theta)
    spread = np.std(beads[:, 0], ddof=1)
    assert 0.2 * fit.error("depth") < spread < 5 * fit.error("depth")
    # the data of the original method are untouched
    assert np.array_equal(sys.data.flux, fitted[0].data.flux)


def test_the_jacobian_rows_are_the_compiled_batch_once_numba_is_loaded(monkeypatch, kit,
                                                                        xo3_epoch):
    """With numba loaded (a run's worker), the Jacobian's rows are ``AstroModel.batch``, the
    same values as a row at a time (issue 40: KR/Data's prayer bead, 0.8 s of its rows);
    without it, a row at a time, so that a least-squares fit does not load numba."""
    import sys

    import numba  # noqa: F401  (loaded, as in a worker after an MCMC)

    data = epoch_data_from_table(xo3_epoch["table"]())
    model = AstroModel(data.time_bmjd, xo3_epoch["system"], phase="linear")
    problem = _Problem(kit.PolyGain(data), model)
    theta = model.initial(t_event_bmjd=xo3_epoch["t_true"])
    calls = []
    batch = model.batch
    monkeypatch.setattr(model, "batch", lambda rows: calls.append(len(rows)) or batch(rows))
    fast = problem.jacobian(theta, central=True)
    assert calls == [2 * len(theta)]
    monkeypatch.delitem(sys.modules, "numba")
    slow = problem.jacobian(theta, central=True)
    assert calls == [2 * len(theta)] and np.array_equal(fast, slow)


def test_inputs_are_not_modified(kit, trapezoid_epoch):
    data = epoch_data_from_table(trapezoid_epoch["table"])
    before = data.flux.copy()
    model = AstroModel(data.time_bmjd, None, phase="flat", shape=trapezoid_epoch["shape"])
    fit_leastsq(kit.PolyGain(data), model, model.initial(t_event_bmjd=trapezoid_epoch["t_ecl"]))
    assert np.array_equal(data.flux, before)
    assert isinstance(data, EpochData)


def _jacobian_by_columns(problem, theta, central):
    """The finite-difference Jacobian one column at a time (the fitter's former loop)."""
    steps = 1e-2 * problem.scales(theta)
    f0 = problem.residuals(theta)
    cols = []
    for i, h in enumerate(steps):
        up = theta.copy()
        if up[i] + h > problem.upper[i]:
            h = -h
        up[i] += h
        if central:
            down = theta.copy()
            down[i] -= h
            cols.append((problem.residuals(up) - problem.residuals(down)) / (2 * h))
        else:
            cols.append((problem.residuals(up) - f0) / h)
    return np.column_stack(cols)


@pytest.mark.parametrize("method", ["polygain", "kr-data"])
@pytest.mark.parametrize("central", [False, True])
def test_batched_jacobian_is_the_column_by_column_one(kit, trapezoid_epoch, method, central):
    """All shifted parameter vectors in one call (a method's residuals_batch, KR/Data's own
    compiled pass): the same bytes, also for a step turned back at a bound."""
    data = epoch_data_from_table(trapezoid_epoch["table"])
    sys = kit.PolyGain(data) if method == "polygain" else get_method("kr-data")(data)
    model = AstroModel(data.time_bmjd, None, phase="quadratic", shape=trapezoid_epoch["shape"])
    problem = _Problem(sys, model)
    theta = np.concatenate([model.initial(depth=1e-3, t_event_bmjd=trapezoid_epoch["t_ecl"]),
                            sys.initial_params()])
    bounded = int(np.flatnonzero(np.isfinite(problem.upper))[0])
    theta[bounded] = problem.upper[bounded] - 1e-4 * problem.scales(theta)[bounded]
    jac = problem.jacobian(theta, central=central)
    assert jac.shape == (len(data), len(theta)) and jac.flags.c_contiguous
    assert np.array_equal(jac, _jacobian_by_columns(problem, theta, central))


def test_forward_jacobian_starts_from_the_residuals_just_evaluated(kit, trapezoid_epoch,
                                                                 monkeypatch):
    """least_squares asks for the Jacobian where it has just evaluated the residuals: they are
    not evaluated again (the same bytes), unless the problem was told to forget them."""
    data = epoch_data_from_table(trapezoid_epoch["table"])
    sys = kit.PolyGain(data)
    model = AstroModel(data.time_bmjd, None, phase="quadratic", shape=trapezoid_epoch["shape"])
    problem = _Problem(sys, model)
    theta = np.concatenate([model.initial(depth=1e-3, t_event_bmjd=trapezoid_epoch["t_ecl"]),
                            sys.initial_params()])
    expected = _jacobian_by_columns(problem, theta, False)
    calls = []
    residuals = type(sys).residuals
    monkeypatch.setattr(type(sys), "residuals",
                        lambda self, *a: calls.append(1) or residuals(self, *a))
    problem.residuals(theta)
    calls.clear()
    assert np.array_equal(problem.jacobian(theta), expected)
    assert len(calls) == len(theta)                 # the shifted vectors only
    calls.clear()
    problem.forget()
    assert np.array_equal(problem.jacobian(theta), expected)
    assert len(calls) == len(theta) + 1
    calls.clear()
    problem.jacobian(theta + 1e-9)                  # elsewhere: its own residuals
    assert len(calls) == len(theta) + 1
