"""The data challenge end to end: simulate, photometry, reduce, stats, report.

:func:`build_tasks` turns a configuration into a graph of file-producing
tasks (:mod:`.engine`); :func:`run_challenge` runs it and returns the
summary. The run folder ``DIR``::

    DIR/run_config.toml                    the configuration of the run (guards resume)
    DIR/simulation/                        the simulated challenge (docs/contracts.md)
    DIR/simulation_flat/                   its systematics-free twin (empirical photon limit)
    DIR/photometry[_flat]/epoch_NN.fits    one photometry table per epoch
    DIR/results[_flat]/<method>/epoch_NN.json (+ .lc.ecsv)   one reduction per epoch x method
    DIR/depths.ecsv                        method, epoch, depth_ppm, error_ppm
    DIR/summary.json                       statistics + photon limits + truth + seed + config
    DIR/report/index.html                  figures and tables
    DIR/timings.ecsv                       when, where and how long each task of the
                                           last invocation ran (not part of the results)

Each task writes its files atomically, its declared output last, so a task
is done exactly when that file exists: rerunning after an interruption
redoes only what is missing, and since every random stream is keyed by what
it is for (:mod:`eclipsebench.seeding`), the numbers are the same whatever
was interrupted and however many workers ran.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, replace
from functools import lru_cache
from pathlib import Path

import numpy as np

from ..config import Config, dump_toml, to_mapping
from ..errors import ConfigError, DataError, InputError
from ..io.atomic import atomic_path, write_json, write_text
from ..progress import get_logger
from .engine import RunReport, Task, run_tasks

__all__ = ["Layout", "resolve_methods", "twin_config", "build_tasks", "run_challenge",
           "summary_config", "EXECUTION_KEYS"]

log = get_logger("challenge")

#: ``[run]`` keys that say how to execute, not what to compute; left out of
#: ``summary.json`` and of the resume guard so 1 and 2 workers give the same bytes.
EXECUTION_KEYS = ("workers", "scheduler")


@dataclass(frozen=True)
class Layout:
    """Where each task of a run writes (see the module docstring)."""

    root: Path

    def sim(self, flat: bool = False) -> Path:
        return self.root / ("simulation_flat" if flat else "simulation")

    def photometry(self, epoch: int, flat: bool = False) -> Path:
        return self.root / ("photometry_flat" if flat else "photometry") / f"epoch_{epoch:02d}.fits"

    def result(self, method: str, epoch: int, flat: bool = False) -> Path:
        return (self.root / ("results_flat" if flat else "results") / method
                / f"epoch_{epoch:02d}.json")

    @property
    def depths(self) -> Path:
        return self.root / "depths.ecsv"

    @property
    def summary(self) -> Path:
        return self.root / "summary.json"

    @property
    def timings(self) -> Path:
        return self.root / "timings.ecsv"

    @property
    def report(self) -> Path:
        return self.root / "report" / "index.html"

    @property
    def run_config(self) -> Path:
        return self.root / "run_config.toml"


def resolve_methods(cfg: Config) -> list[str]:
    """``run.methods`` checked against the registry (empty: every registered method)."""
    from ..decorrelate import available_methods

    known = list(available_methods())
    if not cfg.run.methods:
        return known
    unknown = [m for m in cfg.run.methods if m not in known]
    if unknown:
        raise ConfigError("run.methods", f"unknown method(s) {', '.join(unknown)} "
                                         f"(registered: {', '.join(known)})")
    return list(dict.fromkeys(cfg.run.methods))


def twin_config(cfg: Config) -> Config:
    """The systematics-free twin: no pointing motion, no calibration set, same seeds."""
    return replace(cfg, simulation=replace(cfg.simulation, pointing_motion=False,
                                           write_calibration=False))


def summary_config(cfg: Config) -> dict:
    """The configuration mapping without the execution-only ``[run]`` keys."""
    mapping = to_mapping(cfg)
    for key in EXECUTION_KEYS:
        mapping["run"].pop(key, None)
    return mapping


def photon_limit_method(cfg: Config, methods: list[str]) -> str:
    """The method that reduces the systematics-free twins."""
    name = cfg.run.photon_limit_method or methods[0]
    if name not in methods:
        from ..decorrelate import available_methods
        if name not in available_methods():
            raise ConfigError("run.photon_limit_method", f"unknown method {name!r}")
    return name


# --------------------------------------------------------------------------- task functions
# Module-level so that Dask can ship them to worker processes.

@lru_cache(maxsize=4)
def _light_curve(system_section):
    """L(t) of a ``[system]`` section, built once per worker process (it takes seconds)."""
    from ..astro.lightcurve import light_curve_from_config

    return light_curve_from_config(system_section)


def simulate_aor_task(cfg: Config, plan, aor_index: int, sim_dir: str, seed: int) -> None:
    """Render and write one AOR (``simulate.challenge.simulate_aor``)."""
    from ..simulate.challenge import simulate_aor

    simulate_aor(cfg, plan, aor_index, sim_dir, seed, light_curve=_light_curve(cfg.system))


def calibration_task(cfg: Config, sim_dir: str) -> None:
    """The KR/Pmap calibration-star set of a simulated challenge."""
    from ..simulate.calibration import write_calibration_set

    write_calibration_set(cfg, sim_dir)


def finalize_simulation_task(cfg: Config, sim_dir: str, calibration: bool) -> None:
    """Per-epoch truth, light curves and ``truth.ecsv`` once every AOR is on disk.

    ``simulate_challenge`` skips the complete AORs and only writes the
    per-epoch tables and ``truth.ecsv`` (last).
    """
    from ..simulate.challenge import simulate_challenge

    simulate_challenge(cfg, sim_dir, workers=1, calibration=calibration)


def photometry_task(cfg: Config, sim_dir: str, epoch: int, aorkeys: list[int],
                    out_path: str) -> None:
    """Photometry of one simulated epoch (its AOR folders) into ``out_path``."""
    from ..io.bcd_read import find_bcd_files, group_epochs, read_bcd_header
    from ..photometry.pipeline import process_epoch
    from ..photometry.table import write_photometry

    root = Path(sim_dir)
    files = [p for a in aorkeys for p in find_bcd_files(root / f"r{a}")]
    epochs = group_epochs([read_bcd_header(p) for p in files],
                          gap_days=cfg.photometry.epoch_gap_days)
    if len(epochs) != 1 or epochs[0].number != epoch:
        raise RuntimeError(f"AORs {aorkeys} of epoch {epoch} were grouped as epochs "
                           f"{[e.number for e in epochs]}")
    write_photometry(process_epoch(epochs[0], cfg.photometry, input_root=root), out_path)


def _system(cfg: Config):
    from ..astro.catalogue import get_system

    return get_system(cfg.system.name, cfg.system.catalogue or None)


def reduce_task(cfg: Config, table_path: str, method: str, epoch: int, seed: int,
                out_path: str) -> None:
    """Reduce one epoch with one method; write the light curve, then the result JSON.

    A method that refuses the epoch's data (an :class:`InputError`, e.g.
    frames outside KR/Pmap's calibration coverage) is an outcome of the
    benchmark, not a crash: the JSON records ``failed`` and the message, the
    statistics leave that epoch out and list it, and a rerun does not retry it
    (it would fail the same way).
    """
    from ..fit.reduce import reduce_epoch

    out = Path(out_path)
    try:
        result = reduce_epoch(table_path, method, options=cfg.reduce, system=_system(cfg),
                              seed=seed, epoch=epoch)
    except InputError as exc:
        log.warning("%s epoch %d: %s", method, epoch, exc)
        write_json(out, {"method": method, "epoch": epoch, "failed": True, "error": str(exc),
                         "depth_ppm": None, "depth_err_ppm": None})
        return
    with atomic_path(out.with_suffix(".lc.ecsv")) as tmp:
        result.lightcurve_table().write(tmp, format="ascii.ecsv")
    write_json(out, result.to_dict())


def _read_table(path: Path):
    try:
        from ..photometry.table import read_photometry
    except ImportError:  # the photometry stage is not installed
        from astropy.table import Table
        return Table.read(path)
    return read_photometry(path)


def _good(table) -> np.ndarray:
    if "flag" in table.colnames:
        return np.asarray(table["flag"]) == 0
    return np.ones(len(table), dtype=bool)


def _truth_rows(sim_dir: Path):
    from astropy.table import Table

    path = sim_dir / "truth.ecsv"
    return Table.read(path, format="ascii.ecsv") if path.is_file() else None


def _collect_depths(layout: Layout, methods: list[str], epochs: list[int], flat: bool):
    """The depth table of the usable results, and the failures (method, epoch, error)."""
    from astropy.table import Table

    rows, failures = [], []
    for m in methods:
        for e in epochs:
            path = layout.result(m, e, flat)
            res = json.loads(path.read_text())
            depth, err = res.get("depth_ppm"), res.get("depth_err_ppm")
            if res.get("failed") or depth is None or err is None or not (
                    np.isfinite(depth) and np.isfinite(err) and err > 0):
                failures.append({"method": m, "epoch": e,
                                 "error": res.get("error") or f"no usable depth ({depth}) "
                                                              f"and error ({err})"})
                continue
            rows.append((m, e, float(depth), float(err)))
    table = Table(rows=rows or None, names=["method", "epoch", "depth_ppm", "error_ppm"],
                  dtype=[str, int, float, float])
    return table, failures


def _f_in(cfg: Config, tables: dict[int, object], truth) -> float:
    """Fraction of frames in eclipse: configured, or from the eclipse geometry."""
    from .photon import in_eclipse_fraction

    if cfg.run.f_in > 0:
        return float(cfg.run.f_in)
    from ..astro.eclipse import EclipseShape

    system = _system(cfg)
    by_epoch = {int(r["epoch"]): float(r["t_ecl_bmjd"]) for r in truth} if truth is not None else {}
    fractions = []
    for epoch, t in tables.items():
        time = np.asarray(t["time_bmjd"], float)[_good(t)]
        t_ecl = by_epoch.get(epoch)
        if t_ecl is None or not np.isfinite(t_ecl):
            from ..fit.reduce import predicted_eclipse_bmjd
            t_ecl = predicted_eclipse_bmjd(system, time)
        fractions.append(in_eclipse_fraction(EclipseShape(time, system).visible_fraction(t_ecl)))
    return float(np.mean(fractions))


def _readout(cfg: Config) -> dict:
    read_noise = getattr(cfg.simulation, "read_noise_e", None)
    if read_noise is None:
        from ..simulate.challenge import read_noise_of
        read_noise = read_noise_of(cfg)
    return {"fowler": cfg.observation.fowler, "wait": cfg.observation.wait,
            "read_noise_e": float(read_noise)}


def stats_task(cfg: Config, root: str, methods: list[str], epochs: list[int],
               plm: str | None) -> None:
    """Depth table, photon limits and the statistics; ``summary.json`` last."""
    from ..stats.summary import summarize
    from .photon import analytic_photon_limit, empirical_photon_limit

    layout = Layout(Path(root))
    depths, failures = _collect_depths(layout, methods, epochs, flat=False)
    counts = {m: int(np.sum(depths["method"] == m)) for m in methods}
    scored = [m for m in methods if counts[m] >= 2]
    if not scored:
        raise DataError(layout.root / "results", "no method has usable depths in 2 or more "
                                                 "epochs; see the 'error' of the result files")
    excluded = [m for m in methods if m not in scored]
    with atomic_path(layout.depths) as tmp:
        depths.write(tmp, format="ascii.ecsv")
    truth = _truth_rows(layout.sim())
    truth_ppm = None
    truth_varies = False
    if truth is not None and "depth_ppm" in truth.colnames:
        values = np.asarray(truth["depth_ppm"], float)
        truth_ppm = float(np.mean(values))
        truth_varies = bool(np.ptp(values) > 1e-9)
    tables = {e: _read_table(layout.photometry(e)) for e in epochs}
    depth_for_noise = truth_ppm if truth_ppm is not None else float(np.mean(depths["depth_ppm"]))
    analytic = analytic_photon_limit(
        [np.asarray(t["flux"], float)[_good(t)] for t in tables.values()],
        [np.asarray(t["background"], float)[_good(t)] for t in tables.values()],
        depth_ppm=depth_for_noise, f_in=_f_in(cfg, tables, truth),
        aperture_radius_px=cfg.photometry.radius_px,
        annulus_px=tuple(cfg.photometry.annulus_px), **_readout(cfg))
    empirical = None
    if plm is not None:
        flat, flat_failures = _collect_depths(layout, [plm], epochs, flat=True)
        empirical = empirical_photon_limit(flat["depth_ppm"], flat["error_ppm"])
        empirical["method"] = plm
        empirical["failures"] = flat_failures
    sigma = analytic["sigma_phot_ppm"]
    summary = summarize(depths, sigma_phot_ppm=sigma, truth_ppm=truth_ppm, methods=scored,
                        seed=cfg.challenge.seed, n_bootstrap=cfg.run.bootstrap)
    summary.update({
        "challenge": cfg.challenge.name,
        "seed": cfg.challenge.seed,
        "epochs": epochs,
        "method_names": scored,
        "failures": failures,
        "methods_excluded": excluded,
        "sigma_phot_ppm_analytic": sigma,
        "sigma_phot_ppm_empirical": None if empirical is None else empirical["sigma_phot_ppm"],
        "photon_limit": {"used": "analytic", "analytic": analytic, "empirical": empirical},
        "truth_ppm": truth_ppm,
        "truth_varies": truth_varies,
        "config": summary_config(cfg),
    })
    write_json(layout.summary, _finite(summary))


def _finite(obj):
    """JSON-safe copy: non-finite floats become None (stable bytes, valid JSON)."""
    if isinstance(obj, dict):
        return {str(k): _finite(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_finite(v) for v in obj]
    if isinstance(obj, (float, np.floating)):
        return float(obj) if np.isfinite(obj) else None
    if isinstance(obj, np.integer):
        return int(obj)
    return obj


def _phase(time_bmjd, system) -> np.ndarray:
    from ..astro.orbit import orbital_phase

    p = np.asarray(orbital_phase(np.asarray(time_bmjd, float), system))
    return np.where(p > 0.5, p - 1.0, p)


def _gain_map(sim_dir: Path):
    """The intra-pixel gain around the sweet spot from the calibration star (KR, as Fig. 2)."""
    from ..decorrelate.kernel import pmap_gain
    from ..decorrelate.pmap import load_pmap

    path = sim_dir / "calibration" / "pmap_calibration.fits"
    if not path.is_file():
        return None
    cal = load_pmap(path)
    gx = np.linspace(float(np.percentile(cal.x, 1)), float(np.percentile(cal.x, 99)), 41)
    gy = np.linspace(float(np.percentile(cal.y, 1)), float(np.percentile(cal.y, 99)), 41)
    xx, yy = np.meshgrid(gx, gy)
    gain = pmap_gain(cal, xx.ravel(), yy.ravel(), None, k=50, scales=np.ones(2))
    return gx, gy, gain.reshape(xx.shape)


def report_task(cfg: Config, root: str, methods: list[str], epochs: list[int]) -> None:
    """Figures, tables and ``report/index.html`` (written last)."""
    from astropy.table import Table

    from ..report.build import build_report

    layout = Layout(Path(root))
    summary = json.loads(layout.summary.read_text())
    depths = Table.read(layout.depths, format="ascii.ecsv")
    system = _system(cfg)
    photometry = {}
    for e in epochs:
        t = _read_table(layout.photometry(e))
        good = _good(t)
        photometry[e] = {"phase": _phase(np.asarray(t["time_bmjd"])[good], system),
                         **{k: np.asarray(t[k], float)[good]
                            for k in ("x", "y", "noise_pixels", "background", "flux")}}
    lc_epoch = min(cfg.run.lightcurve_epoch, max(epochs))
    curves = {}
    for m in methods:
        path = layout.result(m, lc_epoch).with_suffix(".lc.ecsv")
        if path.is_file():
            lc = Table.read(path, format="ascii.ecsv")
            curves[m] = {"phase": _phase(lc["time_bmjd"], system),
                         "flux_corrected": np.asarray(lc["flux_corrected"], float),
                         "astro_model": np.asarray(lc["astro_model"], float)}
    truth_curve = None
    truth_lc = layout.sim() / "lightcurves" / f"epoch_{lc_epoch:02d}.ecsv"
    if truth_lc.is_file():
        t = Table.read(truth_lc, format="ascii.ecsv")
        truth_curve = (_phase(t["time_bmjd"], system), np.asarray(t["flux_true"], float))
    try:
        gain_map = _gain_map(layout.sim())
    except InputError as exc:
        log.warning("no gain map behind the centroids: %s", exc)
        gain_map = None
    notes = {"challenge": summary.get("challenge"), "seed": summary.get("seed"),
             "epochs": len(epochs), "methods": ", ".join(methods),
             "sigma_phot (analytic, Section 3.3)": _ppm(summary.get("sigma_phot_ppm_analytic")),
             "sigma_phot (empirical, no pointing motion)":
                 _ppm(summary.get("sigma_phot_ppm_empirical")),
             "true depth": _ppm(summary.get("truth_ppm"))}
    build_report(layout.report.parent, summary=summary, depths=depths,
                 truth_ppm=summary.get("truth_ppm"), photometry=photometry, lightcurves=curves,
                 lightcurve_epoch=lc_epoch, truth_curve=truth_curve, gain_map=gain_map,
                 title=f"eclipsebench: {summary.get('challenge')}", notes=notes)


def _ppm(v) -> str:
    return "n/a" if v is None else f"{v:.1f} ppm"


# --------------------------------------------------------------------------- the graph
def _plans(cfg: Config):
    from ..simulate.plan import plan_challenge

    period = _system(cfg).period_days
    return plan_challenge(cfg.observation, cfg.challenge.epochs, period, cfg.challenge.seed)


def build_tasks(cfg: Config, root: str | Path) -> list[Task]:
    """Every task of a challenge run, in a sensible submission order."""
    layout = Layout(Path(root))
    methods = resolve_methods(cfg)
    seed = cfg.challenge.seed
    plans = _plans(cfg)
    epochs = [p.epoch for p in plans]
    aorkeys = {p.epoch: [a.aorkey for a in p.aors] for p in plans}
    plm = photon_limit_method(cfg, methods) if cfg.run.empirical_photon_limit else None
    variants = [False] + ([True] if plm is not None else [])
    calibration = bool(cfg.simulation.write_calibration and cfg.simulation.calibration_frames > 0)
    tasks: list[Task] = []
    reduce_keys: list[str] = []
    for flat in variants:
        vcfg = twin_config(cfg) if flat else cfg
        sim = layout.sim(flat)
        tag = "_flat" if flat else ""
        aor_keys = []
        # the longest AORs first keeps every worker busy
        aors = sorted(((plan, i) for plan in plans for i in range(len(plan.aors))),
                      key=lambda pi: -pi[0].aors[pi[1]].n_cubes)
        for plan, i in aors:
            aor = plan.aors[i]
            key = f"simulate{tag}/r{aor.aorkey}"
            tasks.append(Task(key, "simulate", simulate_aor_task,
                              (vcfg, plan, i, str(sim), seed),
                              (sim / ".simstate" / f"r{aor.aorkey}.npz",)))
            aor_keys.append(key)
        cal = calibration and not flat
        if cal:
            tasks.append(Task("simulate/calibration", "simulate", calibration_task,
                              (vcfg, str(sim)),
                              (sim / "calibration" / "pmap_calibration.fits",)))
            aor_keys.append("simulate/calibration")
        tasks.append(Task(f"simulate{tag}/truth", "simulate", finalize_simulation_task,
                          (vcfg, str(sim), cal), (sim / "truth.ecsv",), tuple(aor_keys)))
        run_methods = [plm] if flat else methods
        for e in epochs:
            phot = layout.photometry(e, flat)
            tasks.append(Task(f"photometry{tag}/epoch_{e:02d}", "photometry", photometry_task,
                              (vcfg, str(sim), e, aorkeys[e], str(phot)), (phot,),
                              (f"simulate{tag}/truth",)))
            for m in run_methods:
                key = f"reduce{tag}/{m}/epoch_{e:02d}"
                out = layout.result(m, e, flat)
                tasks.append(Task(key, "reduce", reduce_task, (vcfg, str(phot), m, e, seed,
                                                               str(out)),
                                  (out,), (f"photometry{tag}/epoch_{e:02d}",)))
                reduce_keys.append(key)
    tasks.append(Task("stats", "stats", stats_task, (cfg, str(layout.root), methods, epochs, plm),
                      (layout.summary,), tuple(reduce_keys)))
    if cfg.run.report:
        tasks.append(Task("report", "report", report_task,
                          (cfg, str(layout.root), methods, epochs), (layout.report,), ("stats",)))
    return tasks


def _guard(cfg: Config, layout: Layout) -> None:
    """Refuse to resume into a folder that holds a run of another configuration.

    The stored configuration is read back through the current schema, so keys
    added since (with their defaults) do not count as a difference.
    """
    from ..config import from_mapping, load_toml

    text = dump_toml(summary_config(cfg))
    if layout.run_config.is_file():
        try:
            stored = summary_config(from_mapping(Config, load_toml(layout.run_config)))
        except InputError:
            stored = None
        if stored != summary_config(cfg):
            raise InputError(f"{layout.root}: holds a run with a different configuration "
                             f"(see {layout.run_config.name}); use another --out or remove it")
        if layout.run_config.read_text() == text:
            return
    write_text(layout.run_config, text)


def run_challenge(cfg: Config, root: str | Path, *, workers: int | None = None,
                  scheduler: str | None = None) -> tuple[dict, RunReport]:
    """Run (or resume) a challenge in ``root``; return the summary and what ran.

    Parameters
    ----------
    cfg : Config
        The effective configuration.
    root : path
        The run folder.
    workers : int, optional
        Default ``run.workers``; 1 runs in this process.
    scheduler : str, optional
        Address of an existing Dask scheduler (default ``run.scheduler``).
    """
    layout = Layout(Path(root))
    if layout.root.exists() and not layout.root.is_dir():
        raise InputError(f"--out {layout.root}: exists and is not a folder")
    layout.root.mkdir(parents=True, exist_ok=True)
    tasks = build_tasks(cfg, layout.root)
    _guard(cfg, layout)
    report = run_tasks(tasks, workers=cfg.run.workers if workers is None else workers,
                       scheduler=(scheduler if scheduler is not None else cfg.run.scheduler) or None)
    if report.timeline:
        write_timings(report, layout.timings)
    return json.loads(layout.summary.read_text()), report


def write_timings(report: RunReport, path: Path) -> None:
    """The tasks' timeline (key, stage, start, seconds, worker) as ECSV, sorted by start."""
    from astropy.table import Table

    rows = sorted(report.timeline, key=lambda t: t.start_s)
    table = Table({"key": [t.key for t in rows],
                   "stage": [t.key.split("/", 1)[0] for t in rows],
                   "start_s": np.array([t.start_s for t in rows]),
                   "seconds": np.array([t.seconds for t in rows]),
                   "worker": [t.worker for t in rows]})
    table["start_s"].unit = table["seconds"].unit = "s"
    table.meta["executor"] = report.executor
    table.meta["wall_s"] = round(report.wall_s, 3)
    with atomic_path(path) as tmp:
        table.write(tmp, format="ascii.ecsv")
