"""A campaign: many real observations of one planet, on the one runner (issue 38, item 1).

Inputs are epochs (:class:`EpochInput`): each is one photometry table of any
pipeline (read with ``reduce``'s column map and time options,
:func:`eclipsebench.fit.data.standardise_table`) or the archive AOR folders and
BCD files of one visit (measured by the one photometry,
:func:`eclipsebench.photometry.pipeline.process_epoch`). :func:`build_campaign_tasks`
plans, on the run folder's :class:`~eclipsebench.engine.layout.Layout`:

=================================== ============================================ =========
task                                writes                                       needs
=================================== ============================================ =========
``photometry/epoch_NN``             ``photometry/epoch_NN.fits`` (times BMJD_TDB)
``reduce[_paper]/<m>/epoch_NN``     ``results[_paper]/<m>/epoch_NN.json``        its table
                                    (run's planner, :func:`.reduce_stage.plan_reduce_tasks`)
``joint/<m>[_chN]``                 ``joint/<m>[_chN].json`` (one depth, every   the tables
                                    epoch of the channel: :func:`joint_task`)    (and <m>'s
                                                                                 reductions)
``stats``                           ``depths[_paper].ecsv``, ``tables/``,        everything
                                    ``summary.json`` (:func:`campaign_stats_task`)
``report`` (``run.report``)         ``report/index.html``                        ``stats``
                                    (:func:`campaign_report_task`)
=================================== ============================================ =========

and :func:`run_campaign` runs them on the engine with ``run``'s folder protocol
(the marker with every input by content, the lock, the settings guard, the
free-space check) and ``run``'s resume rule (the engine's stamps and
:func:`.reduce_stage.result_ok`). With ``twins`` (``--twins N``) each epoch also gets
``twins/epoch_NN``: the trust run of its table (:func:`eclipsebench.trust.run.run_trust`,
in ``twins/epoch_NN/``, its answer copied to ``twins/epoch_NN.json``), and the
statistics are computed a second time with each method's honest error.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
from astropy.table import Table, vstack

from .. import __version__
from ..astro.catalogue import PlanetSystem, system_for, system_from_meta
from ..astro.events import event_for
from ..config import Config, load_toml
from ..config.photometry import PhotometrySection
from ..decorrelate import get_method
from ..engine.cluster import ClusterOptions, SchedulerUnreachable, external_security
from ..engine.folder import Input, check_free_space, check_kind, claim, planet_input
from ..engine.layout import Layout
from ..engine.lock import run_lock
from ..engine.tasks import RunReport, Task, check_outputs_inside, run_tasks
from ..errors import DataError, InputError
from ..fit import reduce as fit_reduce
from ..fit.leastsq import has_hyperparameters
from ..fit.names import EVENTS, TIME_AT, TIME_FORMATS, TIME_SCALES
from ..fit.result import EpochResult, lightcurve_path
from ..fit.target import names_a_system, system_of_table
from ..io.atomic import atomic_path, write_json, write_text
from ..io.bcd_read import BCD_NAME, find_bcd_files, group_epochs, read_bcd_header
from ..io.digest import file_sha256, value_sha256
from ..io.paths import check_links_inside, check_output_path
from ..limits import MAX_EPOCHS, check_size
from ..photometry.pipeline import process_epoch
from ..photometry.table import read_table, write_photometry
from ..progress import get_logger
from ..report.tables import write_tables
from ..stats.challenge import (
    MIN_EPOCHS,
    collect_depths,
    good_frames,
    in_eclipse_fraction_of,
    json_safe,
    readout_of,
)
from ..stats.photon_limit import analytic_photon_limit
from ..stats.summary import summarize
from .photometry_stage import photometry_key
from .reduce_stage import plan_reduce_tasks, reduce_key
from .runner import resolve_methods, summary_config, write_timings

__all__ = ["TableOptions", "EpochInput", "classify_input", "epochs_from_inputs",
           "read_campaign_file", "campaign_planet", "build_campaign_tasks", "run_campaign",
           "combined_depth", "CAMPAIGN_KIND"]

log = get_logger("challenge")

#: The kind of a campaign's run folder (its marker, :mod:`eclipsebench.engine.folder`).
CAMPAIGN_KIND = "campaign"
#: The settings file of a campaign folder (guards its resume).
SETTINGS_FILE = "campaign_config.json"
#: The columns every fit reads (:func:`eclipsebench.fit.data.check_columns`).
FIT_COLUMNS = ("time_bmjd", "flux", "flux_err", "x", "y")
_TABLE_SUFFIXES = (".fits", ".fit", ".fts", ".ecsv", ".csv")
_NEITHER = ("neither an AOR folder (r<AORKEY>/ch*/bcd/), a BCD file (*_bcd.fits) nor a "
            "photometry table (.fits, .ecsv, .csv)")


@dataclass(frozen=True)
class TableOptions:
    """How to read another pipeline's table: ``reduce``'s ``--columns``, ``--time-column``,
    ``--time-format``, ``--time-scale``, ``--time-at`` and ``--observer``."""

    columns: tuple[tuple[str, str], ...] = ()
    time_column: str | None = None
    time_format: str | None = None
    time_scale: str | None = None
    time_at: str | None = None
    observer: str | None = None

    def given(self) -> bool:
        return any(v not in (None, ()) for v in asdict(self).values())

    def time_options(self) -> dict[str, Any]:
        return {k: v for k, v in (("time_scale", self.time_scale), ("time_at", self.time_at),
                                  ("observer", self.observer)) if v is not None}


@dataclass(frozen=True)
class EpochInput:
    """One epoch of a campaign: its number, its inputs and how to read them.

    Attributes
    ----------
    number : int
        The epoch number (1, 2, ... in the order given).
    paths : tuple of str
        One photometry table, or the AOR folders / BCD files of the visit
        (its Pre and Main AORs).
    kind : {"table", "bcd"}
    channel : int or None
        The IRAC channel (default: the table's ``CHANNEL``, the BCD files').
    event : str or None
        ``eclipse``, ``transit`` or ``phase-curve`` (default: ``[reduce] event``).
    table : TableOptions
        The column map and time options of a table.
    """

    number: int
    paths: tuple[str, ...]
    kind: str
    channel: int | None = None
    event: str | None = None
    table: TableOptions = field(default_factory=TableOptions)

    def to_dict(self) -> dict[str, Any]:
        out = asdict(self)
        out["paths"] = list(self.paths)
        out["table"]["columns"] = [list(p) for p in self.table.columns]
        return out


def classify_input(path: str | os.PathLike[str], channel: int | None = None) -> str:
    """``"bcd"`` for an AOR folder or a BCD file, ``"table"`` for a photometry table.

    Raises
    ------
    InputError
        One line naming ``path``: it does not exist, or is neither.
    """
    p = Path(path)
    if not p.exists():
        raise InputError(f"{p}: no such file or folder (expected an AOR folder, a BCD file or "
                         "a photometry table)")
    if p.is_dir():
        try:
            find_bcd_files(p, channel)
        except InputError:
            raise InputError(f"{p}: {_NEITHER}") from None
        return "bcd"
    if BCD_NAME.match(p.name):
        return "bcd"
    if p.is_file() and p.suffix.lower() in _TABLE_SUFFIXES:
        return "table"
    raise InputError(f"{p}: {_NEITHER}")


def _epoch(number: int, paths: Sequence[str], channel: int | None, event: str | None,
           table: TableOptions, where: str) -> EpochInput:
    kinds = {classify_input(p, channel) for p in paths}
    if not paths:
        raise InputError(f"{where}: no inputs")
    if len(kinds) > 1:
        raise InputError(f"{where}: mixes BCD data and photometry tables; one epoch is either "
                         "its AOR folders or one table")
    kind = kinds.pop()
    if kind == "table" and len(paths) > 1:
        raise InputError(f"{where}: {len(paths)} tables; one epoch is one photometry table "
                         "(give each table as an epoch of its own)")
    if event is not None and event not in EVENTS:
        raise InputError(f"{where}: event {event!r} is not one of {', '.join(EVENTS)}")
    if kind == "bcd" and table.given():
        raise InputError(f"{where}: column and time options apply to tables, not to BCD data")
    return EpochInput(number, tuple(str(p) for p in paths), kind, channel, event, table)


def epochs_from_inputs(items: Sequence[str | os.PathLike[str]], *,
                       table: TableOptions = TableOptions(), channel: int | None = None,
                       event: str | None = None) -> list[EpochInput]:
    """One epoch per input given (a table, an AOR folder or a BCD file), numbered 1, 2, ..."""
    check_size("epochs", len(items), MAX_EPOCHS, "epochs")
    return [_epoch(k, [str(p)], channel, event, table, str(p))
            for k, p in enumerate(items, start=1)]


_EPOCH_KEYS = {"inputs", "channel", "event", "columns", "time_column", "time_format",
               "time_scale", "time_at", "observer"}


def _table_options(block: Mapping[str, Any], where: str, base: TableOptions) -> TableOptions:
    def text(key: str, choices: Sequence[str] | None = None) -> str | None:
        value = block.get(key, getattr(base, key))
        if value is None:
            return None
        if not isinstance(value, str) or (choices is not None and value not in choices):
            expected = f"one of {', '.join(choices)}" if choices else "a string"
            raise InputError(f"{where}: {key} = {value!r}, expected {expected}")
        return value

    columns = block.get("columns")
    pairs = base.columns
    if columns is not None:
        if not isinstance(columns, Mapping) or not all(
                isinstance(k, str) and isinstance(v, str) for k, v in columns.items()):
            raise InputError(f"{where}: columns, expected a table of NEW = \"OLD\" names")
        pairs = tuple(sorted(columns.items()))
    return TableOptions(pairs, text("time_column"), text("time_format", tuple(TIME_FORMATS)),
                        text("time_scale", TIME_SCALES), text("time_at", TIME_AT),
                        text("observer"))


def read_campaign_file(path: str | os.PathLike[str]) -> list[EpochInput]:
    """The epochs of a TOML campaign file (paths relative to the file)::

        [table]                       # defaults for every table (reduce's options)
        time_column = "time"
        time_format = "jd"
        time_scale = "utc"
        columns = {flux = "raw_flux", x = "xcent", y = "ycent", flux_err = "err"}

        [[epoch]]
        inputs = ["r46467072", "r46471424"]   # its Pre and Main AORs
        channel = 2
        event = "eclipse"

    Raises
    ------
    InputError
        One line naming the file and the key.
    """
    p = Path(path)
    data = load_toml(p)
    unknown = sorted(set(data) - {"table", "epoch"})
    if unknown:
        raise InputError(f"{p}: unknown section(s) {', '.join(unknown)} (expected [table] and "
                         "[[epoch]])")
    base = _table_options(data.get("table") or {}, f"{p} [table]", TableOptions())
    blocks = data.get("epoch")
    if not isinstance(blocks, list) or not blocks:
        raise InputError(f"{p}: no [[epoch]] tables (each names its inputs)")
    check_size("epochs", len(blocks), MAX_EPOCHS, "epochs")
    epochs = []
    for k, block in enumerate(blocks, start=1):
        where = f"{p} epoch {k}"
        bad = sorted(set(block) - _EPOCH_KEYS)
        if bad:
            raise InputError(f"{where}: unknown key(s) {', '.join(bad)} (expected "
                             f"{', '.join(sorted(_EPOCH_KEYS))})")
        inputs = block.get("inputs")
        if isinstance(inputs, str):
            inputs = [inputs]
        if not isinstance(inputs, list) or not all(isinstance(i, str) for i in inputs):
            raise InputError(f"{where}: inputs, expected a list of paths")
        channel = block.get("channel")
        if channel is not None and channel not in (1, 2, 3, 4):
            raise InputError(f"{where}: channel = {channel!r}, expected 1, 2, 3 or 4")
        paths = [str((p.parent / i) if not Path(i).is_absolute() else Path(i)) for i in inputs]
        epochs.append(_epoch(k, paths, channel, block.get("event"),
                             _table_options(block, where, base), where))
    return epochs


# ----------------------------------------------------------------------------- the planet
def _meta_of(epoch: EpochInput) -> dict[str, Any]:
    """What an epoch's data say about its target (a table's metadata, a BCD's header)."""
    if epoch.kind == "table":
        return dict(read_table(epoch.paths[0]).meta or {})
    from astropy.io import fits

    first = find_bcd_files(epoch.paths[0], epoch.channel)[0]
    header = fits.getheader(first)
    return {k: header[k] for k in ("OBJECT",) if k in header}


