"""The data challenge end to end: simulate, photometry, reduce, stats, report.

The runner does no stage work: :func:`build_tasks` composes the stages'
planners into one graph of file-producing tasks, and :func:`run_challenge`
runs it on the engine (:mod:`.engine`) and returns the summary.

=========== ============================================ ===========================
stage       planner                                       task keys
=========== ============================================ ===========================
simulate    :func:`eclipsebench.simulation.stage.plan_simulate_tasks`
                                                          ``simulate[_flat]/...``
photometry  :func:`.photometry_stage.plan_photometry_tasks` ``photometry[_flat]/epoch_NN``
reduce      :func:`.reduce_stage.plan_reduce_tasks`        ``reduce[_flat|_paper]/<m>/epoch_NN``
stats       :func:`eclipsebench.stats.challenge.plan_stats_tasks`    ``stats``
report      :func:`eclipsebench.report.challenge.plan_report_tasks`  ``report/figures-*``, ``report``
=========== ============================================ ===========================

The run folder is described by :class:`eclipsebench.engine.layout.Layout`. Each task writes
its files atomically, its declared output last, and the engine stamps it
with the hashes of its outputs and inputs, so rerunning after an
interruption redoes only what is missing or not whole; and since every
random stream is keyed by what it is for (:mod:`eclipsebench.seeding`), the
numbers are the same whatever was interrupted and however many workers ran.
A lock file (``run.lock``) keeps a second run out of the folder.
"""

from __future__ import annotations

import contextlib
import json
import os
from dataclasses import replace
from pathlib import Path

import numpy as np
from astropy.table import Table

from ..astro.catalogue import system_for
from ..astro.events import event_for
from ..config import Config, dump_toml, from_mapping, load_toml, to_mapping
from ..decorrelate import available_methods
from ..decorrelate.base import unknown_methods
from ..engine.cluster import ClusterOptions, SchedulerUnreachable, external_security
from ..engine.folder import check_free_space, check_kind, claim, planet_input
from ..engine.layout import Layout
from ..engine.lock import run_lock
from ..engine.tasks import RunReport, Task, check_outputs_inside, run_tasks
from ..errors import ConfigError, InputError
from ..io.atomic import atomic_path, write_text
from ..io.paths import check_links_inside, check_output_path
from ..report.challenge import plan_photometry_figures_task, plan_report_tasks
from ..simulation.stage import challenge_plans, plan_simulate_tasks, simulated_bytes
from ..stats.challenge import MIN_EPOCHS, plan_stats_tasks
from .photometry_stage import photometry_key, plan_photometry_tasks
from .reduce_stage import plan_reduce_tasks, reduce_key

__all__ = ["Layout", "resolve_methods", "twin_config", "build_tasks", "run_challenge",
           "summary_config", "EXECUTION_KEYS"]

#: ``[run]`` keys that say how to execute, not what to compute; left out of
#: ``summary.json`` and of the resume guard so 1 and 2 workers give the same bytes.
EXECUTION_KEYS = ("workers", "scheduler")


def resolve_methods(cfg: Config) -> list[str]:
    """``run.methods`` checked against the registry (empty: every registered method)."""
    known = list(available_methods())
    if not cfg.run.methods:
        return known
    if problem := unknown_methods(cfg.run.methods):
        raise ConfigError("run.methods", problem)
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
    if name not in methods and name not in available_methods():
        raise ConfigError("run.photon_limit_method", f"unknown method {name!r}")
    return name


def check_run_config(cfg: Config) -> None:
    """What makes a run pointless, refused before any work."""
    for key, event in (("observation.event", cfg.observation.event),
                       ("reduce.event", cfg.reduce.event)):
        if not event_for(event).scored:
            raise ConfigError(key, f"a run scores eclipse depths against the truth, not "
                                   f"{event}s; simulate them with `simulate` and fit them with "
                                   f"`reduce --event {event}`")
    if cfg.challenge.epochs < MIN_EPOCHS:
        raise ConfigError("challenge.epochs", f"the ensemble statistics of a run need at least "
                                              f"{MIN_EPOCHS} epochs, got {cfg.challenge.epochs}")


def build_tasks(cfg: Config, root: str | Path) -> list[Task]:
    """Every task of a challenge run (the stages' planners composed), in submission order."""
    check_run_config(cfg)
    layout = Layout(Path(root))
    methods = resolve_methods(cfg)
    plans = challenge_plans(cfg)
    epochs = [p.epoch for p in plans]
    plm = photon_limit_method(cfg, methods) if cfg.run.empirical_photon_limit else None
    tasks: list[Task] = []
    # The plan's order is the engine's priority: the systematics-free twin's short chain
    # (simulate, measure, one method) before the long list of reductions, so that the run
    # ends on reductions that both workers share rather than on that chain.
    for flat in [False] + ([True] if plm is not None else []):
        vcfg = twin_config(cfg) if flat else cfg  # the twin writes no calibration set
        sim_tasks = plan_simulate_tasks(vcfg, layout.sim(flat),
                                        prefix="simulate_flat" if flat else "simulate")
        tasks += sim_tasks
        tasks += plan_photometry_tasks(vcfg, layout, plans, flat=flat,
                                       after=(sim_tasks[-1].key,))
        if not flat and cfg.run.report:
            tasks += plan_photometry_figures_task(cfg, layout, epochs, after=tuple(
                photometry_key(e) for e in epochs))
        if flat and plm is not None:
            tasks += plan_reduce_tasks(vcfg, layout, epochs, [plm], flat=True)
    for profile in cfg.run.profiles:
        tasks += plan_reduce_tasks(cfg, layout, epochs, methods, profile=profile)
    results = [reduce_key(m, e, profile=p) for p in cfg.run.profiles for e in epochs
               for m in methods]
    reads = (results + ([reduce_key(plm, e, True) for e in epochs] if plm is not None else [])
             + [photometry_key(e) for e in epochs] + ["simulate/truth"])
    tasks += plan_stats_tasks(cfg, layout, methods, epochs, plm, summary_config(cfg),
                              after=tuple(reads))
    if cfg.run.report:
        tasks += plan_report_tasks(cfg, layout, methods, epochs,
                                   after=("stats", *(photometry_key(e) for e in epochs),
                                          *results))
    return tasks


