"""The stats stage of a run: depth table, photon limits and the ensemble statistics.

Pure functions (:func:`collect_depths`, :func:`in_eclipse_fraction_of`,
:func:`readout_of`; :func:`json_safe` is :mod:`eclipsebench.io.plain`'s), the task function :func:`stats_task`
(writes ``depths.ecsv`` and ``depths_paper.ecsv``, then ``summary.json`` last) and the planner
:func:`plan_stats_tasks`.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from pathlib import Path

import numpy as np
from astropy.table import Table

from ..astro.catalogue import system_for
from ..astro.eclipse import EclipseShape
from ..config import Config
from ..config.detector import read_noise_of
from ..engine.layout import Layout
from ..engine.tasks import Task
from ..errors import DataError
from ..fit.reduce import predicted_event_bmjd
from ..io.atomic import atomic_path, write_json
from ..io.plain import json_safe
from ..photometry.table import read_photometry
from .photon_limit import analytic_photon_limit, empirical_photon_limit, in_eclipse_fraction
from .summary import summarize

__all__ = ["collect_depths", "good_frames", "in_eclipse_fraction_of", "readout_of",
           "json_safe", "stats_task", "summary_ok", "plan_stats_tasks", "MIN_EPOCHS"]

#: Ensemble statistics (an SD over epochs) need at least this many epochs.
MIN_EPOCHS = 2


def good_frames(table) -> np.ndarray:
    """The frames of a photometry table with flag 0 (all of them without a flag column)."""
    if "flag" in table.colnames:
        return np.asarray(table["flag"]) == 0
    return np.ones(len(table), dtype=bool)


def collect_depths(layout: Layout, methods: list[str], epochs: list[int], flat: bool = False,
                   profile: str = "controlled"):
    """The depth table of the usable results, and the failures (method, epoch, error)."""
    rows, failures = [], []
    for m in methods:
        for e in epochs:
            res = json.loads(layout.result(m, e, flat, profile).read_text())
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


def in_eclipse_fraction_of(cfg: Config, tables: Mapping[int, Table], truth) -> float:
    """Fraction of frames in eclipse: ``run.f_in``, or from the eclipse geometry.

    The eclipse time of each epoch is the truth's, else the one predicted
    from the ephemeris.
    """
    if cfg.run.f_in > 0:
        return float(cfg.run.f_in)
    system = system_for(cfg.system)
    by_epoch = {int(r["epoch"]): float(r["t_ecl_bmjd"]) for r in truth} if truth is not None else {}
    fractions = []
    for epoch, t in tables.items():
        time = np.asarray(t["time_bmjd"], float)[good_frames(t)]
        t_ecl = by_epoch.get(epoch)
        if t_ecl is None or not np.isfinite(t_ecl):
            t_ecl = predicted_event_bmjd(system, time)
        fractions.append(in_eclipse_fraction(EclipseShape(time, system).visible_fraction(t_ecl)))
    return float(np.mean(fractions))


def readout_of(cfg: Config) -> dict:
    """Fowler number, wait ticks and read noise of the configuration's readout."""
    return {"fowler": cfg.observation.fowler, "wait": cfg.observation.wait,
            "read_noise_e": float(read_noise_of(cfg))}


def _truth_rows(path: Path):
    return Table.read(path, format="ascii.ecsv") if path.is_file() else None


