"""Simulate a whole data challenge: plans, pointing, cubes, truth, calibration set.

``simulate_challenge(config, out_dir)`` writes the folder described in
``docs/contracts.md``::

    DIR/config.toml, DIR/truth.ecsv, DIR/r<AORKEY>/ch<N>/bcd/*_bcd.fits (+ _bunc),
    DIR/lightcurves/epoch_NN.ecsv, DIR/calibration/pmap_calibration.fits

This module is the simulate *stage*: pure functions (:func:`simulate_aor`,
:func:`epoch_truth_row`, ...), the module-level task functions and the
planner :func:`plan_simulate_tasks`, which turns a configuration and a
challenge folder into engine tasks (:mod:`eclipsebench.engine.tasks`):
one per AOR, the calibration set, one per epoch (its light-curve table and
truth row) and ``truth.ecsv`` last. ``simulate_challenge`` runs them on the
engine, as ``eclipsebench run`` does among its other stages.

Every random stream is keyed by what it is for (``("simulate", epoch,
"pointing")``, ``("simulate", epoch, aorkey, expid, "photon")``, ...), so the
bytes depend on the seed only, never on the number of workers or the order.

Resuming: an AOR task writes its cubes, then ``DIR/.simstate/r<AORKEY>.npz``
(its per-frame truth) last; an epoch task writes its light-curve table, then
``DIR/.simstate/epoch_NN.json``. The engine's stamps (``.<name>.task.json``)
record the hashes of those files and of what they were made from; a rerun
redoes only what is missing or not whole.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Callable
from dataclasses import dataclass, fields, replace
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np
from astropy.table import Table

from ..astro.catalogue import system_for
from ..astro.lightcurve import LightCurve, cached_light_curve
from ..astro.orbit import eclipse_time_bmjd, transit_time_bmjd
from ..astro.phase_curves import fit_harmonic_light_curve, fit_harmonics, harmonic_summary
from ..astro.thermal import DEFAULT_WAVELENGTH_UM
from ..config import Config, dump_toml, from_mapping, to_mapping
from ..config.base import load_toml
from ..config.detector import fluxconv_of, gain_of, noise_factor_of, read_noise_of
from ..detector.constants import ReadoutMode, channel_constants
from ..detector.fowler import bunc_mjysr, electrons_to_mjysr
from ..engine.tasks import Task, check_outputs_inside, run_tasks
from ..errors import ConfigError, InputError
from ..instrument.pointing import (
    ParamRange,
    PointingModel,
    PointingParams,
    PointingRanges,
    draw_pointing_params,
    frame_windows,
)
from ..io.atomic import atomic_path, write_json, write_text
from ..io.bcd_write import AorWriter, bcd_path, bmjd_to_utc, bunc_path
from ..io.header_template import XO3_DEC_DEG, XO3_RA_DEG, BcdHeaderInfo
from ..io.paths import check_links_inside
from ..progress import get_logger, progress
from ..seeding import rng
from .calibration import write_calibration_set
from .plan import SECONDS_PER_DAY, AORPlan, EpochPlan, plan_challenge
from .render import FrameModel, render_frames, stamp_origin, tick_moments
from .star import StarImager, make_star_imager, prf_label

__all__ = ["simulate_challenge", "ChallengeResult", "pointing_ranges_from_config",
           "readout_from_config", "system_of", "frame_model_from_config", "STATE_DIR", "light_curve_of",
           "challenge_plans", "plan_simulate_tasks", "simulate_aor", "aor_state_path",
           "epoch_marker_path", "phase_curve_truth", "simulated_bytes"]

STATE_DIR = ".simstate"
TRUTH_COLUMNS = ("epoch", "aorkey_pre", "aorkey_main", "start_bmjd", "t_ecl_bmjd", "depth_ppm",
                 "x_mean", "x_sd", "y_mean", "y_sd", "xy_cov", "n_frames")
log = get_logger("simulate")


def system_of(cfg: Config):
    """``cfg.system`` for the channel observed.

    The ``[system]`` default ``wavelength_um`` (4.5095 um, IRACSIM's for
    channel 2) becomes channel 1's effective wavelength (3.551 um, IRAC
    Instrument Handbook Table 2.2) when ``observation.channel = 1``; any other
    value is kept.
    """
    system = cfg.system
    if cfg.observation.channel == 1 and math.isclose(system.wavelength_um, DEFAULT_WAVELENGTH_UM):
        system = replace(system, wavelength_um=channel_constants(1).effective_wavelength_um)
    return system


def light_curve_of(cfg: Config) -> LightCurve:
    """L(t) of ``cfg.system`` at the channel's wavelength (:func:`system_of`; the one
    per-process cache, :func:`cached_light_curve`)."""
    return cached_light_curve(system_of(cfg))


def readout_from_config(cfg: Config) -> ReadoutMode:
    """The :class:`ReadoutMode` of ``[observation]`` (``readout``, or ``"custom"``)."""
    return cfg.observation.readout_mode()


def frame_model_from_config(cfg: Config) -> FrameModel:
    """The :class:`FrameModel` of a configuration."""
    sim = cfg.simulation
    mode = readout_from_config(cfg)
    return FrameModel(mode=mode, noise_model=sim.noise_model,
                      read_noise_e=read_noise_of(cfg), noise_factor=noise_factor_of(cfg),
                      subsamples=sim.subsamples,
                      stamp_px=sim.stamp_px, shape=mode.shape)


def pointing_ranges_from_config(cfg: Config) -> PointingRanges:
    """Table 5's ranges with the ``simulation.pointing_ranges`` overrides applied.

    Each override is ``"name=C:value"``, ``"name=U:lo:hi"`` or ``"name=G:lo:hi"``
    with ``name`` a :class:`~eclipsebench.instrument.pointing.PointingRanges` field.
    """
    key = "simulation.pointing_ranges"
    names = {f.name for f in fields(PointingRanges)}
    changes: dict[str, ParamRange] = {}
    for text in cfg.simulation.pointing_ranges:
        name, sep, spec = text.partition("=")
        name = name.strip()
        if not sep or name not in names:
            raise ConfigError(key, f"{text!r}: expected name=KIND:values with name one of "
                                   + ", ".join(sorted(names)))
        parts = spec.strip().split(":")
        kind = parts[0].upper()
        try:
            values = [float(v) for v in parts[1:]]
        except ValueError:
            raise ConfigError(key, f"{text!r}: values must be numbers") from None
        if kind == "C" and len(values) == 1:
            changes[name] = ParamRange("C", values[0])
        elif kind in ("U", "G") and len(values) == 2 and values[0] <= values[1]:
            default = getattr(PointingRanges(), name)
            limits = default.limits if kind == "G" else None
            changes[name] = ParamRange(kind, values[0], values[1], limits)
        else:
            raise ConfigError(key, f"{text!r}: expected C:value, U:lo:hi or G:lo:hi (lo <= hi)")
    return PointingRanges(**{**{f.name: getattr(PointingRanges(), f.name)
                                for f in fields(PointingRanges)}, **changes})


def draw_epoch_pointing(cfg: Config, epoch: int, seed: int) -> PointingParams:
    """The pointing parameters of ``epoch`` (stream ``("simulate", epoch, "pointing")``)."""
    try:
        return draw_pointing_params(rng(seed, "simulate", epoch, "pointing"),
                                    pointing_ranges_from_config(cfg))
    except ConfigError:
        raise
    except InputError as exc:
        raise ConfigError("simulation.pointing_ranges", str(exc)) from None


def _grid_index(t_s: np.ndarray, dt_s: float) -> np.ndarray:
    idx = np.rint(np.asarray(t_s) / dt_s).astype(np.int64)
    return idx


def _header_info(cfg: Config, aor: AORPlan, seed: int, mode: ReadoutMode, ra: float,
                 dec: float, object_name: str, read_noise_e: float) -> BcdHeaderInfo:
    sim = cfg.simulation
    obs = cfg.observation
    label = f"{cfg.challenge.name}_e{aor.epoch:02d}_{aor.label.lower()}"
    return BcdHeaderInfo(
        aorkey=aor.aorkey, aorlabel=label[:68], object_name=object_name, epoch=aor.epoch,
        seed=seed, noise_model=sim.noise_model, fowler=mode.fowler, wait=mode.wait,
        sample_time_s=mode.sample_time_s, frame_time_s=round(mode.t_int_s, 6),
        frame_interval_s=obs.frame_interval_s, exptime_s=round(mode.t_exp_s, 6),
        frames_per_cube=obs.frames_per_cube, fluxconv=fluxconv_of(cfg),
        gain_e_per_dn=gain_of(cfg), read_noise_e=read_noise_e, ra_deg=ra, dec_deg=dec,
        star_x_px=aor.x0_px, star_y_px=aor.y0_px, pointing_motion=sim.pointing_motion,
        flat_gain=sim.flat_gain, prf=prf_label(sim.prf), channel=obs.channel,
        subarray=mode.subarray, system_name=system_for(cfg.system).name)


def _target(cfg: Config) -> tuple[float, float, str]:
    """RA, Dec (deg) and OBJECT of the target: XO-3's unless the catalogue knows better."""
    system = system_for(cfg.system)
    ra = getattr(system, "ra_deg", None)
    dec = getattr(system, "dec_deg", None)
    # the star: the planet's name without a qualifier ("XO-3b (2015 challenge)") or its letter
    name = system.name.split("(", 1)[0].strip()
    name = name[:-1] if name.endswith("b") else name
    if ra is None or dec is None:
        ra, dec = XO3_RA_DEG, XO3_DEC_DEG
    return float(ra), float(dec), name.rstrip()