def campaign_planet(epochs: Sequence[EpochInput], section: Any) -> PlanetSystem:
    """The one planet of the campaign: ``--system`` (the configuration's ``[system]``), else
    the one the data name; epochs whose data name two planets are refused.

    Raises
    ------
    InputError
        One line: two epochs name different planets (or one other than
        ``--system``), or no epoch names a planet and none was given.
    """
    catalogue = getattr(section, "catalogue", "") or None
    named: list[tuple[EpochInput, PlanetSystem]] = []
    for e in epochs:
        found, _ = system_from_meta(_meta_of(e), catalogue)
        if found is not None:
            named.append((e, found))
    for (e1, s1), (e2, s2) in zip(named, named[1:], strict=False):
        if s1.name != s2.name:
            raise InputError(f"{e2.paths[0]}: epoch {e2.number} is of {s2.name}, epoch "
                             f"{e1.number} ({e1.paths[0]}) of {s1.name}; a campaign is many "
                             "observations of one planet")
    if names_a_system(section):
        system = system_for(section)
        if named and named[0][1].name != system.name:
            e, s = named[0]
            raise InputError(f"{e.paths[0]}: epoch {e.number} is of {s.name}, not of "
                             f"--system {system.name}; a campaign is of one planet")
        return system
    if not named:
        return system_of_table({}, section=section, source=epochs[0].paths[0])
    return named[0][1]


