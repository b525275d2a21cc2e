"""``eclipsebench run``: the whole data challenge (simulate, photometry, reduce, stats, report)."""

from __future__ import annotations

import argparse
from dataclasses import replace
from pathlib import Path

from ..config import Config, load_config
from ..engine.cluster import (
    DEFAULT_CONNECT_TIMEOUT_S,
    TLS_ENV,
    ClusterOptions,
    scheduler_from_environment,
)
from ..errors import InputError
from ..io.paths import check_output_path
from ..limits import MAX_EPOCHS, MAX_WORKERS
from .options import (
    add_config_options,
    add_planet_options,
    method_list,
    planet_overrides,
    positive_float,
    positive_int,
    run_overrides,
)

NAME = "run"
HELP = ("Run the data challenge end to end on Dask: simulate every epoch, photometry, every method "
        "on every epoch, statistics (Tables 3-4), photon limits and the report; resumable.")


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_config_options(p)
    add_planet_options(p)
    p.add_argument("--out", metavar="DIR",
                   help="run folder (default: runs/<challenge>-seed<SEED>-<EPOCHS>ep); rerunning "
                        "the same command resumes it")
    p.add_argument("--seed", type=positive_int(minimum=0), metavar="N",
                   help="challenge seed (challenge.seed)")
    p.add_argument("--epochs", type=positive_int(maximum=MAX_EPOCHS), metavar="K",
                   help="number of simulated epochs (challenge.epochs); e.g. 200 for Monte Carlo")
    p.add_argument("--methods", type=method_list, metavar="A,B,...",
                   help="methods to run (run.methods; default: every registered method)")
    p.add_argument("--profiles", type=_profile_list, metavar="P[,P]",
                   help="controlled, paper or both (run.profiles; default both)")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--workers", type=positive_int(maximum=MAX_WORKERS), metavar="N",
                   help="Dask worker processes of a local cluster; 1 runs in this process")
    g.add_argument("--scheduler", metavar="ADDRESS",
                   help="address of an existing Dask scheduler, e.g. tcp://host:8786 or "
                        "tls://host:8786 (default: the environment variable "
                        "ECLIPSEBENCH_SCHEDULER; never a configuration file)")
    add_cluster_options(p)


def add_cluster_options(p: argparse.ArgumentParser) -> None:
    """The Dask options of ``run``: the dashboard, the connection timeout, TLS files."""
    p.add_argument("--dashboard", action="store_true",
                   help="serve the local cluster's Dask dashboard on 127.0.0.1 and print its "
                        "address (off by default)")
    p.add_argument("--connect-timeout", type=positive_float(), default=DEFAULT_CONNECT_TIMEOUT_S,
                   metavar="S", help="seconds to reach --scheduler, its handshake included")
    for name, what in (("ca-file", "the certificate authority that signed the scheduler's "
                                   "certificate"),
                       ("cert", "this client's certificate"),
                       ("key", "this client's private key, unless in --tls-cert's file")):
        env = TLS_ENV["tls_" + name.replace("-", "_")]
        p.add_argument(f"--tls-{name}", metavar="FILE.pem", default=None,
                       help=f"for a tls:// --scheduler: {what} (default: ${env})")


def _profile_list(text: str) -> list[str]:
    items = [p.strip() for p in text.split(",") if p.strip()]
    bad = [p for p in items if p not in ("controlled", "paper")]
    if not items or bad or len(set(items)) != len(items):
        raise argparse.ArgumentTypeError(f"{text!r}: expected controlled, paper or "
                                         "controlled,paper")
    return items


def _overrides(args: argparse.Namespace) -> list[str]:
    extra = []
    if args.epochs is not None:
        extra.append(f"challenge.epochs={args.epochs}")
    extra += run_overrides(args)
    return list(args.overrides) + extra + planet_overrides(args)


def _config(args: argparse.Namespace) -> Config:
    """CONFIG with ``--set`` and the options that name a key; ``--seed``, parsed to an int,
    goes in as that int (``challenge.seed``), not through the text of an override."""
    cfg = load_config(args.config, _overrides(args))
    if args.seed is not None:
        cfg = replace(cfg, challenge=replace(cfg.challenge, seed=args.seed))
    return cfg