def simulate_aor(cfg: Config, plan: EpochPlan, aor_index: int, out_dir: str | Path, seed: int,
                 *, light_curve: Callable | None = None, star: StarImager | None = None,
                 show_progress: bool = True) -> dict[str, np.ndarray]:
    """Render and write every cube of one AOR; return its per-frame truth.

    The truth arrays (``time_bmjd``, ``flux_true`` = L(t), ``x_true``,
    ``y_true``, ``expid``, ``frame``, ``sky_e_per_px``) are also written to
    ``DIR/.simstate/r<AORKEY>.npz`` after the last cube, marking the AOR done.
    """
    out_dir = Path(out_dir)
    aor = plan.aors[aor_index]
    sim = cfg.simulation
    model = frame_model_from_config(cfg)
    mode = model.mode
    lc = light_curve if light_curve is not None else light_curve_of(cfg)
    star = star if star is not None else make_star_imager(cfg)
    ra, dec, object_name = _target(cfg)
    writer = AorWriter(out_dir, _header_info(cfg, aor, seed, mode, ra, dec, object_name,
                                             model.read_noise_e))

    dt_s = mode.sample_time_s / model.subsamples
    params = draw_epoch_pointing(cfg, plan.epoch, seed)
    pointing = None
    if sim.pointing_motion:
        pointing = PointingModel(params, duration_s=plan.duration_s + 10.0, dt_s=dt_s,
                                 rng=rng(seed, "simulate", plan.epoch, "pointing-model"),
                                 aor_starts_s=plan.aor_starts_s())

    frame_starts = aor.frame_starts_s()                       # (n_cubes, F)
    cube_bmjd = plan.to_bmjd(aor.cube_starts_s())
    cube_mjd, cube_iso = bmjd_to_utc(cube_bmjd, ra, dec)
    n_grid = model.grid_samples_per_frame
    tick_mid = 0.5 * (mode.n_max + 1) * mode.sample_time_s  # centre of the Fowler weights
    flux_per_tick = star.electrons_per_unit(sim.flux_aperture_e) / model.ticks_per_exposure
    sky_e = star.sky_e_per_px(sim.background_e_per_px, sim.flux_aperture_e,
                              sim.background_reference)
    bg_per_tick = sky_e / model.ticks_per_exposure
    ny, nx = model.shape
    fluxconv, gain = fluxconv_of(cfg), gain_of(cfg)

    truth: dict[str, list[Any]] = {k: [] for k in ("time_bmjd", "flux_true", "x_true", "y_true", "expid", "frame",
                             "sky_e_per_px")}
    cubes = range(aor.n_cubes)
    if show_progress:
        cubes = progress(cubes, desc=f"epoch {plan.epoch} r{aor.aorkey}", total=aor.n_cubes,
                         unit="cube")
    for c in cubes:
        starts = frame_starts[c]
        nf = starts.size
        if pointing is not None:
            dx, dy = frame_windows(pointing.offsets_grid, _grid_index(starts, dt_s), n_grid)
        else:
            dx = dy = np.zeros((nf, n_grid))
        x_off, y_off, moments = tick_moments(dx, dy, model)
        x_f = aor.x0_px + x_off
        y_f = aor.y0_px + y_off
        t_mid_s = starts + tick_mid
        time_bmjd = plan.to_bmjd(t_mid_s)
        flux_true = np.asarray(lc(time_bmjd), dtype=float)
        bg = bg_per_tick * (1.0 + sim.background_slope_per_day * t_mid_s / SECONDS_PER_DAY)
        sx0, sy0 = stamp_origin(np.array([x_f.mean()]), np.array([y_f.mean()]),
                                model.stamp_px, model.shape)
        basis = star.taylor_basis(x_f, y_f, int(sx0[0]), int(sy0[0]), model.stamp_px)
        wings = star.image(float(x_f.mean()), float(y_f.mean()), (ny, nx))
        expid = c
        frames_e, expected_e = render_frames(
            model=model, moments=moments, basis=basis, stamp_x0=int(sx0[0]),
            stamp_y0=int(sy0[0]), wings=wings, star_e_per_tick=flux_per_tick * flux_true,
            background_e_per_tick=bg,
            rng_photon=rng(seed, "simulate", plan.epoch, aor.aorkey, expid, "photon"),
            rng_read=rng(seed, "simulate", plan.epoch, aor.aorkey, expid, "read"))
        bcd = electrons_to_mjysr(frames_e, fluxconv=fluxconv, gain=gain,
                                 t_exp_s=mode.t_exp_s).astype(np.float32)
        bunc = bunc_mjysr(expected_e, mode, read_noise_e=model.read_noise_e,
                          fluxconv=fluxconv, gain=gain).astype(np.float32)
        writer.write_cube(expid=expid, bcd_mjysr=bcd, bunc_mjysr=bunc,
                          bmjd_obs=float(cube_bmjd[c]), mjd_obs=float(cube_mjd[c]),
                          date_obs=cube_iso[c], xy_mean=np.column_stack([x_f, y_f]))
        truth["time_bmjd"].append(time_bmjd)
        truth["flux_true"].append(flux_true)
        truth["x_true"].append(x_f)
        truth["y_true"].append(y_f)
        truth["expid"].append(np.full(nf, expid))
        truth["frame"].append(np.arange(nf))
        truth["sky_e_per_px"].append(bg * model.ticks_per_exposure)
    out = {k: np.concatenate(v) for k, v in truth.items()}
    out["aorkey"] = np.full(out["time_bmjd"].size, aor.aorkey)
    with atomic_path(aor_state_path(out_dir, aor.aorkey)) as tmp:
        with open(tmp, "wb") as fh:
            np.savez(fh, **out)  # type: ignore[arg-type]  # numpy's stub types **kwds as allow_pickle
    return out


