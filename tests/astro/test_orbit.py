"""Kepler's equation, event times (with light-travel time) and time scales."""

from __future__ import annotations

import dataclasses
import math

import batman
import numpy as np
import pytest

from eclipsebench.astro import orbit
from eclipsebench.astro.catalogue import get_system


def test_kepler_residual_below_1e12_over_the_grid():
    ecc = np.linspace(0.0, 0.95, 96)[:, None]
    m = np.linspace(0.0, 2 * np.pi, 4001, endpoint=False)[None, :]
    big_e = orbit.solve_kepler(m, ecc)
    resid = np.abs(big_e - ecc * np.sin(big_e) - m)
    assert resid.max() < 1e-12


def test_kepler_other_branches_and_scalars():
    m = np.array([-20.0, -np.pi, 7.5, 100.0])
    big_e = orbit.solve_kepler(m, 0.9)
    assert np.abs(big_e - 0.9 * np.sin(big_e) - m).max() < 1e-12
    assert isinstance(orbit.solve_kepler(1.0, 0.3), float)
    with pytest.raises(ValueError):
        orbit.solve_kepler(1.0, 1.0)


def test_true_anomaly_round_trip():
    f = np.linspace(-3.1, 3.1, 101)
    for e in (0.0, 0.3, 0.9):
        m = orbit.mean_anomaly_from_true(f, e)
        back = orbit.eccentric_to_true(orbit.solve_kepler(m, e), e)
        assert np.allclose(back, f, atol=1e-12)


def test_catalogue_transit_is_returned_exactly():
    s = get_system("XO-3b")
    assert orbit.transit_time_bmjd(s, s.t_transit_bmjd) == pytest.approx(s.t_transit_bmjd,
                                                                          abs=1e-9)
    later = orbit.transit_time_bmjd(s, s.t_transit_bmjd + 100 * s.period_days + 0.3)
    assert later == pytest.approx(s.t_transit_bmjd + 100 * s.period_days, abs=1e-9)


def _circular(name="HD 209458b", **kw):
    return dataclasses.replace(get_system(name), ecc=0.0, **kw)


def test_circular_eclipse_half_a_period_after_transit_plus_light_time():
    s = _circular()
    t_tr = orbit.transit_time_bmjd(s, s.t_transit_bmjd)
    t_ecl = orbit.eclipse_time_bmjd(s, t_tr + 0.5 * s.period_days)
    light = 2 * s.a_rs * math.sin(math.radians(s.inc_deg)) * s.r_star_rsun / orbit.C_RSUN_PER_DAY
    assert t_ecl - t_tr - 0.5 * s.period_days == pytest.approx(light, abs=1e-9)
    # and exactly half a period for a point-like star (no light-travel time)
    tiny = dataclasses.replace(s, r_star_rsun=1e-9)
    t_tr = orbit.transit_time_bmjd(tiny, tiny.t_transit_bmjd)
    assert orbit.eclipse_time_bmjd(tiny, t_tr + 1.0) - t_tr == pytest.approx(
        0.5 * s.period_days, abs=1e-9)


def test_xo3b_eclipse_offset_matches_e_cos_omega_to_first_order():
    s = get_system("XO-3b")
    t_tr = orbit.transit_time_bmjd(s, s.t_transit_bmjd)
    offset = orbit.eclipse_time_bmjd(s, t_tr + 1.6) - t_tr - 0.5 * s.period_days
    first_order = 2 * s.period_days / math.pi * s.ecc * math.cos(math.radians(s.omega_deg))
    assert offset == pytest.approx(0.54593, abs=2e-5)
    assert abs(offset - first_order) / first_order < 0.01  # 0.5 %: the O(e^2) terms


def test_conjunctions_agree_with_batman_and_light_time_is_added():
    s = get_system("XO-3b")
    t_tr = orbit.transit_time_bmjd(s, s.t_transit_bmjd, reference="conjunction")
    t_ecl = orbit.eclipse_time_bmjd(s, t_tr + 1.6, reference="conjunction")
    p = batman.TransitParams()
    p.t0, p.per, p.rp, p.a, p.inc = 0.0, s.period_days, s.rp_rs, s.a_rs, s.inc_deg
    p.ecc, p.w, p.u, p.limb_dark = s.ecc, s.omega_deg, [], "uniform"
    geometric = batman.TransitModel(p, np.zeros(1)).get_t_secondary(p) % s.period_days
    clock = s.clock
    f_tr, f_ecl = math.pi / 2 - clock.omega, 1.5 * math.pi - clock.omega
    light = (clock.radius(f_tr) + clock.radius(f_ecl)) * math.sin(clock.inc) \
        * s.r_star_rsun / orbit.C_RSUN_PER_DAY
    assert light * 86400 == pytest.approx(41.6, abs=0.2)
    assert t_ecl - t_tr == pytest.approx(geometric + light, abs=1e-9)


def test_mid_eclipse_follows_conjunction_by_90_s_for_xo3b():
    s = get_system("XO-3b")
    mid = orbit.eclipse_time_bmjd(s, 57234.5)
    conj = orbit.eclipse_time_bmjd(s, 57234.5, reference="conjunction")
    assert (mid - conj) * 86400 == pytest.approx(90.8, abs=1.0)


def test_time_scales_and_phase():
    assert orbit.bjd_to_bmjd(2457234.8406) == pytest.approx(57234.3406, abs=1e-9)
    assert orbit.bmjd_to_bjd(57234.3406) == pytest.approx(2457234.8406, abs=1e-9)
    assert orbit.jd2455000_to_bmjd(2234.8406) == pytest.approx(57234.3406, abs=1e-9)
    assert np.allclose(orbit.bjd_to_bmjd(np.array([2400000.5, 2400001.5])), [0.0, 1.0])
    s = get_system("XO-3b")
    assert orbit.orbital_phase(s.t_transit_bmjd, s) == pytest.approx(0.0, abs=1e-12)
    ph = orbit.orbital_phase(orbit.eclipse_time_bmjd(s, 57234.5), s)
    assert ph == pytest.approx(0.5 + 0.54593 / s.period_days, abs=1e-4)
    assert orbit.orbital_phase(orbit.eclipse_time_bmjd(s, 57234.5), s,
                               reference="eclipse") == pytest.approx(0.0, abs=1e-9)


def test_light_time_round_trip():
    s = get_system("XO-3b")
    t = 57234.0 + np.linspace(0, 3, 50)
    back = orbit.observed_to_geometric(orbit.geometric_to_observed(t, s), s)
    assert np.abs(back - t).max() < 1e-12


def test_separations():
    s = get_system("XO-3b")
    t = 57234.0 + np.linspace(0, 3.2, 200)
    r = orbit.separation(t, s)
    assert r.min() >= s.a_rs * (1 - s.ecc) - 1e-9 and r.max() <= s.a_rs * (1 + s.ecc) + 1e-9
    x, y, z = orbit.sky_coordinates(t, s)
    assert np.allclose(np.sqrt(x * x + y * y + z * z), r)
    assert np.allclose(orbit.sky_separation(t, s), np.hypot(x, y))
    # at mid-transit the sky separation is the impact parameter
    b = orbit.sky_separation(orbit.observed_to_geometric(s.t_transit_bmjd, s), s)
    assert b == pytest.approx(s.impact_parameter, rel=2e-3)
