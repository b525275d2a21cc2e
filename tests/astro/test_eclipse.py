"""Eclipse and transit shapes: the centre lands where asked, agreement with batman, batman run once per shape."""

from __future__ import annotations

import batman
import numpy as np
import pytest

from eclipsebench.astro import orbit
from eclipsebench.astro.catalogue import get_system
from eclipsebench.astro.eclipse import EclipseShape, TransitShape

XO3B = get_system("XO-3b")
T_ECL = orbit.eclipse_time_bmjd(XO3B, 57234.5)
T_FINE = T_ECL + np.arange(-3 * 3600, 3 * 3600, 0.5) / 86400  # 0.5 s cadence


def _centre(t, shape):
    """Midpoint between first and last contact (where the shape leaves 1)."""
    inside = np.flatnonzero(shape < 1.0 - 1e-12)
    return 0.5 * (t[inside[0]] + t[inside[-1]])


@pytest.mark.parametrize("shift_s", [0.0, 123.4, -1000.0])
def test_eclipse_centre_lands_on_the_time_asked_for(shift_s):
    t_ecl = T_ECL + shift_s / 86400
    vis = EclipseShape(T_FINE, XO3B).visible_fraction(t_ecl)
    assert vis.min() == 0.0 and vis.max() == 1.0 and np.all((vis >= 0) & (vis <= 1))
    # t_ecl is the minimum of the sky-projected separation; the planet speeds up
    # towards periastron during the eclipse, so the contact midpoints trail it by 1.5 s
    assert abs(_centre(T_FINE, vis) - t_ecl) * 86400 < 2.0
    total = T_FINE[vis == 0.0]
    assert abs(0.5 * (total[0] + total[-1]) - t_ecl) * 86400 < 2.0
    assert np.interp(t_ecl, T_FINE, vis) == 0.0


def test_batman_t_secondary_is_the_conjunction_not_the_centre():
    """The gotcha the class corrects: batman centres nothing on ``t_secondary``."""
    p = batman.TransitParams()
    p.t0 = p.t_secondary = T_ECL
    p.per, p.rp, p.a, p.inc = XO3B.period_days, XO3B.rp_rs, XO3B.a_rs, XO3B.inc_deg
    p.ecc, p.w, p.u, p.limb_dark, p.fp = XO3B.ecc, XO3B.omega_deg, [], "uniform", 1.0
    raw = batman.TransitModel(p, T_FINE, transittype="secondary").light_curve(p) - 1.0
    offset_s = (_centre(T_FINE, raw) - T_ECL) * 86400
    assert offset_s == pytest.approx(90.8 + 1.5, abs=1.5)  # conjunction -> centre, +1.5 s contacts


def test_matches_a_direct_batman_call_at_the_same_times():
    shape = EclipseShape(T_FINE, XO3B)
    ours = shape.visible_fraction(T_ECL)
    # direct: batman at the geometric conjunction that puts the centre at T_ECL
    t_geom = orbit.observed_to_geometric(T_FINE, XO3B)
    t_conj = orbit.observed_to_geometric(T_ECL, XO3B) + shape.t_conjunction_offset_days
    p = batman.TransitParams()
    p.t0 = p.t_secondary = t_conj
    p.per, p.rp, p.a, p.inc = XO3B.period_days, XO3B.rp_rs, XO3B.a_rs, XO3B.inc_deg
    p.ecc, p.w, p.u, p.limb_dark, p.fp = XO3B.ecc, XO3B.omega_deg, [], "uniform", 1.0
    direct = batman.TransitModel(p, t_geom, transittype="secondary").light_curve(p) - 1.0
    assert np.abs(ours - direct).max() < 1e-5


def test_periodic_and_outside_is_one():
    t = np.concatenate([T_FINE, T_FINE + 5 * XO3B.period_days])
    vis = EclipseShape(t, XO3B).visible_fraction(T_ECL)
    assert np.allclose(vis[: T_FINE.size], vis[T_FINE.size:], atol=1e-9)
    far = EclipseShape(T_ECL + np.array([0.3, 1.0, -1.2]), XO3B).visible_fraction(T_ECL)
    assert np.all(far == 1.0)


def test_cheap_to_call_inside_a_fit(monkeypatch):
    """batman runs once, when the shape is built; a call in the fit's loop only interpolates
    (the speed itself is bench/bench_lightcurve.py's, not a timed test)."""
    t = 57234.3406 + np.arange(0, 8.8 * 3600, 2.008) / 86400
    shape = EclipseShape(t, XO3B)
    before = [shape.visible_fraction(T_ECL + k * 1e-4) for k in range(3)]
    monkeypatch.setattr(EclipseShape, "_batman",
                        lambda *a: pytest.fail("batman called again inside the loop"))
    for k in range(1000):
        shape.visible_fraction(T_ECL + k * 1e-6)
    after = [shape.visible_fraction(T_ECL + k * 1e-4) for k in range(3)]
    assert all(np.array_equal(a, b) for a, b in zip(before, after, strict=True))


def test_transit_shape_quadratic_limb_darkening():
    t_tr = XO3B.t_transit_bmjd
    t = t_tr + np.arange(-3 * 3600, 3 * 3600, 1.0) / 86400
    flux = TransitShape(t, XO3B).flux(t_tr)
    assert flux.max() == 1.0
    assert abs(_centre(t, flux) - t_tr) * 86400 < 2.0
    k2 = XO3B.rp_rs ** 2
    # limb darkening makes the centre deeper than k^2 for this impact parameter (b = 0.70)
    assert 0.9 * k2 < 1.0 - flux.min() < 1.2 * k2
    uniform = TransitShape(t, XO3B, limb_dark="uniform").flux(t_tr)
    assert 1.0 - uniform.min() == pytest.approx(k2, rel=1e-4)
    nonlinear = TransitShape(t, XO3B, limb_dark="nonlinear", u=[0.5, -0.2, 0.3, -0.1]).flux(t_tr)
    assert nonlinear.min() < 1.0
    with pytest.raises(ValueError):
        TransitShape(t, XO3B, limb_dark="quadratic", u=[0.1])
