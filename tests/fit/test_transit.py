"""Transits (issue 17 point 1): the model, its batch, priors, reduce --event transit.

The model is checked against ``batman.TransitModel`` itself and against the
simulator's transit (:class:`eclipsebench.astro.eclipse.TransitShape`); the
round trip fits a synthetic epoch whose flux is the simulator's L(t) (transit,
the planet's phase curve) times a known intra-pixel gain, with the test-only
PolyGain method (tests/fit/conftest.py). The pixel-level round trip is slow.
"""

from __future__ import annotations

import json
import math

import batman
import numpy as np
import pytest

from eclipsebench.astro.catalogue import get_system
from eclipsebench.astro.eclipse import TransitShape
from eclipsebench.astro.lightcurve import cached_light_curve
from eclipsebench.astro.orbit import transit_time_bmjd
from eclipsebench.config import load_config
from eclipsebench.config.reduce import ReduceSection
from eclipsebench.config.system import SystemSection
from eclipsebench.errors import ConfigError, InputError
from eclipsebench.fit.leastsq import _Problem
from eclipsebench.fit.model import AstroModel, TransitSettings, q_from_u, u_from_q
from eclipsebench.fit.reduce import reduce_epoch, reduce_joint

SYSTEM = get_system(SystemSection().name)   # the default planet (2015 challenge's XO-3b)
T_TR = transit_time_bmjd(SYSTEM, 57234.0)
TIME = T_TR - 0.16 + np.arange(0.0, 0.36, 4.0 / 86400.0)


def _batman(time, t0, rp, a_rs, inc, u):
    p = batman.TransitParams()
    p.t0, p.per, p.rp, p.a, p.inc = t0, SYSTEM.period_days, rp, a_rs, inc
    p.ecc, p.w, p.u, p.limb_dark = SYSTEM.ecc, SYSTEM.omega_deg, list(u), "quadratic"
    return batman.TransitModel(p, time).light_curve(p)


def test_kipping_q_and_u_invert_each_other():
    for u1, u2 in ((0.07, 0.15), (0.4, 0.25), (0.9, -0.1)):
        assert u_from_q(*q_from_u(u1, u2)) == pytest.approx((u1, u2), abs=1e-15)
    # the corners of Kipping's triangle: q1 = 0 is a uniform disc
    assert u_from_q(0.0, 0.3) == (0.0, 0.0)
    assert u_from_q(1.0, 0.0) == (0.0, 1.0) and u_from_q(1.0, 0.5) == (1.0, 0.0)


def test_the_transit_is_batmans_and_the_simulators():
    m = AstroModel(TIME, SYSTEM, phase="flat", event="transit")
    theta = m.initial(t_event_bmjd=T_TR + 0.001)
    assert m.names == ("rp_rs", "t_transit_bmjd")
    # batman's t0 is the conjunction: 138 s after this eccentric orbit's mid-transit
    offset = m.describe()["conjunction_minus_mid_transit_s"] / 86400.0
    assert offset * 86400.0 == pytest.approx(138.4, abs=0.1)
    ref = _batman(TIME, T_TR + 0.001 + offset, SYSTEM.rp_rs, SYSTEM.a_rs, SYSTEM.inc_deg,
                  SYSTEM.ld_quadratic)
    assert np.max(np.abs(m(theta) - ref)) < 1e-9          # the tabulated separation
    free = AstroModel(TIME, SYSTEM, phase="flat", event="transit",
                      settings=TransitSettings(free=("a_rs", "b")))
    theta_free = free.initial(t_event_bmjd=T_TR + 0.001)
    assert theta_free[2:].tolist() == pytest.approx([SYSTEM.a_rs, SYSTEM.impact_parameter])
    assert np.max(np.abs(free(theta_free) - ref)) < 1e-12  # batman's rsky at the data times
    # the simulator's L(t) transit (light travel included): the same to 1e-5 of the flux
    sim = TransitShape(TIME, SYSTEM).flux(T_TR + 0.001)
    assert np.max(np.abs(m(theta) - sim)) < 1e-5
    # the minimum sits at the mid-transit time asked for
    assert abs(TIME[np.argmin(m(theta))] - (T_TR + 0.001)) < 6.0 / 86400.0
    # a larger a/R* at the same b shortens the transit
    wider = theta_free.copy()
    wider[2] *= 1.2
    assert np.sum(free(wider) < 1.0) < np.sum(free(theta_free) < 1.0)


