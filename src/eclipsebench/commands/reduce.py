"""``eclipsebench reduce``: fit one epoch's photometry table with one method."""

from __future__ import annotations

import argparse
import math
from dataclasses import replace
from pathlib import Path

from ..astro.catalogue import PlanetSystem, system_for
from ..config import load_config
from ..config.base import parse_override
from ..errors import InputError
from ..fit.names import (
    ECLIPSE_SHAPES,
    EVENTS,
    PHASE_CURVE_MODELS,
    PHASE_MODELS,
    RAMP_MODELS,
    TIME_AT,
    TIME_FORMATS,
    TIME_SCALES,
)
from ..fit.target import system_of_table
from ..io.atomic import atomic_path, write_json
from ..io.paths import check_plot_path
from ..limits import MAX_MCMC_WALKERS
from .options import (
    add_planet_options,
    check_output_path,
    planet_overrides,
    positive_float,
    positive_int,
)

NAME = "reduce"
HELP = ("Fit one epoch's photometry table with one decorrelation method and the shared "
        "eclipse + phase-curve model; write the depth (JSON) and the decorrelated light curve.")


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("table", metavar="TABLE", nargs="+",
                   help="photometry table of one epoch (FITS, ECSV or CSV; another pipeline's "
                        "table needs time_bmjd, flux, flux_err, x, y: docs/photometry.md); "
                        "several tables, or a folder of them, are fitted jointly with one "
                        "depth (each epoch's own time, phase and systematics)")
    p.add_argument("--method", required=True, metavar="NAME",
                   help="decorrelation method: the paper's bliss, gp, ica, kr-data, kr-pmap, pld, "
                        "segpoly; SPCA's poly2-poly5, pld-aper; or a plugin's (eb.methods())")
    p.add_argument("--phase", choices=PHASE_MODELS + PHASE_CURVE_MODELS + ("bic",),
                   default=None,
                   help="phase-curve model (default: [reduce] phase, quadratic); with "
                        "--event phase-curve harmonic1, harmonic2 or bic (both fitted, the "
                        "least BIC reported; [reduce] phase_curve_model, default bic)")
    p.add_argument("--ramp", choices=RAMP_MODELS, default=None,
                   help="detector ramp (default: [reduce] ramp, none)")
    p.add_argument("--eclipse-shape", choices=ECLIPSE_SHAPES, default=None,
                   help="eclipse shape (default: [reduce] eclipse_shape, physical; the paper "
                        "profile takes each team's, the box for segpoly)")
    p.add_argument("--event", choices=EVENTS, default=None,
                   help="event fitted (default: [reduce] event, eclipse); transit: Rp/R* and "
                        "mid-transit time with batman's quadratic limb darkening, a/R*, b, q1, "
                        "q2 fixed to the catalogue unless [reduce] transit_free names them; "
                        "phase-curve: a whole phase curve over several AORs (eclipses, "
                        "transits, harmonic phase variation, an offset per AOR)"),
    p.add_argument("--profile", choices=("controlled", "paper"), default=None,
                   help="controlled: the shared [reduce] settings (default); paper: the "
                        "method's team's centroid, phase model, sampler and reported error "
                        "(docs/methods.md, 'The paper profile')")
    p.add_argument("--sampler", choices=("auto", "mcmc", "leastsq"), default=None,
                   help="mcmc: least squares then emcee, the posterior's error reported; "
                        "leastsq: least squares only, for speed; auto (default): mcmc for "
                        "an eclipse or transit, leastsq for a whole phase curve")
    p.add_argument("--prayer-bead", type=positive_int(minimum=0), default=None, metavar="N",
                   help="cyclic residual shifts for the prayer-bead error (0: none; default "
                        "16; computed where the error rule can report it: with --sampler "
                        "leastsq, error_rule largest, or a team that used it)")
    p.add_argument("--walkers", type=positive_int(minimum=4, maximum=MAX_MCMC_WALKERS),
                   default=None, metavar="N",
                   help="MCMC walkers (even; default 16)")
    p.add_argument("--steps", type=positive_int(minimum=100), default=None, metavar="N",
                   help="MCMC step cap (default 5000)")
    p.add_argument("--radius", type=positive_float(), default=None, metavar="PX",
                   help="aperture radius whose flux column is fitted (default: the table's flux)")
    add_table_options(p, "map the table's column names to the package's, e.g. "
                         "--columns flux=FLUX,flux_err=FLUX_ERR (repeatable)")
    p.add_argument("--pmap", metavar="PATH", default=None,
                   help="calibration set for kr-pmap (a calibration-star table, the SSC pmap, or "
                        "a folder of SSC map versions: the one in force at the observation's "
                        "date is used); simulated tables find theirs through SIMDIR")
    p.add_argument("--system", metavar="NAME", default=None,
                   help="planet (default: the one the table names: a simulation's SYSTEM, or "
                        "the archive header's OBJECT looked up in the catalogue, e.g. XO-3 -> "
                        "XO-3b; a table that names none needs --system)")
    add_planet_options(p)
    p.add_argument("--epoch", type=positive_int(minimum=0), default=None, metavar="N",
                   help="epoch number (default: the table's EPOCH)")
    p.add_argument("--seed", type=positive_int(minimum=0), default=0, metavar="N",
                   help="run seed (MCMC stream: reduce/epoch/method/mcmc)")
    p.add_argument("--option", dest="method_options", action="append", default=[],
                   metavar="KEY=VALUE", help="method option (repeatable), e.g. --option k=50")
    p.add_argument("--config", metavar="CONFIG", default=None,
                   help="configuration file whose [reduce] and [system] sections are used")
    p.add_argument("--set", dest="overrides", action="append", default=[],
                   metavar="SECTION.KEY=VALUE", help="override one configuration value")
    p.add_argument("--compare-phases", action="store_true",
                   help="also fit every phase model and report BIC and AIC for each")
    p.add_argument("--out", metavar="RESULT.json", default=None,
                   help="result file (default: beside TABLE, <table stem>.<method>.json); the "
                        "light curve goes to RESULT.lc.ecsv")
    p.add_argument("--plot", metavar="FILE.png", default=None,
                   help="plot the binned decorrelated light curve with the model")


