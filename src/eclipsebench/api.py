"""The public Python API: ``import eclipsebench as eb``.

Every command of the CLI is a thin shell around one of these functions, so a
notebook can do what the command line does, with the same checks. Errors are
:class:`~eclipsebench.errors.InputError` (or a subclass) whose one-line
message names the argument or file at fault. ``docs/api.md`` walks through
them: simulate a small epoch, measure it, reduce it with two methods, score
the depths.
"""

from __future__ import annotations

import inspect
import os
from collections.abc import Mapping, Sequence
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from astropy.table import Table
from astropy.time import Time

from .config import Config
from .config import load_config as _load_config
from .decorrelate.base import MethodOptions, Systematics, available_methods, get_method
from .errors import InputError
from .fit.error_rule import check_reported_error
from .fit.reduce import (
    EpochResult,
    JointResult,
    PhaseSelection,
    configured_method_options,
    reduce_epoch,
    reduce_joint,
    resolve_method_options,
    select_phase_model,
)
from .fit.result import read_result as _read_result
from .photometry.table import read_photometry as _read_photometry

# The challenge, the campaign, the simulation, the photometry pipeline, the statistics and the
# engine (Dask) are imported by the functions that use them: `eclipsebench reduce` imports this
# module and needs none of them (about 0.5 s of CPU, issue 40).
if TYPE_CHECKING:  # pragma: no cover
    from .engine import RunReport
    from .simulation.challenge import ChallengeResult
    from .trust.result import TrustResult

__all__ = ["load_config", "methods", "method_class", "measure", "reduce", "compare_phases",
           "simulate",
           "run_challenge", "campaign", "score", "trust", "read_result", "read_photometry"]


def load_config(path: str | os.PathLike | None = None, overrides: Sequence[str] = (),
                **sections: Mapping[str, Any]) -> Config:
    """A validated configuration: a TOML file (or the defaults), then overrides.

    Parameters
    ----------
    path : path, optional
        A TOML configuration file; None gives the built-in XO-3b challenge.
    overrides : sequence of str
        ``"section.key=value"`` overrides, as ``--set`` on the command line.
    **sections : mapping
        Whole-section overrides, e.g. ``challenge={"epochs": 2}``; a planet in
        no catalogue is ``system={"name": "test-b", "planet": {"period_days":
        3.19, ...}}`` (the keys of a catalogue row).

    Examples
    --------
    >>> cfg = load_config(challenge={"epochs": 2}, overrides=["challenge.seed=7"])
    >>> cfg.challenge.epochs, cfg.challenge.seed
    (2, 7)
    """
    return _load_config(path, list(overrides), sections)


def _config(config: Config | str | os.PathLike | None) -> Config:
    if config is None:
        return _load_config(None)
    if isinstance(config, Config):
        return config
    if isinstance(config, (str, os.PathLike)):
        return _load_config(config)
    raise InputError(f"config: expected a Config, the path of a TOML file or None, "
                     f"got {type(config).__name__}")


def methods() -> tuple[str, ...]:
    """The registered method names, built-in and plugins (the paper's seven first).

    Examples
    --------
    >>> methods()[:3]
    ('bliss', 'gp', 'ica')
    """
    return available_methods()


def method_class(name: str) -> type[Systematics]:
    """The class registered as ``name`` (its ``Options`` lists the options).

    Examples
    --------
    >>> method_class("kr-data").Options().k
    50
    """
    return get_method(name)


