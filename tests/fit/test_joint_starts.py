"""reduce_joint started from the epochs' own reductions (``starts=``): the same answer, without
fitting each epoch alone again; a start that is not that fit is not used (issue 38, speed)."""

from __future__ import annotations

import json
from dataclasses import replace

import pytest

from eclipsebench.config.reduce import ReduceSection
from eclipsebench.fit import joint as fit_joint
from eclipsebench.fit.reduce import reduce_epoch, reduce_joint
from eclipsebench.fit.result import EpochResult
from eclipsebench.io.atomic import write_json

LSQ = ReduceSection(phase="quadratic", sampler="leastsq", prayer_bead_shifts=0)


@pytest.fixture
def epochs(polygain, xo3_epoch, tmp_path):
    """Two synthetic epochs and their reductions, written and read back from their JSON
    (its keys sorted: ``params`` no longer in the fit's order) as a campaign reads them."""
    tables = [xo3_epoch["table"](seed=21), xo3_epoch["table"](seed=22)]
    done = [reduce_epoch(t, polygain.name, options=LSQ, epoch=e, seed=4)
            for e, t in zip((1, 2), tables, strict=True)]
    back = []
    for r in done:
        write_json(tmp_path / f"epoch_{r.epoch}.json", r.to_dict())
        back.append(EpochResult.from_dict(json.loads((tmp_path / f"epoch_{r.epoch}.json")
                                                     .read_text())))
    assert list(back[0].params) != list(done[0].params)   # the order the JSON gives
    return tables, back


def _count_fits_alone(monkeypatch) -> list[int]:
    calls: list[int] = []
    real = fit_joint.fit_leastsq

    def counted(*args, **kwargs):
        calls.append(1)
        return real(*args, **kwargs)

    monkeypatch.setattr(fit_joint, "fit_leastsq", counted)
    return calls


def test_a_joint_fit_from_the_epochs_reductions_fits_none_alone_and_answers_the_same(
        epochs, polygain, monkeypatch):
    tables, results = epochs
    calls = _count_fits_alone(monkeypatch)
    alone = reduce_joint(tables, polygain.name, options=LSQ, epochs=[1, 2], seed=4)
    assert len(calls) == 2
    seeded = reduce_joint(tables, polygain.name, options=LSQ, epochs=[1, 2], seed=4,
                          starts=results)
    assert len(calls) == 2          # no epoch fitted alone again
    # the reductions' least-squares solution is the fit alone to the bit, so the joint
    # fit starts from the same point and ends at the same one
    assert seeded == alone
    for e, r in zip(seeded.per_epoch, results, strict=True):
        assert e["depth_alone_ppm"] == r.depth_leastsq_ppm


@pytest.mark.parametrize("change", ["mcmc", "phase", "seed", "epoch", "method_options",
                                    "hyperparameters"])
def test_a_start_that_is_not_the_fit_alone_is_not_used(epochs, polygain, monkeypatch, change):
    """A reduction sampled by MCMC (its errors are the posterior's), with another phase
    model, seed, epoch number or method options is not the joint's fit alone: that epoch
    is fitted alone again, and the answer is the unseeded one. Nor is any result of a
    method with maximum-likelihood settings (GP, PLD, SegPoly): its fit alone leaves them
    on the method for the joint fit, and a result does not record them."""
    tables, results = epochs
    other = results[1]
    if change == "hyperparameters":
        monkeypatch.setattr(polygain, "optimise_hyperparameters", lambda self, astro: None)
        calls = _count_fits_alone(monkeypatch)
        seeded = reduce_joint(tables, polygain.name, options=LSQ, epochs=[1, 2], seed=4,
                              starts=results)
        assert len(calls) == 2
        assert seeded == reduce_joint(tables, polygain.name, options=LSQ, epochs=[1, 2], seed=4)
        return
    if change == "mcmc":
        other = replace(other, sampler="mcmc")
    elif change == "phase":
        other = replace(other, phase="linear")
    elif change == "seed":
        other = replace(other, seed=5)
    elif change == "epoch":
        other = replace(other, epoch=7)
    else:
        other = replace(other, options={**other.options, "extra": 1})
    calls = _count_fits_alone(monkeypatch)
    seeded = reduce_joint(tables, polygain.name, options=LSQ, epochs=[1, 2], seed=4,
                          starts=[results[0], other])
    assert len(calls) == 1          # epoch 2 only
    assert seeded == reduce_joint(tables, polygain.name, options=LSQ, epochs=[1, 2], seed=4)


def test_one_start_per_table(epochs, polygain):
    from eclipsebench.errors import InputError

    tables, results = epochs
    with pytest.raises(InputError, match="one start"):
        reduce_joint(tables, polygain.name, options=LSQ, epochs=[1, 2], starts=results[:1])
