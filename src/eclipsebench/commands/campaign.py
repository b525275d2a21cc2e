"""``eclipsebench campaign``: many real observations of one planet, end to end."""

from __future__ import annotations

import argparse
from dataclasses import replace
from pathlib import Path

from ..config import Config, load_config
from ..errors import InputError
from ..fit.names import EVENTS
from ..io.paths import check_output_path
from ..limits import MAX_WORKERS
from .options import (
    add_planet_options,
    method_list,
    planet_overrides,
    positive_int,
    run_overrides,
)
from .run import _profile_list, _scheduler, add_cluster_options
from .table_options import TABLE_LABELS, add_table_options, column_map

NAME = "campaign"
HELP = ("Reduce many real observations of one planet (photometry tables of any pipeline, or "
        "archive AOR folders) with every method, and score them across epochs: the paper's "
        "Table 3 statistics, a joint depth per method and one depth across methods; "
        "resumable.")


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("inputs", nargs="*", metavar="INPUT",
                   help="one epoch per input: a photometry table (FITS, ECSV, CSV), an AOR "
                        "folder (r<AORKEY>/ch*/bcd/) or a BCD file; or give --file")
    p.add_argument("--file", metavar="CAMPAIGN.toml", default=None,
                   help="a campaign file naming each epoch's inputs (its Pre and Main AORs), "
                        "channel and event (docs/campaign.md)")
    p.add_argument("--out", required=True, metavar="DIR",
                   help="run folder; rerunning the same command resumes it")
    p.add_argument("--system", metavar="NAME", default=None,
                   help="planet (default: the one the data name, as reduce finds it)")
    add_planet_options(p)
    p.add_argument("--config", metavar="CONFIG", default=None,
                   help="configuration file ([reduce], [system], [photometry], [run])")
    p.add_argument("--set", dest="overrides", action="append", default=[],
                   metavar="SECTION.KEY=VALUE", help="override one configuration value")
    p.add_argument("--methods", type=method_list, metavar="A,B,...",
                   help="methods to run (run.methods; default: every registered one)")
    p.add_argument("--profiles", type=_profile_list, metavar="P[,P]",
                   help="controlled, paper or both (run.profiles; default both)")
    p.add_argument("--event", choices=EVENTS, default=None,
                   help="event fitted in every epoch (default: [reduce] event, eclipse; a "
                        "campaign file may name each epoch's)")
    p.add_argument("--sampler", choices=("auto", "mcmc", "leastsq"), default=None,
                   help="reduce.sampler (auto: mcmc for an eclipse, leastsq for a phase curve)")
    p.add_argument("--channel", type=positive_int(minimum=1, maximum=4), default=None,
                   metavar="N", help="IRAC channel of the inputs (default: the data's)")
    add_table_options(p, "map every table's column names to the package's, e.g. "
                         "--columns flux=raw_flux,x=xcent (repeatable)")
    p.add_argument("--seed", type=positive_int(minimum=0), metavar="N",
                   help="the one seed (challenge.seed)")
    p.add_argument("--twins", type=positive_int(minimum=0), default=0, metavar="N",
                   help="digital twins of each epoch (trust as a stage, docs/trust.md; 10 or "
                        "more): the Table 3 statistics a second time with each method's "
                        "honest error (default 0: none)")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--workers", type=positive_int(maximum=MAX_WORKERS), metavar="N",
                   help="Dask worker processes of a local cluster; 1 runs in this process")
    g.add_argument("--scheduler", metavar="ADDRESS",
                   help="address of an existing Dask scheduler (default: the environment "
                        "variable ECLIPSEBENCH_SCHEDULER)")
    add_cluster_options(p)


def _config(args: argparse.Namespace) -> Config:
    extra = run_overrides(args)
    for key, value in (("event", args.event), ("sampler", args.sampler)):
        if value is not None:
            extra.append(f'reduce.{key}="{value}"')
    cfg = load_config(args.config, list(args.overrides) + extra
                      + planet_overrides(args, args.system))
    if args.seed is not None:
        cfg = replace(cfg, challenge=replace(cfg.challenge, seed=args.seed))
    return cfg