def measure(input_dir: str | os.PathLike, out: str | os.PathLike | None = None, *,
            config: Config | str | os.PathLike | None = None, channel: int | None = None,
            **photometry: Any) -> list[Table]:
    """Photometry of every epoch of IRAC BCD cubes under ``input_dir``.

    Parameters
    ----------
    input_dir : path
        A folder of BCD cubes (``*_bcd.fits``), simulated or from the archive.
    out : path, optional
        A folder: each epoch's table is also written there as ``epoch_NN.fits``.
    config : Config or path, optional
        Its ``[photometry]`` section is used (default: the built-in one).
    channel : int, optional
        Keep only this IRAC channel's files.
    **photometry
        ``[photometry]`` values to change, e.g. ``centroid="gaussian"``.

    Returns
    -------
    list of astropy.table.Table
        One photometry table per epoch (``docs/contracts.md``), in epoch order.
    """
    from .photometry.pipeline import photometry_tables, replace_options
    from .photometry.table import write_photometry

    options = _config(config).photometry
    if photometry:
        options = replace_options(options, **photometry)
    tables = []
    for epoch, table in photometry_tables(input_dir, options, channel=channel):
        if out is not None:
            write_photometry(table, Path(out) / f"epoch_{epoch.number:02d}.fits")
        tables.append(table)
    return tables


def reduce(table: Table | str | os.PathLike | Sequence[Table | str | os.PathLike], method: str,
           *, system: Any = None, seed: int = 0,
           options: Mapping[str, Any] | MethodOptions | None = None,
           config: Config | str | os.PathLike | None = None, epoch: int | None = None,
           resources: Mapping[str, Any] | None = None,
           columns: Mapping[str, str] | None = None, time_column: str | None = None,
           time_format: str | None = None, time_scale: str | None = None,
           time_at: str | None = None, observer: Any = None,
           labels: Mapping[str, str] | None = None,
           **reduce_options: Any) -> EpochResult | JointResult:
    """Fit one epoch with one method and the shared eclipse + phase-curve model.

    ``eclipsebench reduce`` is this function: the same checks, the same
    refusals (a table without the columns a fit needs, with the likely ones
    named; tables of two planets in a joint fit; a joint fit asked for
    ``sampler="mcmc"`` or ``profile="paper"``; a zero or non-finite error),
    the same result.

    Parameters
    ----------
    table : astropy.table.Table or path, or a list or tuple of them
        One epoch's photometry table (from :func:`measure`, or a FITS, ECSV or
        CSV file, also from another pipeline: ``docs/photometry.md``, "Photometry
        from other pipelines"). A list or tuple of tables is fitted jointly
        with one depth (each epoch its own time, phase and systematics; least
        squares): a :class:`~eclipsebench.fit.result.JointResult`.
    method : str
        A name from :func:`methods`.
    system : str, mapping or PlanetSystem, optional
        The planet (default: the one ``config`` names, else the one the table
        names: a simulation's ``SYSTEM``, or the archive's ``OBJECT`` looked
        up in the catalogue, ``"XO-3 ch2 peak-up"`` -> ``"XO-3b"``; a table
        naming none raises InputError asking for it): a name (searched in the configuration's
        ``[system] catalogue``, then the built-in one), a
        :class:`~eclipsebench.astro.catalogue.PlanetSystem`, or a mapping of
        a planet in no catalogue, ``{"name": ..., "period_days": ..., ...}``
        (the keys of a catalogue row, checked as one).
    seed : int
        Run seed: every random stream of the fit and the method derives from it.
    options : mapping or the method's Options, optional
        The method's options, over ``[reduce.options.<method>]`` of ``config``.
    config : Config or path, optional
        Its ``[reduce]`` and ``[system]`` sections are used.
    epoch : int, optional
        Epoch number (default: the table's ``EPOCH``).
    resources : mapping, optional
        What a method needs besides the table, e.g. ``{"pmap": path}`` for
        ``kr-pmap`` (simulated tables find their calibration set themselves).
    columns : mapping, optional
        The package's column name -> the table's, e.g. ``{"flux": "FLUX"}``.
    time_column : str, optional
        The table's time column (default ``time_bmjd``).
    time_format : {"bmjd", "bjd", "mjd", "jd"}, optional
        Its format (default ``"bmjd"``): ``bjd``/``bmjd`` barycentric, ``jd``/``mjd``
        at the observer (converted to BMJD_TDB with the planet's ``ra_deg`` and
        ``dec_deg``: :mod:`eclipsebench.astro.timescales`; the result's
        ``time_conversion`` says how).
    time_scale : {"utc", "tt", "tdb"}, optional
        The times' scale (default: a ``Time`` column's or the table's
        ``TIMESYS``, else TDB for barycentric times; needed for jd/mjd).
    time_at : {"start", "mid", "end"}, optional
        Where in its frame each time stamp lies (default ``"mid"``).
    observer : "geocentre" or (x_km, y_km, z_km, mjd_utc), optional
        Where jd/mjd times were taken: for Spitzer ``SPTZR_X, SPTZR_Y,
        SPTZR_Z, MJD_OBS`` of a BCD header of the observation.
    labels : mapping, optional
        How errors name the table's arguments and the planet (default: these
        keywords; the command line gives its options, ``{"columns": "--columns",
        "system": "--system NAME", ...}``).
    **reduce_options
        ``[reduce]`` values to change, e.g. ``phase="linear"``, ``sampler="mcmc"``.

    Returns
    -------
    EpochResult or JointResult
        ``depth_ppm``, ``depth_err_ppm``, every error estimate, the decorrelated
        light curve (one epoch); ``to_dict()`` is the result file's content.

    Raises
    ------
    InputError
        One line naming the table or the argument: missing columns, no planet,
        an eclipse outside the data, tables of two planets, a zero or
        non-finite depth error, an unknown method or option.
    """
    joint = isinstance(table, (list, tuple))
    section, how = _reduce_inputs(locals(), controlled=joint)
    if isinstance(table, (list, tuple)):
        if epoch is not None:
            raise InputError("epoch: a joint fit takes each table's EPOCH")
        _check_joint_settings(section, len(table), labels)
        return reduce_joint(list(table), method, options=section, **how)
    result = reduce_epoch(table, method, options=section, epoch=epoch, **how)
    source = (os.fspath(table) if isinstance(table, (str, os.PathLike))
              else str((getattr(table, "meta", None) or {}).get("FILENAME",
                                                               "the photometry table")))
    check_reported_error(result.depth_ppm, result.depth_err_ppm, method=method, source=source)
    return result


