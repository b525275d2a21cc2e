"""``eclipsebench simulate``: write a simulated IRAC eclipse challenge (BCD cubes + truth)."""

from __future__ import annotations

import argparse

from ..config import load_config, replace
from ..errors import InputError
from ..limits import MAX_EPOCHS, MAX_WORKERS
from .options import (
    add_config_options,
    add_planet_options,
    check_output_path,
    planet_overrides,
    positive_int,
)

NAME = "simulate"
HELP = ("Simulate Spitzer/IRAC channel-2 subarray BCD cubes of an eclipsing planet with known "
        "truth (IRACSIM, Ingalls et al. 2016 Appendix A); default: the XO-3b 2015 challenge.")


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_config_options(p)
    add_planet_options(p)
    p.add_argument("--out", required=True, metavar="DIR",
                   help="challenge folder to write (complete epochs are kept on a rerun)")
    p.add_argument("--seed", type=positive_int(minimum=0), metavar="N",
                   help="random seed (default: challenge.seed of the configuration)")
    p.add_argument("--epochs", type=positive_int(maximum=MAX_EPOCHS), metavar="K",
                   help="number of epochs (default: challenge.epochs)")
    p.add_argument("--workers", type=positive_int(maximum=MAX_WORKERS), metavar="N",
                   help="worker processes (default: run.workers)")
    p.add_argument("--no-calibration", action="store_true",
                   help="do not write the calibration-star set for KR/Pmap")


def run(args: argparse.Namespace) -> dict:
    # the simulation and task engine (~0.5 s to import): loaded by this command only
    from ..simulation.challenge import simulate_challenge

    check_output_path(args.out, "--out", "folder")
    cfg = load_config(args.config, args.overrides + planet_overrides(args))
    challenge = cfg.challenge
    if args.seed is not None:
        challenge = replace(challenge, seed=args.seed)
    if args.epochs is not None:
        challenge = replace(challenge, epochs=args.epochs)
    cfg = replace(cfg, challenge=challenge)
    if not str(args.out).strip():
        raise InputError("--out: expected a folder")
    result = simulate_challenge(cfg, args.out, workers=args.workers,
                                calibration=False if args.no_calibration else None)
    return result.to_dict()


def format_text(result: dict) -> str:
    lines = [f"wrote {result['files']} cube files for {result['epochs']} epochs to "
             f"{result['out_dir']}"
             + (f" ({result['skipped_aors']} AORs already complete)" if result["skipped_aors"]
                else ""),
             f"truth      {result['out_dir']}/truth.ecsv ({result['truth_rows']} rows)"]
    if result["calibration"]:
        lines.append(f"calibration {result['calibration']}")
    lines.append("epoch  aorkeys                     event time (BMJD)   x_sd    y_sd    "
                 "xy_cov(1e-4)")
    for r in result["truth"]:
        keys = f"{r['aorkey_pre']}/{r['aorkey_main']}"
        if r.get("aorkey_main_last", r["aorkey_main"]) != r["aorkey_main"]:
            keys += f"-{r['aorkey_main_last']}"
        t_ecl = r.get("t_ecl_bmjd", float("nan"))
        t_tr = r.get("t_transit_bmjd", float("nan"))
        when = f"ecl {t_ecl:.5f}" if t_ecl == t_ecl or not t_tr == t_tr else f"tr  {t_tr:.5f}"
        lines.append(f"{r['epoch']:>5}  {keys:<26}  {when}  {r['x_sd']:.4f}  {r['y_sd']:.4f}  "
                     f"{1e4 * r['xy_cov']:8.2f}")
        if "phase_amplitude_ppm" in r:
            lines.append(f"       phase curve truth: amplitude {r['phase_amplitude_ppm']:.1f} ppm, "
                         f"offset {r['phase_offset_deg']:+.1f} deg, night side "
                         f"{r['nightside_flux_ppm']:.1f} ppm (first harmonic)")
    return "\n".join(lines)
