"""observation.event = "phase-curve": whole-orbit plans, the harmonic truth, the built-in
configuration xo3b-phase-curve (issue 17 point 3, the phase-curve half)."""

from __future__ import annotations

import logging
import math

import numpy as np
import pytest
from astropy.table import Table

from eclipsebench.astro.catalogue import system_for
from eclipsebench.astro.phase_curves import (
    fit_harmonic_light_curve,
    fit_harmonics,
    harmonic_summary,
)
from eclipsebench.cli import main
from eclipsebench.config import builtin_config_names, load_config
from eclipsebench.errors import ConfigError, InputError
from eclipsebench.simulation.challenge import simulate_challenge
from eclipsebench.simulation.from_config import light_curve_of
from eclipsebench.simulation.plan import (
    SECONDS_PER_DAY,
    eclipse_half_duration_d,
    phase_curve_main_cubes,
)
from eclipsebench.simulation.stage import challenge_plans
from eclipsebench.simulation.truth import epoch_truth_row

PHASE_KEYS = ("rp_rs", "transit_depth_ppm", "t_transit_bmjd", "phase_amplitude_ppm",
              "phase_offset_deg", "nightside_flux_ppm", "phase_amplitude_h2_ppm",
              "phase_offset_h2_deg", "nightside_flux_h2_ppm", "aorkey_main_last")


def _window(plan):
    return plan.start_bmjd, plan.start_bmjd + plan.duration_s / SECONDS_PER_DAY


def _frames(plan):
    """The frames' mid-times of a plan (as simulate_aor computes them) and fixed positions."""
    time = np.concatenate([plan.to_bmjd(a.frame_starts_s().ravel() + 1.005) for a in plan.aors])
    keys = np.concatenate([np.full(a.n_frames, a.aorkey) for a in plan.aors])
    return {"time_bmjd": time, "aorkey": keys, "x_true": np.full(time.size, 15.1),
            "y_true": np.full(time.size, 15.2)}


def test_the_xo3b_phase_curve_plan_is_one_orbit_of_12_hour_aors(caplog):
    cfg = load_config("xo3b-phase-curve")
    assert cfg.observation.event == "phase-curve" and cfg.challenge.epochs == 1
    system = system_for(cfg.system)
    with caplog.at_level(logging.WARNING):
        (plan,) = challenge_plans(cfg)
    assert "holds no" not in caplog.text
    obs = cfg.observation
    # the Pre AOR first (the 2015 challenge's 11 cubes), then Main AORs of at most 12 h
    assert plan.aors[0].label == "Pre" and plan.aors[0].n_cubes == obs.pre_cubes == 11
    mains = plan.aors[1:]
    assert [a.label for a in mains] == [f"Main{k}" for k in range(1, len(mains) + 1)]
    assert all(a.duration_s <= 12 * 3600.0 for a in plan.aors)
    assert [a.n_cubes for a in mains[:-1]] == [333] * (len(mains) - 1)  # 333 x 129.4 s < 12 h
    # the Main AORs last one orbit (to a cube) and each follows a repointing gap
    cubes = sum(a.n_cubes for a in mains)
    assert cubes == round(system.period_days * SECONDS_PER_DAY / obs.cube_interval_s)
    for before, after in zip(plan.aors[:-1], plan.aors[1:], strict=True):
        assert after.t0_s == pytest.approx(before.t0_s + before.duration_s + obs.aor_gap_s)
    # unique, consecutive keys; every AOR its own peak-up position
    keys = [a.aorkey for a in plan.aors]
    assert keys == list(range(obs.aorkey_base, obs.aorkey_base + len(keys)))
    assert len({(a.x0_px, a.y0_px) for a in plan.aors}) == len(plan.aors)
    # the window holds a whole eclipse (first contact phase_curve_lead_h into Main1) and a transit
    lc = light_curve_of(cfg)
    t0, t1 = _window(plan)
    (t_ecl, *_) = lc.eclipse_times_bmjd(t0, t1)
    first_contact = t_ecl - eclipse_half_duration_d(system)
    main1_start = plan.to_bmjd(mains[0].t0_s)
    assert (first_contact - main1_start) * 24 == pytest.approx(obs.phase_curve_lead_h)
    assert t_ecl + eclipse_half_duration_d(system) < plan.to_bmjd(mains[0].t0_s
                                                                   + mains[0].duration_s)
    assert len(lc.transit_times_bmjd(t0, t1)) == 1
    assert plan.n_frames == (11 + cubes) * 64  # about 140,000 frames


def test_phase_curve_keys_do_not_collide_across_epochs_and_with_pre_cubes_0():
    cfg = load_config(None, ['observation.event="phase-curve"', "challenge.epochs=4",
                             "observation.phase_curve_duration_d=1.2",
                             "observation.max_aor_hours=5"])
    plans = challenge_plans(cfg)
    keys = [a.aorkey for p in plans for a in p.aors]
    assert len(keys) == len(set(keys)) == 4 * (1 + len(plans[0].aors[1:]))
    assert all(a.duration_s <= 5 * 3600.0 for p in plans for a in p.aors)
    no_pre = challenge_plans(load_config(None, ['observation.event="phase-curve"',
                                                "challenge.epochs=3", "observation.pre_cubes=0",
                                                "observation.phase_curve_duration_d=1.2"]))
    keys = [a.aorkey for p in no_pre for a in p.aors]
    assert len(keys) == len(set(keys)) and no_pre[0].aors[0].label == "Main1"
    assert no_pre[0].aors[0].t0_s == 0.0