def compare_phases(table: Table | str | os.PathLike, method: str, *, system: Any = None,
                   seed: int = 0, options: Mapping[str, Any] | MethodOptions | None = None,
                   config: Config | str | os.PathLike | None = None, epoch: int | None = None,
                   resources: Mapping[str, Any] | None = None,
                   columns: Mapping[str, str] | None = None, time_column: str | None = None,
                   time_format: str | None = None, time_scale: str | None = None,
                   time_at: str | None = None, observer: Any = None,
                   labels: Mapping[str, str] | None = None,
                   **reduce_options: Any) -> PhaseSelection:
    """Fit every phase-curve model to one epoch, with BIC and AIC for each (paper Section 4.2).

    The arguments are :func:`reduce`'s (one table); each model is fitted by
    least squares with the controlled settings (``eclipsebench reduce
    --compare-phases``). ``to_dict()`` gives the rows, ``best_bic``,
    ``best_aic`` and the ``bracket`` of models between them.
    """
    section, how = _reduce_inputs(locals(), controlled=True)
    return select_phase_model(table, method, options=section, epoch=epoch, **how)


#: The ``[reduce]`` settings a joint fit refuses: it is least squares with the controlled
#: settings (its method options never the team's), so a posterior or a team's profile asked
#: for would be silently ignored.
_JOINT_REFUSES = (("sampler", "mcmc"), ("profile", "paper"))


def _check_joint_settings(section: Any, n_tables: int, labels: Mapping[str, str] | None) -> None:
    """Refuse, in one line, a setting a joint fit of ``n_tables`` tables cannot honour, named as
    the caller names it (``labels``: the command line's ``--sampler``; else the keyword)."""
    for key, value in _JOINT_REFUSES:
        if getattr(section, key) == value:
            name = (f"{labels[key]} {value}" if labels and key in labels
                    else f'{key}="{value}"')
            raise InputError(f"{name}: applies to one table; a joint fit of {n_tables} "
                             "tables is least squares with the controlled settings")


