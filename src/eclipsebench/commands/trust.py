"""``eclipsebench trust``: how far to trust the depth of *this* observation (digital twins)."""

from __future__ import annotations

import argparse
import shlex
from pathlib import Path

from ..astro.events import event_for
from ..config import load_config
from ..detector.constants import READOUT_MODES
from ..errors import InputError
from ..fit.names import EVENTS
from ..limits import MAX_WORKERS
from .options import (
    add_planet_options,
    method_list,
    method_options,
    planet_overrides,
    positive_float,
    positive_int,
)
from .table_options import TABLE_LABELS, add_table_options, table_keywords

#: The readouts twins are made for (subarray modes).
SUBARRAY_READOUTS = tuple(name for name, mode in READOUT_MODES.items() if mode.subarray)

NAME = "trust"
HELP = ("Simulate digital twins of a real observation (its times, pointing track, flux, "
        "background and readout, with a known eclipse), reduce each like the real table with "
        "every chosen method, and report each method's bias, scatter, error calibration and "
        "honest error on the real depth, with a recommended method and the methods the twins "
        "cannot tell from it; resumable.")


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("table", metavar="TABLE",
                   help="photometry table of the real observation: made by 'eclipsebench "
                        "photometry' (it records the readout, background and noise pixels), or "
                        "another pipeline's (time, flux in any unit, flux_err, x, y), completed "
                        "by inference into DIR/observation.fits (docs/trust.md, 'Any table')")
    p.add_argument("--out", required=True, metavar="DIR",
                   help="trust folder (rerunning the same command resumes it)")
    p.add_argument("--system", metavar="NAME", default=None,
                   help="planet (default: the one the table names, e.g. OBJECT XO-3 -> XO-3b)")
    add_planet_options(p)
    p.add_argument("--twins", type=_twin_count, default=50, metavar="N",
                   help="number of twins (10-10000); another number into the same --out "
                        "keeps the twins already made")
    p.add_argument("--methods", type=method_list, metavar="A,B,...", default=None,
                   help="methods to measure (default: every registered method); the first "
                        "one's real depth is injected unless --depth is given")
    p.add_argument("--event", choices=EVENTS, default=None,
                   help="the observation's event (default: [reduce] event, eclipse); "
                        "phase-curve: a whole phase curve of several AORs (the table's aorkey), "
                        "scored also on its amplitude and peak offset")
    p.add_argument("--depth", type=positive_float(), default=None, metavar="PPM",
                   help="depth injected into the twins (default: the first method's real depth)")
    p.add_argument("--profile", choices=("controlled", "paper"), default=None,
                   help="reduction profile of the real table and its twins (default: [reduce] "
                        "profile, controlled)")
    p.add_argument("--sampler", choices=("auto", "mcmc", "leastsq"), default=None,
                   help="sampler of the real table and its twins (default: [reduce] sampler)")
    p.add_argument("--option", dest="method_options", action="append", default=[],
                   metavar="METHOD.KEY=VALUE",
                   help="a method's option (repeatable), e.g. --option kr-data.k=40")
    p.add_argument("--pmap", metavar="PATH", default=None,
                   help="pixel map: kr-pmap's calibration (as reduce --pmap) and, when it is a "
                        "gridded SSC map (or a folder of dated versions), the twins' gain")
    p.add_argument("--seed", type=positive_int(minimum=0), default=0, metavar="N",
                   help="one seed for every twin's noise and every reduction")
    add_table_options(p, "map another pipeline's column names to the package's, as reduce "
                         "--columns (repeatable)")
    p.add_argument("--readout", choices=SUBARRAY_READOUTS, default=None,
                   help="another pipeline's subarray readout (default: the mode whose frame "
                        "time is the table's cadence)")
    p.add_argument("--channel", type=int, choices=(1, 2), default=None,
                   help="another pipeline's IRAC channel (default: its CHANNEL, else 2)")
    p.add_argument("--workers", type=positive_int(maximum=MAX_WORKERS), default=None, metavar="N",
                   help="Dask worker processes (default: run.workers); 1 runs in this process")
    p.add_argument("--config", metavar="CONFIG", default=None,
                   help="configuration file whose [reduce], [system] and [run] sections are used")
    p.add_argument("--set", dest="overrides", action="append", default=[],
                   metavar="SECTION.KEY=VALUE", help="override one configuration value")


def _twin_count(text: str) -> int:
    """``--twins``: an integer within the trust run's bounds (checked before any work)."""
    from ..trust.run import MAX_TWINS, MIN_TWINS

    value = positive_int()(text)
    if not MIN_TWINS <= value <= MAX_TWINS:
        raise argparse.ArgumentTypeError(f"expected {MIN_TWINS} to {MAX_TWINS} twins, got "
                                         f"{value}")
    return value


#: How the library's refusals name this command's options.
LABELS = {**TABLE_LABELS, "out": "--out", "depth_ppm": "--depth"}


def run(args: argparse.Namespace) -> dict:
    # the simulator and every method: imported when the command runs, not for --help
    from ..api import trust_with_report
    from ..astro.catalogue import system_for
    from ..decorrelate.base import unknown_methods

    if args.methods and (problem := unknown_methods(args.methods)):   # before the table
        raise InputError(f"--methods: {problem}")

    cfg = load_config(args.config, args.overrides + planet_overrides(args, args.system))
    changes = {k: v for k, v in (("profile", args.profile), ("sampler", args.sampler),
                                 ("event", args.event)) if v is not None}
    explicit = args.system is not None or bool(args.planet)
    command = shlex.join(["eclipsebench", *getattr(args, "_argv", [])])   # for the page
    summary, report = trust_with_report(
        args.table, Path(args.out), command=command, config=cfg,
        system=system_for(cfg.system) if explicit else None, twins=args.twins,
        methods=args.methods, depth_ppm=args.depth, seed=args.seed,
        options=method_options(args.method_options), pmap=args.pmap,
        readout=args.readout, channel=args.channel, labels=LABELS,
        workers=args.workers or cfg.run.workers, **table_keywords(args), **changes)
    return {**summary, "_run": {"out": str(Path(args.out)), "ran": len(report.ran),
                                "skipped": len(report.skipped), "wall_s": report.wall_s,
                                "stage_seconds": report.stage_seconds()}}


