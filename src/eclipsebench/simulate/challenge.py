"""Simulate a whole data challenge: plans, pointing, cubes, truth, calibration set.

``simulate_challenge(config, out_dir)`` writes the folder described in
``docs/contracts.md``::

    DIR/config.toml, DIR/truth.ecsv, DIR/r<AORKEY>/ch2/bcd/*_bcd.fits (+ _bunc),
    DIR/lightcurves/epoch_NN.ecsv, DIR/calibration/pmap_calibration.fits

Work is split in AOR tasks (run in worker processes when ``run.workers`` > 1).
Every random stream is keyed by what it is for (``("simulate", epoch,
"pointing")``, ``("simulate", epoch, aorkey, expid, "photon")``, ...), so the
bytes depend on the seed only, never on the number of workers or the order.

Resuming: an AOR task writes its cubes, then ``DIR/.simstate/r<AORKEY>.npz``
(its per-frame truth) last; an epoch is complete when its
``DIR/.simstate/epoch_NN.json`` exists, written after its light-curve table.
A rerun skips complete AORs and epochs.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass, fields
from pathlib import Path

import numpy as np

from ..config import Config, dump_toml, to_mapping
from ..errors import ConfigError
from ..instrument.constants import ReadoutMode
from ..instrument.fowler import bunc_mjysr, electrons_to_mjysr
from ..instrument.pointing import (
    ParamRange,
    PointingModel,
    PointingParams,
    PointingRanges,
    draw_pointing_params,
)
from ..io.atomic import atomic_path, write_json, write_text
from ..io.bcd_write import AorWriter, bcd_path, bmjd_to_utc, bunc_path
from ..io.header_template import XO3_DEC_DEG, XO3_RA_DEG, BcdHeaderInfo
from ..progress import get_logger, progress
from ..seeding import rng
from .plan import SECONDS_PER_DAY, AORPlan, EpochPlan, plan_challenge
from .render import FrameModel, render_frames, stamp_origin, tick_moments
from .star import StarImager, make_star_imager, prf_label

__all__ = ["simulate_challenge", "ChallengeResult", "pointing_ranges_from_config",
           "readout_from_config", "frame_model_from_config", "STATE_DIR"]

STATE_DIR = ".simstate"
CAL_CHUNKS_PER_TASK = 3
TRUTH_COLUMNS = ("epoch", "aorkey_pre", "aorkey_main", "start_bmjd", "t_ecl_bmjd", "depth_ppm",
                 "x_mean", "x_sd", "y_mean", "y_sd", "xy_cov", "n_frames")
log = get_logger("simulate")


_LC_CACHE: dict = {}


def light_curve_of(cfg: Config):
    """L(t) of ``cfg.system`` (cached per process: building it takes seconds)."""
    from ..astro.lightcurve import light_curve_from_config

    lc = _LC_CACHE.get(cfg.system)
    if lc is None:
        lc = light_curve_from_config(cfg.system)
        _LC_CACHE.clear()
        _LC_CACHE[cfg.system] = lc
    return lc


def readout_from_config(cfg: Config) -> ReadoutMode:
    """The :class:`ReadoutMode` of ``[observation]`` (subarray)."""
    obs = cfg.observation
    t_int = (2 * obs.fowler + obs.wait) * obs.sample_time_s
    return ReadoutMode("configured", obs.fowler, obs.wait, obs.sample_time_s,
                       round(t_int, 6), True)


def read_noise_of(cfg: Config) -> float:
    """Read noise per read: ``simulation.read_noise_e``, or the model's own when unset."""
    from ..instrument.constants import READ_NOISE_E, READ_NOISE_IRACSIM2015_E

    sim = cfg.simulation
    if sim.read_noise_e is not None:
        return float(sim.read_noise_e)
    return READ_NOISE_IRACSIM2015_E if sim.noise_model == "iracsim2015" else READ_NOISE_E


def frame_model_from_config(cfg: Config) -> FrameModel:
    """The :class:`FrameModel` of a configuration."""
    sim = cfg.simulation
    return FrameModel(mode=readout_from_config(cfg), noise_model=sim.noise_model,
                      read_noise_e=read_noise_of(cfg), subsamples=sim.subsamples,
                      stamp_px=sim.stamp_px)


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
    from ..errors import InputError

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


@dataclass
class _AorTask:
    cfg: Config
    plan: EpochPlan
    aor_index: int
    out_dir: str
    seed: int


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
        frames_per_cube=obs.frames_per_cube, fluxconv=sim.fluxconv,
        gain_e_per_dn=sim.gain_e_per_dn, read_noise_e=read_noise_e, ra_deg=ra, dec_deg=dec,
        star_x_px=aor.x0_px, star_y_px=aor.y0_px, pointing_motion=sim.pointing_motion,
        flat_gain=sim.flat_gain, prf=prf_label(sim.prf))