def _reduce_inputs(given: Mapping[str, Any], *, controlled: bool) -> tuple[Any, dict[str, Any]]:
    """The ``[reduce]`` section and the fit's keywords from :func:`reduce`'s arguments.

    The method's options are parsed once here (every ``[reduce.options.<method>]``
    table checked, the team's in the paper profile unless ``controlled``, then
    ``options``) and passed down as its options dataclass.
    """
    cfg = _config(given["config"])
    section = cfg.reduce
    if given["reduce_options"]:
        section = replace(section, **given["reduce_options"])
        section.validate()
    method_options = resolve_method_options(
        given["method"], section, given["options"], configured=configured_method_options(section),
        profile="controlled" if controlled else section.profile)
    times = {k: given[k] for k in ("time_scale", "time_at", "observer") if given[k] is not None}
    return section, {"system": given["system"], "seed": given["seed"],
                     "method_options": method_options, "resources": given["resources"],
                     "columns": given["columns"], "time_column": given["time_column"],
                     "time_format": given["time_format"], "time_options": times,
                     "system_section": cfg.system, "labels": given["labels"]}


def simulate(out: str | os.PathLike, *, config: Config | str | os.PathLike | None = None,
             seed: int | None = None, epochs: int | None = None, workers: int | None = None,
             calibration: bool | None = None) -> ChallengeResult:
    """Simulate a data challenge (IRAC BCD cubes and the truth) into the folder ``out``.

    Parameters
    ----------
    out : path
        The output folder (resumed if it holds an interrupted simulation of
        the same configuration).
    config : Config or path, optional
        The challenge (default: the built-in ten-epoch XO-3b challenge).
    seed, epochs : int, optional
        ``challenge.seed`` and ``challenge.epochs`` to change.
    workers : int, optional
        Parallel workers (default ``run.workers``).
    calibration : bool, optional
        Write the KR/Pmap calibration-star set (default ``simulation.write_calibration``).
    """
    from .simulation.challenge import simulate_challenge

    cfg = _config(config)
    changes: dict[str, Any] = {k: v for k, v in (("seed", seed), ("epochs", epochs))
                               if v is not None}
    if changes:
        cfg = replace(cfg, challenge=replace(cfg.challenge, **changes))
        cfg.challenge.validate()
    return simulate_challenge(cfg, out, workers=workers, calibration=calibration)


def run_challenge(out: str | os.PathLike, *, config: Config | str | os.PathLike | None = None,
                  workers: int | None = None,
                  scheduler: str | None = None) -> tuple[dict, RunReport]:
    """Simulate, measure, reduce with every method and score: the whole challenge.

    Resumes an interrupted run in the same folder. Returns the summary (the
    content of ``out/summary.json``) and what ran.
    """
    from .challenge.runner import run_challenge as _run_challenge

    return _run_challenge(_config(config), out, workers=workers, scheduler=scheduler)


