"""MCMC (emcee) against least squares, seeding, and the method's preferred move."""

from __future__ import annotations

from typing import ClassVar

import numpy as np
import pytest

from eclipsebench.config.reduce import ReduceSection
from eclipsebench.decorrelate import base
from eclipsebench.decorrelate.record import FitterPolicy, MethodRecord
from eclipsebench.fit.reduce import reduce_epoch

MCMC = ReduceSection(phase="flat", sampler="mcmc", mcmc_walkers=16, mcmc_steps=3000,
                     mcmc_block_steps=500, prayer_bead_shifts=0)


@pytest.fixture(scope="module")
def small_table(xo3_epoch):
    return xo3_epoch["table"](seed=5)[::8]


def test_mcmc_agrees_with_least_squares(polygain, small_table):
    res = reduce_epoch(small_table, polygain.name, options=MCMC, seed=7)
    mc = res.mcmc
    assert mc["move"] == "de" and mc["converged"]   # the default move
    assert mc["steps"] > 50 * mc["tau_max"]
    assert 0.15 < mc["acceptance"] < 0.8
    # posterior median within a fifth of a sigma of the maximum likelihood (the controlled
    # profile reports the latter, with the posterior's width)
    assert res.depth_ppm == res.depth_leastsq_ppm
    assert abs(mc["depth_median_ppm"] - res.depth_leastsq_ppm) < 0.2 * res.depth_err_jacobian_ppm
    # posterior width and Jacobian error agree (linear-Gaussian problem) within 20 %
    assert res.depth_err_mcmc_ppm == pytest.approx(res.depth_err_jacobian_ppm, rel=0.2)
    assert res.to_dict()["mcmc_converged"] is True


def test_same_seed_same_chain_different_seed_different(polygain, small_table):
    opts = ReduceSection(phase="flat", sampler="mcmc", mcmc_walkers=8, mcmc_steps=100,
                         mcmc_block_steps=50, prayer_bead_shifts=0)
    a = reduce_epoch(small_table, polygain.name, options=opts, seed=3)
    b = reduce_epoch(small_table, polygain.name, options=opts, seed=3)
    c = reduce_epoch(small_table, polygain.name, options=opts, seed=4)
    assert a.to_dict() == b.to_dict()
    assert a.mcmc["depth_median_ppm"] != c.mcmc["depth_median_ppm"]
    assert not a.mcmc["converged"]  # 100 steps cannot be 50 tau


def test_the_chain_is_emcees_own_without_the_state_copies(monkeypatch, polygain, small_table):
    """The sampler that keeps no copy of its generator's state in each step's State draws
    what emcee's own does, over several blocks (issue 40: 39 us a step saved)."""
    import emcee

    from eclipsebench.fit import mcmc

    steps = []
    original = mcmc._sampler_class()

    class Counting(original):
        def run_mcmc(self, state, n, **kw):
            out = super().run_mcmc(state, n, **kw)
            steps.append(out.random_state)
            return out

    opts = ReduceSection(phase="flat", sampler="mcmc", mcmc_walkers=8, mcmc_steps=300,
                         mcmc_block_steps=50, prayer_bead_shifts=0)
    monkeypatch.setattr(mcmc, "_sampler_class", lambda: Counting)
    ours = reduce_epoch(small_table, polygain.name, options=opts, seed=3)
    assert len(steps) == 6 and all(s is None for s in steps)   # no state carried
    monkeypatch.setattr(mcmc, "_sampler_class", lambda: emcee.EnsembleSampler)
    theirs = reduce_epoch(small_table, polygain.name, options=opts, seed=3)
    assert ours.to_dict() == theirs.to_dict()


def test_stretch_move_when_the_method_prefers_it(monkeypatch, polygain, small_table):
    class DePoly(polygain):
        name: ClassVar[str] = "test-polygain-stretch"
        record: ClassVar[MethodRecord] = MethodRecord(
            policy=FitterPolicy(preferred_move="stretch"))

    monkeypatch.setitem(base._REGISTRY, DePoly.name, DePoly)
    opts = ReduceSection(phase="flat", sampler="mcmc", mcmc_walkers=16, mcmc_steps=2000,
                         mcmc_block_steps=500, prayer_bead_shifts=0)
    res = reduce_epoch(small_table, DePoly.name, options=opts, seed=1)
    assert res.mcmc["move"] == "stretch"
    assert res.depth_err_mcmc_ppm == pytest.approx(res.depth_err_jacobian_ppm, rel=0.25)
    assert np.isfinite(res.mcmc["tau_max"])