# ----------------------------------------------------------------------------- the tasks
#: The tables :func:`standard_table` made last in this process, by the file's path and
#: SHA-256, the epoch's table options and the planet, at most :data:`KEPT_TABLE_BYTES`: a
#: campaign checks every table before it writes anything, and its photometry task, in the
#: same process with one worker, made the same table again (each frame's barycentric delay:
#: about 1.4 s of a K2-141b visit; issue 40).
_KEPT_TABLES: dict[str, Table] = {}
KEPT_TABLE_BYTES = 256 * 2**20


def _table_bytes(table: Table) -> int:
    return sum(np.asarray(c).nbytes for c in table.itercols())


def standard_table(epoch: EpochInput, system: PlanetSystem,
                   labels: Mapping[str, str] | None = None) -> Table:
    """An epoch's table with the package's columns and BMJD_TDB times (``reduce``'s reading,
    :func:`eclipsebench.fit.data.standardise_table` and
    :func:`~eclipsebench.fit.data.check_columns`); ``labels`` name the options in errors
    (the command line's ``--time-scale`` ...), which name the table. A copy of the one this
    process made last from the same bytes, options and planet, if it is kept."""
    path = epoch.paths[0]
    key = value_sha256([str(path), file_sha256(path), repr(epoch.table), repr(system)])
    kept = _KEPT_TABLES.get(key)
    if kept is None:
        kept = _standard_table(epoch, system, labels)
        if _table_bytes(kept) + sum(map(_table_bytes, _KEPT_TABLES.values())) > KEPT_TABLE_BYTES:
            _KEPT_TABLES.clear()
        if _table_bytes(kept) <= KEPT_TABLE_BYTES:
            _KEPT_TABLES[key] = kept
    return kept.copy()


def _standard_table(epoch: EpochInput, system: PlanetSystem,
                    labels: Mapping[str, str] | None) -> Table:
    from ..fit.data import check_columns, standardise_table

    path = epoch.paths[0]
    table = read_table(path)
    table.meta.setdefault("FILENAME", str(path))
    opts = epoch.table
    try:
        out = standardise_table(table, columns=dict(opts.columns),
                                time_column=opts.time_column, time_format=opts.time_format,
                                target=system, labels=labels, **opts.time_options())
    except InputError as exc:
        message = str(exc)
        raise InputError(message if message.startswith(str(path)) else f"{path}: {message}"
                         ) from None
    check_columns(out, str(path), labels=labels)
    return out


def photometry_of_epoch(epoch: EpochInput, system: PlanetSystem,
                        options: PhotometrySection) -> Table:
    """An epoch's photometry table: its table read as ``reduce`` reads it, or its BCD data
    measured by the one photometry; ``EPOCH``, ``SOURCE`` and ``TIMECONV`` in its metadata."""
    if epoch.kind == "table":
        table = standard_table(epoch, system)
        table.meta.setdefault("TIMECONV", "none: the table's times are BMJD_TDB at "
                                          "mid-exposure")
    else:
        files = [f for p in epoch.paths for f in find_bcd_files(p, epoch.channel)]
        infos = [read_bcd_header(f) for f in files]
        groups = group_epochs(infos, gap_days=math.inf)
        root = Path(os.path.commonpath([str(Path(p).resolve()) for p in epoch.paths]))
        root = root if root.is_dir() else root.parent
        table = process_epoch(groups[0], options, input_root=root)
        table.meta["TIMECONV"] = ("BCD headers: BMJD_OBS (barycentric, UTC unless the header "
                                  "says TDB) and each frame's offset -> BMJD_TDB at "
                                  "mid-exposure")
    table.meta["EPOCH"] = int(epoch.number)
    table.meta["SOURCE"] = ", ".join(str(p) for p in epoch.paths)
    if epoch.channel is not None:
        table.meta["CHANNEL"] = int(epoch.channel)
    return table