def campaign(inputs: Sequence[str | os.PathLike] | str | os.PathLike, out: str | os.PathLike,
             *, system: str | None = None, config: Config | str | os.PathLike | None = None,
             methods: Sequence[str] | None = None, event: str | None = None,
             channel: int | None = None, columns: Mapping[str, str] | None = None,
             time_column: str | None = None, time_format: str | None = None,
             time_scale: str | None = None, time_at: str | None = None,
             observer: str | None = None, twins: int = 0, workers: int | None = None,
             scheduler: str | None = None) -> tuple[dict, RunReport]:
    """Many real observations of one planet, end to end (``eclipsebench campaign``).

    Parameters
    ----------
    inputs : sequence of path, or path
        One epoch per item (a photometry table, an AOR folder or a BCD file), or
        the path of a TOML campaign file (``docs/campaign.md``).
    out : path
        The run folder (rerunning resumes it).
    system : str, optional
        The planet (default: the one the data name).
    config : Config or path, optional
        ``[reduce]``, ``[system]``, ``[photometry]`` and ``[run]`` (methods,
        profiles, bootstrap); ``challenge.seed`` is the one seed.
    methods, event : optional
        ``run.methods`` and ``reduce.event``.
    channel, columns, time_column, time_format, time_scale, time_at, observer : optional
        How to read the tables given as ``inputs`` (``eb.reduce``'s names).
    twins : int
        Digital twins per epoch (0: none; 10 or more): each epoch's ``trust``
        run, and the statistics a second time with the honest errors.
    workers, scheduler : optional
        As :func:`run_challenge`.

    Returns
    -------
    (dict, RunReport)
        The content of ``out/summary.json`` and what ran.
    """
    from .challenge.campaign import TableOptions, epochs_from_inputs, read_campaign_file
    from .challenge.campaign import run_campaign as _run_campaign

    cfg = _config(config)
    changes: dict[str, Any] = {}
    if system is not None:
        cfg = replace(cfg, system=replace(cfg.system, name=system, planet={}))
    if methods is not None:
        cfg = replace(cfg, run=replace(cfg.run, methods=tuple(methods)))
    if event is not None:
        changes["event"] = event
    if changes:
        cfg = replace(cfg, reduce=replace(cfg.reduce, **changes))
        cfg.reduce.validate()
    table = TableOptions(tuple(sorted((columns or {}).items())), time_column, time_format,
                         time_scale, time_at, observer)
    if isinstance(inputs, (str, os.PathLike)) and Path(inputs).suffix.lower() == ".toml":
        if table.given() or channel is not None:
            raise InputError("campaign: a campaign file names each epoch's table options and "
                             "channel itself")
        epochs = read_campaign_file(inputs)
    else:
        items = [inputs] if isinstance(inputs, (str, os.PathLike)) else list(inputs)
        epochs = epochs_from_inputs(items, table=table, channel=channel)
    return _run_campaign(cfg, out, epochs, workers=workers, scheduler=scheduler, twins=twins)


def score(depths: Table | str | os.PathLike | Mapping[str, Sequence], *,
          truth_ppm: float | None = None, sigma_phot_ppm: float | None = None,
          methods: Sequence[str] | None = None, seed: int = 0, n_bootstrap: int = 2000) -> dict:
    """The paper's statistics of many epochs and methods (Section 3, Tables 3-6).

    Parameters
    ----------
    depths : Table, path or mapping of columns
        Columns ``method``, ``epoch``, ``depth_ppm``, ``error_ppm``.
    truth_ppm, sigma_phot_ppm : float, optional
        The true depth (accuracy statistics) and the photon limit.
    methods : sequence of str, optional
        Restrict to these methods.
    seed, n_bootstrap : int
        The bootstrap of the confidence intervals.
    """
    from .stats.depth_table import check_depth_table, read_depth_table
    from .stats.summary import summarize

    if isinstance(depths, (str, os.PathLike)):
        table = read_depth_table(depths)
    else:
        table = check_depth_table(depths if isinstance(depths, Table) else Table(dict(depths)),
                                  "depths")
    return summarize(table, sigma_phot_ppm=sigma_phot_ppm, truth_ppm=truth_ppm,
                     methods=methods, seed=seed, n_bootstrap=n_bootstrap)


def _call_text(name: str, func, given: Mapping[str, Any]) -> str:
    """The call ``name(...)`` with the arguments given other than their defaults, as Python
    text (an object other than a plain value is named by its type)."""
    def shown(value: Any) -> str:
        if isinstance(value, os.PathLike):
            value = os.fspath(value)
        plain = (str, int, float, bool, type(None), list, tuple, dict)
        return repr(value) if isinstance(value, plain) else f"<{type(value).__name__}>"

    parts = []
    for p in inspect.signature(func).parameters.values():
        value = given.get(p.name, p.default)
        if p.kind is inspect.Parameter.VAR_KEYWORD:
            parts += [f"{k}={shown(v)}" for k, v in (value or {}).items()]
        elif p.default is inspect.Parameter.empty:
            parts.append(shown(value))
        elif value is not p.default and value != p.default:
            parts.append(f"{p.name}={shown(value)}")
    return f"{name}({', '.join(parts)})"