# ---------------------------------------------------------------- the batched likelihood seam
def _psf_epoch(n=900, seed=11):
    """A small epoch with 5x5 Gaussian-PSF stamps through a smooth gain (every method's input)."""
    from scipy.special import erf

    from eclipsebench.decorrelate.base import EpochData

    g = np.random.default_rng(seed)
    time = 57000.0 + np.arange(n) * 20.0 / 86400.0
    t = time - time[0]
    x = 15.05 + 0.05 * np.sin(2 * np.pi * t / 0.028) + 0.1 * t + 0.01 * g.standard_normal(n)
    y = 14.98 + 0.04 * np.cos(2 * np.pi * t / 0.021) - 0.1 * t + 0.01 * g.standard_normal(n)
    dx, dy = x - 15.0, y - 15.0
    gain = 1.0 + 0.03 * dx - 0.02 * dy - 0.6 * dx**2 - 0.4 * dy**2
    total = 1e5 * gain * (1.0 + 1e-3 * g.standard_normal(n))
    edges = np.arange(13, 18)[None, :]
    s = 0.55 * np.sqrt(2)
    fx = 0.5 * (erf((edges + 0.5 - x[:, None]) / s) - erf((edges - 0.5 - x[:, None]) / s))
    fy = 0.5 * (erf((edges + 0.5 - y[:, None]) / s) - erf((edges - 0.5 - y[:, None]) / s))
    pix = total[:, None, None] * fy[:, :, None] * fx[:, None, :]
    flux = pix.sum(axis=(1, 2))
    return EpochData(time_bmjd=time, flux=flux, flux_err=np.full(n, 100.0), x=x, y=y,
                     noise_pixels=7.0 + 0.1 * np.sin(50 * time), pixels=pix.reshape(n, 25),
                     aorkey=np.full(n, 1), width_x=0.6 + 0.01 * np.sin(40 * time),
                     width_y=0.6 + 0.01 * np.cos(30 * time))


def _calibration(seed=12):
    from eclipsebench.decorrelate.pmap import CalibrationSet

    g = np.random.default_rng(seed)
    x, y = g.uniform(14.8, 15.4, 20000), g.uniform(14.7, 15.3, 20000)
    dx, dy = x - 15.0, y - 15.0
    flux = 5e4 * (1.0 + 0.03 * dx - 0.02 * dy - 0.6 * dx**2 - 0.4 * dy**2)
    return CalibrationSet(x=x, y=y, noise_pixels=7.0 + 0.05 * g.standard_normal(20000),
                          flux=flux, flux_err=np.sqrt(flux), source="test")


@pytest.fixture(scope="module")
def psf_epoch():
    return _psf_epoch()


def _method_options(name):
    return {"pld": {"bin_frames": 4}, "pld-aper": {"bin_frames": 4, "psf_width": True},
            "poly2": {"bin_frames": 16}, "poly3": {"bin_frames": 1}, "poly4": {"bin_frames": 8},
            "poly5": {"bin_frames": 8}, "bliss": {"knot_spacing_px": 0.03},
            "kr-pmap": {"use_noise_pixels": False, "min_occupancy": 0.0}}.get(name, {})


@pytest.mark.parametrize("name", base.available_methods())
def test_batch_likelihood_equals_the_loop(name, psf_epoch):
    """Every method's log_likelihood_batch returns log_likelihood of each row (to rounding)."""
    from eclipsebench.astro.catalogue import get_system
    from eclipsebench.fit.model import AstroModel

    cls = base.get_method(name)
    model = cls.build(psf_epoch, seed=1,
                      resources={"pmap": _calibration()} if "pmap" in cls.resources else None,
                      **_method_options(name))
    t = model.data.time_bmjd
    astro_model = AstroModel(t, get_system("XO-3b"), phase="quadratic",
                             shape=_ShiftedShape(t))
    g = np.random.default_rng(3)
    theta = astro_model.initial(depth=2e-3, t_event_bmjd=float(np.median(t)))
    thetas = theta + np.column_stack([3e-4 * g.standard_normal(6), 2e-3 * g.standard_normal(6),
                                      1e-3 * g.standard_normal((6, 2))])
    astro = astro_model.batch(thetas)
    n_sys = len(model.param_names)
    theta_s = 0.01 * g.standard_normal((6, n_sys)) if n_sys else None
    loop = [model.log_likelihood(a, None if theta_s is None else theta_s[i], noise_scale=1.3)
            for i, a in enumerate(astro)]
    batch = model.log_likelihood_batch(astro, theta_s, noise_scale=1.3)
    assert batch.shape == (6,)
    np.testing.assert_allclose(batch, loop, rtol=1e-11, atol=1e-6)


