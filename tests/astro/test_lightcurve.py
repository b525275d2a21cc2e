"""Thermal phase curves and L(t): physics checks, the paper's depth and Section 4.2's biases."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest
from scipy.integrate import quad

from eclipsebench.astro import phase_curves
from eclipsebench.astro.bias import EPOCH10_START_BMJD, epoch_times, phase_model_bias
from eclipsebench.astro.catalogue import get_system
from eclipsebench.astro.lightcurve import light_curve_from_config, light_curve_function
from eclipsebench.astro.thermal import ThermalModel, planck_lambda
from eclipsebench.cli import main
from eclipsebench.config.system import CHALLENGE_SYSTEM, SystemSection
from eclipsebench.errors import InputError
from eclipsebench.simulation.from_config import challenge_epoch_times_bmjd

XO3B = get_system("XO-3b")                   # Wong et al. 2014 elements
XO3B_2015 = get_system(CHALLENGE_SYSTEM)     # the 2015 challenge's (Winn et al. 2008)
PAPER_BIAS_PPM = {"flat": -51.0, "linear": -27.0, "quadratic": -2.0}  # Section 4.2


@pytest.fixture(scope="module")
def challenge():
    """The challenge's settings on XO-3b (Wong et al. 2014 elements): A=0, tau_rad=1 d,
    Omega_rot=1, 4.5095 um, 1875 ppm."""
    return light_curve_function(XO3B)


@pytest.fixture(scope="module")
def challenge_2015():
    """The built-in challenge's light curve: the same settings on its own elements."""
    return light_curve_function(XO3B_2015)


@pytest.fixture(scope="module")
def epoch10_frames():
    """Mid-frame times of the built-in challenge's epoch 10 (the paper's figure)."""
    return challenge_epoch_times_bmjd(10)


@pytest.fixture(scope="module")
def instantaneous():
    return light_curve_function(XO3B, tau_rad_days=0.0, fix_depth_ppm=0.0)


def test_xo3b_model_depths(challenge, instantaneous):
    # exact disk integral, instantaneous re-radiation: 1762 ppm (6.0 % below the paper's 1875)
    assert instantaneous.model_depth_ppm == pytest.approx(1762.4, abs=1.0)
    # tau_rad = 1 day (at the periastron temperature): the day side lags the rising heating
    assert challenge.model_depth_ppm == pytest.approx(1138.1, abs=1.0)
    assert challenge.depth_ppm == pytest.approx(1875.0, abs=1e-9)


def test_iracsim_quadrature_reproduces_the_papers_depth():
    lc = light_curve_function(XO3B, tau_rad_days=0.0, fix_depth_ppm=0.0, quadrature="iracsim2015")
    assert abs(lc.model_depth_ppm / 1875.0 - 1.0) < 0.05
    assert lc.model_depth_ppm == pytest.approx(1863.1, abs=1.0)


def test_instantaneous_disk_integral_matches_a_1d_integral():
    """Edge-on circular planet at full phase: F = 2 k^2 int B(T mu^1/4) mu dmu / B(T*)."""
    s = dataclasses.replace(get_system("HD 209458b"), ecc=0.0, inc_deg=90.0)
    table = ThermalModel(s, tau_rad_days=0.0).flux_table()
    t_ss = s.teff_star_k / np.sqrt(s.a_rs)
    integral = quad(lambda mu: float(planck_lambda(4.5095, t_ss * mu ** 0.25)) * mu, 0, 1)[0]
    expected = s.rp_rs ** 2 * 2 * integral / float(planck_lambda(4.5095, s.teff_star_k))
    assert table.ratio.max() == pytest.approx(expected, rel=2e-4)
    assert table.ratio.min() < 1e-3 * table.ratio.max()  # cold night side at transit


def test_synchronous_circular_planet_does_not_depend_on_tau():
    s = dataclasses.replace(XO3B, ecc=0.0)
    r0 = ThermalModel(s, tau_rad_days=0.0, n_time=256).flux_table().ratio
    r1 = ThermalModel(s, tau_rad_days=1.0, n_time=256).flux_table().ratio
    assert np.allclose(r0, r1, rtol=1e-6, atol=1e-12)