def photometry_task(epoch: EpochInput, system: PlanetSystem, options: PhotometrySection,
                    out_path: str) -> None:
    """Write one epoch's photometry table (:func:`photometry_of_epoch`) into the run folder."""
    write_photometry(photometry_of_epoch(epoch, system, options), out_path)


def twins_task(cfg: Config, table_path: str, system: PlanetSystem, methods: list[str],
               n_twins: int, trust_dir: str, out_path: str) -> None:
    """The digital twins of one epoch: ``trust`` on its table (in this process, one worker),
    in ``trust_dir``; its answer (``trust.json``) copied to ``out_path``."""
    from ..trust.run import run_trust, trust_settings

    settings = trust_settings(table_path, trust_dir, reduce=cfg.reduce, system=system,
                              system_section=cfg.system, methods=methods, n_twins=n_twins,
                              seed=cfg.challenge.seed)
    result, _ = run_trust(settings, trust_dir, workers=1)
    write_json(Path(out_path), json_safe(dict(result)))


def twins_ok(path: Path) -> bool:
    """Resume check of a twins task: the answer parses and has its methods."""
    data = json.loads(Path(path).read_text())
    return isinstance(data, dict) and isinstance(data.get("methods"), dict)


def table_ok(path: Path) -> bool:
    """Resume check of an epoch's table: it reads and has the columns every fit needs."""
    table = read_table(path)
    return len(table) > 0 and all(c in table.colnames for c in FIT_COLUMNS)


def joint_task(cfg: Config, table_paths: list[str], epochs: list[int], method: str,
               method_options: Any, out_path: str,
               result_paths: Sequence[str] | None = None) -> None:
    """One depth over every epoch of a channel for one method.

    An eclipse is :func:`eclipsebench.fit.joint.reduce_joint` (each epoch its own
    eclipse time, phase and systematics, one depth), started from the campaign's own
    reductions of the epochs (``result_paths``, the controlled profile's, one per
    table): an epoch whose reduction is the fit alone ``reduce_joint`` would make is not
    fitted again (:func:`eclipsebench.fit.joint.start_of` says when). A whole phase curve is one
    phase-curve fit of every epoch's frames (:func:`eclipsebench.fit.reduce.reduce_epoch`,
    one flux offset per AOR: each epoch's frames are their own AOR unless the table
    says which). A method that refuses the data is recorded, as in ``run``.
    """
    system = system_for(cfg.system)
    base = {"method": method, "epochs": list(epochs), "event": cfg.reduce.event,
            "eclipsebench_version": __version__}
    try:
        if event_for(cfg.reduce.event).joint_fit:
            tables = [read_table(p) for p in table_paths]
            starts = ([_reduction(p) for p in result_paths] if result_paths is not None
                      else None)
            result = fit_reduce.reduce_joint(tables, method, options=cfg.reduce, system=system,
                                             seed=cfg.challenge.seed, epochs=epochs,
                                             method_options=method_options, starts=starts)
            out = {**base, "how": "joint fit: one depth, each epoch its own eclipse time, "
                                  "phase and systematics (fit/joint.py)",
                   **{k: v for k, v in result.to_dict().items() if k not in base}}
        else:
            parts = []
            for path, e in zip(table_paths, epochs, strict=True):
                t = read_table(path)
                if "aorkey" not in t.colnames:
                    t["aorkey"] = np.full(len(t), int(e), dtype=np.int64)
                t.meta = {}
                parts.append(t)
            joined = vstack(parts, join_type="inner", metadata_conflicts="silent")
            joined.meta = dict(read_table(table_paths[0]).meta)
            joined.meta["EPOCH"] = 0
            single = fit_reduce.reduce_epoch(joined, method, options=cfg.reduce, system=system,
                                             seed=cfg.challenge.seed, epoch=0,
                                             method_options=method_options)
            res = single.to_dict()
            out = {**base, "how": "one phase-curve fit of every epoch's frames (a flux offset "
                                  "per AOR)",
                   "depth_ppm": res["depth_ppm"], "depth_err_ppm": res["depth_err_ppm"],
                   "depth_err_method": res.get("depth_err_method"),
                   "n_points": len(joined), "time_conversion": res.get("time_conversion")}
    except InputError as exc:
        log.warning("joint %s: %s", method, exc)
        out = {**base, "failed": True, "error": str(exc), "depth_ppm": None,
               "depth_err_ppm": None}
    write_json(Path(out_path), json_safe(out))


def _reduction(path: str) -> EpochResult | None:
    """A reduction's result written at ``path`` (without its light curve), None for a
    recorded failure."""
    data = json.loads(Path(path).read_text())
    return None if data.get("failed") else EpochResult.from_dict(data)


def joint_ok(method: str, path: Path) -> bool:
    """Resume check of a joint result: it parses, names its method, and has a depth (or a
    recorded failure)."""
    res = json.loads(Path(path).read_text())
    if not isinstance(res, dict) or res.get("method") != method:
        return False
    if res.get("failed"):
        return isinstance(res.get("error"), str)
    return isinstance(res.get("depth_ppm"), (int, float)) and isinstance(
        res.get("depth_err_ppm"), (int, float))


def channel_groups(epochs: Sequence[EpochInput], channels: Mapping[int, int | None]
                   ) -> dict[str, list[int]]:
    """Epoch numbers by channel (``"ch2"``; ``"all"`` when no epoch names its channel)."""
    groups: dict[str, list[int]] = {}
    for e in epochs:
        ch = channels.get(e.number)
        groups.setdefault("all" if ch is None else f"ch{ch}", []).append(e.number)
    return groups


