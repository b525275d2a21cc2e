"""Whole phase curves (issue 17 points 2 and 5): the model, the fit, binned tables.

The model ``A = R O [T + v p]`` is checked piece by piece against the transit
event's T(t), the eclipse shape's v(t) and the lead's harmonic curve p(t); the
fit recovers a noiseless synthetic phase curve (flux = the model x a known
intra-pixel gain sampled along a pointing track that moves at each repointing,
test-only PolyGain method) to numerical precision; and a phase curve with
noise, binned per 64 frames and written to CSV, gives the amplitude and offset
of its unbinned frames within one sigma.
"""

from __future__ import annotations

import json
import math
from dataclasses import replace

import numpy as np
import pytest
from astropy.table import Table

from eclipsebench.astro.catalogue import get_system
from eclipsebench.astro.eclipse import EclipseShape
from eclipsebench.astro.orbit import eclipse_time_bmjd, transit_time_bmjd
from eclipsebench.astro.phase_curves import harmonic_curve, harmonic_summary
from eclipsebench.cli import main
from eclipsebench.config.reduce import ReduceSection
from eclipsebench.config.system import SystemSection
from eclipsebench.errors import ConfigError, InputError
from eclipsebench.fit.model import AstroModel, PhaseCurveSettings, integration_offsets_d
from eclipsebench.fit.reduce import predicted_event_bmjd, reduce_epoch

SYSTEM = get_system(SystemSection().name)   # the 2015 challenge's XO-3b (e = 0.29)
PERIOD = SYSTEM.period_days
T_ECL = eclipse_time_bmjd(SYSTEM, 57234.0)
F0 = 2.0e5
OPTIONS = replace(ReduceSection(), event="phase-curve", prayer_bead_shifts=0,
                  phase_curve_model="harmonic1")


def _times(cadence_s: float, start: float = -0.08, span: float = PERIOD + 0.16) -> np.ndarray:
    return T_ECL + start + np.arange(0.0, span, cadence_s / 86400.0)