def test_free_limb_darkening_phase_and_ramp_and_the_batch_is_bit_identical():
    m = AstroModel(TIME, SYSTEM, phase="quadratic", ramp="linear", event="transit",
                   settings=TransitSettings(free=("q2", "q1")))
    assert m.names == ("rp_rs", "t_transit_bmjd", "q1", "q2", "c1_per_day", "c2_per_day2",
                       "ramp_slope_per_day")
    theta = m.initial(t_event_bmjd=T_TR)
    assert theta[2:4].tolist() == pytest.approx(list(q_from_u(*SYSTEM.ld_quadratic)))
    theta[4:] = [2e-3, -1e-2, 5e-4]
    u = u_from_q(*theta[2:4])
    offset = m.describe()["conjunction_minus_mid_transit_s"] / 86400.0
    tr = _batman(TIME, T_TR + offset, SYSTEM.rp_rs, SYSTEM.a_rs, SYSTEM.inc_deg, u)
    dt = TIME - T_TR
    expected = (tr + dt * (2e-3 - 1e-2 * dt)) * (1.0 + 5e-4 * (TIME - TIME[0]))
    assert np.max(np.abs(m(theta) - expected)) < 1e-9
    rng = np.random.default_rng(3)
    rows = theta + rng.normal(0.0, 1.0, (7, len(theta))) * m.scales
    batch = m.batch(rows)
    assert batch.shape == (7, len(TIME))
    assert all(np.array_equal(batch[i], m(rows[i])) for i in range(7))
    lo, hi = m.bounds
    assert (lo[0], hi[0], lo[2], hi[2], lo[3], hi[3]) == (0.0, 0.5, 0.0, 1.0, 0.0, 1.0)
    assert (lo[1], hi[1]) == (TIME.min(), TIME.max())


def test_the_depth_is_rp_rs_squared_and_errors_propagate():
    m = AstroModel(TIME, SYSTEM, phase="flat", event="transit")
    assert m.depth_ppm(0.1) == pytest.approx(10000.0)
    assert m.depth_error_ppm(0.1, 0.001) == pytest.approx(200.0)
    assert m.depth_difference_ppm(0.099, 0.1) == pytest.approx(199.0)
    ecl = AstroModel(TIME, SYSTEM, phase="flat")
    assert ecl.names[0] == "depth" and ecl.depth_ppm(0.002) == 2000.0
    assert ecl.depth_error_ppm(0.002, 1e-4) == 100.0


def test_gaussian_priors_enter_residuals_and_log_prior():
    m = AstroModel(TIME, SYSTEM, phase="flat", event="transit",
                   settings=TransitSettings(free=("q1", "q2"), priors={"q1": (0.05, 0.01)}))
    assert m.n_priors == 1
    theta = m.initial(t_event_bmjd=T_TR)
    assert theta[2] == 0.05                       # a prior's mean starts the parameter
    theta[2] = 0.08
    assert m.prior_residuals(theta).tolist() == pytest.approx([3.0])
    assert m.log_prior_batch(np.vstack([theta, theta])).tolist() == pytest.approx([-4.5, -4.5])

    class Sys:   # the least-squares problem appends the prior to the method's residuals
        param_names = ()
        data = None

        def param_bounds(self):
            return [], []

        def residuals(self, astro, theta_s):
            return np.zeros(3)

    assert _Problem(Sys(), m).residuals(theta).tolist() == pytest.approx([0, 0, 0, 3.0])
    assert _Problem(Sys(), AstroModel(TIME, SYSTEM, phase="flat")).residuals(
        np.array([1e-3, T_TR])).tolist() == [0, 0, 0]


@pytest.mark.parametrize("kwargs, message", [
    ({"free": ("rp",)}, "transit_free"),
    ({"free": ("q1",), "priors": {"q2": (0.1, 0.1)}}, "transit_priors.q2"),
    ({"free": ("q1",), "priors": {"q1": (0.1, 0.0)}}, "sigma > 0"),
    ({"limb_darkening_q": (1.2, 0.3)}, "limb_darkening_q"),
])
def test_bad_transit_settings_are_one_line_errors(kwargs, message):
    with pytest.raises(InputError, match=message):
        AstroModel(TIME, SYSTEM, event="transit", settings=TransitSettings(**kwargs))
    with pytest.raises(InputError, match="event"):
        AstroModel(TIME, SYSTEM, event="occultation")
    # a transit's settings given to an eclipse are refused, not ignored
    with pytest.raises(InputError, match="TransitSettings: the settings of another event; "
                                         "event 'eclipse' takes EclipseSettings"):
        AstroModel(TIME, SYSTEM, settings=TransitSettings(free=("q1",)))