def add_table_options(p: argparse.ArgumentParser, columns_help: str) -> None:
    """How to read another pipeline's table (reduce and trust): ``--columns``,
    ``--time-column``, ``--time-format``, ``--time-scale``, ``--time-at``, ``--observer``."""
    p.add_argument("--columns", dest="columns", action="append", default=[],
                   metavar="NEW=OLD,...", help=columns_help)
    p.add_argument("--time-column", metavar="NAME", default=None,
                   help="the table's time column (default: time_bmjd)")
    p.add_argument("--time-format", choices=tuple(TIME_FORMATS), default=None,
                   help="format of the time column: bmjd (default, BJD - 2400000.5) or bjd, "
                        "barycentric; mjd or jd, at the observer, converted to BMJD_TDB with "
                        "the planet's ra_deg/dec_deg and --observer (docs/photometry.md)")
    p.add_argument("--time-scale", choices=TIME_SCALES, default=None,
                   help="time scale of the time column (default: the table's TIMESYS, else "
                        "tdb for bmjd/bjd; required for mjd/jd)")
    p.add_argument("--time-at", choices=TIME_AT, default=None,
                   help="where in its frame each time stamp lies (default mid; start/end "
                        "move it by half the frame time, the median cadence)")
    p.add_argument("--observer", metavar="X,Y,Z,MJD|geocentre", default=None,
                   help="where mjd/jd times were taken: for Spitzer SPTZR_X,SPTZR_Y,SPTZR_Z,"
                        "MJD_OBS of a BCD header of the observation (km, UTC MJD); geocentre "
                        "(for Spitzer wrong by minutes)")


def _method_options(items: list[str]) -> dict:
    out = {}
    for item in items:
        if "=" not in item or not item.split("=", 1)[0].strip():
            raise InputError(f"--option {item!r}: expected KEY=VALUE")
        path, value = parse_override(item)
        if len(path) != 1:
            raise InputError(f"--option {item!r}: expected KEY=VALUE")
        out[path[0]] = value
    return out