def aor_state_path(out_dir: str | Path, aorkey: int) -> Path:
    """``DIR/.simstate/r<AORKEY>.npz``: an AOR's per-frame truth, written after its cubes."""
    return Path(out_dir) / STATE_DIR / f"r{aorkey}.npz"


def epoch_marker_path(out_dir: str | Path, epoch: int) -> Path:
    """``DIR/.simstate/epoch_NN.json``: an epoch's truth row, written after its light curve."""
    return Path(out_dir) / STATE_DIR / f"epoch_{epoch:02d}.json"


def epoch_lightcurve_path(out_dir: str | Path, epoch: int) -> Path:
    """``DIR/lightcurves/epoch_NN.ecsv``: the true L(t) and position per frame."""
    return Path(out_dir) / "lightcurves" / f"epoch_{epoch:02d}.ecsv"


def calibration_path(out_dir: str | Path) -> Path:
    """``DIR/calibration/pmap_calibration.fits``: the KR/Pmap calibration-star set."""
    return Path(out_dir) / "calibration" / "pmap_calibration.fits"


def _load_aor_truth(out_dir: Path, aor: AORPlan) -> dict[str, np.ndarray]:
    with np.load(aor_state_path(out_dir, aor.aorkey)) as data:
        return {k: data[k] for k in data.files}


