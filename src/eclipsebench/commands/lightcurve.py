"""``eclipsebench lightcurve``: the model light curve L(t) of a planet, written and summarised."""

from __future__ import annotations

import argparse

import numpy as np
from astropy.table import Table

from ..astro.bias import EPOCH10_START_BMJD, epoch_times
from ..astro.catalogue import get_system
from ..astro.lightcurve import light_curve_function
from ..astro.orbit import BMJD_OFFSET
from ..errors import InputError
from ..io.atomic import atomic_path
from ..io.paths import check_plot_path
from .options import check_output_path, finite_float, nonnegative_float, positive_float

NAME = "lightcurve"
HELP = ("Model light curve L(t) of a star and planet (Cowan & Agol thermal phase curve, "
        "eclipses, transits); defaults are the 2015 challenge's XO-3b settings.")


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("system", metavar="SYSTEM", nargs="?", default="XO-3b",
                   help="planet name from the catalogue (e.g. XO-3b, 'HD 189733b')")
    p.add_argument("--catalogue", metavar="FILE.toml", default=None,
                   help="a user catalogue of systems (TOML), searched before the built-in one")
    p.add_argument("--start", type=finite_float(), default=EPOCH10_START_BMJD, metavar="BMJD",
                   help="first sample, BMJD_TDB (default: the paper's simulated epoch 10)")
    p.add_argument("--hours", type=positive_float(), default=8.8, metavar="H",
                   help="length of the light curve in hours")
    p.add_argument("--cadence-s", type=positive_float(), default=2.008, metavar="S",
                   help="sampling interval in seconds (IRAC 2 s subarray frames by default)")
    p.add_argument("--albedo", type=nonnegative_float(), default=0.0, metavar="A",
                   help="Bond albedo, 0 <= A < 1")
    p.add_argument("--tau-rad", type=nonnegative_float(), default=1.0, metavar="DAYS",
                   help="radiative time at the periastron sub-stellar temperature (0: instantaneous)")
    p.add_argument("--omega-rot", type=finite_float(), default=1.0, metavar="W",
                   help="gas angular velocity in units of the periastron orbital angular velocity")
    p.add_argument("--flux-ratio-model", choices=("monochromatic", "tophat"),
                   default="monochromatic",
                   help="ratio of blackbodies at --wavelength, or averaged over 4.0-5.0 um")
    p.add_argument("--wavelength", type=positive_float(), default=4.5095, metavar="UM",
                   help="wavelength of the monochromatic flux ratio, micron")
    p.add_argument("--fix-depth", type=nonnegative_float(), default=1875.0, metavar="PPM",
                   help="scale the planet's flux so the eclipse depth is this (0: the model's own)")
    p.add_argument("--quadrature", choices=("gauss", "iracsim2015"), default="gauss",
                   help="surface sum of the thermal model (iracsim2015 reproduces the challenge's)")
    p.add_argument("--out", metavar="FILE.ecsv", help="write time_bmjd, flux and its components")
    p.add_argument("--plot", metavar="FILE.png", help="plot the light curve")