def test_aor_split_follows_iracsims_wrapper_and_bad_keys_are_refused():
    obs = load_config(None, ['observation.event="phase-curve"',
                             "observation.phase_curve_duration_d=1.0"]).observation
    # 1 d = 668 cubes of 129.4 s: two AORs of 333 (<= 12 h), then the rest
    assert phase_curve_main_cubes(obs, 99.0) == (333, 333, 2)
    for key, value in (("phase_curve_duration_d", "0"), ("max_aor_hours", "0.01"),
                       ("phase_curve_lead_h", "-1")):
        with pytest.raises(ConfigError, match=f"observation.{key}"):
            load_config(None, [f"observation.{key}={value}"])
    with pytest.raises(ConfigError, match="observation.aorkey_base"):
        challenge_plans(load_config("xo3b-phase-curve", ["observation.aorkey_base=99999000",
                                                         "challenge.epochs=200"]))


def test_truth_row_of_a_phase_curve_has_the_harmonic_truth():
    cfg = load_config("xo3b-phase-curve")
    (plan,) = challenge_plans(cfg)
    lc = light_curve_of(cfg)
    frames = _frames(plan)
    row = epoch_truth_row(cfg, plan, frames, lc, 2015)
    for key in PHASE_KEYS:
        assert key in row and math.isfinite(row[key]), key
    system = system_for(cfg.system)
    assert row["rp_rs"] == system.rp_rs
    assert row["aorkey_main"] == plan.aors[1].aorkey
    assert row["aorkey_main_last"] == plan.aors[-1].aorkey
    assert row["depth_ppm"] == pytest.approx(1875.0)
    # the truth: the reducer's model without systematics fitted to the noiseless L(t) of
    # the Main AORs, one normalisation per AOR (fit_harmonic_light_curve), summarised
    t, keys = frames["time_bmjd"], frames["aorkey"]
    main = keys != plan.aors[0].aorkey
    t_ecl, t_tr = row["t_ecl_bmjd"], row["t_transit_bmjd"]
    phase_tr = 2 * math.pi * (t_tr - t_ecl) / system.period_days
    tm = t[main]
    depth, h = fit_harmonic_light_curve(tm, lc(tm), lc.visible_fraction(tm),
                                        lc.stellar_flux(tm), t_ecl, system.period_days,
                                        segments=keys[main])
    s = harmonic_summary(depth, h, transit_phase_rad=phase_tr)
    assert row["phase_amplitude_ppm"] == pytest.approx(1e6 * s["phase_amplitude"], rel=1e-12)
    assert row["phase_offset_deg"] == pytest.approx(s["phase_offset_deg"], rel=1e-12)
    assert row["nightside_flux_ppm"] == pytest.approx(1e6 * s["nightside_flux"], rel=1e-12)
    assert row["harmonic_depth_ppm"] == pytest.approx(1e6 * depth, rel=1e-12)
    # the planet's own harmonic fit (F(t) out of eclipse and transit), for comparison
    out = (lc.visible_fraction(tm) >= 1.0) & (lc.stellar_flux(tm) >= 1.0)
    assert 0 < row["n_phase_frames"] == out.sum() < t.size
    depth_p, h_p = fit_harmonics(tm[out], lc.planet_flux(tm[out]), t_ecl, system.period_days)
    s_p = harmonic_summary(depth_p, h_p, transit_phase_rad=phase_tr)
    assert row["planet_harmonic_amplitude_ppm"] == pytest.approx(1e6 * s_p["phase_amplitude"])
    assert row["planet_harmonic_depth_ppm"] == pytest.approx(1e6 * depth_p)
    eclipse_row = epoch_truth_row(load_config(None), plan, frames, lc, 2015)
    assert not any(k in eclipse_row for k in PHASE_KEYS)


def test_a_tiny_phase_curve_writes_the_truth_columns(tmp_path):
    # two Main AORs of 2 cubes each (a 43-s "phase curve"), noise-free, no calibration
    cfg = load_config("xo3b-phase-curve", [
        "observation.pre_cubes=1", "observation.frames_per_cube=4",
        "observation.cube_interval_s=10.0", "observation.phase_curve_duration_d=0.0005",
        "observation.max_aor_hours=0.006", "observation.aor_gap_s=20",
        'simulation.noise_model="none"', "simulation.write_calibration=false",
        "simulation.subsamples=1"])
    result = simulate_challenge(cfg, tmp_path / "sim", workers=1)
    truth = Table.read(tmp_path / "sim" / "truth.ecsv", format="ascii.ecsv")
    assert len(truth) == 1 and result.epochs == 1
    for key in PHASE_KEYS:
        assert key in truth.colnames, key
    keys = sorted(int(p.name[1:]) for p in (tmp_path / "sim").glob("r*"))
    # 43.2 s / 10 s = 4 Main cubes, 2 per AOR (2 x 8 s frames + 10 s <= 21.6 s): keys base + 0..2
    assert keys == [20150000, 20150001, 20150002]
    assert truth["aorkey_main_last"][0] == keys[-1]
    assert truth["n_frames"][0] == (1 + 4) * 4  # 1 Pre cube + 4 Main cubes of 4 frames


def test_the_builtin_name_resolves_everywhere_and_a_bad_name_is_one_line(capsys):
    assert "xo3b-phase-curve" in builtin_config_names()
    assert main(["config", "xo3b-phase-curve"]) == 0
    out = capsys.readouterr().out
    assert 'event = "phase-curve"' in out and 'name = "xo3b-phase-curve"' in out
    with pytest.raises(InputError, match="built-in: xo3b-phase-curve"):
        load_config("xo3b-phase-curv")
    assert main(["simulate", "no-such-config", "--out", "unused"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert "no-such-config" in err and "xo3b-phase-curve" in err