def phase_curve_truth(time_bmjd, lc, t_ecl_bmjd: float, aorkey=None) -> dict[str, float]:
    """The harmonic truth of a phase curve: what a perfect fit of ``reduce --event phase-curve`` reports.

    The noiseless light curve ``L(t)`` at the frames' times is fitted with the
    reducer's astrophysical model without systematics, ``F0 [S(t) + V(t)
    p(t)]`` (``S``, ``V`` the true transit and eclipse;
    :func:`~eclipsebench.astro.phase_curves.fit_harmonic_light_curve`, one
    ``F0`` per AOR when ``aorkey`` is given, as the reducer's offsets), with
    the first harmonic and, separately, the first two (phase 0 at
    ``t_ecl_bmjd``), and summarised as the literature does
    (:func:`~eclipsebench.astro.phase_curves.harmonic_summary`, the transit
    phase ``2 pi (t_tr - t_ecl) / P`` with ``t_tr`` the first mid-transit
    after ``t_ecl_bmjd``). The first-harmonic values are the truth
    (``phase_amplitude_ppm``, ``phase_offset_deg``, ``nightside_flux_ppm``);
    ``*_h2_*`` are the two-harmonic ones, and ``harmonic_depth*_ppm`` each
    fit's ``p(t_ecl)``. When the planet's phase curve is not a harmonic series
    (the eccentric XO-3b's thermal curve has two maxima), these differ from
    the planet's own curve; ``planet_harmonic_*`` give the harmonic fit to the
    planet flux alone, out of eclipse and transit
    (:func:`~eclipsebench.astro.phase_curves.fit_harmonics`), to show by how
    much.

    Parameters
    ----------
    time_bmjd : array_like
        Frame mid-times (BMJD_TDB) of the epoch.
    lc : LightCurve
        The epoch's light curve L(t).
    t_ecl_bmjd : float
        A mid-eclipse time (phase 0).
    aorkey : array_like, optional
        The AOR of each frame (a normalisation per AOR).

    Returns
    -------
    dict
        ``phase_amplitude_ppm``, ``phase_offset_deg``, ``nightside_flux_ppm``,
        ``planet_flux_min_ppm``, ``harmonic_depth_ppm``, the same with ``_h2``
        for two harmonics, ``planet_harmonic_amplitude_ppm``,
        ``planet_harmonic_offset_deg``, ``planet_harmonic_depth_ppm`` and
        ``n_phase_frames`` (frames out of eclipse and transit).
    """
    t = np.asarray(time_bmjd, dtype=float)
    period = lc.system.period_days
    visible, stellar = lc.visible_fraction(t), lc.stellar_flux(t)
    t_tr = lc.transit_times_bmjd(t_ecl_bmjd, t_ecl_bmjd + period)[0]
    transit_phase = 2.0 * math.pi * (t_tr - t_ecl_bmjd) / period
    out_of_events = (visible >= 1.0) & (stellar >= 1.0)
    row: dict[str, float] = {"n_phase_frames": int(np.sum(out_of_events))}
    for n_harmonics, tag in ((1, ""), (2, "_h2")):
        depth, harmonics = fit_harmonic_light_curve(t, lc(t), visible, stellar, t_ecl_bmjd,
                                                    period, n_harmonics=n_harmonics,
                                                    segments=aorkey)
        summary = harmonic_summary(depth, harmonics, transit_phase_rad=transit_phase)
        row.update({f"phase_amplitude{tag}_ppm": 1e6 * summary["phase_amplitude"],
                    f"phase_offset{tag}_deg": summary["phase_offset_deg"],
                    f"nightside_flux{tag}_ppm": 1e6 * summary["nightside_flux"],
                    f"planet_flux_min{tag}_ppm": 1e6 * summary["planet_flux_min"],
                    f"harmonic_depth{tag}_ppm": 1e6 * depth})
    t_fit = t[out_of_events]
    depth, harmonics = fit_harmonics(t_fit, lc.planet_flux(t_fit), t_ecl_bmjd, period)
    summary = harmonic_summary(depth, harmonics, transit_phase_rad=transit_phase)
    row.update({"planet_harmonic_amplitude_ppm": 1e6 * summary["phase_amplitude"],
                "planet_harmonic_offset_deg": summary["phase_offset_deg"],
                "planet_harmonic_depth_ppm": 1e6 * depth})
    return row


