"""One AOR of the challenge rendered and written: its cubes, their headers and its per-frame
truth (``.simstate/r<AORKEY>.npz``, written last: the AOR's marker).
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from ..astro.catalogue import system_for
from ..config import Config
from ..config.detector import fluxconv_of, gain_of
from ..detector.constants import ReadoutMode
from ..detector.fowler import bunc_mjysr, electrons_to_mjysr
from ..engine.layout import SimulationLayout
from ..instrument.pointing import (
    PointingModel,
    frame_windows,
)
from ..io.atomic import atomic_path
from ..io.bcd_write import AorWriter, bmjd_to_utc
from ..io.header_template import BcdHeaderInfo
from ..progress import progress
from ..seeding import rng
from .from_config import draw_epoch_pointing, frame_model_from_config, light_curve_of, target_of
from .plan import SECONDS_PER_DAY, AORPlan, EpochPlan
from .render import render_cube
from .star import StarImager, make_star_imager, prf_label

__all__ = ['simulate_aor']

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
    ra, dec, object_name = target_of(cfg)
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
        t_mid_s = starts + tick_mid
        time_bmjd = plan.to_bmjd(t_mid_s)
        flux_true = np.asarray(lc(time_bmjd), dtype=float)
        bg = bg_per_tick * (1.0 + sim.background_slope_per_day * t_mid_s / SECONDS_PER_DAY)
        expid = c
        frames_e, expected_e, x_f, y_f = render_cube(
            model=model, star=star, x_px=aor.x0_px, y_px=aor.y0_px, dx=dx, dy=dy,
            star_e_per_tick=flux_per_tick * flux_true, background_e_per_tick=bg,
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
    with atomic_path(SimulationLayout(out_dir).aor_state(aor.aorkey)) as tmp:
        with open(tmp, "wb") as fh:
            np.savez(fh, **out)  # type: ignore[arg-type]  # numpy's stub types **kwds as allow_pickle
    return out