def _channels(epochs: Sequence[EpochInput]) -> dict[int, int | None]:
    """Each epoch's channel: given, else its table's ``CHANNEL``, else its BCD files'."""
    out: dict[int, int | None] = {}
    for e in epochs:
        ch = e.channel
        if ch is None and e.kind == "table":
            value = read_table(e.paths[0]).meta.get("CHANNEL")
            ch = int(value) if isinstance(value, (int, np.integer)) else None
        elif ch is None:
            ch = read_bcd_header(find_bcd_files(e.paths[0])[0]).channel
        out[e.number] = ch
    return out


def _event_of(cfg: Config, epoch: EpochInput) -> Config:
    if epoch.event is None or epoch.event == cfg.reduce.event:
        return cfg
    event: Any = epoch.event   # checked against EVENTS when the epoch was read
    return replace(cfg, reduce=replace(cfg.reduce, event=event))


def _joint_name(method: str, group: str) -> str:
    return method if group == "all" else f"{method}_{group}"


def build_campaign_tasks(cfg: Config, root: str | Path, epochs: Sequence[EpochInput],
                         system: PlanetSystem, channels: Mapping[int, int | None],
                         twins: int = 0) -> list[Task]:
    """Every task of a campaign, in submission order (module docstring); ``twins`` > 0 adds
    each epoch's trust run."""
    layout = Layout(Path(root))
    methods = resolve_methods(cfg)
    numbers = [e.number for e in epochs]
    tasks: list[Task] = []
    for e in epochs:
        out = layout.photometry(e.number)
        tasks.append(Task(photometry_key(e.number), "photometry", photometry_task,
                          (e, system, cfg.photometry, str(out)), (out,),
                          check=table_ok))
    reductions: list[Task] = []
    for profile in cfg.run.profiles:
        for e in epochs:
            reductions += plan_reduce_tasks(_event_of(cfg, e), layout, [e.number], methods,
                                            profile=profile)
    # a joint fit that waits for no reduction is submitted before them, so that the longest
    # (GP's, which fits every epoch alone) overlaps them instead of running after them
    early: list[Task] = []
    late: list[Task] = []
    groups = channel_groups(epochs, channels)
    joints: dict[str, dict[str, str]] = {}
    by_number = {e.number: e for e in epochs}
    configured = fit_reduce.configured_method_options(cfg.reduce)
    for group, members in groups.items():
        events = {(by_number[n].event or cfg.reduce.event) for n in members}
        if len(members) < MIN_EPOCHS or len(events) != 1 or not event_for(*events).campaign_group:
            continue
        gcfg = _event_of(cfg, by_number[members[0]])
        joints[group] = {}
        for m in methods:
            out = layout.joint(_joint_name(m, group))
            key = f"joint/{_joint_name(m, group)}"
            opts = fit_reduce.resolve_method_options(m, gcfg.reduce, configured=configured)
            # an eclipse's joint fit starts from the controlled least-squares reductions
            # (not fitted alone again); with MCMC, or a method with maximum-likelihood
            # settings, they are not its start (fit.joint.start_of), so not waited for
            seeded = (event_for(gcfg.reduce.event).joint_fit and "controlled" in cfg.run.profiles
                      and gcfg.reduce.resolved_sampler() == "leastsq"
                      and not has_hyperparameters(get_method(m)))
            starts = [str(layout.result(m, n)) for n in members] if seeded else None
            deps = tuple(photometry_key(n) for n in members) + (
                tuple(reduce_key(m, n) for n in members) if seeded else ())
            (late if seeded else early).append(Task(
                key, "joint", joint_task,
                (gcfg, [str(layout.photometry(n)) for n in members], members, m, opts,
                 str(out), starts),
                (out,), deps, check=lambda p, m=m: joint_ok(m, p)))
            joints[group][m] = str(out)
    tasks += early + reductions + late
    twin_files: dict[str, str] = {}
    for e in epochs if twins else ():
        out = layout.root / "twins" / f"epoch_{e.number:02d}.json"
        tasks.append(Task(f"twins/epoch_{e.number:02d}", "twins", twins_task,
                          (_event_of(cfg, e), str(layout.photometry(e.number)), system, methods,
                           twins, str(out.with_suffix("")), str(out)),
                          (out,), (photometry_key(e.number),), check=twins_ok))
        twin_files[str(e.number)] = str(out)
    results = [reduce_key(m, n, profile=p) for p in cfg.run.profiles for n in numbers
               for m in methods]
    outputs = (*(layout.depths_of(p) for p in cfg.run.profiles), layout.summary)
    tasks.append(Task("stats", "stats", campaign_stats_task,
                      (cfg, str(layout.root), methods, [e.to_dict() for e in epochs],
                       {str(k): v for k, v in channels.items()}, joints, system.name,
                       summary_config(cfg), twin_files),
                      outputs, tuple(results) + tuple(t.key for t in tasks
                                                      if t.stage in ("joint", "photometry",
                                                                     "twins")),
                      check=campaign_summary_ok))
    if cfg.run.report:
        first = cfg.run.profiles[0]
        figures = []
        for n in numbers:
            record = _figure_record(layout, n)
            figures.append(Task(f"report/lightcurves/epoch_{n:02d}", "report",
                                lightcurve_figure_task,
                                (cfg, str(layout.root), methods, n, str(record)), (record,),
                                tuple(t.key for t in reductions
                                      if t.key in {reduce_key(m, n, profile=first)
                                                   for m in methods})))
        tasks += figures
        tasks.append(Task("report", "report", campaign_report_task,
                          (cfg, str(layout.root), methods, numbers, twin_files),
                          (layout.report,), ("stats", *(t.key for t in figures))))
    return tasks