def epoch_truth_row(cfg: Config, plan: EpochPlan, frames: dict[str, np.ndarray], lc,
                    seed: int) -> dict:
    """One ``truth.ecsv`` row: AORKEYs, times, depth, realised centroid statistics, pointing.

    With ``observation.event = "transit"`` or ``"phase-curve"`` the row adds
    ``rp_rs`` (the planet's), ``transit_depth_ppm`` (``rp_rs^2 * 1e6``, the
    geometric depth that ``reduce --event transit`` reports) and
    ``t_transit_bmjd`` (the observed mid-transit in the window, NaN if none).
    A phase curve's row also has the harmonic truth of :func:`phase_curve_truth`
    (phase 0 at ``t_ecl_bmjd``, or at the eclipse nearest the window's middle
    when it holds none), ``aorkey_main`` the first Main AOR's key and
    ``aorkey_main_last`` the last one's (the keys between are the epoch's).
    """
    x, y = frames["x_true"], frames["y_true"]
    t0 = plan.start_bmjd
    t1 = float(frames["time_bmjd"].max())
    eclipses = lc.eclipse_times_bmjd(t0, t1)
    mains = [a.aorkey for a in plan.aors if a.label.startswith("Main")]
    pre = [a.aorkey for a in plan.aors if a.label == "Pre"]
    row: dict[str, Any] = {"epoch": plan.epoch, "aorkey_pre": pre[0] if pre else -1,
           "aorkey_main": mains[0], "start_bmjd": t0,
           "t_ecl_bmjd": float(eclipses[0]) if eclipses else float("nan"),
           "depth_ppm": float(lc.depth_ppm), "x_mean": float(x.mean()), "x_sd": float(x.std()),
           "y_mean": float(y.mean()), "y_sd": float(y.std()),
           "xy_cov": float(np.mean((x - x.mean()) * (y - y.mean()))),
           "n_frames": int(x.size)}
    event = cfg.observation.event
    if event in ("transit", "phase-curve"):
        transits = lc.transit_times_bmjd(t0, t1)
        rp_rs = float(lc.system.rp_rs)
        row.update({"rp_rs": rp_rs, "transit_depth_ppm": rp_rs * rp_rs * 1e6,
                    "t_transit_bmjd": float(transits[0]) if transits else float("nan")})
    if event == "phase-curve":
        row["aorkey_main_last"] = mains[-1]
        if eclipses:
            t_ref = float(eclipses[0])
        else:
            p = lc.system.period_days
            mid = 0.5 * (t0 + t1)
            t_ref = min(lc.eclipse_times_bmjd(mid - p, mid + p), key=lambda t: abs(t - mid))
        # The frames the reducer fits: the Main AORs (the settling rule drops the Pre AOR).
        fitted = np.isin(frames["aorkey"], mains)
        row.update(phase_curve_truth(frames["time_bmjd"][fitted], lc, t_ref,
                                     aorkey=frames["aorkey"][fitted]))
    for a in plan.aors:
        row[f"x0_{a.label.lower()}_px"] = a.x0_px
        row[f"y0_{a.label.lower()}_px"] = a.y0_px
    for k, v in draw_epoch_pointing(cfg, plan.epoch, seed).to_dict().items():
        row[f"ptg_{k}"] = v
    row["seed"] = seed
    row["noise_model"] = cfg.simulation.noise_model
    return row