def _target(cfg: Config) -> tuple[float, float, str]:
    """RA, Dec (deg) and OBJECT of the target: XO-3's unless the catalogue knows better."""
    from ..astro.catalogue import get_system

    system = get_system(cfg.system.name, cfg.system.catalogue or None)
    ra = getattr(system, "ra_deg", None)
    dec = getattr(system, "dec_deg", None)
    name = system.name[:-1] if system.name.endswith("b") else system.name
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

    truth = {k: [] for k in ("time_bmjd", "flux_true", "x_true", "y_true", "expid", "frame",
                             "sky_e_per_px")}
    cubes = range(aor.n_cubes)
    if show_progress:
        cubes = progress(cubes, desc=f"epoch {plan.epoch} r{aor.aorkey}", total=aor.n_cubes,
                         unit="cube")
    for c in cubes:
        starts = frame_starts[c]
        nf = starts.size
        if pointing is not None:
            first = _grid_index(starts[0], dt_s)
            offs = _grid_index(starts, dt_s) - first
            gx, gy = pointing.offsets_grid(int(first), int(offs[-1] + n_grid))
            win = offs[:, None] + np.arange(n_grid)[None, :]
            dx, dy = gx[win], gy[win]
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
        bcd = electrons_to_mjysr(frames_e, fluxconv=sim.fluxconv, gain=sim.gain_e_per_dn,
                                 t_exp_s=mode.t_exp_s).astype(np.float32)
        bunc = bunc_mjysr(expected_e, mode, read_noise_e=model.read_noise_e,
                          fluxconv=sim.fluxconv, gain=sim.gain_e_per_dn).astype(np.float32)
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
    state = out_dir / STATE_DIR / f"r{aor.aorkey}.npz"
    with atomic_path(state) as tmp:
        with open(tmp, "wb") as fh:
            np.savez(fh, **out)
    return out


def _aor_done(out_dir: Path, aor: AORPlan) -> bool:
    state = out_dir / STATE_DIR / f"r{aor.aorkey}.npz"
    if not state.is_file():
        return False
    return all(bcd_path(out_dir, aor.aorkey, c).is_file() and bunc_path(out_dir, aor.aorkey,
                                                                          c).is_file()
               for c in range(aor.n_cubes))


def _load_aor_truth(out_dir: Path, aor: AORPlan) -> dict[str, np.ndarray]:
    with np.load(out_dir / STATE_DIR / f"r{aor.aorkey}.npz") as data:
        return {k: data[k] for k in data.files}


def _run_aor_task(task: _AorTask) -> tuple[int, int]:
    from ..errors import InputError

    try:
        simulate_aor(task.cfg, task.plan, task.aor_index, task.out_dir, task.seed,
                     show_progress=False)
    except InputError as exc:  # ConfigError/DataError do not survive pickling
        raise InputError(str(exc)) from None
    return task.plan.epoch, task.aor_index


def _run_calibration_task(cfg: Config, chunks: list[int]) -> tuple[list[int], list[dict]]:
    from ..errors import InputError
    from .calibration import calibration_chunk

    try:
        return chunks, [calibration_chunk(cfg, c) for c in chunks]
    except InputError as exc:  # ConfigError/DataError do not survive pickling
        raise InputError(str(exc)) from None


def _epoch_marker(out_dir: Path, epoch: int) -> Path:
    return out_dir / STATE_DIR / f"epoch_{epoch:02d}.json"


def epoch_truth_row(cfg: Config, plan: EpochPlan, frames: dict[str, np.ndarray], lc,
                    seed: int) -> dict:
    """One ``truth.ecsv`` row: AORKEYs, times, depth, realised centroid statistics, pointing."""
    x, y = frames["x_true"], frames["y_true"]
    t0 = plan.start_bmjd
    t1 = float(frames["time_bmjd"].max())
    eclipses = lc.eclipse_times_bmjd(t0, t1)
    keys = {a.label: a.aorkey for a in plan.aors}
    row = {"epoch": plan.epoch, "aorkey_pre": keys.get("Pre", -1),
           "aorkey_main": keys["Main"], "start_bmjd": t0,
           "t_ecl_bmjd": float(eclipses[0]) if eclipses else float("nan"),
           "depth_ppm": float(lc.depth_ppm), "x_mean": float(x.mean()), "x_sd": float(x.std()),
           "y_mean": float(y.mean()), "y_sd": float(y.std()),
           "xy_cov": float(np.mean((x - x.mean()) * (y - y.mean()))),
           "n_frames": int(x.size)}
    for a in plan.aors:
        row[f"x0_{a.label.lower()}_px"] = a.x0_px
        row[f"y0_{a.label.lower()}_px"] = a.y0_px
    for k, v in draw_epoch_pointing(cfg, plan.epoch, seed).to_dict().items():
        row[f"ptg_{k}"] = v
    row["seed"] = seed
    row["noise_model"] = cfg.simulation.noise_model
    return row