def external_system(cfg: Config) -> bool:
    """Whether the planet comes from outside the package (a user catalogue or its values)."""
    return bool(cfg.system.catalogue or cfg.system.planet)


def _guarded(mapping: dict) -> dict:
    """A run's configuration as the guard compares it: the catalogue's path left out (the
    planet's elements, by content, are in the folder's marker)."""
    return {**mapping, "system": {k: v for k, v in mapping["system"].items()
                                  if k != "catalogue"}}


def _guard(cfg: Config, layout: Layout) -> None:
    """Refuse to resume into a folder that holds a run of another configuration.

    The stored configuration is read back through the current schema, so keys
    added since (with their defaults) do not count as a difference.
    """
    text = dump_toml(summary_config(cfg))
    if layout.run_config.is_file():
        try:
            stored = _guarded(summary_config(from_mapping(Config, load_toml(layout.run_config))))
        except InputError:
            stored = None
        if stored != _guarded(summary_config(cfg)):
            raise InputError(f"{layout.root}: holds a run with a different configuration "
                             f"(see {layout.run_config.name}); use another --out or remove it")
        if layout.run_config.read_text() == text:
            return
    write_text(layout.run_config, text)


def run_challenge(cfg: Config, root: str | os.PathLike[str], *, workers: int | None = None,
                  scheduler: str | None = None,
                  cluster: ClusterOptions | None = None) -> tuple[dict, RunReport]:
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
        Address of an existing Dask scheduler (``tcp://`` or ``tls://``).
    cluster : ClusterOptions, optional
        Dashboard, connection timeout and TLS files of the Dask cluster
        (:mod:`eclipsebench.engine.cluster`).

    Raises
    ------
    InputError
        ``root`` is a file, holds a run of another configuration, or another
        run is working in it (``run.lock``); a :class:`ConfigError` for a
        configuration that cannot make a run (e.g. fewer than 2 epochs).
    """
    layout = Layout(check_output_path(root, "root", "folder"))
    tasks = build_tasks(cfg, layout.root)  # every configuration error before any work
    planet = planet_input(system_for(cfg.system))
    if external_system(cfg):   # the stamps of every task record the planet by content
        tasks = [replace(t, sources=(planet.sha256,)) for t in tasks]
    check_kind(layout.root, "run")
    check_links_inside(layout.root)
    check_outputs_inside(tasks, layout.root)
    if scheduler:
        external_security(scheduler, cluster or ClusterOptions())  # TLS files named, readable
    needed, what = estimated_bytes(cfg, layout)
    check_free_space(layout.root, needed, what)
    layout.root.mkdir(parents=True, exist_ok=True)
    with run_lock(layout.lock):
        fresh = not layout.run_config.exists()
        claim(layout.root, "run", {"system": planet}, legacy_ok=not external_system(cfg))
        _guard(cfg, layout)
        try:
            report = run_tasks(tasks, workers=cfg.run.workers if workers is None else workers,
                               scheduler=scheduler or None, cluster=cluster, root=layout.root)
        except SchedulerUnreachable:
            if fresh:  # nothing ran: leave the folder as it was
                layout.run_config.unlink(missing_ok=True)
                layout.marker.unlink(missing_ok=True)
            raise
        if report.timeline:
            write_timings(report, layout.timings)
        return json.loads(layout.summary.read_text()), report


def _bytes_under(folder: Path) -> int:
    """Bytes of the files under ``folder`` (links not followed), 0 when it does not exist."""
    total = 0
    for dirpath, _, names in os.walk(folder):
        for name in names:
            with contextlib.suppress(OSError):
                total += os.lstat(os.path.join(dirpath, name)).st_size
    return total


def estimated_bytes(cfg: Config, layout: Layout) -> tuple[int, str]:
    """What a run will write, less what its simulations already hold: the simulated cubes
    (and their no-motion twins'), the bulk of a run; ``(bytes, what it counts)``."""
    cubes = simulated_bytes(cfg) * (2 if cfg.run.empirical_photon_limit else 1)
    held = _bytes_under(layout.sim(False)) + _bytes_under(layout.sim(True))
    twins = " and their no-motion twins'" if cfg.run.empirical_photon_limit else ""
    return max(0, cubes - held), f"the simulated cubes{twins}"


def write_timings(report: RunReport, path: Path) -> None:
    """The tasks' timeline (key, stage, start, seconds, worker) as ECSV, sorted by start."""
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