class _ShiftedShape:
    """A trapezoid eclipse that depends on t - t_ecl only (not an EclipseShape: the loop path)."""

    def __init__(self, time):
        self.time = np.asarray(time, float)

    def visible_fraction(self, t_ecl):
        return np.clip((np.abs(self.time - t_ecl) - 0.045) / 0.012, 0.0, 1.0)


def test_a_subclass_that_redefines_predict_gets_the_loop(psf_epoch):
    from eclipsebench.decorrelate.bliss import Bliss

    class Doubled(Bliss):
        name: ClassVar[str] = "test-doubled"

        def predict(self, astro, theta=None):
            return 2.0 * super().predict(astro, theta)

    model = Doubled(psf_epoch, knot_spacing_px=0.03)
    astro = np.vstack([np.ones(len(model.data)), np.full(len(model.data), 1.001)])
    np.testing.assert_allclose(model.log_likelihood_batch(astro),
                               [model.log_likelihood(a) for a in astro], rtol=1e-12)


@pytest.mark.parametrize("shape", ["physical", "box"])
@pytest.mark.parametrize("phase", ["flat", "linear", "quadratic", "sinusoid"])
@pytest.mark.parametrize("ramp", ["none", "linear", "exponential"])
def test_astro_batch_is_the_model_of_each_row(xo3_epoch, shape, phase, ramp):
    from eclipsebench.fit.model import AstroModel

    time = xo3_epoch["time"][::4]
    model = AstroModel(time, xo3_epoch["system"], phase=phase, ramp=ramp, eclipse_shape=shape)
    g = np.random.default_rng(8)
    thetas = np.tile(model.initial(t_event_bmjd=xo3_epoch["t_true"]), (5, 1))
    thetas[:, 0] += 1e-4 * g.standard_normal(5)
    thetas[:, 1] += 3e-3 * g.standard_normal(5)
    thetas[:, 2:] += 1e-3 * np.abs(g.standard_normal((5, thetas.shape[1] - 2)))
    thetas[0, 1] = time[3]             # eclipse at the first frames
    thetas[1, 1] = time[len(time) // 2]  # centre exactly on a frame
    batch = model.batch(thetas)
    assert np.array_equal(batch, np.stack([model(th) for th in thetas]))


@pytest.mark.parametrize("phase", ["flat", "quadratic"])
@pytest.mark.parametrize("ramp", ["none", "linear"])
@pytest.mark.parametrize("order", ["sorted", "shuffled"])
def test_astro_batch_at_the_tables_ends_and_in_any_order(xo3_epoch, phase, ramp, order):
    """The compiled batch's two-pass form (times in order: bisection for the table's
    frames) and its one-loop form (times in any order) give each row's model exactly,
    with the eclipse's table ending on a frame, beyond the data or at no finite time."""
    from eclipsebench.fit.model import AstroModel

    time = np.array(xo3_epoch["time"][::4], dtype=float)
    if order == "shuffled":
        time = np.random.default_rng(3).permutation(time)
    model = AstroModel(time, xo3_epoch["system"], phase=phase, ramp=ramp)
    thetas = np.tile(model.initial(t_event_bmjd=xo3_epoch["t_true"]), (6, 1))
    thetas[:, 2:] += 1e-3
    xp = model.shape._offset
    t_sorted = np.sort(time)
    thetas[0, 1] = t_sorted[0] - xp[0]     # the table starts on the first frame
    thetas[1, 1] = t_sorted[-1] - xp[-1]   # and ends on the last one
    thetas[2, 1] = t_sorted[40] - xp[7]    # a frame on a table point
    thetas[3, 1] = t_sorted[0] - 0.2       # the eclipse before the data
    thetas[4, 1] = t_sorted[-1] + 0.2      # and after them
    batch = model.batch(thetas)
    assert model._eclipse.time_ordered is (order == "sorted")
    assert np.array_equal(batch, np.stack([model(th) for th in thetas]))
    thetas[5, 1] = np.nan                  # the one-loop form: NaN wherever the shape is asked
    rows = model.batch(thetas)
    assert np.array_equal(rows[:5], batch[:5]) and np.all(np.isnan(rows[5]))


def test_chain_is_fifty_tau_long_after_burn_in(polygain, small_table):
    res = reduce_epoch(small_table, polygain.name, options=MCMC, seed=7)
    mc = res.mcmc
    assert mc["converged"]
    assert mc["steps"] - mc["burn_in"] > 50 * mc["tau_max"]
    assert mc["burn_in"] >= 2 * mc["tau_max"] - 1
