"""observation.event = "transit": windows around the transits, transit truth columns
(issue 17 point 3, the transit half)."""

from __future__ import annotations

import logging
import math

import numpy as np
import pytest

from eclipsebench.astro.catalogue import system_for
from eclipsebench.astro.orbit import eclipse_time_bmjd, transit_time_bmjd
from eclipsebench.config import load_config
from eclipsebench.errors import ConfigError
from eclipsebench.simulation.from_config import light_curve_of
from eclipsebench.simulation.plan import (
    SECONDS_PER_DAY,
    epoch_start_times_bmjd,
    plan_challenge,
    transit_window_starts_bmjd,
)
from eclipsebench.simulation.stage import challenge_plans
from eclipsebench.simulation.truth import epoch_truth_row


def _window(plan):
    return plan.start_bmjd, plan.start_bmjd + plan.duration_s / SECONDS_PER_DAY


def test_transit_windows_put_the_transit_where_the_eclipse_was(caplog):
    eclipse_cfg = load_config(None)
    transit_cfg = load_config(None, ['observation.event="transit"'])
    system = system_for(transit_cfg.system)
    with caplog.at_level(logging.WARNING):
        eclipse_plans = challenge_plans(eclipse_cfg)
        transit_plans = challenge_plans(transit_cfg)
    assert "no transit" not in caplog.text and "no eclipse" not in caplog.text
    assert len(transit_plans) == len(eclipse_plans) == 10
    for ecl, tra in zip(eclipse_plans, transit_plans, strict=True):
        e0, e1 = _window(ecl)
        t0, t1 = _window(tra)
        assert t1 - t0 == pytest.approx(e1 - e0)
        t_ecl = eclipse_time_bmjd(system, 0.5 * (e0 + e1))
        t_tr = transit_time_bmjd(system, 0.5 * (t0 + t1))
        assert t0 <= t_tr <= t1 and e0 <= t_ecl <= e1
        # the same place in the window, on the transit before the eclipse
        assert t_tr - t0 == pytest.approx(t_ecl - e0, abs=1e-9)
        assert 0 < t_ecl - t_tr < system.period_days
        # the rest of the plan (AORs, cubes, peak-up draws) is the eclipse plan's
        assert [a.n_cubes for a in tra.aors] == [a.n_cubes for a in ecl.aors]
        assert [a.x0_px for a in tra.aors] == [a.x0_px for a in ecl.aors]


def test_the_eclipse_default_plan_is_unchanged():
    cfg = load_config(None)
    system = system_for(cfg.system)
    starts = epoch_start_times_bmjd(cfg.observation.start_times_jd, 10, system.period_days)
    plans = plan_challenge(cfg.observation, 10, system.period_days, cfg.challenge.seed)
    assert [p.start_bmjd for p in plans] == starts.tolist()
    assert cfg.observation.event == "eclipse"


def test_a_window_that_holds_a_transit_is_kept_and_a_plan_needs_the_orbit():
    cfg = load_config(None, ['observation.event="transit"'])
    system = system_for(cfg.system)
    t_tr = transit_time_bmjd(system, 57300.0)
    assert transit_window_starts_bmjd([t_tr - 0.2], 0.37, system).tolist() == [t_tr - 0.2]
    with pytest.raises(ConfigError, match="observation.event"):
        plan_challenge(cfg.observation, 1, system.period_days, 1)
    with pytest.raises(ConfigError, match="observation.event"):
        load_config(None, ['observation.event="occultation"'])


def test_an_epoch_without_a_transit_is_named(caplog):
    # a 6.5-minute window that ends before the challenge's first eclipse, moved by the
    # eclipse-to-transit interval, ends before the transit too
    cfg = load_config(None, ['observation.event="transit"', "challenge.epochs=1",
                             "observation.main_cubes=3", "observation.pre_cubes=0"])
    with caplog.at_level(logging.WARNING):
        challenge_plans(cfg)
    assert "holds no transit of XO-3b" in caplog.text


def test_truth_rows_of_transit_epochs_have_rp_rs_depth_and_time():
    cfg = load_config(None, ['observation.event="transit"', "challenge.epochs=1"])
    plan = challenge_plans(cfg)[0]
    lc = light_curve_of(cfg)
    t0, t1 = _window(plan)
    time = np.linspace(t0, t1, 50)
    frames = {"x_true": np.full(50, 15.0), "y_true": np.full(50, 15.0), "time_bmjd": time}
    row = epoch_truth_row(cfg, plan, frames, lc, 1)
    system = system_for(cfg.system)
    assert row["rp_rs"] == system.rp_rs
    assert row["transit_depth_ppm"] == pytest.approx(system.rp_rs ** 2 * 1e6)
    assert row["t_transit_bmjd"] == pytest.approx(transit_time_bmjd(system, 0.5 * (t0 + t1)))
    assert math.isnan(row["t_ecl_bmjd"])
    eclipse_row = epoch_truth_row(load_config(None, ["challenge.epochs=1"]), plan, frames, lc, 1)
    assert "rp_rs" not in eclipse_row and "t_transit_bmjd" not in eclipse_row