def stats_task(cfg: Config, root: str, methods: list[str], epochs: list[int],
               plm: str | None, config_mapping: dict) -> None:
    """Depth table, photon limits and the statistics; ``summary.json`` last.

    ``plm``: the method reduced on the systematics-free twins (empirical
    photon limit), or None. ``config_mapping``: the configuration recorded in
    the summary (without execution-only keys).
    """
    layout = Layout(Path(root))
    collected = {}
    for profile in cfg.run.profiles:
        depths, failures = collect_depths(layout, methods, epochs, profile=profile)
        counts = {m: int(np.sum(depths["method"] == m)) for m in methods}
        scored = [m for m in methods if counts[m] >= MIN_EPOCHS]
        if not scored:
            raise DataError(layout.result(methods[0], epochs[0], profile=profile).parent.parent,
                            f"no method has usable depths in 2 or more epochs ({profile} "
                            "profile); see the 'error' of the result files")
        collected[profile] = (depths, failures, scored)
    for profile, (depths, _, _) in collected.items():
        with atomic_path(layout.depths_of(profile)) as tmp:
            depths.write(tmp, format="ascii.ecsv")
    truth = _truth_rows(layout.truth())
    truth_ppm = None
    truth_varies = False
    if truth is not None and "depth_ppm" in truth.colnames:
        values = np.asarray(truth["depth_ppm"], float)
        truth_ppm = float(np.mean(values))
        truth_varies = bool(np.ptp(values) > 1e-9)
    tables = {e: read_photometry(layout.photometry(e)) for e in epochs}
    first = collected[cfg.run.profiles[0]][0]
    depth_for_noise = truth_ppm if truth_ppm is not None else float(np.mean(first["depth_ppm"]))
    analytic = analytic_photon_limit(
        [np.asarray(t["flux"], float)[good_frames(t)] for t in tables.values()],
        [np.asarray(t["background"], float)[good_frames(t)] for t in tables.values()],
        depth_ppm=depth_for_noise, f_in=in_eclipse_fraction_of(cfg, tables, truth),
        aperture_radius_px=cfg.photometry.radius_px,
        annulus_px=(cfg.photometry.annulus_px[0], cfg.photometry.annulus_px[1]),
        **readout_of(cfg))
    empirical = None
    if plm is not None:
        flat, flat_failures = collect_depths(layout, [plm], epochs, flat=True)
        empirical = empirical_photon_limit(flat["depth_ppm"], flat["error_ppm"])
        empirical["method"] = plm
        empirical["failures"] = flat_failures
    sigma = analytic["sigma_phot_ppm"]
    profiles = {}
    for profile, (depths, failures, scored) in collected.items():
        profiles[profile] = summarize(depths, sigma_phot_ppm=sigma, truth_ppm=truth_ppm,
                                      methods=scored, seed=cfg.challenge.seed,
                                      n_bootstrap=cfg.run.bootstrap)
        profiles[profile].update({"method_names": scored, "failures": failures,
                                  "methods_excluded": [m for m in methods if m not in scored]})
    # The top level is the first profile's (the layout every earlier summary had).
    summary = dict(profiles[cfg.run.profiles[0]])
    summary.update({
        "profile": cfg.run.profiles[0],
        "profiles": profiles,
        "challenge": cfg.challenge.name,
        "seed": cfg.challenge.seed,
        "epochs": epochs,
        "sigma_phot_ppm_analytic": sigma,
        "sigma_phot_ppm_empirical": None if empirical is None else empirical["sigma_phot_ppm"],
        "photon_limit": {"used": "analytic", "analytic": analytic, "empirical": empirical},
        "truth_ppm": truth_ppm,
        "truth_varies": truth_varies,
        "config": config_mapping,
    })
    write_json(layout.summary, json_safe(summary))


def summary_ok(*paths: Path) -> bool:
    """Resume check: ``summary.json`` (the last path) parses and has every profile's
    statistics; each depth table (the other paths) reads."""
    *depth_tables, summary = paths
    data = json.loads(Path(summary).read_text())
    profiles = data.get("profiles") if isinstance(data, dict) else None
    return (isinstance(data, dict) and isinstance(data.get("methods"), dict)
            and "photon_limit" in data and isinstance(profiles, dict)
            and all(isinstance(p, dict) and isinstance(p.get("methods"), dict)
                    for p in profiles.values())
            and all("method" in Table.read(d, format="ascii.ecsv").colnames
                    for d in depth_tables))


def plan_stats_tasks(cfg: Config, layout: Layout, methods: list[str], epochs: list[int],
                     plm: str | None, config_mapping: dict, *,
                     after: tuple[str, ...]) -> list[Task]:
    """The one ``stats`` task, after every reduction (and the photometry and truth it reads)."""
    depth_tables = tuple(layout.depths_of(p) for p in cfg.run.profiles)
    return [Task("stats", "stats", stats_task,
                 (cfg, str(layout.root), methods, epochs, plm, config_mapping),
                 (*depth_tables, layout.summary), tuple(after), check=summary_ok)]