def test_fast_rotation_or_long_tau_flattens_the_phase_curve():
    def amplitude(**kw):
        r = ThermalModel(XO3B, n_time=256, **kw).flux_table().ratio
        return (r.max() - r.min()) / r.max()
    assert amplitude(tau_rad_days=10.0, omega_rot=3.0) < 0.5 * amplitude(tau_rad_days=0.0)


def test_steady_state_is_periodic():
    m = ThermalModel(XO3B, tau_rad_days=1.0, n_time=256)
    _, temps = m.temperature_history()
    assert m.newton_iterations < 20
    assert temps.min() > 0 and temps.max() < 1.0 + 1e-9  # T~ <= 1: hottest at periastron


def test_light_curve_normalisation_and_events(challenge):
    t_ecl = challenge.t_eclipse_bmjd
    assert challenge(np.array([t_ecl]))[0] == 1.0  # the star alone in total eclipse
    out = challenge(np.array([t_ecl - 0.1, t_ecl + 0.1]))
    assert np.allclose(out - 1.0, challenge.planet_flux(np.array([t_ecl - 0.1, t_ecl + 0.1])))
    # the depth is F(t_ecl) interpolated to the centre of the occultation
    assert challenge.planet_flux(np.array([t_ecl]))[0] * 1e6 == pytest.approx(1875.0)
    ecl = challenge.eclipse_times_bmjd(57234.0, 57234.0 + 10 * XO3B.period_days)
    assert len(ecl) == 10 and np.allclose(np.diff(ecl), XO3B.period_days)
    tr = challenge.transit_times_bmjd(XO3B.t_transit_bmjd - 0.1, XO3B.t_transit_bmjd + 0.1)
    assert tr == [pytest.approx(XO3B.t_transit_bmjd, abs=1e-9)]
    star = challenge.stellar_flux(np.array(tr))[0]
    assert 1.0 - star == pytest.approx(XO3B.rp_rs ** 2, rel=0.05)  # limb darkening, b = 0.70
    # L = S + F V: the warm night side (tau_rad = 1 d) still shines during the transit
    assert challenge(np.array(tr))[0] == pytest.approx(star + challenge.planet_flux(
        np.array(tr))[0], abs=1e-15)


def test_fixing_the_depth_keeps_the_shape(challenge):
    free = light_curve_function(XO3B, fix_depth_ppm=0.0)
    t = 57234.0 + np.linspace(0, 3.2, 500)
    ratio = challenge.planet_flux(t) / free.planet_flux(t)
    assert np.allclose(ratio, 1875.0 / free.model_depth_ppm, rtol=1e-12)
    assert challenge.planet_scale == pytest.approx(1875.0 / 1138.1, rel=1e-3)


def test_tophat_band_and_albedo():
    mono = light_curve_function(XO3B, tau_rad_days=0.0, fix_depth_ppm=0.0)
    band = light_curve_function(XO3B, tau_rad_days=0.0, fix_depth_ppm=0.0,
                                flux_ratio_model="tophat")
    assert abs(band.model_depth_ppm / mono.model_depth_ppm - 1) < 0.05
    reflective = light_curve_function(XO3B, tau_rad_days=0.0, fix_depth_ppm=0.0, albedo=0.3)
    assert reflective.model_depth_ppm < 0.9 * mono.model_depth_ppm


def test_invalid_options_are_input_errors():
    for kw in ({"albedo": 1.0}, {"tau_rad_days": -1.0}, {"fix_depth_ppm": -5.0},
               {"flux_ratio_model": "bolometric"}, {"wavelength_um": 0.0}):
        with pytest.raises(InputError):
            light_curve_function(XO3B, **kw)


def test_from_config_section():
    lc = light_curve_from_config(SystemSection())
    assert lc.system.name == CHALLENGE_SYSTEM and lc.depth_ppm == pytest.approx(1875.0)
    assert lc.options["tau_rad_days"] == 1.0 and lc.options["flux_ratio_model"] == "monochromatic"
    raw = light_curve_from_config(SystemSection(name="XO-3b", tau_rad_days=0.0,
                                                fix_depth_ppm=0.0, quadrature="iracsim2015"))
    assert raw.options["quadrature"] == "iracsim2015"
    assert raw.model_depth_ppm == pytest.approx(1863.1, abs=1.0)