def _twin_lines(twins: dict) -> list[str]:
    """What was fitted to make the twins resemble the real frames (``docs/trust.md``)."""
    cal = twins.get("calibration") or {}
    bound = twins.get("motion_bound") or {}
    if bound.get("photometry_only"):
        return [f"twins' PSF    the committed PSF (no noise pixels in the table); motion within an "
                f"exposure {twins['motion_rms_px']:.3f} px rms (A_fbm "
                f"{twins['motion_peak_px']:.3f}): the most whose pilot twin is no redder than the "
                f"real residuals ({len(bound['steps']) - 1} motions tried)"]
    if "blur_px" not in cal:
        return []
    lines = [f"twins' PSF    blur {cal['blur_px']:.3f} px (builtin {cal['blur_px_builtin']:.3f}), "
             f"motion within an exposure {twins['motion_rms_px']:.3f} px rms (A_fbm "
             f"{twins['motion_peak_px']:.3f}): noise pixels {cal['noise_pixels_twins']:.2f}, "
             f"SD over cubes {cal['noise_pixels_cube_sd_twins']:.3f} (real "
             f"{cal['noise_pixels_real']:.2f}, {cal['noise_pixels_cube_sd_real']:.3f}; "
             f"{cal['target_vs_grid']})"]
    if bound.get("bounded"):
        first = bound["steps"][0]
        lines.append(f"twins' motion bounded by the photometry: A_fbm {first['motion_peak_px']:.3f}"
                     f" (blur {cal['noise_pixels_only']['blur_px']:.3f}) made a pilot twin redder"
                     f" than the real residuals in {first['bins_twin_in_excess']} frequency bins; "
                     f"{len(bound['steps']) - 1} gentler PSFs tried")
    bg, noise = twins.get("background") or {}, twins.get("correlated_noise") or {}
    if bg:
        lines.append(f"twins' noise  background {bg['share']:.2f} of the real frame-to-frame "
                     f"deviations (real {bg['background_sd_real']:.2f} e/px rms, twins' own "
                     f"{bg['background_sd_twin_noise']:.2f})" + (
                         f"; real correlated noise {noise['rms_ppm']:.0f} ppm rms in "
                         f"{noise['bins_in_excess']} of {noise['bins']} frequency bins (real "
                         f"beta_red {noise['beta_red_real']:.2f}, pilot twin "
                         f"{noise['beta_red_pilot']:.2f})" if "rms_ppm" in noise else ""))
    return lines


def format_text(result: dict) -> str:
    from ..trust.report import ranking_text
    from ..trust.rows import (
        DEPTH_COLUMNS,
        PHASE_HEAD,
        TIME_COLUMNS,
        cautions,
        method_rows,
        phase_rows,
        phase_units,
        text_table,
    )

    lines = []
    if result.get("quote"):   # the line to quote first
        lines += [f"quote         {result['quote']['text']}",
                  f"ranking       {ranking_text(result)}"]
    lines += [f"{result['system']}: {result['n_twins']} twins with a "
             f"{result['twin_depth_ppm']:.1f} ppm {result['twins']['event']} "
             f"({result['profile']} profile, {result['sampler']})",
             *_twin_lines(result.get("twins") or {})]
    head, units, rows = method_rows(result, DEPTH_COLUMNS)
    lines += text_table(head, units, rows)
    head, units, rows = method_rows(result, TIME_COLUMNS)
    if rows:
        lines.append(f"the {event_for(result['twins']['event']).conjunction}"
                     "'s mid-time, against the injected one (the twins whose fit freed it):")
        lines += text_table(["mid-time", *head[1:]], units, rows)
    for name, unit, rows in phase_rows(result):
        lines.append(f"the phase curve's {name.replace('_', ' ')}, against the injected "
                     f"{result[f'twin_{name}_{unit}']:.1f} {unit}:")
        lines += text_table([name.split("_")[-1], *PHASE_HEAD], ["", *phase_units(unit)], rows)
    lines.append(f"recommended   {result['recommended']} ({result['recommended_because']})")
    if result.get("near_equals"):
        from ..trust.score import DISTINGUISHABLE_AT

        lines.append(f"near equals   {', '.join(result['near_equals'])}: mean squared error "
                     f"within {DISTINGUISHABLE_AT:g} paired standard errors of the recommended "
                     "method's (the twins cannot tell them apart)")
    lines += [f"caution       {c}" for c in cautions(result, ranking=False)]
    if result.get("source_table"):
        lines.append(f"table         {result['source_table']}, another pipeline's, completed as "
                     f"{result['table']}")
        for key, what in (result.get("inferred") or {}).items():
            if not key.endswith("_per_unit"):
                lines.append(f"inferred      {key}: {what}")
    if result.get("time_conversion"):
        lines.append(f"times         {result['time_conversion']}")
    run = result.get("_run")
    if run:
        lines.append(f"{run['out']}: {run['ran']} tasks run, {run['skipped']} already done, "
                     f"{run['wall_s']:.1f} s; report in {run['out']}/report/index.html")
    return "\n".join(lines)
