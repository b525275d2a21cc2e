"""Every registered systematics method through the same interface tests.

The test walks the registry, so a method added later (gp, ica, segpoly, ...)
is tested as soon as its module registers itself: output shape, finite
values, inputs left unchanged, a real reduction of the scatter on simulated
pointing systematics, and a one-line InputError when a column it needs is
missing.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from eclipsebench.decorrelate import available_methods, get_method
from eclipsebench.decorrelate.base import EpochData, Systematics
from eclipsebench.errors import InputError

METHODS = available_methods()
ARRAY_FIELDS = ("time_bmjd", "flux", "flux_err", "x", "y", "noise_pixels", "pixels", "aorkey")


def _snapshot(data: EpochData) -> dict:
    return {f: None if getattr(data, f) is None else np.array(getattr(data, f), copy=True)
            for f in ARRAY_FIELDS}


def test_the_four_first_methods_are_registered():
    assert {"bliss", "kr-data", "kr-pmap", "pld"} <= set(METHODS)


def test_unknown_method_is_an_input_error():
    with pytest.raises(InputError, match="unknown method"):
        get_method("no-such-method")


@pytest.mark.parametrize("name", METHODS)
def test_class_declares_its_pieces(name):
    cls = get_method(name)
    assert issubclass(cls, Systematics)
    assert cls.name == name
    assert cls.requires, "a method must name the columns it needs"
    assert all(r in ARRAY_FIELDS for r in cls.requires)
    assert cls.description
    assert cls.__doc__


@pytest.fixture(scope="module")
def built(epoch_small):
    """One instance per method on the systematics epoch, with input snapshots."""
    out = {}
    for name in METHODS:
        before = _snapshot(epoch_small.data)
        model = get_method(name).build(epoch_small.data)
        out[name] = (model, before)
    return out


@pytest.mark.parametrize("name", METHODS)
def test_predict_shape_finite_and_inputs_unchanged(name, built, epoch_small, synth):
    model, before = built[name]
    flux, astro_kept = synth.kept_frames(model, epoch_small)
    astro = astro_kept.copy()
    theta = model.initial_params()
    pred = model.predict(astro, theta)
    assert pred.shape == flux.shape
    assert np.all(np.isfinite(pred))
    np.testing.assert_array_equal(astro, astro_kept)
    after = _snapshot(epoch_small.data)
    for f in ARRAY_FIELDS:
        if before[f] is None:
            assert after[f] is None
        else:
            np.testing.assert_array_equal(after[f], before[f], err_msg=f"{name} modified {f}")
    # Deterministic: the same call gives the same numbers.
    np.testing.assert_array_equal(model.predict(astro, theta), pred)
    corrected = model.correct(astro, theta)
    assert corrected.shape == pred.shape and np.all(np.isfinite(corrected))
    assert isinstance(model.n_effective_params(), int) and model.n_effective_params() >= 0
    assert np.isfinite(model.log_likelihood(astro, theta))


@pytest.mark.parametrize("name", METHODS)
def test_scatter_is_reduced_on_simulated_systematics(name, built, epoch_small, synth):
    model, _ = built[name]
    flux, astro = synth.kept_frames(model, epoch_small)
    raw = flux / astro
    raw_rms = np.std(raw / np.mean(raw))
    resid = (flux - model.predict(astro, model.initial_params())) / flux
    assert raw_rms > 5e-4        # the simulated systematics are really there
    assert np.std(resid) < 0.5 * raw_rms, f"{name}: rms {np.std(resid):.2e} vs raw {raw_rms:.2e}"


@pytest.mark.parametrize("name", METHODS)
def test_missing_required_column_is_one_line_input_error(name, epoch_small):
    cls = get_method(name)
    for column in cls.requires:
        data = dataclasses.replace(epoch_small.data, **{column: None})
        with pytest.raises(InputError) as info:
            cls(data)
        message = str(info.value)
        assert "\n" not in message and column in message