def _write_epoch(cfg: Config, plan: EpochPlan, out_dir: Path, lc, seed: int) -> dict:
    from astropy.table import Table

    parts = [_load_aor_truth(out_dir, a) for a in plan.aors]
    frames = {k: np.concatenate([p[k] for p in parts]) for k in parts[0]}
    table = Table({"time_bmjd": frames["time_bmjd"], "aorkey": frames["aorkey"],
                   "expid": frames["expid"], "frame": frames["frame"],
                   "flux_true": frames["flux_true"], "x_true": frames["x_true"],
                   "y_true": frames["y_true"], "sky_e_per_px": frames["sky_e_per_px"]})
    table.meta = {"epoch": plan.epoch, "seed": seed,
                  "description": "true L(t) (1 = star alone) and true mean position (0-based px) "
                                 "per frame; time_bmjd at the centre of the Fowler weights"}
    path = out_dir / "lightcurves" / f"epoch_{plan.epoch:02d}.ecsv"
    with atomic_path(path) as tmp:
        table.write(tmp, format="ascii.ecsv")
    row = epoch_truth_row(cfg, plan, frames, lc, seed)
    write_json(_epoch_marker(out_dir, plan.epoch), row)
    return row


def _write_truth(rows: list[dict], out_dir: Path) -> Path:
    from astropy.table import Table

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


def simulate_challenge(cfg: Config, out_dir: str | Path, *, workers: int | None = None,
                       calibration: bool | None = None) -> ChallengeResult:
    """Simulate ``cfg.challenge.epochs`` epochs (and the calibration set) into ``out_dir``.

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
    out.mkdir(parents=True, exist_ok=True)
    seed = cfg.challenge.seed
    workers = cfg.run.workers if workers is None else int(workers)
    calibration = cfg.simulation.write_calibration if calibration is None else calibration
    cal_file = out / "calibration" / "pmap_calibration.fits"
    calibration = bool(calibration) and cfg.simulation.calibration_frames > 0
    cal_needed = calibration and not cal_file.is_file()
    lc = light_curve_of(cfg)
    make_star_imager(cfg)  # fail early on a bad PRF choice
    for epoch in range(1, cfg.challenge.epochs + 1):
        draw_epoch_pointing(cfg, epoch, seed)  # ... and on bad pointing ranges
    config_text = dump_toml(to_mapping(cfg))
    existing = out / "config.toml"
    if existing.is_file() and existing.read_text() != config_text:
        from ..errors import InputError

        raise InputError(f"--out {out}: holds a challenge simulated with a different "
                         "configuration (see its config.toml); choose another folder")
    write_text(existing, config_text)
    plans = plan_challenge(cfg.observation, cfg.challenge.epochs, lc.system.period_days, seed)

    rows: dict[int, dict] = {}
    todo: list[_AorTask] = []
    skipped = 0
    for plan in plans:
        marker = _epoch_marker(out, plan.epoch)
        if marker.is_file():
            rows[plan.epoch] = json.loads(marker.read_text())
            skipped += len(plan.aors)
            continue
        for i, aor in enumerate(plan.aors):
            if _aor_done(out, aor):
                skipped += 1
            else:
                todo.append(_AorTask(cfg, plan, i, str(out), seed))
    # the longest tasks first keeps both workers busy
    todo.sort(key=lambda t: -t.plan.aors[t.aor_index].n_cubes)

    cal_path = None
    from .calibration import concat_chunks, n_chunks, write_calibration_table

    cal_tasks = ([list(range(c, min(c + CAL_CHUNKS_PER_TASK, n_chunks(cfg))))
                  for c in range(0, n_chunks(cfg), CAL_CHUNKS_PER_TASK)] if cal_needed else [])
    cal_parts: dict[int, dict] = {}
    bar = progress(total=len(todo) + len(cal_tasks), desc="simulate (AORs, calibration)",
                   unit="task")
    if workers > 1 and len(todo) + len(cal_tasks) > 1:
        with ProcessPoolExecutor(max_workers=workers) as pool:
            futures = [pool.submit(_run_aor_task, t) for t in todo]
            futures += [pool.submit(_run_calibration_task, cfg, ch) for ch in cal_tasks]
            for fut in as_completed(futures):
                res = fut.result()
                if isinstance(res[1], list):
                    cal_parts.update(zip(res[0], res[1], strict=True))
                bar.update(1)
    else:
        for t in todo:
            simulate_aor(t.cfg, t.plan, t.aor_index, t.out_dir, t.seed, light_curve=lc)
            bar.update(1)
        for ch in cal_tasks:
            cal_parts.update(zip(*_run_calibration_task(cfg, ch), strict=True))
            bar.update(1)
    bar.close()
    if cal_needed:
        data = concat_chunks([cal_parts[c] for c in sorted(cal_parts)])
        cal_path = Path(write_calibration_table(cfg, data, out))

    for plan in plans:
        if plan.epoch not in rows:
            rows[plan.epoch] = _write_epoch(cfg, plan, out, lc, seed)
    truth_rows = [rows[p.epoch] for p in plans]
    _write_truth(truth_rows, out)
    if calibration and cal_path is None:
        cal_path = cal_file
    n_files = sum(2 * a.n_cubes for p in plans for a in p.aors)
    return ChallengeResult(out_dir=out, epochs=len(plans), truth_rows=truth_rows, files=n_files,
                           skipped_aors=skipped, calibration=cal_path)