def test_challenge_elements_model_depths(challenge_2015):
    """The challenge row (e = 0.2884, omega = 346 deg): a hotter periastron, deeper model."""
    assert challenge_2015.model_depth_ppm == pytest.approx(1152.3, abs=1.0)
    assert challenge_2015.depth_ppm == pytest.approx(1875.0, abs=1e-9)
    raw = light_curve_function(XO3B_2015, tau_rad_days=0.0, fix_depth_ppm=0.0,
                               quadrature="iracsim2015")
    assert raw.model_depth_ppm == pytest.approx(1888.5, abs=1.0)  # +0.7 % from the paper's 1875


def test_epoch10_frames_are_the_simulated_epoch():
    t = challenge_epoch_times_bmjd(10)
    assert t.size == (11 + 233) * 64
    assert t[0] == pytest.approx(EPOCH10_START_BMJD + 1.005 / 86400, abs=1e-9)  # mid-frame
    gaps = np.diff(t) * 86400
    assert np.allclose(np.sort(gaps)[:14000], 2.008)
    assert gaps.max() == pytest.approx(300.0 + 2.008, abs=1e-3)  # the Pre -> Main gap
    with pytest.raises(InputError, match="1-10"):
        challenge_epoch_times_bmjd(11)


def test_section_4_2_biases_with_the_challenge_elements(challenge_2015, epoch10_frames):
    """Paper Section 4.2 (-51 / -27 / -2 ppm), each within 15 ppm, with the challenge's own
    elements on the frames of its epoch 10. Measured -39.5 / -28.8 / -1.8."""
    bias = phase_model_bias(challenge_2015, epoch10_frames)
    for name, paper in PAPER_BIAS_PPM.items():
        assert bias[name] == pytest.approx(paper, abs=15.0), name
    assert bias["flat"] == pytest.approx(-39.5, abs=0.5)
    assert bias["linear"] == pytest.approx(-28.8, abs=0.5)
    assert bias["quadratic"] == pytest.approx(-1.8, abs=0.5)


def test_section_4_2_biases_with_wong_elements(challenge, epoch10_frames):
    """XO-3b's own (Wong et al. 2014) elements put the eclipse 0.47 h earlier in the window:
    linear and quadratic still within 15 ppm (-25.2, +1.3), flat not (-19.6 against -51)."""
    bias = phase_model_bias(challenge, epoch10_frames)
    assert bias["flat"] == pytest.approx(-19.6, abs=0.5)
    assert bias["linear"] == pytest.approx(-25.2, abs=0.5)
    assert bias["quadratic"] == pytest.approx(1.3, abs=0.5)
    assert abs(bias["flat"] - PAPER_BIAS_PPM["flat"]) > 15.0
    # the lead's even 2.008 s grid over 8.8 h gives nearly the same (docs/astro.md)
    grid = phase_model_bias(challenge, epoch_times(EPOCH10_START_BMJD, 8.8))
    assert grid["flat"] == pytest.approx(-21.4, abs=0.5)
    assert grid["linear"] == pytest.approx(bias["linear"], abs=0.5)


def test_phase_curve_design_matrices_match_the_functions():
    t = 57234.5 + np.linspace(-0.2, 0.2, 41)
    for name, coeffs in (("flat", [1e-3]), ("linear", [1e-3, 2e-4]),
                         ("quadratic", [1e-3, 2e-4, -3e-3]), ("sinusoid", [1e-3, 3e-4, -1e-4])):
        a = phase_curves.design_matrix(name, t, t_ref=57234.5, period=3.19)
        direct = phase_curves.evaluate(name, t, coeffs, t_ref=57234.5, period=3.19)
        assert np.allclose(a @ np.array(coeffs), direct, rtol=0, atol=1e-15)
        assert phase_curves.evaluate(name, np.array([57234.5]), coeffs, t_ref=57234.5,
                                     period=3.19)[0] == pytest.approx(coeffs[0])
    with pytest.raises(ValueError):
        phase_curves.evaluate("cubic", t, [1.0])