def _column_map(items: list[str]) -> dict[str, str]:
    """``--columns NEW=OLD,...`` (repeatable) as ``{NEW: OLD}``."""
    out: dict[str, str] = {}
    for item in items:
        for pair in item.split(","):
            new, sep, old = (part.strip() for part in pair.partition("="))
            if not sep or not new or not old:
                raise InputError(f"--columns {pair.strip()!r}: expected NEW=OLD (the package's "
                                 "name = the table's)")
            if out.get(new, old) != old:
                raise InputError(f"--columns: {new} is mapped twice ({out[new]}, {old})")
            out[new] = old
    return out


#: How errors about the table's names and time format name the options.
_TABLE_LABELS = {"columns": "--columns", "time_column": "--time-column",
                 "time_format": "--time-format", "time_scale": "--time-scale",
                 "time_at": "--time-at", "observer": "--observer",
                 "coordinates": "--planet ra_deg=DEG --planet dec_deg=DEG, or --system"}


def _options(args: argparse.Namespace):
    cfg = load_config(args.config, args.overrides + planet_overrides(args, args.system))
    changes = {"phase": args.phase, "ramp": args.ramp, "eclipse_shape": args.eclipse_shape,
               "event": args.event,
               "sampler": args.sampler, "prayer_bead_shifts": args.prayer_bead,
               "mcmc_walkers": args.walkers, "mcmc_steps": args.steps, "radius_px": args.radius,
               "profile": args.profile}
    event = args.event or cfg.reduce.event
    if args.phase in PHASE_CURVE_MODELS + ("bic",):
        if event != "phase-curve":
            raise InputError(f"--phase {args.phase}: a whole phase curve's model (give "
                             "--event phase-curve)")
        changes["phase"], changes["phase_curve_model"] = None, args.phase
    elif args.phase is not None and event == "phase-curve":
        raise InputError(f"--phase {args.phase}: --event phase-curve takes "
                         f"{', '.join(PHASE_CURVE_MODELS)} or bic")
    options = replace(cfg.reduce, **{k: v for k, v in changes.items() if v is not None})
    try:
        options.validate()
    except InputError as exc:
        raise InputError(str(exc).replace("config key '", "option '")) from None
    return options, cfg.system


def _system(args: argparse.Namespace, section, table, source) -> PlanetSystem:
    """The planet asked for (``--system``, ``--planet``, a configuration's ``[system]``), else
    the one the table's metadata name; one line asking for ``--system`` when none is found."""
    explicit = args.system is not None or bool(getattr(args, "planet", None))
    return system_of_table(table.meta, system=system_for(section) if explicit else None,
                           section=section, source=str(source))


def time_options(args: argparse.Namespace) -> dict:
    """``--time-scale``, ``--time-at`` and ``--observer`` as ``standardise_table``'s keywords."""
    return {k: v for k, v in (("time_scale", args.time_scale), ("time_at", args.time_at),
                              ("observer", args.observer)) if v is not None}


def _standard_table(args: argparse.Namespace, section, path: Path):
    """The table at ``path`` with the package's names and times (BMJD_TDB), and its planet.

    Times at the observer (``--time-format`` jd or mjd) are converted with the
    planet's coordinates, so the planet is then found first.
    """
    from ..fit.data import check_columns, standardise_table
    from ..photometry.table import read_table

    table = read_table(path)
    table.meta.setdefault("FILENAME", str(path))
    system = (_system(args, section, table, path) if args.time_format in ("jd", "mjd")
              else None)
    table = standardise_table(table, columns=_column_map(args.columns),
                              time_column=args.time_column, time_format=args.time_format,
                              target=system, labels=_TABLE_LABELS, **time_options(args))
    check_columns(table, str(path), radius_px=args.radius, labels=_TABLE_LABELS)
    return table, system if system is not None else _system(args, section, table, path)


