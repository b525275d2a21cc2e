"""``eclipsebench reduce``: fit one epoch's photometry table with one method.

A thin shell around :func:`eclipsebench.reduce` (and :func:`eclipsebench.compare_phases`):
the arguments become its keywords, its result is written (``RESULT.json``, the
light curve, the chain, the plots) and printed. Every rule a result obeys, and
every refusal, is the library's.
"""

from __future__ import annotations

import argparse
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, cast

from ..astro.catalogue import system_for
from ..astro.events import event_for
from ..config import Config, load_config
from ..errors import InputError
from ..fit.names import ECLIPSE_SHAPES, EVENTS, PHASE_CURVE_MODELS, PHASE_MODELS, RAMP_MODELS
from ..io.atomic import atomic_path, write_json
from ..io.paths import check_plot_path
from ..io.plain import json_safe
from ..limits import MAX_MCMC_WALKERS
from .options import (
    add_planet_options,
    check_output_path,
    method_options,
    planet_overrides,
    positive_float,
    positive_int,
)
from .reduce_text import format_text as format_text  # the CLI prints with it
from .table_options import TABLE_LABELS, add_table_options, table_keywords, table_paths

if TYPE_CHECKING:  # pragma: no cover
    from ..fit.result import EpochResult

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


#: How the library's refusals name this command's options.
LABELS = {**TABLE_LABELS, "sampler": "--sampler", "profile": "--profile"}


def _config(args: argparse.Namespace) -> Config:
    """The configuration with ``[reduce]`` as the options give it (checked, named as options)."""
    cfg = load_config(args.config, args.overrides + planet_overrides(args, args.system))
    changes = {"phase": args.phase, "ramp": args.ramp, "eclipse_shape": args.eclipse_shape,
               "event": args.event,
               "sampler": args.sampler, "prayer_bead_shifts": args.prayer_bead,
               "mcmc_walkers": args.walkers, "mcmc_steps": args.steps, "radius_px": args.radius,
               "profile": args.profile}
    whole_orbit = event_for(args.event or cfg.reduce.event).whole_orbit
    if args.phase in PHASE_CURVE_MODELS + ("bic",):
        if not whole_orbit:
            raise InputError(f"--phase {args.phase}: a whole phase curve's model (give "
                             "--event phase-curve)")
        changes["phase"], changes["phase_curve_model"] = None, args.phase
    elif args.phase is not None and whole_orbit:
        raise InputError(f"--phase {args.phase}: --event phase-curve takes "
                         f"{', '.join(PHASE_CURVE_MODELS)} or bic")
    options = replace(cfg.reduce, **{k: v for k, v in changes.items() if v is not None})
    try:
        options.validate()
    except InputError as exc:
        raise InputError(str(exc).replace("config key '", "option '")) from None
    return replace(cfg, reduce=options)


def _keywords(args: argparse.Namespace, cfg: Config) -> dict:
    """The keywords of :func:`eclipsebench.reduce` the arguments give (all but the table)."""
    # the planet asked for (--system, --planet), else the library's rule: [system], the table's
    explicit = args.system is not None or bool(getattr(args, "planet", None))
    return {"system": system_for(cfg.system) if explicit else None, "seed": args.seed,
            "options": method_options(args.method_options, args.method).get(args.method),
            "config": cfg, "resources": {"pmap": args.pmap} if args.pmap is not None else None,
            "labels": LABELS, **table_keywords(args)}


def _run_joint(args: argparse.Namespace, paths: list[Path]) -> dict:
    """Several epochs with one depth (issue 17 point 4): ``eb.reduce`` of a list, one JSON."""
    from ..api import reduce

    # the command's own options; a sampler or profile a joint fit refuses is the library's
    # rule (eclipsebench.api.reduce), which names them as --sampler and --profile (LABELS)
    for flag, value in (("--compare-phases", args.compare_phases), ("--plot", args.plot)):
        if value:
            raise InputError(f"{flag}: applies to one table; a joint fit of {len(paths)} "
                             "tables is least squares with the controlled settings")
    out = Path(args.out) if args.out else paths[0].parent / f"joint.{args.method}.json"
    check_output_path(out, "--out", "file")
    cfg = _config(args)
    result = reduce([str(p) for p in paths], args.method, **_keywords(args, cfg))
    summary = json_safe({**result.to_dict(), "tables": [str(p) for p in paths]})
    write_json(out, summary)
    summary["result_file"] = str(out)
    return summary


def run(args: argparse.Namespace) -> dict:
    paths = table_paths(args.table)
    # The fitter pulls in every method (numba, scikit-learn, about 2 s): imported once the
    # table is found, not for `eclipsebench --help` or a misspelt path.
    from ..decorrelate.base import unknown_methods

    if problem := unknown_methods([args.method]):   # before any path is made
        raise InputError(f"--method: {problem}")
    if len(paths) > 1:
        return _run_joint(args, paths)
    from ..api import compare_phases, reduce
    from ..fit.result import chain_path, lightcurve_path

    table_path = paths[0]
    out = Path(args.out) if args.out else table_path.with_name(
        f"{table_path.stem}.{args.method}.json")
    lc_path = lightcurve_path(out)
    check_output_path(out, "--out", "file")
    check_output_path(lc_path, "--out (its light curve)", "file")
    check_output_path(chain_path(out), "--out (its chain)", "file")
    if args.plot:
        check_plot_path(args.plot, "--plot")
    cfg = _config(args)
    keywords = _keywords(args, cfg)
    # one table: an EpochResult (a list of them is the joint fit's JointResult)
    result = cast("EpochResult", reduce(str(table_path), args.method, epoch=args.epoch,
                                        **keywords))
    summary = result.to_dict()
    if args.compare_phases:   # the controlled settings: the team's options only in the paper fit
        summary["phase_models"] = compare_phases(str(table_path), args.method, epoch=args.epoch,
                                                 **keywords).to_dict()
    summary.update({"table": str(table_path), "lightcurve_file": str(lc_path)})
    chain = chain_path(out) if result.chain is not None else None
    summary = _write(args, result, summary, out, lc_path, chain)
    summary["result_file"] = str(out)
    return summary


def _write(args: argparse.Namespace, result, summary: dict, out: Path, lc_path: Path,
           chain: Path | None) -> dict:
    """The light curve, the chain and the plots, then ``RESULT.json`` last; none without it."""
    with atomic_path(lc_path) as tmp:
        result.lightcurve_table().write(tmp, format="ascii.ecsv")
    try:
        if chain is not None:
            result.write_chain(chain)
            summary["chain_file"] = str(chain)
        if args.plot:
            from ..fit.result.plot import plot_corner, plot_reduced_lightcurve  # matplotlib: --plot
            plot_reduced_lightcurve(result, args.plot)
            summary["plot_file"] = str(args.plot)
            if result.chain is not None:
                corner = Path(args.plot).with_suffix(".corner.png")
                plot_corner(result.chain["names"], result.chain["samples"], corner)
                summary["corner_file"] = str(corner)
        summary = json_safe(summary)
        write_json(out, summary)
    except BaseException:
        lc_path.unlink(missing_ok=True)  # no light curve or chain without its result
        if chain is not None:
            chain.unlink(missing_ok=True)
        raise
    return summary
