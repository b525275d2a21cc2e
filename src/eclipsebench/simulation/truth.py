"""The truth of a simulated challenge: each epoch's light-curve table and truth row, the
harmonic truth of a phase curve, and ``truth.ecsv``.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
from astropy.table import Table

from ..astro.events import event_for
from ..astro.phase_curves import fit_harmonic_light_curve, fit_harmonics, harmonic_summary
from ..config import Config
from ..engine.layout import SimulationLayout
from ..io.atomic import atomic_path, write_json
from .from_config import draw_epoch_pointing
from .plan import AORPlan, EpochPlan

__all__ = ['TRUTH_COLUMNS', 'load_aor_truth', 'phase_curve_truth', 'epoch_truth_row', 'write_epoch', 'write_truth']

TRUTH_COLUMNS = ("epoch", "aorkey_pre", "aorkey_main", "start_bmjd", "t_ecl_bmjd", "depth_ppm",
                 "x_mean", "x_sd", "y_mean", "y_sd", "xy_cov", "n_frames")


def load_aor_truth(out_dir: Path, aor: AORPlan) -> dict[str, np.ndarray]:
    """An AOR's per-frame truth (what :func:`~.aor.simulate_aor` returned), from its state file."""
    with np.load(SimulationLayout(out_dir).aor_state(aor.aorkey)) as data:
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
    event = event_for(cfg.observation.event)
    if event.observes_transit:
        transits = lc.transit_times_bmjd(t0, t1)
        rp_rs = float(lc.system.rp_rs)
        row.update({"rp_rs": rp_rs, "transit_depth_ppm": rp_rs * rp_rs * 1e6,
                    "t_transit_bmjd": float(transits[0]) if transits else float("nan")})
    if event.whole_orbit:
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


def write_epoch(cfg: Config, plan: EpochPlan, out_dir: Path, lc, seed: int) -> dict:
    """An epoch's light-curve table, then its truth row (the epoch's marker), from its AORs."""
    parts = [load_aor_truth(out_dir, a) for a in plan.aors]
    frames = {k: np.concatenate([p[k] for p in parts]) for k in parts[0]}
    table = Table({"time_bmjd": frames["time_bmjd"], "aorkey": frames["aorkey"],
                   "expid": frames["expid"], "frame": frames["frame"],
                   "flux_true": frames["flux_true"], "x_true": frames["x_true"],
                   "y_true": frames["y_true"], "sky_e_per_px": frames["sky_e_per_px"]})
    table.meta = {"epoch": plan.epoch, "seed": seed,
                  "description": "true L(t) (1 = star alone) and true mean position (0-based px) "
                                 "per frame; time_bmjd at the centre of the Fowler weights"}
    with atomic_path(SimulationLayout(out_dir).epoch_lightcurve(plan.epoch)) as tmp:
        table.write(tmp, format="ascii.ecsv")
    row = epoch_truth_row(cfg, plan, frames, lc, seed)
    write_json(SimulationLayout(out_dir).epoch_marker(plan.epoch), row)
    return row


def write_truth(rows: list[dict], out_dir: Path) -> Path:
    """``truth.ecsv``: one row per epoch, the known columns first, the pointing's last."""
    rows = sorted(rows, key=lambda r: r["epoch"])
    seen = {k for r in rows for k in r}
    names = [k for k in TRUTH_COLUMNS if k in seen]
    names += sorted(k for k in seen if k not in names and not k.startswith("ptg_")
                    and k not in ("seed", "noise_model"))
    names += sorted(k for k in seen if k.startswith("ptg_")) + ["seed", "noise_model"]
    cols = {k: [r.get(k, np.nan) for r in rows] for k in names}
    table = Table(cols)
    table.meta = {"description": "one row per simulated epoch (eclipsebench simulate)"}
    path = SimulationLayout(out_dir).truth
    with atomic_path(path) as tmp:
        table.write(tmp, format="ascii.ecsv")
    return path