def _clean(obj):
    if isinstance(obj, dict):
        return {k: _clean(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_clean(v) for v in obj]
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


#: a depth error below this (1e-12 of the flux: rounding) is zero, never a result
ZERO_ERROR_PPM = 1e-6


def lightcurve_path(result_path: str | Path) -> Path:
    """``RESULT.json`` -> ``RESULT.lc.ecsv`` (:func:`eclipsebench.fit.result.lightcurve_path`)."""
    from ..fit.result import lightcurve_path as path_of  # the result's module (astropy)

    return path_of(result_path)


_TABLE_SUFFIXES = (".fits", ".fit", ".ecsv", ".csv")


def _table_paths(items: list[str]) -> list[Path]:
    """The tables named, a folder's tables (sorted by name), each checked to exist."""
    paths: list[Path] = []
    for item in items:
        p = Path(item)
        if p.is_dir():
            found = sorted(q for q in p.iterdir() if q.is_file()
                           and q.suffix.lower() in _TABLE_SUFFIXES and ".lc." not in q.name)
            if not found:
                raise InputError(f"{p}: no photometry tables (.fits, .ecsv, .csv) in this folder")
            paths += found
        elif p.is_file():
            paths.append(p)
        else:
            raise InputError(f"{p}: no such photometry table")
    if len(set(paths)) != len(paths):
        raise InputError("TABLE: a table is given twice")
    return paths


def _run_joint(args: argparse.Namespace, paths: list[Path]) -> dict:
    """Several epochs with one depth (issue 17 point 4): ``reduce_joint``, one JSON."""
    from ..fit.reduce import configured_method_options, reduce_joint, resolve_method_options

    for flag, value in (("--sampler mcmc", args.sampler == "mcmc"),
                        ("--profile paper", args.profile == "paper"),
                        ("--compare-phases", args.compare_phases), ("--plot", args.plot)):
        if value:
            raise InputError(f"{flag}: applies to one table; a joint fit of {len(paths)} "
                             "tables is least squares with the controlled settings")
    out = Path(args.out) if args.out else paths[0].parent / f"joint.{args.method}.json"
    check_output_path(out, "--out", "file")
    options, section = _options(args)
    method_options = resolve_method_options(args.method, options,
                                            _method_options(args.method_options),
                                            configured=configured_method_options(options))
    tables = []
    systems = []
    for path in paths:
        table, system = _standard_table(args, section, path)
        tables.append(table)
        systems.append(system)
    system = systems[0]
    for other, path in zip(systems[1:], paths[1:], strict=True):
        if other.name != system.name:
            raise InputError(f"{path}: names {other.name}, {paths[0]} names {system.name}; a "
                             "joint fit is of one planet (give --system NAME)")
    result = reduce_joint(tables, args.method, options=options, system=system, seed=args.seed,
                          pmap=args.pmap, method_options=method_options)
    summary = _clean({**result.to_dict(), "tables": [str(p) for p in paths]})
    write_json(out, summary)
    summary["result_file"] = str(out)
    return summary


def chain_file(result_path: str | Path) -> Path:
    """``RESULT.json`` -> ``RESULT.chain.npz`` (:func:`eclipsebench.fit.result.chain_path`)."""
    from ..fit.result import chain_path  # the result's module (astropy)

    return chain_path(result_path)


def _check_pmap(args: argparse.Namespace, table, table_path: Path) -> None:
    """A method that needs the ``pmap`` resource (kr-pmap) needs a map: ``--pmap``, or a
    simulated table's SIMDIR (named on the command line).

    The ``--option`` values were resolved before (:func:`run`), so an unknown
    option is the error reported, as for any other method.
    """
    from ..decorrelate import get_method
    from ..io.pmap_files import check_pmap_path

    if args.pmap is not None:   # a device or a FIFO is refused before the fit
        check_pmap_path(args.pmap)
    cls = get_method(args.method)
    if "pmap" not in cls.resources or args.pmap is not None:
        return
    if not (table.meta.get("SIMDIR") or table.meta.get("simdir")):
        raise InputError(f"--method {cls.name}: needs --pmap PATH (a calibration-star table, the "
                         f"SSC pmap, or a folder of its versions); {table_path} names no "
                         "simulation folder (SIMDIR) to find one in")


def run(args: argparse.Namespace) -> dict:
    paths = _table_paths(args.table)
    # The fitter pulls in every method (numba, scikit-learn, about 2 s): imported once the
    # table is found, not for `eclipsebench --help` or a misspelt path.
    from ..decorrelate.base import unknown_methods

    if problem := unknown_methods([args.method]):   # before any path is made
        raise InputError(f"--method: {problem}")
    if len(paths) > 1:
        return _run_joint(args, paths)
    from ..fit.reduce import (
        configured_method_options,
        reduce_epoch,
        resolve_method_options,
        select_phase_model,
    )

    table_path = paths[0]
    out = Path(args.out) if args.out else table_path.with_name(
        f"{table_path.stem}.{args.method}.json")
    lc_path = lightcurve_path(out)
    check_output_path(out, "--out", "file")
    check_output_path(lc_path, "--out (its light curve)", "file")
    check_output_path(chain_file(out), "--out (its chain)", "file")
    if args.plot:
        check_plot_path(args.plot, "--plot")
    options, section = _options(args)
    # The method's options, parsed once here (the configuration's tables, the team's in
    # the paper profile, --option) and passed down as its options dataclass.
    configured = configured_method_options(options)
    given = _method_options(args.method_options)
    method_options = resolve_method_options(args.method, options, given,
                                            profile=options.profile, configured=configured)
    table, system = _standard_table(args, section, table_path)
    _check_pmap(args, table, table_path)
    result = reduce_epoch(table, args.method, options=options, system=system,
                          seed=args.seed, epoch=args.epoch, pmap=args.pmap,
                          method_options=method_options)
    error = result.depth_err_ppm
    if error is None or not math.isfinite(error) or error < ZERO_ERROR_PPM:
        raise InputError(f"{table_path}: the {args.method} fit gives depth "
                         f"{result.depth_ppm:.1f} +- {error:.3g} ppm: a zero or non-finite error "
                         "is not a result (constant flux or a degenerate fit); nothing written")
    summary = result.to_dict()
    if args.compare_phases:   # the controlled settings: the team's options only in the paper fit
        phase_options = (method_options if options.profile != "paper" else
                         resolve_method_options(args.method, options, given, configured=configured))
        sel = select_phase_model(table, args.method, options=options, system=system,
                                 seed=args.seed, epoch=args.epoch, pmap=args.pmap,
                                 method_options=phase_options)
        summary["phase_models"] = sel.to_dict()
    summary.update({"table": str(table_path), "lightcurve_file": str(lc_path)})
    chain_path = chain_file(out) if result.chain is not None else None
    with atomic_path(lc_path) as tmp:
        result.lightcurve_table().write(tmp, format="ascii.ecsv")
    try:
        if chain_path is not None:
            result.write_chain(chain_path)
            summary["chain_file"] = str(chain_path)
        if args.plot:
            from ..fit.plot import plot_corner, plot_reduced_lightcurve  # matplotlib: --plot
            plot_reduced_lightcurve(result, args.plot)
            summary["plot_file"] = str(args.plot)
            if result.chain is not None:
                corner = Path(args.plot).with_suffix(".corner.png")
                plot_corner(result.chain["names"], result.chain["samples"], corner)
                summary["corner_file"] = str(corner)
        summary = _clean(summary)
        write_json(out, summary)
    except BaseException:
        lc_path.unlink(missing_ok=True)  # no light curve or chain without its result
        if chain_path is not None:
            chain_path.unlink(missing_ok=True)
        raise
    summary["result_file"] = str(out)
    return summary


def _num(value, digits: int = 2) -> str:
    """A number for the text summary; "n/a" for null (e.g. beta_red of too few points)."""
    return "n/a" if value is None else f"{value:.{digits}f}"


def format_text(result: dict) -> str:
    if result.get("joint"):
        lines = [f"method        {result['method']}, joint fit of {len(result['epochs'])} "
                 f"epochs ({result['phase']} phase)",
                 f"depth         {result['depth_ppm']:.1f} +- {result['depth_err_ppm']:.1f} ppm "
                 "(one depth for every epoch)",
                 f"combined      {result['depth_combined_ppm']:.1f} +- "
                 f"{result['depth_combined_err_ppm']:.1f} ppm (the epochs fitted alone, "
                 "inverse-variance mean)"]
        lines.append(f"BIC / AIC     {_num(result['bic'], 1)} / {_num(result['aic'], 1)} "
                     f"(k = {result['k']}, on {result['bic_data']}: comparable only with fits "
                     "of the same points)")
        for e in result["per_epoch"]:
            lines.append(f"  epoch {e['epoch']}: alone {e['depth_alone_ppm']:7.1f} +- "
                         f"{e['depth_alone_err_ppm']:5.1f} ppm, beta_red {_num(e['beta_red'])}")
        lines.append(f"wrote         {result['result_file']}")
        return "\n".join(lines)
    when = "t_transit" if result.get("event") == "transit" else "t_ecl"
    lines = [f"method        {result['method']} (epoch {result['epoch']}, phase {result['phase']}, "
             f"{result['sampler']}, {result.get('profile', 'controlled')} profile)",
             f"depth         {result['depth_ppm']:.1f} +- {result['depth_err_ppm']:.1f} ppm "
             f"(error from {result['depth_err_method']})",
             f"{when:<14}{result[when + '_bmjd']:.5f} +- {result[when + '_err_d'] * 86400:.0f} s "
             "BMJD_TDB",
             f"rms           {result['rms_ppm']:.0f} ppm, beta_red {_num(result['beta_red'])}, "
             f"chi2_red {result['chi2_red']:.3f}",
             f"BIC / AIC     {_num(result['bic'], 1)} / {_num(result['aic'], 1)} (k = {result['k']}, "
             f"on {result.get('bic_data', 'points not recorded')}: comparable only with fits "
             "of the same points)"]
    if when == "t_transit":
        lines.insert(2, f"rp_rs         {result['rp_rs']:.5f} +- {result['rp_rs_err']:.5f} "
                        "(depth = rp_rs^2)")
    if result.get("event") == "phase-curve":
        lines[2:2] = [
            f"amplitude     {result['phase_amplitude_ppm']:.1f} +- "
            f"{result['phase_amplitude_err_ppm']:.1f} ppm (semi-amplitude)",
            f"offset        {result['phase_offset_deg']:.1f} +- "
            f"{result['phase_offset_err_deg']:.1f} deg (hotspot, east positive)",
            f"night side    {result['nightside_flux_ppm']:.1f} +- "
            f"{result['nightside_flux_err_ppm']:.1f} ppm; minimum "
            f"{result['planet_flux_min_ppm']:.1f} ppm"
            + (" (NEGATIVE)" if result.get("planet_flux_negative") else ""),
            f"rp_rs         {result['rp_rs']:.5f} +- {result['rp_rs_err']:.5f}"]
    models = result.get("phase_models")
    if models:
        lines.append("phase models  (BIC picks " + models["best_bic"] + ", AIC picks "
                     + models["best_aic"] + ")")
        for row in models["models"]:
            lines.append(f"  {row['phase']:<10} depth {row['depth_ppm']:7.1f} +- "
                         f"{row['depth_err_ppm']:5.1f} ppm  dBIC {row['delta_bic']:7.1f}  "
                         f"dAIC {row['delta_aic']:7.1f}")
    if result.get("mcmc_steps"):
        lines.insert(2, f"posterior     median {result['mcmc_depth_median_ppm']:.1f} "
                        f"-{result['mcmc_depth_err_lo_ppm']:.1f} / "
                        f"+{result['mcmc_depth_err_hi_ppm']:.1f} ppm ({result['mcmc_move']}, "
                        f"{result['mcmc_walkers']} walkers x {result['mcmc_steps']} steps, "
                        f"N/tau {result.get('mcmc_n_over_tau') or float('nan'):.0f})")
    if result.get("time_conversion"):
        lines.append(f"times         {result['time_conversion']}")
    wrote = [result["result_file"], result["lightcurve_file"]] + [
        result[k] for k in ("chain_file", "plot_file", "corner_file") if result.get(k)]
    lines.append("wrote         " + ", ".join(wrote))
    return "\n".join(lines)