def test_reduce_section_keys_are_checked():
    cfg = load_config(None, ['reduce.event="transit"', 'reduce.transit_free=["a_rs", "b"]',
                             "reduce.transit_priors.b=[0.7, 0.05]",
                             "reduce.limb_darkening_q=[0.05, 0.2]"])
    assert cfg.reduce.event == "transit" and cfg.reduce.transit_priors == {"b": (0.7, 0.05)}
    for bad, key in ((['reduce.event="occultation"'], "reduce.event"),
                     (['reduce.transit_free=["inc"]'], "reduce.transit_free"),
                     (["reduce.transit_priors.q1=[0.1, 0.1]"], "reduce.transit_priors.q1"),
                     (["reduce.limb_darkening_q=[0.1]"], "reduce.limb_darkening_q")):
        with pytest.raises(ConfigError, match=key):
            load_config(None, bad)


@pytest.fixture(scope="module")
def transit_table(kit):
    """A synthetic transit epoch: the simulator's L(t) (true mid-transit 90 s after the
    ephemeris) times the conftest's gain along its pointing track, 2000 ppm white noise."""
    lc = cached_light_curve(SystemSection())
    rng = np.random.default_rng(11)
    flux_true = lc(TIME - 90.0 / 86400.0)
    x, y = kit.pointing(TIME, rng)
    flux = kit.F0 * kit.gain(x, y) * flux_true * (1.0 + 2e-3 * rng.standard_normal(len(TIME)))
    table = kit.make_epoch_table(t_ecl=T_TR, visible=np.ones_like(TIME), time=TIME, noise=0.0,
                                 depth=0.0, c1=0.0, c2=0.0)
    table["flux"], table["x"], table["y"] = flux, x, y
    table["flux_err"] = np.full(len(TIME), kit.F0 * 2e-3)
    return table


def test_reduce_event_transit_recovers_rp_rs_and_the_time(transit_table, polygain, tmp_path):
    options = ReduceSection(event="transit", phase="linear", prayer_bead_shifts=4)
    res = reduce_epoch(transit_table, polygain.name, options=options, system=SYSTEM)
    out = res.to_dict()
    for key in ("rp_rs", "rp_rs_err", "transit_depth_ppm", "transit_depth_err_ppm",
                "t_transit_bmjd", "t_transit_err_d", "t_transit_predicted_bmjd"):
        assert math.isfinite(out[key]), key
    assert "t_ecl_bmjd" not in out and out["event"] == "transit"
    assert out["transit_depth_ppm"] == pytest.approx(out["rp_rs"] ** 2 * 1e6)
    assert out["depth_ppm"] == out["transit_depth_ppm"]
    assert out["transit_depth_err_ppm"] == pytest.approx(2e6 * out["rp_rs"] * out["rp_rs_err"])
    assert out["t_transit_predicted_bmjd"] == pytest.approx(T_TR, abs=1e-9)
    # the planet's night side (1119 ppm) dilutes the transit: Rp/R* low by 5.6e-4 of itself
    assert 5e-5 < out["rp_rs_err"] < 1e-3
    assert abs(out["rp_rs"] - SYSTEM.rp_rs) < 3.0 * out["rp_rs_err"], out["rp_rs"]
    assert abs(out["t_transit_bmjd"] - (T_TR + 90.0 / 86400.0)) < 3.0 * out["t_transit_err_d"]
    assert out["transit_model"]["transit_fixed"]["a_rs"] == SYSTEM.a_rs
    json.dumps(out)
    # a free q1 with a tight prior stays at the prior's mean; an eclipse fit of the same
    # frames finds no eclipse there
    free = reduce_epoch(transit_table, polygain.name, system=SYSTEM,
                        options=ReduceSection(event="transit", phase="linear",
                                              prayer_bead_shifts=0, transit_free=("q1",),
                                              transit_priors={"q1": (0.0484, 1e-4)}))
    assert free.params["q1"] == pytest.approx(0.0484, abs=5e-4)
    assert free.to_dict()["q1_err"] < 2e-4
    with pytest.raises(InputError, match="no eclipse in these frames"):
        reduce_epoch(transit_table, polygain.name, system=SYSTEM)
    with pytest.raises(InputError, match="fit each transit alone"):
        reduce_joint([transit_table, transit_table], polygain.name, system=SYSTEM,
                     options=ReduceSection(event="transit"))