def run(args: argparse.Namespace) -> dict:
    if args.out:
        check_output_path(args.out, "--out", "file")
    if args.plot:
        check_plot_path(args.plot, "--plot")
    if not 0.0 <= args.albedo < 1.0:
        raise InputError(f"--albedo: expected 0 <= A < 1, got {args.albedo}")
    system = get_system(args.system, args.catalogue)
    options = dict(albedo=args.albedo, tau_rad_days=args.tau_rad, omega_rot=args.omega_rot,
                   flux_ratio_model=args.flux_ratio_model, wavelength_um=args.wavelength,
                   quadrature=args.quadrature)
    lc = light_curve_function(system, fix_depth_ppm=args.fix_depth, **options)
    instantaneous = lc if args.tau_rad == 0 else light_curve_function(
        system, fix_depth_ppm=0.0, **{**options, "tau_rad_days": 0.0})
    n = int(np.floor(args.hours * 3600.0 / args.cadence_s)) + 1
    if n > 50_000_000:
        raise InputError("--hours/--cadence-s: more than 5e7 samples requested")
    time = epoch_times(args.start, args.hours, args.cadence_s)
    flux = lc(time)
    stop = float(time[-1])
    mid = 0.5 * (args.start + stop)
    t_ecl = min(lc.eclipse_times_bmjd(mid - system.period_days, mid + system.period_days),
                key=lambda t: abs(t - mid))
    t_tr = min(lc.transit_times_bmjd(mid - system.period_days, mid + system.period_days),
               key=lambda t: abs(t - mid))
    result = {
        "system": system.name,
        "eclipse_depth_ppm": lc.depth_ppm,
        "model_depth_ppm": lc.model_depth_ppm,
        "model_depth_instantaneous_ppm": instantaneous.model_depth_ppm,
        "depth_fixed": args.fix_depth > 0,
        "t_transit_bjd": t_tr + BMJD_OFFSET,
        "t_eclipse_bjd": t_ecl + BMJD_OFFSET,
        "t_transit_bmjd": t_tr,
        "t_eclipse_bmjd": t_ecl,
        "start_bmjd": float(args.start),
        "stop_bmjd": stop,
        "n_samples": int(n),
        "eclipses_in_window": lc.eclipse_times_bmjd(args.start, stop),
        "transits_in_window": lc.transit_times_bmjd(args.start, stop),
        "flux_min": float(flux.min()),
        "flux_max": float(flux.max()),
        "options": lc.options,
        "system_values": {k: v for k, v in system.to_dict().items() if k != "references"},
    }
    if args.out:
        _write_table(args.out, lc, time, flux)
        result["out_file"] = str(args.out)
    if args.plot:
        _plot(args.plot, lc, time, flux)
        result["plot_file"] = str(args.plot)
    return result


def _write_table(path: str, lc, time: np.ndarray, flux: np.ndarray) -> None:
    table = Table({"time_bmjd": time, "flux": flux,
                   "planet_flux": lc.planet_flux(time),
                   "visible_fraction": lc.visible_fraction(time),
                   "stellar_flux": lc.stellar_flux(time)})
    table.meta.update({"system": lc.system.name, "depth_ppm": lc.depth_ppm,
                       "model_depth_ppm": lc.model_depth_ppm,
                       "t_eclipse_bmjd": lc.t_eclipse_bmjd, "t_transit_bmjd": lc.t_transit_bmjd,
                       "options": dict(lc.options),
                       "normalisation": "1 = the star alone (flux in total eclipse)"})
    with atomic_path(path) as tmp:
        table.write(tmp, format="ascii.ecsv")


def _plot(path: str, lc, time: np.ndarray, flux: np.ndarray) -> None:
    # matplotlib (about 0.5 s to import) only when a plot is asked for.
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(7, 3.5))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(1, 1, 1)
    hours = (time - time[0]) * 24.0
    ax.plot(hours, (flux - 1.0) * 1e6, lw=1.0)
    ax.set_xlabel(f"hours since BMJD {time[0]:.4f}")
    ax.set_ylabel("L(t) - 1 (ppm)")
    ax.set_title(f"{lc.system.name}: depth {lc.depth_ppm:.0f} ppm "
                 f"(A={lc.options['albedo']:g}, tau_rad={lc.options['tau_rad_days']:g} d, "
                 f"Omega_rot={lc.options['omega_rot']:g})", fontsize=9)
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format=path.rsplit(".", 1)[-1] if "." in path else "png", dpi=120)


def format_text(result: dict) -> str:
    lines = [
        f"system                {result['system']}",
        f"eclipse depth         {result['eclipse_depth_ppm']:.1f} ppm"
        + (" (fixed)" if result["depth_fixed"] else ""),
        f"model depth           {result['model_depth_ppm']:.1f} ppm "
        f"(tau_rad = {result['options']['tau_rad_days']:g} d); "
        f"instantaneous re-radiation {result['model_depth_instantaneous_ppm']:.1f} ppm",
        f"transit / eclipse     BJD {result['t_transit_bjd']:.5f} / {result['t_eclipse_bjd']:.5f}",
        f"samples               {result['n_samples']} from BMJD {result['start_bmjd']:.5f} "
        f"to {result['stop_bmjd']:.5f}",
    ]
    if "out_file" in result:
        lines.append(f"written               {result['out_file']}")
    if "plot_file" in result:
        lines.append(f"plot                  {result['plot_file']}")
    return "\n".join(lines)