# ----------------------------------------------------------------------------- statistics
def combined_depth(per_method: Mapping[str, Mapping[str, Any]]) -> dict[str, Any] | None:
    """One depth from several methods, with their spread as a systematic term.

    ``D_comb`` is the mean of the methods' depths ``D_m`` (each method's weighted mean
    over the epochs, Eq. ``weighted_mean``); ``sigma_stat`` is the mean of their
    errors ``sigma_TOT,m`` (the methods measure the same photons, so their errors
    are not averaged down); ``sigma_sys`` is the sample SD of ``D_m`` across the
    methods; ``sigma = sqrt(sigma_stat^2 + sigma_sys^2)``. None with fewer than
    two methods (no spread to measure).
    """
    names = [m for m, s in per_method.items() if s.get("D_mean") is not None
             and s.get("sigma_tot") is not None]
    if len(names) < 2:
        return None
    d = np.array([per_method[m]["D_mean"] for m in names], float)
    e = np.array([per_method[m]["sigma_tot"] for m in names], float)
    stat = float(np.mean(e))
    sys_ = float(np.std(d, ddof=1))
    return {"depth_ppm": float(np.mean(d)), "sigma_stat_ppm": stat, "sigma_sys_ppm": sys_,
            "error_ppm": float(math.hypot(stat, sys_)), "methods": names,
            "formula": "mean of the methods' D_mean; sigma_stat = mean of their sigma_TOT; "
                       "sigma_sys = SD of D_mean across methods; error = sqrt(sigma_stat^2 + "
                       "sigma_sys^2)"}


def _photon_limit(cfg: Config, layout: Layout, members: list[int],
                  depth_ppm: float) -> dict | None:
    """The analytic photon limit (Section 3.3) of an eclipse campaign whose tables have a
    background column (this package's photometry), at ``depth_ppm`` (the mean measured
    depth, as ``run`` without a truth); None otherwise."""
    if not event_for(cfg.reduce.event).scored:
        return None
    tables = {e: read_table(layout.photometry(e)) for e in members}
    if not all("background" in t.colnames for t in tables.values()):
        return None
    flux = [np.asarray(t["flux"], float)[good_frames(t)] for t in tables.values()]
    return analytic_photon_limit(
        flux, [np.asarray(t["background"], float)[good_frames(t)] for t in tables.values()],
        depth_ppm=depth_ppm, f_in=in_eclipse_fraction_of(cfg, tables, None),
        aperture_radius_px=cfg.photometry.radius_px,
        annulus_px=(cfg.photometry.annulus_px[0], cfg.photometry.annulus_px[1]),
        **readout_of(cfg))


def honest_depths(depths: Table, twin_files: Mapping[str, str]) -> Table:
    """The depth table with each error replaced by the twins' honest error of that method
    and epoch (``trust.json``'s ``honest_err_ppm``); rows without one are left out."""
    honest = {}
    for epoch, path in twin_files.items():
        for m, s in json.loads(Path(path).read_text()).get("methods", {}).items():
            if isinstance(s, dict) and isinstance(s.get("honest_err_ppm"), (int, float)) \
                    and s["honest_err_ppm"] > 0:
                honest[(m, int(epoch))] = float(s["honest_err_ppm"])
    keep = [(str(r["method"]), int(r["epoch"])) in honest for r in depths]
    out = depths[np.asarray(keep, dtype=bool)]
    out["error_ppm"] = [honest[(str(r["method"]), int(r["epoch"]))] for r in out]
    return out


def _table3(cfg: Config, layout: Layout, rows: Table, methods: list[str], members: list[int],
            stem: str, caption: str) -> dict[str, Any]:
    """Table 3 of one depth table (one profile, one channel): ``stats.summary.summarize``, the
    photon limit, the combined depth, the AASTeX table."""
    counts = {m: int(np.sum(rows["method"] == m)) for m in methods}
    scored = [m for m in methods if counts[m] >= MIN_EPOCHS]
    entry: dict[str, Any] = {"epochs": members, "method_names": scored,
                             "methods_excluded": [m for m in methods if m not in scored]}
    if scored:
        used = rows[np.isin(np.asarray(rows["method"]), scored)]
        pl = _photon_limit(cfg, layout, members, float(np.mean(used["depth_ppm"])))
        sigma = None if pl is None else pl["sigma_phot_ppm"]
        entry.update(summarize(rows, sigma_phot_ppm=sigma, methods=scored,
                               seed=cfg.challenge.seed, n_bootstrap=cfg.run.bootstrap))
        entry["photon_limit"] = pl
        entry["combined"] = combined_depth(entry["methods"])
        write_tables(json_safe(entry), layout.root / "tables", stem=stem, caption=caption)
    entry["depths"] = [{"method": str(r["method"]), "epoch": int(r["epoch"]),
                        "depth_ppm": float(r["depth_ppm"]),
                        "error_ppm": float(r["error_ppm"])} for r in rows]
    return entry


def campaign_stats_task(cfg: Config, root: str, methods: list[str], epochs: list[dict],
                        channels: dict[str, int | None], joints: dict[str, dict[str, str]],
                        planet: str, config_mapping: dict,
                        twin_files: Mapping[str, str] | None = None) -> None:
    """Depth tables, the paper's Table 3 statistics per profile and channel (a second time
    with the twins' honest errors, when twins ran), the joint and combined depths;
    ``summary.json`` last."""
    layout = Layout(Path(root))
    numbers = [int(e["number"]) for e in epochs]
    groups: dict[str, list[int]] = {}
    for n in numbers:
        ch = channels.get(str(n))
        groups.setdefault("all" if ch is None else f"ch{ch}", []).append(n)
    profiles: dict[str, Any] = {}
    for profile in cfg.run.profiles:
        depths, failures = collect_depths(layout, methods, numbers, profile=profile)
        depths["channel"] = [channels.get(str(int(e))) or 0 for e in depths["epoch"]]
        with atomic_path(layout.depths_of(profile)) as tmp:
            depths.write(tmp, format="ascii.ecsv")
        by_group = {}
        for group, members in groups.items():
            rows = depths[np.isin(np.asarray(depths["epoch"]), members)]
            entry = _table3(cfg, layout, rows, methods, members, f"table3_{profile}_{group}",
                            f"{planet}: eclipse depth statistics ({profile} profile, {group})")
            entry["failures"] = [f for f in failures if f["epoch"] in members]
            if twin_files and profile == "controlled":
                entry["honest"] = _table3(
                    cfg, layout, honest_depths(rows, twin_files), methods, members,
                    f"table3_{profile}_{group}_honest",
                    f"{planet}: eclipse depth statistics with the twins' honest errors "
                    f"({profile} profile, {group})")
            by_group[group] = entry
        profiles[profile] = {"channels": by_group}
    if not any(g.get("methods") for p in profiles.values() for g in p["channels"].values()):
        raise DataError(layout.root, "no method has usable depths in 2 or more epochs of one "
                                     "channel; see the 'error' of the result files")
    joint = {g: {m: json.loads(Path(p).read_text()) for m, p in by_m.items()}
             for g, by_m in joints.items()}
    records = []
    for e in epochs:
        meta = read_table(layout.photometry(int(e["number"]))).meta
        records.append({**e, "channel": channels.get(str(e["number"])),
                        "time_conversion": str(meta.get("TIMECONV", ""))})
    summary = {"kind": CAMPAIGN_KIND, "planet": planet, "seed": cfg.challenge.seed,
               "event": cfg.reduce.event, "epochs": records, "methods_run": methods,
               "profiles": profiles, "joint": joint, "config": config_mapping,
               "twins": {e: _twins_answer(p, layout.root) for e, p in
                         (twin_files or {}).items()},
               "eclipsebench_version": __version__}
    write_json(layout.summary, json_safe(summary))