def _aors(time: np.ndarray) -> np.ndarray:
    """12 h AORs (a repointing between them), numbered from 70000."""
    return 70000 + ((time - time[0]) // 0.5).astype(int)


def _pointing(time: np.ndarray, aor: np.ndarray, rng) -> tuple[np.ndarray, np.ndarray]:
    """Jitter, wobble and a drift that restarts at each repointing, which lands elsewhere."""
    k = aor - aor[0]
    since = time - np.array([time[aor == a].min() for a in np.unique(aor)])[k]
    x = 15.02 + 0.05 * np.sin(2 * np.pi * since / 0.028) + 0.06 * since + 0.03 * np.sin(1.7 * k)
    y = 14.95 + 0.04 * np.cos(2 * np.pi * since / 0.021) - 0.08 * since + 0.03 * np.cos(2.3 * k)
    return x + 0.01 * rng.standard_normal(len(x)), y + 0.01 * rng.standard_normal(len(y))


def _table(model: AstroModel, theta, *, noise: float, seed: int, kit) -> Table:
    time = model.time_bmjd
    aor = _aors(time)
    rng = np.random.default_rng(seed)
    x, y = _pointing(time, aor, rng)
    flux = F0 * kit.gain(x, y) * model(theta)
    if noise:
        flux = flux * (1.0 + noise * rng.standard_normal(len(time)))
    err = np.full(len(time), F0 * max(noise, 1e-4))
    return Table({"time_bmjd": time, "flux": flux, "flux_err": err, "x": x, "y": y,
                  "aorkey": aor})


def _truth(model: AstroModel, harmonics, *, depth=2.0e-3, rp_rs=0.0906, offsets=()):
    theta = model.initial(t_event_bmjd=T_ECL, depth=depth, rp_rs=rp_rs)
    theta[3:3 + len(harmonics)] = harmonics
    if offsets:
        theta[-len(offsets):] = offsets
    return theta


# ------------------------------------------------------------------------------ the model
def test_the_model_is_transit_plus_visible_planet_and_the_batch_is_bit_identical():
    time = _times(60.0)
    aor = _aors(time)
    m = AstroModel(time, SYSTEM, phase="harmonic2", event="phase-curve",
                   settings=PhaseCurveSettings(aorkey=aor, exposure_s=0.0))
    assert m.names == ("depth", "t_ecl_bmjd", "rp_rs", "phase_a1", "phase_b1", "phase_a2",
                       "phase_b2", *(f"aor_offset_{k}" for k in range(1, 7)))
    theta = _truth(m, (3e-4, -1.2e-4, 5e-5, 2e-5), offsets=(1e-4, -2e-4, 3e-4, 0.0, 5e-5, 1e-5))
    # T(t): the transit event's own curve at the transit that follows from the eclipse time
    t_tr = T_ECL + m.transit_minus_eclipse_d
    assert t_tr == pytest.approx(transit_time_bmjd(SYSTEM, T_ECL - 0.5 * PERIOD), abs=1e-9)
    tr = AstroModel(time, SYSTEM, phase="flat", event="transit")
    transit = tr(tr.initial(t_event_bmjd=t_tr + PERIOD, rp_rs=0.0906))   # the next one: same
    assert np.allclose(m.stellar_flux(theta), transit, rtol=0, atol=1e-12)
    assert transit.min() < 0.995                                        # the data hold it
    # v(t): the eclipse event's shape, every eclipse in the data (the next one a period on)
    v = EclipseShape(time, SYSTEM).visible_fraction(T_ECL)
    assert np.array_equal(m.visible_fraction(T_ECL), v)
    assert np.sum(v < 0.5) == 2 * np.sum(v[:len(v) // 2] < 0.5) > 0   # two eclipses
    # p(t): the lead's harmonic curve; O(t): 1 + o_k from the second AOR on
    p = harmonic_curve((2 * np.pi / PERIOD) * (time - T_ECL), theta[0], theta[3:7])
    assert np.array_equal(m.planet(theta), p)
    o = np.r_[1.0, 1.0 + theta[7:]][aor - aor[0]]
    assert np.array_equal(m.aor_factor(theta), o)
    assert np.allclose(m(theta), (m.stellar_flux(theta) + v * p) * o, rtol=0, atol=1e-15)
    # the MCMC's batch is the per-row call, bit for bit
    rows = np.vstack([theta, theta * (1 + 1e-3), m.initial(t_event_bmjd=T_ECL + 0.01)])
    batch = m.batch(rows)
    assert all(np.array_equal(batch[i], m(r)) for i, r in enumerate(rows))
    # what the literature reports: the lead's summary at this orbit's mid-transit phase
    s = m.phase_summary(theta)
    assert s == harmonic_summary(theta[0], theta[3:7],
                                 transit_phase_rad=2 * np.pi * (t_tr - T_ECL) / PERIOD)
    assert s["nightside_flux"] == pytest.approx(float(m.planet(theta)[np.argmin(transit)]),
                                                abs=2e-7)   # the frame nearest mid-transit


def test_long_rows_are_averaged_over_their_exposure():
    assert integration_offsets_d(2.0).tolist() == [0.0]
    assert len(integration_offsets_d(128.0)) == 13
    fine = _times(2.0, start=-0.06, span=0.12)               # 2 s frames across ingress
    rows = fine[:len(fine) // 64 * 64].reshape(-1, 64).mean(axis=1)
    binned = AstroModel(rows, SYSTEM, phase="harmonic1", event="phase-curve",
                         settings=PhaseCurveSettings(exposure_s=128.0))
    frames = AstroModel(fine, SYSTEM, phase="harmonic1", event="phase-curve")
    theta = _truth(frames, (3e-4, -1e-4))
    mean = frames(theta)[:len(rows) * 64].reshape(-1, 64).mean(axis=1)
    instant = AstroModel(rows, SYSTEM, phase="harmonic1", event="phase-curve",
                          settings=PhaseCurveSettings(exposure_s=0.0))
    # the exposure-averaged model of a 64-frame row is the mean of its frames to ~1e-7
    assert np.max(np.abs(binned(theta) - mean)) < 2e-7
    assert np.max(np.abs(instant(theta) - mean)) > 10 * np.max(np.abs(binned(theta) - mean))


def test_bad_phase_curve_settings_are_one_line_errors():
    time = _times(600.0)
    with pytest.raises(InputError, match="harmonic1, harmonic2"):
        AstroModel(time, SYSTEM, phase="quadratic", event="phase-curve")
    with pytest.raises(InputError, match="PhaseCurveSettings: the settings of another event; "
                                         "event 'eclipse' takes EclipseSettings"):
        AstroModel(time, SYSTEM, phase="flat", settings=PhaseCurveSettings(aorkey=_aors(time)))
    with pytest.raises(InputError, match="use 'physical'"):
        AstroModel(time, SYSTEM, phase="harmonic1", event="phase-curve", eclipse_shape="box")
    with pytest.raises(ConfigError, match="exposure_s"):
        replace(ReduceSection(), exposure_s=-1.0).validate()
    # the eclipse that starts the series is the first one whose centre lies in the data
    assert predicted_event_bmjd(SYSTEM, time, event="phase-curve") == pytest.approx(T_ECL)
    late = time[time > T_ECL + 0.2]
    assert predicted_event_bmjd(SYSTEM, late, event="phase-curve") == pytest.approx(
        T_ECL + PERIOD)


# ------------------------------------------------------------------------------ the fit
@pytest.mark.parametrize("phase, harmonics", [("harmonic1", (4e-4, -1.5e-4)),
                                              ("harmonic2", (4e-4, -1.5e-4, 6e-5, -3e-5))])
def test_a_noiseless_phase_curve_is_recovered_exactly(phase, harmonics, polygain, kit):
    model = AstroModel(_times(16.0), SYSTEM, phase=phase, event="phase-curve",
                       settings=PhaseCurveSettings(aorkey=_aors(_times(16.0))))
    offsets = (2e-4, -3e-4, 1e-4, 4e-4, -1e-4, 2.5e-4)
    theta = _truth(model, harmonics, offsets=offsets)
    table = _table(model, theta, noise=0.0, seed=3, kit=kit)
    opts = replace(OPTIONS, phase_curve_model=phase, settling_aor="keep")
    res = reduce_epoch(table, polygain.name, options=opts, system=SYSTEM).to_dict()
    truth = model.phase_summary(theta)
    assert res["event"] == "phase-curve" and res["phase"] == phase
    assert res["depth_ppm"] == pytest.approx(theta[0] * 1e6, abs=1e-3)
    assert res["t_ecl_bmjd"] == pytest.approx(T_ECL, abs=1e-7)
    assert res["phase_amplitude_ppm"] == pytest.approx(truth["phase_amplitude"] * 1e6, abs=1e-3)
    assert res["phase_offset_deg"] == pytest.approx(truth["phase_offset_deg"], abs=1e-4)
    assert res["nightside_flux_ppm"] == pytest.approx(truth["nightside_flux"] * 1e6, abs=1e-3)
    assert res["planet_flux_min_ppm"] == pytest.approx(truth["planet_flux_min"] * 1e6, abs=1e-3)
    assert res["rp_rs"] == pytest.approx(0.0906, abs=1e-7)
    assert not res["planet_flux_negative"]
    fitted = [o["offset"] for o in res["aor_offsets"]]
    assert [o["aorkey"] for o in res["aor_offsets"]] == list(range(70000, 70007))
    assert np.allclose(fitted, (0.0,) + offsets, rtol=0, atol=1e-9)
    for key in ("depth_err_ppm", "phase_amplitude_err_ppm", "phase_offset_err_deg",
                "nightside_flux_err_ppm", "rp_rs_err"):
        assert np.isfinite(res[key]) and res[key] >= 0.0
    json.dumps(res)


def test_the_planet_flux_can_be_kept_non_negative(polygain, kit):
    time = _times(64.0)
    model = AstroModel(time, SYSTEM, phase="harmonic1", event="phase-curve",
                       settings=PhaseCurveSettings(aorkey=_aors(time)))
    theta = _truth(model, (6e-4, 0.0), depth=8e-4)             # minimum 8e-4 - 2 x 6e-4 < 0
    table = _table(model, theta, noise=1e-3, seed=5, kit=kit)
    free = reduce_epoch(table, polygain.name, options=OPTIONS, system=SYSTEM).to_dict()
    assert free["planet_flux_negative"] and free["planet_flux_min_ppm"] < -200.0
    kept = reduce_epoch(table, polygain.name, options=replace(OPTIONS, nonnegative_planet=True),
                        system=SYSTEM).to_dict()
    assert kept["planet_flux_min_ppm"] > -5.0                  # the penalty: 1 ppm = 1 in chi2
    assert kept["chi2_red"] > free["chi2_red"]
    # the MCMC's prior is -inf where the planet goes negative
    prior = AstroModel(time, SYSTEM, phase="harmonic1", event="phase-curve",
                       settings=PhaseCurveSettings(nonnegative_planet=True))
    rows = np.array([prior.initial(t_event_bmjd=T_ECL, depth=8e-4) for _ in range(2)])
    rows[0, 3] = 6e-4
    assert prior.log_prior_batch(rows).tolist() == [-np.inf, 0.0]
    assert prior.prior_residuals(rows[1]).tolist() == [0.0]
    assert prior.prior_residuals(rows[0])[0] == pytest.approx((8e-4 - 1.2e-3) / 1e-6)


def test_a_binned_csv_gives_the_unbinned_amplitude_and_offset(tmp_path, polygain, kit):
    """Issue 17 acceptance: one row per 64-frame cube, written to CSV, read back by reduce."""
    time = _times(2.0, start=-0.05, span=PERIOD + 0.1)
    model = AstroModel(time, SYSTEM, phase="harmonic1", event="phase-curve",
                       settings=PhaseCurveSettings(aorkey=_aors(time)))
    theta = _truth(model, (4e-4, -1.5e-4), offsets=(2e-4, -3e-4, 1e-4, 4e-4, -1e-4, 2.5e-4))
    frames = _table(model, theta, noise=4e-3, seed=11, kit=kit)
    n = len(frames) // 64 * 64
    cubes = Table({name: np.asarray(frames[name])[:n].reshape(-1, 64).mean(axis=1)
                   for name in ("time_bmjd", "flux", "x", "y")})
    cubes["flux_err"] = np.asarray(frames["flux_err"])[:n:64] / 8.0
    cubes["aorkey"] = np.asarray(frames["aorkey"])[:n:64]
    path = tmp_path / "phase_curve_binned.csv"
    cubes.write(path, format="ascii.csv")
    unbinned = reduce_epoch(frames, polygain.name, options=OPTIONS, system=SYSTEM).to_dict()
    binned = reduce_epoch(path, polygain.name, options=OPTIONS, system=SYSTEM).to_dict()
    assert binned["cadence_s"] == pytest.approx(128.0, abs=0.01)
    assert binned["phase_curve_model"]["n_subexposures"] == 13
    assert len(binned["aor_offsets"]) == 7
    for key in ("phase_amplitude", "phase_offset", "depth"):
        unit = "deg" if key == "phase_offset" else "ppm"
        a, b = unbinned[f"{key}_{unit}"], binned[f"{key}_{unit}"]
        assert abs(a - b) < unbinned[f"{key}_err_{unit}"], key
    truth = model.phase_summary(theta)
    assert abs(binned["phase_amplitude_ppm"] - truth["phase_amplitude"] * 1e6) \
        < 3 * binned["phase_amplitude_err_ppm"]


def test_reduce_command_fits_a_phase_curve(tmp_path, polygain, kit, capsys):
    time = _times(128.0)
    model = AstroModel(time, SYSTEM, phase="harmonic2", event="phase-curve",
                       settings=PhaseCurveSettings(aorkey=_aors(time)))
    table = _table(model, _truth(model, (4e-4, -1e-4, 0.0, 0.0)), noise=1e-3, seed=2, kit=kit)
    path = tmp_path / "pc.ecsv"
    table.write(path)
    out = tmp_path / "pc.json"
    code = main(["reduce", str(path), "--method", polygain.name, "--event", "phase-curve",
                 "--phase", "harmonic2", "--prayer-bead", "0", "--out", str(out),
                 "--system", SYSTEM.name])
    assert code == 0
    res = json.loads(out.read_text())
    assert res["phase"] == "harmonic2" and "phase_b2" in res
    assert math.isfinite(res["phase_offset_deg"])
    assert "amplitude" in capsys.readouterr().out
    assert main(["reduce", str(path), "--method", polygain.name, "--phase", "harmonic1"]) == 2
    assert main(["reduce", str(path), "--method", polygain.name, "--event", "phase-curve",
                 "--phase", "quadratic"]) == 2


def test_one_systematics_model_per_aor(polygain, kit):
    """[reduce] systematics_per_aor: each AOR its own method (and flux level), no offsets."""
    time = _times(16.0)
    model = AstroModel(time, SYSTEM, phase="harmonic1", event="phase-curve",
                       settings=PhaseCurveSettings(aorkey=_aors(time)))
    theta = _truth(model, (4e-4, -1.5e-4), offsets=(2e-4, -3e-4, 1e-4, 4e-4, -1e-4, 2.5e-4))
    table = _table(model, theta, noise=0.0, seed=3, kit=kit)
    opts = replace(OPTIONS, systematics_per_aor=True, settling_aor="keep")
    res = reduce_epoch(table, polygain.name, options=opts, system=SYSTEM).to_dict()
    truth = model.phase_summary(theta)
    assert res["aor_offsets"] == [] and not any(k.startswith("aor_offset_") for k in res)
    assert [d["aorkey"] for d in res["diagnostics"]["systematics_per_aor"]] == list(
        range(70000, 70007))
    assert res["k"] == 5 + 7 * 6   # depth, time, rp_rs, a1, b1 and six coefficients per AOR
    assert res["phase_amplitude_ppm"] == pytest.approx(truth["phase_amplitude"] * 1e6, abs=1e-3)
    assert res["phase_offset_deg"] == pytest.approx(truth["phase_offset_deg"], abs=1e-4)
    assert res["depth_ppm"] == pytest.approx(theta[0] * 1e6, abs=1e-3)
    with pytest.raises(ConfigError, match="systematics_per_aor"):
        replace(ReduceSection(), systematics_per_aor=True).validate()
    # one systematics model and no offsets ([reduce] aor_offsets = false)
    plain = reduce_epoch(table, polygain.name, system=SYSTEM,
                         options=replace(OPTIONS, aor_offsets=False, settling_aor="keep"))
    assert plain.to_dict()["aor_offsets"] == [] and plain.k == 5 + 6


@pytest.mark.parametrize("method", ["bliss", "kr-data"])
def test_map_and_neighbour_methods_fit_a_binned_phase_curve(method, kit):
    """One row per 64-frame cube: BLISS's knots and KR's neighbours work on the cubes."""
    time = _times(128.0)
    model = AstroModel(time, SYSTEM, phase="harmonic1", event="phase-curve",
                       settings=PhaseCurveSettings(aorkey=_aors(time)))
    theta = _truth(model, (4e-4, -1.5e-4))
    table = _table(model, theta, noise=5e-4, seed=7, kit=kit)
    table["noise_pixels"] = np.full(len(table), 7.0)
    res = reduce_epoch(table, method, options=OPTIONS, system=SYSTEM).to_dict()
    truth = model.phase_summary(theta)
    assert res["cadence_s"] == pytest.approx(128.0, abs=0.01)
    assert res["n_frames"] > 0.9 * len(table)
    for key, unit in (("phase_amplitude", "ppm"), ("phase_offset", "deg")):
        scale = 1e6 if unit == "ppm" else 1.0
        err = res[f"{key}_err_{unit}"]
        assert 0 < err and abs(res[f"{key}_{unit}"] - truth[key if unit == "ppm" else
                                                               "phase_offset_deg"] * scale) < 4 * err


def test_per_aor_systematics_batch_and_refits_equal_their_parts(kit):
    from eclipsebench.decorrelate import get_method
    from eclipsebench.fit.data import epoch_data_from_table
    from eclipsebench.fit.frames import PerAorSystematics, per_aor_systematics

    time = _times(300.0)
    model = AstroModel(time, SYSTEM, phase="harmonic1", event="phase-curve")
    table = _table(model, _truth(model, (4e-4, 0.0)), noise=1e-3, seed=4, kit=kit)
    data = epoch_data_from_table(table)
    joined = per_aor_systematics(data, lambda part: get_method("bliss")(part))
    assert isinstance(joined, PerAorSystematics) and len(joined.parts) == 7
    astro = np.vstack([model(_truth(model, (a, 0.0))) for a in (3e-4, 4e-4, 5e-4)])
    astro = astro[:, np.searchsorted(time, joined.data.time_bmjd)]
    loop = [joined.log_likelihood(a) for a in astro]
    assert np.allclose(joined.log_likelihood_batch(astro), loop, rtol=1e-12, atol=0)
    # the prayer bead's refit: each part rebuilt on its own rows equals a fresh build
    def poly(part):
        return get_method("poly2")(part, bin_frames=1)

    flux = data.flux * (1.0 + 1e-3 * np.sin(np.arange(len(data))))
    fresh = per_aor_systematics(replace(data, flux=flux), poly)
    refit = per_aor_systematics(data, poly).with_flux(flux)
    a = model(_truth(model, (4e-4, 0.0)))
    assert np.allclose(refit.predict(a), fresh.predict(a), rtol=1e-12, atol=0)
    assert np.array_equal(refit.data.flux, flux)


def test_errors_from_mcmc_samples_agree_with_the_delta_method(polygain, kit):
    time = _times(900.0)   # instantaneous rows (exposure 1 s): one sample each, a quick model
    model = AstroModel(time, SYSTEM, phase="harmonic1", event="phase-curve",
                       settings=PhaseCurveSettings(aorkey=_aors(time), exposure_s=1.0))
    table = _table(model, _truth(model, (4e-4, -1.5e-4)), noise=5e-4, seed=9, kit=kit)
    options = replace(OPTIONS, exposure_s=1.0)
    delta = reduce_epoch(table, polygain.name, options=options, system=SYSTEM).to_dict()
    opts = replace(options, sampler="mcmc", mcmc_steps=400, mcmc_walkers=16)
    mc = reduce_epoch(table, polygain.name, options=opts, system=SYSTEM).to_dict()
    assert delta["phase_errors_from"].startswith("delta method")
    assert mc["phase_errors_from"].startswith("mcmc samples")
    for key in ("phase_amplitude_err_ppm", "phase_offset_err_deg", "nightside_flux_err_ppm"):
        assert 0.5 < mc[key] / delta[key] < 2.0, (key, mc[key], delta[key])
    assert abs(mc["phase_amplitude_ppm"] - delta["phase_amplitude_ppm"]) \
        < delta["phase_amplitude_err_ppm"]


def test_the_harmonic_order_is_chosen_by_bic(polygain, kit):
    """phase_curve_model = "bic" (the default): the order of least BIC, both BICs reported."""
    time = _times(64.0)
    for harmonics, expected in (((4e-4, -1.5e-4), "harmonic1"),
                                ((4e-4, -1.5e-4, 3e-4, 2e-4), "harmonic2")):
        phase = "harmonic2" if len(harmonics) == 4 else "harmonic1"
        model = AstroModel(time, SYSTEM, phase=phase, event="phase-curve",
                       settings=PhaseCurveSettings(aorkey=_aors(time)))
        table = _table(model, _truth(model, harmonics), noise=5e-4, seed=4, kit=kit)
        res = reduce_epoch(table, polygain.name, system=SYSTEM,
                           options=replace(OPTIONS, phase_curve_model="bic")).to_dict()
        bic = res["phase_curve_bic"]
        assert set(bic) == {"harmonic1", "harmonic2"} and min(bic, key=bic.get) == expected
        assert res["phase_curve_model"]["phase"] == expected
    assert ReduceSection().phase_curve_model == "bic"
