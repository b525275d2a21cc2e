"""AstroModel: p(t_ecl) = D for every phase model, ramps, box eclipse, parameter names."""

from __future__ import annotations

import numpy as np
import pytest

from eclipsebench.errors import InputError
from eclipsebench.fit.model import AstroModel, box_visible_fraction

TIME = 57000.0 + np.linspace(0.0, 0.3, 3001)
T_ECL = 57000.16


@pytest.fixture
def shape(kit):
    return lambda: kit.TrapezoidShape(TIME, duration_d=0.12, ingress_d=0.015)


@pytest.mark.parametrize("phase,coefs", [("flat", []), ("linear", [0.01]),
                                         ("quadratic", [0.01, -0.2]),
                                         ("sinusoid", [3e-4, -2e-4])])
def test_phase_models_match_their_formulas(phase, coefs, shape):
    period = 3.19
    m = AstroModel(TIME, None, phase=phase, shape=shape(), period_d=period)
    depth = 2e-3
    theta = np.array([depth, T_ECL] + coefs)
    dt = TIME - T_ECL
    if phase == "flat":
        p = np.full_like(dt, depth)
    elif phase == "linear":
        p = depth + coefs[0] * dt
    elif phase == "quadratic":
        p = depth + coefs[0] * dt + coefs[1] * dt**2
    else:
        arg = 2 * np.pi * dt / period
        p = depth + coefs[0] * (np.cos(arg) - 1) + coefs[1] * np.sin(arg)
    v = shape().visible_fraction(T_ECL)
    assert np.allclose(m(theta), 1.0 + v * p, rtol=0, atol=1e-15)
    # p(t_ecl) = D exactly: the paper's depth relative to the in-eclipse (stellar) flux
    i = np.argmin(np.abs(dt))
    assert m.planet(theta)[i] == pytest.approx(depth + (p[i] - depth), abs=1e-15)
    assert abs(p[i] - depth) < 1e-5
    assert m.names[:2] == ("depth", "t_ecl_bmjd") and len(m.names) == 2 + len(coefs)
    assert np.all(m(theta)[np.abs(dt) < 0.04] == 1.0)  # totality: the star alone


def test_ramps_multiply_the_model(shape):
    lin = AstroModel(TIME, None, phase="flat", ramp="linear", shape=shape())
    theta = np.array([1e-3, T_ECL, 0.02])
    v = shape().visible_fraction(T_ECL)
    assert np.allclose(lin(theta), (1 + 0.02 * (TIME - TIME[0])) * (1 + 1e-3 * v))
    exp = AstroModel(TIME, None, phase="flat", ramp="exponential", shape=shape())
    assert exp.names[-2:] == ("ramp_amplitude", "ramp_tau_days")
    theta = np.array([1e-3, T_ECL, 0.003, 0.02])
    assert np.allclose(exp(theta), (1 - 0.003 * np.exp(-(TIME - TIME[0]) / 0.02)) * (1 + 1e-3 * v))
    lo, hi = exp.bounds
    assert lo[1] == TIME[0] and hi[1] == TIME[-1] and lo[-1] > 0


def test_box_has_the_half_depth_duration_of_the_physical_shape(shape):
    m = AstroModel(TIME, None, phase="flat", eclipse_shape="box", shape=shape())
    # trapezoid: v = 0.5 at |dt| = duration/2 - ingress/2
    assert m.box_duration_d == pytest.approx(0.12 - 0.015, abs=2e-4)
    v = m.visible_fraction(T_ECL)
    assert np.all(v[np.abs(TIME - T_ECL) < 0.05] == 0.0)
    assert np.all(v[np.abs(TIME - T_ECL) > 0.055] == 1.0)
    # the box removes the same planet flux as the trapezoid
    assert np.sum(1 - v) == pytest.approx(np.sum(1 - shape().visible_fraction(T_ECL)), rel=0.01)


def test_box_is_continuous_within_a_frame():
    t = np.arange(10.0)
    v1 = box_visible_fraction(t, 4.5, 4.0, 1.0)
    v2 = box_visible_fraction(t, 4.6, 4.0, 1.0)
    assert 0 < np.sum(np.abs(v2 - v1)) < 0.5


def test_bad_options_are_named(shape):
    with pytest.raises(InputError, match="--phase 'cubic'"):
        AstroModel(TIME, None, phase="cubic", shape=shape())
    with pytest.raises(InputError, match="--ramp"):
        AstroModel(TIME, None, ramp="log", shape=shape())
    with pytest.raises(InputError, match="period"):
        AstroModel(TIME, None, phase="sinusoid", shape=shape())
    m = AstroModel(TIME, None, phase="flat", shape=shape())
    with pytest.raises(InputError, match="outside the data"):
        m.initial(t_event_bmjd=56999.0)


def test_box_duration_of_a_real_system_even_from_a_short_span():
    from eclipsebench.astro.catalogue import get_system
    from eclipsebench.astro.eclipse import EclipseShape
    from eclipsebench.astro.orbit import eclipse_time_bmjd

    system = get_system("XO-3b")
    t_ecl = eclipse_time_bmjd(system, 57000.0)
    fine = t_ecl + np.arange(-0.1, 0.1, 0.5 / 86400)
    v = EclipseShape(fine, system).visible_fraction(t_ecl)
    expected = np.ptp(fine[v < 0.5])
    short = t_ecl + np.linspace(-0.03, 0.03, 200)  # shorter than the eclipse
    m = AstroModel(short, system, phase="flat", eclipse_shape="box")
    assert m.box_duration_d == pytest.approx(expected, abs=2 / 86400)


def test_the_model_is_one_class_per_event_built_by_astro_model(shape):
    """Issue 27: AstroModel(...) builds the event's subclass; each subclass stands alone."""
    import pickle

    from eclipsebench.astro.catalogue import get_system
    from eclipsebench.fit.model import (
        PHASE_CURVE_MODELS,
        PHASE_MODELS,
        RAMP_MODELS,
        EclipseModel,
        PhaseCurveModel,
        TransitModel,
    )
    from eclipsebench.fit.model.parts import PHASE_TERMS, RAMPS

    # every name the command line offers has its phase term or ramp
    assert set(PHASE_TERMS) == set(PHASE_MODELS) | set(PHASE_CURVE_MODELS)
    assert set(RAMPS) == set(RAMP_MODELS)
    system = get_system("XO-3b")
    for event, cls, phase in (("eclipse", EclipseModel, "flat"),
                              ("transit", TransitModel, "flat"),
                              ("phase-curve", PhaseCurveModel, "harmonic1")):
        m = AstroModel(TIME, system, event=event, phase=phase, ramp="linear")
        assert type(m) is cls and isinstance(m, AstroModel) and m.event == event
        direct = cls(TIME, system, phase=phase, ramp="linear")
        theta = m.initial()
        assert np.array_equal(direct(theta), m(theta))
        copy = pickle.loads(pickle.dumps(m))
        assert type(copy) is cls and np.array_equal(copy(theta), m(theta))
    assert type(AstroModel(TIME, None, phase="flat", shape=shape())) is EclipseModel
    with pytest.raises(InputError, match="TransitModel models event 'transit'"):
        TransitModel(TIME, system, event="eclipse")
    with pytest.raises(InputError, match="--event 'occultation'"):
        AstroModel(TIME, system, event="occultation")