def _write_epoch(cfg: Config, plan: EpochPlan, out_dir: Path, lc, seed: int) -> dict:
    parts = [_load_aor_truth(out_dir, a) for a in plan.aors]
    frames = {k: np.concatenate([p[k] for p in parts]) for k in parts[0]}
    table = Table({"time_bmjd": frames["time_bmjd"], "aorkey": frames["aorkey"],
                   "expid": frames["expid"], "frame": frames["frame"],
                   "flux_true": frames["flux_true"], "x_true": frames["x_true"],
                   "y_true": frames["y_true"], "sky_e_per_px": frames["sky_e_per_px"]})
    table.meta = {"epoch": plan.epoch, "seed": seed,
                  "description": "true L(t) (1 = star alone) and true mean position (0-based px) "
                                 "per frame; time_bmjd at the centre of the Fowler weights"}
    with atomic_path(epoch_lightcurve_path(out_dir, plan.epoch)) as tmp:
        table.write(tmp, format="ascii.ecsv")
    row = epoch_truth_row(cfg, plan, frames, lc, seed)
    write_json(epoch_marker_path(out_dir, plan.epoch), row)
    return row


def _write_truth(rows: list[dict], out_dir: Path) -> Path:
    rows = sorted(rows, key=lambda r: r["epoch"])
    seen = {k for r in rows for k in r}
    names = [k for k in TRUTH_COLUMNS if k in seen]
    names += sorted(k for k in seen if k not in names and not k.startswith("ptg_")
                    and k not in ("seed", "noise_model"))
    names += sorted(k for k in seen if k.startswith("ptg_")) + ["seed", "noise_model"]
    cols = {k: [r.get(k, np.nan) for r in rows] for k in names}
    table = Table(cols)
    table.meta = {"description": "one row per simulated epoch (eclipsebench simulate)"}
    path = out_dir / "truth.ecsv"
    with atomic_path(path) as tmp:
        table.write(tmp, format="ascii.ecsv")
    return path


# --------------------------------------------------------------------------- tasks
# Module-level so that Dask can ship them to worker processes.

def simulate_aor_task(cfg: Config, plan: EpochPlan, aor_index: int, out_dir: str,
                      seed: int) -> None:
    """Render and write one AOR (:func:`simulate_aor`) with the process's cached L(t)."""
    try:
        simulate_aor(cfg, plan, aor_index, out_dir, seed, light_curve=light_curve_of(cfg))
    except InputError as exc:  # ConfigError/DataError do not survive pickling
        raise InputError(str(exc)) from None


def calibration_task(cfg: Config, out_dir: str) -> None:
    """The KR/Pmap calibration-star set (``DIR/calibration/pmap_calibration.fits``)."""
    try:
        write_calibration_set(cfg, out_dir)
    except InputError as exc:  # ConfigError/DataError do not survive pickling
        raise InputError(str(exc)) from None


def epoch_task(cfg: Config, plan: EpochPlan, out_dir: str, seed: int) -> None:
    """One epoch's light-curve table and truth row, once its AORs are on disk."""
    _write_epoch(cfg, plan, Path(out_dir), light_curve_of(cfg), seed)


def truth_task(cfg: Config, out_dir: str, epochs: list[int]) -> None:
    """``config.toml`` and ``truth.ecsv`` (last) from the epochs' truth rows."""
    out = Path(out_dir)
    write_text(out / "config.toml", dump_toml(to_mapping(cfg)))
    _write_truth([json.loads(epoch_marker_path(out, e).read_text()) for e in epochs], out)


def _cubes_exist(out_dir: str, aorkey: int, n_cubes: int, *outputs: Path,
                 channel: int = 2) -> bool:
    """Check of an AOR task: every cube its truth marker stands for is on disk."""
    return all(bcd_path(Path(out_dir), aorkey, c, channel).is_file()
               and bunc_path(Path(out_dir), aorkey, c, channel).is_file()
               for c in range(n_cubes))