def _twins_answer(path: str, root: Path) -> dict[str, Any]:
    """An epoch's trust answer for the summary, its table named relative to the run folder
    (the same bytes wherever the folder is)."""
    answer = json.loads(Path(path).read_text())
    if isinstance(answer.get("table"), str) and Path(answer["table"]).is_absolute():
        answer["table"] = os.path.relpath(answer["table"], root)
    return answer


def _event_hours(result: Mapping[str, Any], time_bmjd: np.ndarray) -> tuple[np.ndarray, str]:
    """Hours from the fitted event time of a result (its event's mid-eclipse or
    mid-transit), else from the middle of the visit; and what they count from."""
    event = event_for(result.get("event"))
    t0 = result.get(event.time_key)
    if isinstance(t0, (int, float)) and np.isfinite(t0):
        return (time_bmjd - float(t0)) * 24.0, event.mid_label
    return (time_bmjd - float(np.median(time_bmjd))) * 24.0, "the middle of the visit"


def campaign_report_task(cfg: Config, root: str, methods: list[str], epochs: list[int],
                         twin_files: Mapping[str, str], command: str | None = None) -> None:
    """``report/index.html`` of a campaign (:func:`eclipsebench.report.campaign.build_campaign_report`):
    the Table 3 statistics and the run report's figures per profile and channel, each
    epoch's decorrelated light curves (the first profile's results) and, where twins ran,
    each epoch's trust table with a link to its trust page."""
    from ..report.campaign import build_campaign_report  # matplotlib: only for a report

    layout = Layout(Path(root))
    summary = json.loads(layout.summary.read_text())
    drawn = {e: [Path(f) for f in json.loads(_figure_record(layout, e).read_text())["files"]]
             for e in epochs}
    trust: dict[int, tuple[dict[str, Any], Path | None]] = {}
    for number, answer_path in twin_files.items():
        page = Path(answer_path).with_suffix("") / "report" / "index.html"
        trust[int(number)] = (json.loads(Path(answer_path).read_text()),
                              page if page.is_file() else None)
    notes = {"planet": summary.get("planet"), "event": summary.get("event"),
             "epochs": len(epochs), "methods": ", ".join(methods), "seed": summary.get("seed"),
             "eclipsebench": __version__}
    if command:
        notes["command"] = command
    build_campaign_report(layout.report.parent, summary=summary, lightcurves={},
                          trust=trust, notes=notes, drawn=drawn)


def _figure_record(layout: Layout, epoch: int) -> Path:
    """What :func:`lightcurve_figure_task` drew for ``epoch`` (JSON: ``files``)."""
    return layout.report.parent / "lightcurves" / f"lightcurves_epoch_{epoch:02d}.json"


def lightcurve_figure_task(cfg: Config, root: str, methods: list[str], epoch: int,
                           out_path: str) -> None:
    """Epoch ``epoch``'s decorrelated light curves of the first profile
    (:func:`eclipsebench.report.campaign.draw_epoch_lightcurves`), drawn as soon as its
    reductions are done, so that the report only links them; ``out_path`` records the
    files (none where no method reduced the epoch)."""
    from ..report.campaign import draw_epoch_lightcurves  # matplotlib: only for a report

    layout = Layout(Path(root))
    curves: dict[str, dict[str, np.ndarray]] = {}
    since = "mid-eclipse"
    for m in methods:
        path = layout.result(m, epoch, profile=cfg.run.profiles[0])
        lc_path = lightcurve_path(path)
        if not (path.is_file() and lc_path.is_file()):
            continue
        lc = Table.read(lc_path, format="ascii.ecsv")
        hours, since = _event_hours(json.loads(path.read_text()),
                                    np.asarray(lc["time_bmjd"], float))
        curves[m] = {"hours": hours, "flux_corrected": np.asarray(lc["flux_corrected"], float),
                     "astro_model": np.asarray(lc["astro_model"], float)}
    files = draw_epoch_lightcurves(layout.report.parent, epoch, curves, since)
    write_json(Path(out_path), {"epoch": epoch, "files": [str(f) for f in files]})


def campaign_summary_ok(*paths: Path) -> bool:
    """Resume check of the stats task: every depth table reads and ``summary.json`` (last)
    has its profiles."""
    *depth_tables, summary = paths
    data = json.loads(Path(summary).read_text())
    return (isinstance(data, dict) and data.get("kind") == CAMPAIGN_KIND
            and isinstance(data.get("profiles"), dict)
            and all("method" in Table.read(d, format="ascii.ecsv").colnames
                    for d in depth_tables))