def test_reduce_command_event_transit(transit_table, tmp_path, capsys):
    from eclipsebench.cli import main
    path = tmp_path / "epoch_03.ecsv"
    table = transit_table.copy()
    del table["stamp3"], table["stamp5"]
    table.write(path, format="ascii.ecsv")
    out = tmp_path / "r.json"
    assert main(["reduce", str(path), "--method", "poly2", "--event", "transit", "--phase",
                 "linear", "--prayer-bead", "0", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "rp_rs" in text and "t_transit" in text
    res = json.loads(out.read_text())
    assert res["event"] == "transit" and abs(res["rp_rs"] - SYSTEM.rp_rs) < 4 * res["rp_rs_err"]


@pytest.mark.slow
def test_a_simulated_transit_epoch_round_trips(tmp_path):
    """simulate (observation.event = transit) -> photometry -> reduce --event transit (BLISS)."""
    from astropy.table import Table

    from eclipsebench.cli import main
    tiny = ["observation.event=transit", "observation.pre_cubes=1",
            "observation.frames_per_cube=8", "observation.main_cubes=120",
            "observation.cube_interval_s=200.0", "simulation.subsamples=1"]
    sets = [a for s in tiny for a in ("--set", s)]
    assert main(["simulate", "--out", str(tmp_path / "sim"), "--epochs", "1", "--no-calibration",
                 "--quiet", "--workers", "1", *sets]) == 0
    assert main(["photometry", str(tmp_path / "sim"), "--out", str(tmp_path / "phot"),
                 "--quiet"]) == 0
    out = tmp_path / "bliss.json"
    assert main(["reduce", str(tmp_path / "phot" / "epoch_01.fits"), "--method", "bliss",
                 "--event", "transit", "--out", str(out), "--quiet"]) == 0
    truth = Table.read(tmp_path / "sim" / "truth.ecsv", format="ascii.ecsv")[0]
    res = json.loads(out.read_text())
    assert truth["rp_rs"] == SYSTEM.rp_rs and math.isnan(truth["t_ecl_bmjd"])
    assert abs(res["rp_rs"] - truth["rp_rs"]) < 4 * res["rp_rs_err"], res["rp_rs"]
    assert abs(res["t_transit_bmjd"] - truth["t_transit_bmjd"]) < 4 * res["t_transit_err_d"]


def test_method_hooks_see_the_derivative_per_unit_depth():
    """PLD's time-averaging error counts the transit's frames (mid-ingress to mid-egress)
    from the derivative per unit of transit depth, which is negative in transit."""
    from eclipsebench.decorrelate.pld import eclipse_frames
    m = AstroModel(TIME, SYSTEM, phase="flat", event="transit")
    theta = m.initial(t_event_bmjd=T_TR)
    h = 1e-6
    up = theta.copy()
    up[0] += h
    dastro = (m(up) - m(theta)) / h * m.size_per_depth(theta[0])
    assert dastro.max() <= 0.0 and m.size_per_depth(0.1) == pytest.approx(5.0)
    # the 2015 challenge's XO-3b transit lasts 2.98 h first to last contact
    n = eclipse_frames(dastro)
    assert 2.3 < n * 4.0 / 3600.0 < 2.98
    # an eclipse's (the visible fraction) is counted as before
    ecl = np.ones(100)
    ecl[40:60] = 0.0
    assert eclipse_frames(ecl) == 20


def test_a_transit_result_read_back_equals_it(transit_table, polygain, tmp_path):
    """Issue 29: read_result gives the transit back (its times written as t_transit_*)."""
    from eclipsebench import read_result
    from eclipsebench.io.atomic import write_json

    res = reduce_epoch(transit_table, polygain.name, system=SYSTEM,
                       options=ReduceSection(event="transit", phase="linear",
                                             prayer_bead_shifts=0))
    write_json(tmp_path / "t.json", res.to_dict())
    back = read_result(tmp_path / "t.json")
    assert back == res and back.event_detail["event"] == "transit"
    assert back.t_event_bmjd == res.event_detail["t_transit_bmjd"]
    # the event time's old attribute name reads the same value (issue 39: a transit's time
    # is an event time); the file keeps its keys
    assert back.t_ecl_bmjd == back.t_event_bmjd and back.t_ecl_err_d == back.t_event_err_d
    assert back.t_ecl_predicted_bmjd == back.t_event_predicted_bmjd
    assert "t_event_bmjd" not in res.to_dict() and "t_ecl_bmjd" not in res.to_dict()