def _epoch_row_ok(epoch: int, lightcurve: Path, marker: Path) -> bool:
    """Check of an epoch task: the truth row parses and is this epoch's."""
    row = json.loads(Path(marker).read_text())
    return isinstance(row, dict) and row.get("epoch") == epoch and "t_ecl_bmjd" in row


def _truth_ok(config: Path, truth: Path) -> bool:
    """Check of the truth task: ``truth.ecsv`` reads and has its columns."""
    table = Table.read(truth, format="ascii.ecsv")
    return all(c in table.colnames for c in TRUTH_COLUMNS)


#: A simulated cube's FITS header: three 2880-byte blocks (measured on ``AorWriter``'s).
CUBE_HEADER_BYTES = 3 * 2880


def simulated_bytes(cfg: Config) -> int:
    """Bytes of the BCD and BUNC cubes a simulation of ``cfg`` writes (the calibration set,
    light curves and truth, a few MB, aside): each cube's float32 frames padded to FITS
    blocks, and its header."""
    ny, nx = readout_from_config(cfg).shape
    system = system_for(cfg.system)
    total = 0
    for plan in plan_challenge(cfg.observation, cfg.challenge.epochs, system.period_days,
                               cfg.challenge.seed, system=system):  # challenge_plans, unwarned
        for aor in plan.aors:
            data = aor.frames_per_cube * ny * nx * 4
            total += 2 * aor.n_cubes * (data + (-data) % 2880 + CUBE_HEADER_BYTES)
    return total


def challenge_plans(cfg: Config) -> list[EpochPlan]:
    """The observing plans of every epoch (:func:`.plan.plan_challenge`).

    An epoch whose frames hold no eclipse of the planet (another planet with
    the XO-3b challenge's start times, say) is planned, since a simulation
    without an eclipse has its uses (noise and pointing studies), but a warning
    names it and ``observation.start_times_jd``; its truth row has no eclipse
    time (NaN). With ``observation.event = "transit"`` the windows are moved to
    the transits (:func:`.plan.transit_window_starts_bmjd`) and the warning is
    about an epoch without a transit; a phase curve (``"phase-curve"``,
    :func:`.plan.phase_curve_main_cubes`) is warned about when it lacks either.
    """
    system = system_for(cfg.system)
    event = cfg.observation.event
    plans = plan_challenge(cfg.observation, cfg.challenge.epochs, system.period_days,
                           cfg.challenge.seed, system=system)
    events = {"eclipse": (("eclipse", eclipse_time_bmjd),),
              "transit": (("transit", transit_time_bmjd),),
              "phase-curve": (("eclipse", eclipse_time_bmjd), ("transit", transit_time_bmjd))}
    for plan in plans:
        t0 = plan.start_bmjd
        t1 = t0 + plan.duration_s / SECONDS_PER_DAY
        for name, when in events[event]:
            t_event = float(when(system, 0.5 * (t0 + t1)))
            if not t0 <= t_event <= t1:
                log.warning("epoch %d (%.4f-%.4f BMJD) holds no %s of %s (the nearest is at "
                            "%.4f BMJD): set observation.start_times_jd (JD - 2455000) a few "
                            "hours before its %ss to simulate one", plan.epoch, t0, t1, name,
                            system.name, t_event, name)
    return plans