# ----------------------------------------------------------------------------- the runner
def _inputs(epochs: Sequence[EpochInput], system: PlanetSystem) -> dict[str, Input]:
    """Each epoch's inputs by content (a table's bytes; every BCD file's), and the planet."""
    out = {"system": planet_input(system)}
    for e in epochs:
        files = ([Path(e.paths[0])] if e.kind == "table" else
                 [f for p in e.paths for f in find_bcd_files(p, e.channel)])
        digest = (file_sha256(files[0]) if e.kind == "table"
                  else value_sha256([[f.name, file_sha256(f)] for f in files]))
        what = (f"the table {e.paths[0]}" if e.kind == "table"
                else f"the BCD files of epoch {e.number} ({', '.join(e.paths)})")
        out[f"epoch_{e.number:02d}"] = Input(f"epoch_{e.number:02d}", what, digest)
    return out


def _settings(cfg: Config, epochs: Sequence[EpochInput], twins: int = 0) -> str:
    settings: dict[str, Any] = {"config": summary_config(cfg),
                                "epochs": [e.to_dict() for e in epochs]}
    if twins:
        settings["twins"] = twins
    return json.dumps(settings, indent=1, sort_keys=True, default=str) + "\n"


def _guard(layout: Layout, text: str) -> None:
    """Refuse to resume into a campaign folder made with other settings or epochs."""
    path = layout.root / SETTINGS_FILE
    if path.is_file():
        if path.read_text() != text:
            raise InputError(f"{layout.root}: holds a campaign with different settings or "
                             f"epochs (see {SETTINGS_FILE}); use another --out or remove it")
        return
    write_text(path, text)


def _input_bytes(epochs: Sequence[EpochInput]) -> int:
    total = 0
    for e in epochs:
        for p in e.paths:
            q = Path(p)
            total += (sum(f.stat().st_size for f in find_bcd_files(q, e.channel))
                      if e.kind == "bcd" else q.stat().st_size)
    return total


def run_campaign(cfg: Config, root: str | os.PathLike[str], epochs: Sequence[EpochInput], *,
                 workers: int | None = None, scheduler: str | None = None,
                 cluster: ClusterOptions | None = None,
                 labels: Mapping[str, str] | None = None,
                 twins: int = 0) -> tuple[dict, RunReport]:
    """Run (or resume) a campaign in ``root``; return its summary and what ran.

    Parameters
    ----------
    cfg : Config
        The configuration: ``[reduce]`` (the event, the fit), ``[system]`` (the
        planet, else the data's), ``run.methods``, ``run.profiles``,
        ``run.bootstrap`` and ``challenge.seed`` (the one seed).
    root : path
        The run folder.
    epochs : sequence of EpochInput
        :func:`epochs_from_inputs` or :func:`read_campaign_file`.
    workers, scheduler, cluster
        As :func:`eclipsebench.challenge.runner.run_challenge`.
    labels : mapping, optional
        How errors name the table options (the command line's ``--time-scale`` ...).
    twins : int
        Digital twins per epoch (0: none; else at least
        :data:`eclipsebench.trust.run.MIN_TWINS`): each epoch's trust run, and the
        statistics a second time with the honest errors.

    Raises
    ------
    InputError
        One line before anything is written: an input that is neither an AOR
        folder, a BCD file nor a table; epochs of two planets; a table whose
        columns or time scale cannot be told; a folder of another kind, of
        another campaign, or locked.
    """
    epochs = list(epochs)
    if len(epochs) < MIN_EPOCHS:
        raise InputError(f"a campaign needs at least {MIN_EPOCHS} epochs (the statistics are "
                         f"over epochs), got {len(epochs)}")
    check_size("epochs", len(epochs), MAX_EPOCHS, "epochs")
    layout = Layout(check_output_path(root, "root", "folder"))
    system = campaign_planet(epochs, cfg.system)
    if not names_a_system(cfg.system):
        cfg = replace(cfg, system=replace(cfg.system, name=system.name))
    for e in epochs:   # columns, time scale: every table checked before any write
        if e.kind == "table":
            standard_table(e, system, labels)
    channels = _channels(epochs)
    if twins:
        from ..trust.run import MAX_TWINS, MIN_TWINS

        if not MIN_TWINS <= twins <= MAX_TWINS:
            raise InputError(f"--twins {twins}: expected {MIN_TWINS} to {MAX_TWINS} twins per "
                             "epoch (0: none)")
    tasks = build_campaign_tasks(cfg, layout.root, epochs, system, channels, twins)
    inputs = _inputs(epochs, system)
    sources = tuple(i.sha256 for i in inputs.values())
    tasks = [replace(t, sources=sources) for t in tasks]
    check_kind(layout.root, CAMPAIGN_KIND)
    check_links_inside(layout.root)
    check_outputs_inside(tasks, layout.root)
    if scheduler:
        external_security(scheduler, cluster or ClusterOptions())
    n_results = len(resolve_methods(cfg)) * len(cfg.run.profiles)
    check_free_space(layout.root, _input_bytes(epochs) * (1 + n_results),
                     "the epochs' photometry tables and each result's light curve")
    layout.root.mkdir(parents=True, exist_ok=True)
    with run_lock(layout.lock):
        fresh = not (layout.root / SETTINGS_FILE).exists()
        claim(layout.root, CAMPAIGN_KIND, inputs, legacy_ok=False)
        _guard(layout, _settings(cfg, epochs, twins))
        try:
            report = run_tasks(tasks, workers=cfg.run.workers if workers is None else workers,
                               scheduler=scheduler or None, cluster=cluster, root=layout.root)
        except SchedulerUnreachable:
            if fresh:
                (layout.root / SETTINGS_FILE).unlink(missing_ok=True)
                layout.marker.unlink(missing_ok=True)
            raise
        if report.timeline:
            write_timings(report, layout.timings)
        return json.loads(layout.summary.read_text()), report