def test_cli_json_of_the_real_planet_is_its_own_model_depth(capsys):
    """Issue 26: XO-3b (Wong et al. 2014's elements) gets its thermal model's depth, never the
    challenge's fixed 1875 ppm; the challenge's planet keeps the challenge's depth."""
    assert main(["lightcurve", "XO-3b", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["depth_fixed"] is False
    assert out["eclipse_depth_ppm"] == pytest.approx(out["model_depth_ppm"])
    assert out["model_depth_ppm"] == pytest.approx(1138.1, abs=1.0)
    assert main(["lightcurve", "--json"]) == 0
    challenge = json.loads(capsys.readouterr().out)
    assert challenge["system"] == "XO-3b (2015 challenge)" and challenge["depth_fixed"] is True
    assert challenge["eclipse_depth_ppm"] == pytest.approx(1875.0)
    assert main(["lightcurve", "XO-3b", "--fix-depth", "1875", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["depth_fixed"] is True and out["eclipse_depth_ppm"] == pytest.approx(1875.0)
    assert out["model_depth_instantaneous_ppm"] == pytest.approx(1762.4, abs=1.0)
    assert out["t_transit_bjd"] - 2400000.5 == pytest.approx(out["t_transit_bmjd"])
    assert out["start_bmjd"] == pytest.approx(57234.3406)
    assert len(out["eclipses_in_window"]) == 1
    assert out["options"]["tau_rad_days"] == 1.0 and out["options"]["albedo"] == 0.0
    assert out["options"]["wavelength_um"] == 4.5095


def test_cli_phase_bias_json(capsys):
    assert main(["lightcurve", "--phase-bias", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["system"] == CHALLENGE_SYSTEM and out["epoch"] == 10
    assert set(out["phase_bias_ppm"]) == {"flat", "linear", "quadratic"}
    for name, paper in PAPER_BIAS_PPM.items():
        assert out["phase_bias_ppm"][name] == pytest.approx(paper, abs=15.0), name
    assert out["n_frames"] == 15616 and out["depth_ppm"] == pytest.approx(1875.0)
    assert 4.0 < out["eclipse_after_start_hours"] < 5.5
    # another epoch, another planet: the same frames, other numbers
    assert main(["lightcurve", "XO-3b", "--phase-bias", "--epoch", "3", "--json"]) == 0
    other = json.loads(capsys.readouterr().out)
    assert other["system"] == "XO-3b" and other["epoch"] == 3
    assert other["start_bmjd"] == pytest.approx(2212.5079 + 54999.5, abs=1e-4)


def test_cli_phase_bias_text_and_bad_input(capsys):
    assert main(["lightcurve", "--phase-bias"]) == 0
    text = capsys.readouterr().out
    assert "challenge epoch 10" in text and "quadratic" in text
    for argv, words in [(["--epoch", "11"], "1-10"), (["--start", "57234"], "--start"),
                        (["--out", "x.ecsv"], "--out")]:
        assert main(["lightcurve", "--phase-bias", *argv]) == 2
        err = capsys.readouterr().err
        assert words in err and err.count("\n") == 1, argv
    for argv, words in [(["--epoch", "0"], ">= 1"), (["--epoch", "x"], "integer")]:
        with pytest.raises(SystemExit) as exc:  # argparse's one-line usage error
            main(["lightcurve", "--phase-bias", *argv])
        assert exc.value.code == 2
        err = capsys.readouterr().err
        assert words in err and err.count("\n") == 1, argv
    assert main(["lightcurve", "--epoch", "3"]) == 2
    assert "only with --phase-bias" in capsys.readouterr().err
    assert main(["lightcurve", "HD 189733b", "--phase-bias"]) == 2  # no eclipse in epoch 10
    assert "no eclipse inside challenge epoch 10" in capsys.readouterr().err


def test_cli_writes_table_and_plot(tmp_path, capsys):
    from astropy.table import Table

    ecsv, png = tmp_path / "lc.ecsv", tmp_path / "lc.png"
    assert main(["lightcurve", "WASP-43b", "--hours", "2", "--cadence-s", "60",
                 "--tau-rad", "0", "--fix-depth", "0", "--out", str(ecsv),
                 "--plot", str(png)]) == 0
    assert "eclipse depth" in capsys.readouterr().out
    table = Table.read(ecsv, format="ascii.ecsv")
    assert len(table) == 121 and table.colnames[:2] == ["time_bmjd", "flux"]
    assert png.stat().st_size > 1000