def plan_simulate_tasks(cfg: Config, out_dir: str | Path, *, calibration: bool | None = None,
                        prefix: str = "simulate") -> list[Task]:
    """The simulate stage's tasks for the challenge folder ``out_dir``.

    Keys: ``<prefix>/r<AORKEY>`` (the longest AORs first: keeps every worker
    busy), ``<prefix>/calibration``, ``<prefix>/epoch_NN`` and
    ``<prefix>/truth`` (``truth.ecsv``; the task later stages depend on).

    Parameters
    ----------
    cfg : Config
    out_dir : path
        The challenge folder (``docs/contracts.md``).
    calibration : bool, optional
        Write the calibration-star set (default ``simulation.write_calibration``;
        never when ``simulation.calibration_frames`` is 0).
    prefix : str
        Key prefix (the run's systematics-free twin uses ``simulate_flat``).
    """
    out = Path(out_dir)
    seed = cfg.challenge.seed
    calibration = cfg.simulation.write_calibration if calibration is None else calibration
    calibration = bool(calibration) and cfg.simulation.calibration_frames > 0
    plans = challenge_plans(cfg)
    tasks: list[Task] = []
    aors = sorted(((plan, i) for plan in plans for i in range(len(plan.aors))),
                  key=lambda pi: -pi[0].aors[pi[1]].n_cubes)
    for plan, i in aors:
        aor = plan.aors[i]
        tasks.append(Task(f"{prefix}/r{aor.aorkey}", "simulate", simulate_aor_task,
                          (cfg, plan, i, str(out), seed), (aor_state_path(out, aor.aorkey),),
                          check=partial(_cubes_exist, str(out), aor.aorkey, aor.n_cubes,
                                        channel=cfg.observation.channel)))
    truth_deps = []
    if calibration:
        tasks.append(Task(f"{prefix}/calibration", "simulate", calibration_task, (cfg, str(out)),
                          (calibration_path(out),)))
        truth_deps.append(f"{prefix}/calibration")
    for plan in plans:
        key = f"{prefix}/epoch_{plan.epoch:02d}"
        tasks.append(Task(key, "simulate", epoch_task, (cfg, plan, str(out), seed),
                          (epoch_lightcurve_path(out, plan.epoch),
                           epoch_marker_path(out, plan.epoch)),
                          tuple(f"{prefix}/r{a.aorkey}" for a in plan.aors),
                          check=partial(_epoch_row_ok, plan.epoch)))
        truth_deps.append(key)
    tasks.append(Task(f"{prefix}/truth", "simulate", truth_task,
                      (cfg, str(out), [p.epoch for p in plans]),
                      (out / "config.toml", out / "truth.ecsv"), tuple(truth_deps),
                      check=_truth_ok))
    return tasks


@dataclass
class ChallengeResult:
    """What :func:`simulate_challenge` did."""

    out_dir: Path
    epochs: int
    truth_rows: list[dict]
    files: int
    skipped_aors: int
    calibration: Path | None

    def to_dict(self) -> dict:
        """Summary for ``--json``."""
        return {"out_dir": str(self.out_dir), "epochs": self.epochs, "files": self.files,
                "truth_rows": len(self.truth_rows), "skipped_aors": self.skipped_aors,
                "calibration": None if self.calibration is None else str(self.calibration),
                "truth": self.truth_rows}


def simulate_challenge(cfg: Config, out_dir: str | os.PathLike[str], *, workers: int | None = None,
                       calibration: bool | None = None) -> ChallengeResult:
    """Simulate ``cfg.challenge.epochs`` epochs (and the calibration set) into ``out_dir``.

    Plans the simulate stage (:func:`plan_simulate_tasks`) and runs it on the
    task engine (:func:`eclipsebench.engine.tasks.run_tasks`).

    Parameters
    ----------
    cfg : Config
        The effective configuration (seed in ``challenge.seed``).
    out_dir : path
        The challenge folder; existing complete AORs and epochs are kept.
    workers : int, optional
        Worker processes (default ``run.workers``); 1 runs in this process.
    calibration : bool, optional
        Write the calibration-star set (default ``simulation.write_calibration``).
    """
    out = Path(out_dir)
    seed = cfg.challenge.seed
    workers = cfg.run.workers if workers is None else int(workers)
    calibration = cfg.simulation.write_calibration if calibration is None else calibration
    calibration = bool(calibration) and cfg.simulation.calibration_frames > 0
    light_curve_of(cfg)  # fail early on a bad [system] (and build L(t) once here)
    make_star_imager(cfg)  # ... on a bad PRF choice
    for epoch in range(1, cfg.challenge.epochs + 1):
        draw_epoch_pointing(cfg, epoch, seed)  # ... and on bad pointing ranges
    tasks = plan_simulate_tasks(cfg, out, calibration=calibration)
    check_links_inside(out)  # no output through a symbolic link out of --out
    check_outputs_inside(tasks, out)
    out.mkdir(parents=True, exist_ok=True)
    config_text = dump_toml(to_mapping(cfg))
    existing = out / "config.toml"
    if existing.is_file() and existing.read_text() != config_text:
        # read back through the current schema: keys added since (with their
        # defaults) are no difference
        try:
            stored = from_mapping(Config, load_toml(existing))
        except InputError:
            stored = None
        if stored != cfg:
            raise InputError(f"--out {out}: holds a challenge simulated with a different "
                             "configuration (see its config.toml); choose another folder")
    write_text(existing, config_text)
    report = run_tasks(tasks, workers=workers, root=out)
    plans = challenge_plans(cfg)
    aor_keys = {f"simulate/r{a.aorkey}" for p in plans for a in p.aors}
    truth_rows = [json.loads(epoch_marker_path(out, p.epoch).read_text()) for p in plans]
    n_files = sum(2 * a.n_cubes for p in plans for a in p.aors)
    return ChallengeResult(out_dir=out, epochs=len(plans), truth_rows=truth_rows, files=n_files,
                           skipped_aors=sum(k in aor_keys for k in report.skipped),
                           calibration=calibration_path(out) if calibration else None)