def _scheduler(args: argparse.Namespace) -> str | None:
    """``--scheduler``, else ``ECLIPSEBENCH_SCHEDULER`` (unless ``--workers`` is given)."""
    if args.scheduler is not None:
        if not args.scheduler.strip():
            raise InputError("--scheduler: expected an address such as tcp://host:8786")
        return args.scheduler.strip()
    return None if args.workers is not None else scheduler_from_environment()


def run(args: argparse.Namespace) -> dict:
    # every stage's modules (~1.5 s to import): loaded by this command only, not at CLI start
    from ..challenge.runner import Layout, run_challenge

    cfg = _config(args)
    out = Path(args.out) if args.out else Path(
        "runs") / f"{cfg.challenge.name}-seed{cfg.challenge.seed}-{cfg.challenge.epochs}ep"
    check_output_path(out, "--out", "folder")
    summary, report = run_challenge(cfg, out, scheduler=_scheduler(args), cluster=ClusterOptions(
        dashboard=args.dashboard, connect_timeout_s=args.connect_timeout,
        tls_ca_file=args.tls_ca_file, tls_cert=args.tls_cert, tls_key=args.tls_key))
    if args.json:
        return summary
    layout = Layout(out)
    return {**summary, "_run": {"out": str(out), "ran": len(report.ran),
                                "skipped": len(report.skipped), "wall_s": report.wall_s,
                                "executor": report.executor, "summary": str(layout.summary),
                                "report": str(layout.report) if cfg.run.report else None}}


def format_text(result: dict) -> str:
    from ..report.tables import format_text_table  # astropy: not at CLI start

    profiles = result.get("profiles") or {result.get("profile", "controlled"): result}
    lines = []
    for name, stats in profiles.items():
        lines += [f"{name} profile:", format_text_table(stats)]
        lines += _coverage_lines(stats)
        for f in stats.get("failures", []):
            lines.append(f"not scored ({name}): {f['method']} epoch {f['epoch']}: {f['error']}")
        if stats.get("methods_excluded"):
            lines.append(f"methods left out of the {name} profile (fewer than 2 usable "
                         "epochs): " + ", ".join(stats["methods_excluded"]))
    pl = result.get("photon_limit", {})
    a, e = pl.get("analytic"), pl.get("empirical")
    if a:
        lines.append(f"photon limit (analytic, Section 3.3): {a['sigma_phot_ppm']:.1f} ppm "
                     f"(S/N {a['snr_single']:.0f}, {a['frames']:.0f} frames, f_in {a['f_in']:.3f})")
    if e and e.get("sigma_phot_ppm") is not None:
        lines.append(f"photon limit (empirical, {e['method']} on no-motion twins): "
                     f"{e['sigma_phot_ppm']:.1f} ppm (68%: {e['sigma_phot_lo_ppm']:.1f}-"
                     f"{e['sigma_phot_hi_ppm']:.1f})")
    run = result.get("_run")
    if run:
        where = f"summary in {run['summary']}"
        if run.get("report"):
            where += f", report in {run['report']}"
        lines.append(f"{run['out']}: {run['ran']} tasks run, {run['skipped']} already done, "
                     f"{run['wall_s']:.1f} s ({run['executor']}); {where}")
    return "\n".join(lines)


def _coverage_lines(stats: dict) -> list[str]:
    lines = []
    for n_sigma, key in ((1, "coverage"), (2, "coverage_2sigma")):
        cover = {m: s for m, s in stats["methods"].items() if s.get(key) is not None}
        if cover:
            lines.append(f"fraction of epochs within {n_sigma} sigma of the truth (its 68% "
                         "binomial interval): " + ", ".join(
                f"{m} {s[key]:.2f} ({s[key + '_lo']:.2f}-{s[key + '_hi']:.2f})"
                for m, s in cover.items()))
    return lines
