"""MCMC (emcee) against least squares, seeding, and the method's preferred move."""

from __future__ import annotations

from typing import ClassVar

import numpy as np
import pytest

from eclipsebench.config.reduce import ReduceSection
from eclipsebench.decorrelate import base
from eclipsebench.fit.reduce import reduce_epoch

MCMC = ReduceSection(phase="flat", sampler="mcmc", mcmc_walkers=16, mcmc_steps=3000,
                     mcmc_block_steps=500, prayer_bead_shifts=0)


@pytest.fixture(scope="module")
def small_table(xo3_epoch):
    return xo3_epoch["table"](seed=5)[::8]


def test_mcmc_agrees_with_least_squares(polygain, small_table):
    res = reduce_epoch(small_table, polygain.name, options=MCMC, seed=7)
    mc = res.mcmc
    assert mc["move"] == "stretch" and mc["converged"]
    assert mc["steps"] > 50 * mc["tau_max"]
    assert 0.15 < mc["acceptance"] < 0.8
    # posterior median within a fifth of a sigma of the maximum likelihood
    assert abs(res.depth_ppm - res.depth_leastsq_ppm) < 0.2 * res.depth_err_jacobian_ppm
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
    assert a.depth_ppm != c.depth_ppm
    assert not a.mcmc["converged"]  # 100 steps cannot be 50 tau


def test_de_move_when_the_method_prefers_it(monkeypatch, polygain, small_table):
    class DePoly(polygain):
        name: ClassVar[str] = "test-polygain-de"
        preferred_move: ClassVar[str] = "de"

    monkeypatch.setitem(base._REGISTRY, DePoly.name, DePoly)
    opts = ReduceSection(phase="flat", sampler="mcmc", mcmc_walkers=16, mcmc_steps=2000,
                         mcmc_block_steps=500, prayer_bead_shifts=0)
    res = reduce_epoch(small_table, DePoly.name, options=opts, seed=1)
    assert res.mcmc["move"] == "de"
    assert res.depth_err_mcmc_ppm == pytest.approx(res.depth_err_jacobian_ppm, rel=0.25)
    assert np.isfinite(res.mcmc["tau_max"])