def trust(table: str | os.PathLike, out: str | os.PathLike, *, system: Any = None,
          twins: int = 50, methods: Sequence[str] | None = None, depth_ppm: float | None = None,
          seed: int = 0, config: Config | str | os.PathLike | None = None,
          options: Mapping[str, Mapping[str, Any]] | None = None, pmap: str | None = None,
          workers: int | None = None, columns: Mapping[str, str] | None = None,
          time_column: str | None = None, time_format: str | None = None,
          time_scale: str | None = None, time_at: str | None = None, observer: Any = None,
          readout: str | None = None, channel: int | None = None,
          labels: Mapping[str, str] | None = None, **reduce_options: Any) -> TrustResult:
    """How far to trust the depth of one real observation: its digital twins, every method.

    Simulates ``twins`` copies of the observation (its times, pointing track,
    flux, background, readout and bad frames; the simulator's intra-pixel
    gain; a known eclipse at the real mid-time), reduces each like the real
    table with every method, and scores the methods (``docs/trust.md``).
    Resumes an interrupted run in ``out``.

    Parameters
    ----------
    table : path
        The real observation's photometry table: made by :func:`measure`, or
        another pipeline's (time, flux in any unit, flux_err, x, y; optionally
        noise pixels, background, frame numbers), completed by inference and
        written to ``out/observation.fits`` (``docs/trust.md``, "Any table").
    out : path
        The trust folder (``trust.json``, ``trust.ecsv``, ``report/index.html``).
    system : str, mapping or PlanetSystem, optional
        The planet (default: the one the table names, as :func:`reduce`).
    twins : int
        Number of twins (10-10,000).
    methods : sequence of str, optional
        Methods to measure (default: every registered method); the first
        one's real depth is injected unless ``depth_ppm`` is given.
    depth_ppm : float, optional
        The depth injected into the twins.
    seed : int
        The one seed of every twin's noise and every reduction.
    config : Config or path, optional
        Its ``[reduce]``, ``[system]`` and ``[run]`` sections are used.
    options : mapping, optional
        ``{method: {key: value}}``: method options, as ``reduce(options=...)``.
    pmap : path, optional
        Pixel map: ``kr-pmap``'s calibration and, when it is a gridded SSC
        map (or a folder of dated versions), the twins' intra-pixel gain.
    workers : int, optional
        Dask worker processes (default ``run.workers``).
    columns, time_column, time_format, time_scale, time_at, observer : optional
        Another pipeline's column names and times, as :func:`reduce`.
    readout : str, optional
        Another pipeline's subarray readout (``"sub_2s"``...; default: from the cadence).
    channel : int, optional
        Another pipeline's IRAC channel (default: its ``CHANNEL``, else 2).
    labels : mapping, optional
        How errors name the arguments (default: these keywords; the command
        line gives its options, ``{"out": "--out", "depth_ppm": "--depth",
        "system": "--system NAME", "columns": "--columns", ...}``).
    **reduce_options
        ``[reduce]`` values to change, e.g. ``sampler="leastsq"``, ``profile="paper"``,
        ``event="phase-curve"`` (a whole phase curve of several AORs, scored also on
        its amplitude and peak offset: ``docs/trust.md``, "Whole phase curves").

    Returns
    -------
    TrustResult
        The content of ``trust.json`` (a dict; ``to_table()`` and a notebook
        summary; :func:`eclipsebench.trust.result.read_trust` reads it back): ``methods`` (per method ``bias_ppm``,
        ``sd_ppm``, ``rmse_ppm``, ``mean_err_ppm``, ``z_rms``, coverage,
        ``depth_ppm``, ``honest_err_ppm``, ``mse_excess_sigma``), ``skipped``,
        ``recommended``, ``near_equals`` (the methods the twins cannot tell from
        it), ``n_twins``, ``twin_depth_ppm``.
    """
    return _trust(locals(), _call_text("eb.trust", trust, locals()))[0]   # call: on the page