def run(args: argparse.Namespace) -> dict:
    # every stage's modules: loaded by this command only, not at CLI start
    from ..challenge.campaign import (
        TableOptions,
        epochs_from_inputs,
        read_campaign_file,
        run_campaign,
    )
    from ..engine.cluster import ClusterOptions

    if bool(args.inputs) == bool(args.file):
        raise InputError("INPUT: give the epochs as inputs (one per epoch) or with --file, "
                         "not both" if args.inputs else "INPUT: no epochs (give one input per "
                                                        "epoch, or --file CAMPAIGN.toml)")
    out = Path(args.out)
    check_output_path(out, "--out", "folder")
    table = TableOptions(tuple(sorted(column_map(args.columns).items())), args.time_column,
                         args.time_format, args.time_scale, args.time_at, args.observer)
    if args.file:
        if table.given() or args.channel is not None:
            raise InputError("--file: the campaign file names each epoch's table options and "
                             "channel (its [table] and [[epoch]] keys), not the command line")
        epochs = read_campaign_file(args.file)
    else:
        epochs = epochs_from_inputs(args.inputs, table=table, channel=args.channel)
    cfg = _config(args)
    labels = None if args.file else TABLE_LABELS
    summary, report = run_campaign(cfg, out, epochs, scheduler=_scheduler(args), labels=labels,
                                   twins=args.twins,
                                   cluster=ClusterOptions(
        dashboard=args.dashboard, connect_timeout_s=args.connect_timeout,
        tls_ca_file=args.tls_ca_file, tls_cert=args.tls_cert, tls_key=args.tls_key))
    if args.json:
        return summary
    return {**summary, "_run": {"out": str(out), "ran": len(report.ran),
                                "skipped": len(report.skipped), "wall_s": report.wall_s,
                                "executor": report.executor,
                                "summary": str(out / "summary.json"),
                                "report": (str(out / "report" / "index.html")
                                           if (out / "report" / "index.html").is_file()
                                           else None)}}


def _pm(value, err) -> str:
    if value is None or err is None:
        return "n/a"
    return f"{value:.1f} +- {err:.1f} ppm"


def format_text(result: dict) -> str:
    from ..report.tables import format_text_table  # astropy: not at CLI start

    lines = [f"{result['planet']}: {len(result['epochs'])} epochs, event {result['event']}"]
    for e in result["epochs"]:
        lines.append(f"  epoch {e['number']} ({', '.join(e['paths'])}): times "
                     f"{e['time_conversion']}")
    for profile, p in result["profiles"].items():
        for group, stats in p["channels"].items():
            lines.append(f"{profile} profile, {group}:")
            if stats.get("methods"):
                lines.append(format_text_table(stats))
            per_epoch: dict[str, list[str]] = {}
            for d in stats.get("depths", []):
                per_epoch.setdefault(d["method"], []).append(
                    f"{d['epoch']}: {d['depth_ppm']:.1f} +- {d['error_ppm']:.1f}")
            for m, items in per_epoch.items():
                lines.append(f"  {m} per epoch (ppm): " + "; ".join(items))
            h = stats.get("honest")
            if h and h.get("methods"):
                lines.append(f"{profile} profile, {group}, with the twins' honest errors:")
                lines.append(format_text_table(h))
            c = stats.get("combined")
            if c:
                lines.append(f"  combined across {len(c['methods'])} methods: "
                             f"{c['depth_ppm']:.1f} +- {c['error_ppm']:.1f} ppm (statistical "
                             f"{c['sigma_stat_ppm']:.1f}, systematic {c['sigma_sys_ppm']:.1f})")
            for f in stats.get("failures", []):
                lines.append(f"  not scored: {f['method']} epoch {f['epoch']}: {f['error']}")
    for group, by_method in result.get("joint", {}).items():
        for m, j in by_method.items():
            what = (_pm(j.get("depth_ppm"), j.get("depth_err_ppm")) if not j.get("failed")
                    else f"failed: {j.get('error')}")
            lines.append(f"joint {m} ({group}, epochs {', '.join(map(str, j['epochs']))}): "
                         f"{what}")
    run = result.get("_run")
    if run:
        lines.append(f"{run['out']}: {run['ran']} tasks run, {run['skipped']} already done, "
                     f"{run['wall_s']:.1f} s ({run['executor']}); summary in {run['summary']}"
                     + (f", report in {run['report']}" if run.get("report") else ""))
    return "\n".join(lines)