def trust_with_report(table: str | os.PathLike, out: str | os.PathLike, *, command: str,
                      **keywords: Any) -> tuple[TrustResult, RunReport]:
    """:func:`trust` (the same keywords) and what ran; ``command`` is the text shown on the
    page instead of the call (``eclipsebench trust``'s command line, which prints what ran)."""
    bound = inspect.signature(trust).bind(table, out, **keywords)
    bound.apply_defaults()
    return _trust(bound.arguments, command)


def _trust(given: Mapping[str, Any], command: str) -> tuple[TrustResult, RunReport]:
    """The trust run of :func:`trust`'s arguments ``given``, shown on its page as ``command``."""
    from .engine.folder import check_kind
    from .io.paths import check_output_path
    from .trust.run import run_trust, trust_settings

    labels = dict(given["labels"] or {})
    cfg = _config(given["config"])
    section = cfg.reduce
    if given["reduce_options"]:
        section = replace(section, **given["reduce_options"])
        section.validate()
    root = check_output_path(given["out"], labels.get("out", "out"), "folder")
    check_kind(root, "trust")   # another kind of run's folder: refused before the table is read
    times = {k: given[k] for k in ("time_scale", "time_at", "observer") if given[k] is not None}
    settings = trust_settings(given["table"], root, reduce=section, system=given["system"],
                              system_section=cfg.system, methods=given["methods"],
                              n_twins=given["twins"], depth_ppm=given["depth_ppm"],
                              seed=given["seed"], method_options=given["options"],
                              pmap=given["pmap"], hint=labels.get("system", "system=NAME"),
                              columns=given["columns"], time_column=given["time_column"],
                              time_format=given["time_format"], time_options=times,
                              readout=given["readout"], channel=given["channel"],
                              labels=given["labels"],
                              depth_name=labels.get("depth_ppm", "depth_ppm"))
    workers = cfg.run.workers if given["workers"] is None else given["workers"]
    return run_trust(settings, root, workers=workers, command=command)


def read_result(path: str | os.PathLike):
    """The result of a reduction from its ``RESULT.json``, as :func:`reduce` returned it.

    ``RESULT.lc.ecsv`` (the decorrelated light curve) and ``RESULT.chain.npz``
    (the posterior) beside it are read when present. A joint fit's file gives
    its ``JointResult``.

    Parameters
    ----------
    path : path
        A result file written by ``eclipsebench reduce`` or ``run``
        (``results/<method>/epoch_NN.json``).

    Returns
    -------
    EpochResult or JointResult
        Equal to the written result in every field the file holds.

    Raises
    ------
    InputError
        One line naming the file: missing, not JSON, not a result, a failed
        reduction, written by an older version.

    Examples
    --------
    >>> read_result("no/such/result.json")
    Traceback (most recent call last):
    ...
    eclipsebench.errors.InputError: no/such/result.json: no such result file
    """
    return _read_result(path)


def read_photometry(path: str | os.PathLike) -> Table:
    """A photometry table written by :func:`measure` (or ``eclipsebench photometry``).

    The columns keep their units (``electron``, ``pix``, ``d``, ...) and
    descriptions, the JSON metadata come back as Python objects, and a
    ``time`` column is added first: ``time_bmjd`` as an astropy ``Time``
    (``format="mjd"``, ``scale="tdb"``; barycentric). The table can go to
    :func:`reduce` as it is.

    Raises
    ------
    InputError
        One line naming the file (a ``DataError``): missing, unreadable, or
        lacking a required column.

    Examples
    --------
    >>> read_photometry("no/such/epoch_01.fits")
    Traceback (most recent call last):
    ...
    eclipsebench.errors.DataError: no/such/epoch_01.fits: no such photometry table
    """
    table = _read_photometry(path)
    table.add_column(Time(table["time_bmjd"], format="mjd", scale="tdb"), name="time", index=0)
    table["time"].info.description = "mid-exposure time, barycentric (BMJD_TDB)"
    return table
