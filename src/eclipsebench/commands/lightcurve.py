"""``eclipsebench lightcurve``: the model light curve L(t) of a planet, written and summarised.

``--phase-bias`` is the paper's Section 4.2 check instead: the depth bias of
flat, linear and quadratic phase models fitted to the noiseless L(t) of one
epoch of the built-in challenge (:func:`eclipsebench.astro.bias.phase_model_bias`).
"""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

from ..astro.times import BMJD_OFFSET, EPOCH10_START_BMJD
from ..config.system import CHALLENGE_SYSTEM, SystemSection
from ..errors import InputError
from ..io.atomic import atomic_path
from ..io.paths import check_plot_path
from .lightcurve_text import format_text as format_text  # the CLI prints with it
from .options import (
    add_planet_options,
    check_output_path,
    finite_float,
    nonnegative_float,
    planet_from_args,
    positive_float,
    positive_int,
)

if TYPE_CHECKING:  # pragma: no cover
    import numpy as np

# numpy, astropy and the light-curve model are imported where the work is done, so the
# command line's parser stays light (tests/foundation/test_cli_startup.py).

NAME = "lightcurve"
HELP = ("Model light curve L(t) of a star and planet (Cowan & Agol thermal phase curve, "
        "eclipses, transits), or with --phase-bias the Section 4.2 depth bias of the phase "
        "models; defaults are the 2015 challenge's XO-3b settings.")

PHASE_BIAS_MODELS = ("flat", "linear", "quadratic")
PHASE_BIAS_EPOCH = 10  # the epoch of the paper's figure of the predicted light curve
_WINDOW_DEFAULTS = {"start": EPOCH10_START_BMJD, "hours": 8.8, "cadence_s": 2.008}


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("system", metavar="SYSTEM", nargs="?", default=None,
                   help="planet name or alias from the catalogue (e.g. XO-3b, 'HD 189733b'; "
                        f"default: the built-in challenge's, {CHALLENGE_SYSTEM!r})")
    add_planet_options(p)
    p.add_argument("--start", type=finite_float(), default=None, metavar="BMJD",
                   help="first sample, BMJD_TDB (default: the paper's simulated epoch 10, "
                        f"{EPOCH10_START_BMJD:.4f})")
    p.add_argument("--hours", type=positive_float(), default=None, metavar="H",
                   help="length of the light curve in hours (default: 8.8)")
    p.add_argument("--cadence-s", type=positive_float(), default=None, metavar="S",
                   help="sampling interval in seconds (default: 2.008, IRAC 2 s subarray frames)")
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
    p.add_argument("--fix-depth", type=nonnegative_float(), default=None, metavar="PPM",
                   help="scale the planet's flux so the eclipse depth is this (0: the model's "
                        "own; default: the challenge's 1875 ppm for the challenge's planet, the "
                        "model's own for any other)")
    p.add_argument("--quadrature", choices=("gauss", "iracsim2015"), default="gauss",
                   help="surface sum of the thermal model (iracsim2015 reproduces the challenge's)")
    p.add_argument("--out", metavar="FILE.ecsv", help="write time_bmjd, flux and its components")
    p.add_argument("--plot", metavar="FILE.png", help="plot the light curve")
    p.add_argument("--phase-bias", action="store_true",
                   help="instead: the paper's Section 4.2 check, the fitted-minus-true depth "
                        "(ppm) of flat, linear and quadratic phase models fitted to the "
                        "noiseless L(t) at the frames of one epoch of the built-in challenge")
    p.add_argument("--epoch", type=positive_int(), default=None, metavar="N",
                   help="with --phase-bias: the challenge epoch, 1 to its number of epochs "
                        f"(default: {PHASE_BIAS_EPOCH}, the epoch of the paper's figure)")


def _fixed_depth_ppm(args: argparse.Namespace, system) -> float:
    """``--fix-depth``, else the challenge's fixed depth for the challenge's planet only: a
    real planet's depth is its own thermal model's (its elements, star and albedo)."""
    if args.fix_depth is not None:
        return float(args.fix_depth)
    return SystemSection().fix_depth_ppm if system.name == CHALLENGE_SYSTEM else 0.0


def _light_curve_options(args: argparse.Namespace) -> dict:
    if not 0.0 <= args.albedo < 1.0:
        raise InputError(f"--albedo: expected 0 <= A < 1, got {args.albedo}")
    return dict(albedo=args.albedo, tau_rad_days=args.tau_rad, omega_rot=args.omega_rot,
                flux_ratio_model=args.flux_ratio_model, wavelength_um=args.wavelength,
                quadrature=args.quadrature)


def _run_phase_bias(args: argparse.Namespace) -> dict:
    """Section 4.2: the depth bias of each phase model on one challenge epoch's noiseless L(t)."""
    from ..astro.bias import phase_model_bias
    from ..astro.lightcurve import light_curve_function
    from ..simulation.from_config import challenge_epoch_times_bmjd

    for name in ("start", "hours", "cadence_s", "out", "plot"):
        if getattr(args, name) is not None:
            option = "--" + name.replace("_", "-")
            raise InputError(f"{option}: not with --phase-bias (the frames are those of the "
                             "challenge epoch; choose it with --epoch)")
    epoch = PHASE_BIAS_EPOCH if args.epoch is None else args.epoch
    time = challenge_epoch_times_bmjd(epoch, label="--epoch")
    system = planet_from_args(args, args.system)
    lc = light_curve_function(system, fix_depth_ppm=_fixed_depth_ppm(args, system),
                              **_light_curve_options(args))
    t0, t1 = float(time[0]), float(time[-1])
    inside = lc.eclipse_times_bmjd(t0, t1)
    if not inside:
        raise InputError(f"{system.name}: no eclipse inside challenge epoch {epoch} "
                         f"(BMJD {t0:.4f}-{t1:.4f}); the phase-model bias needs one")
    t_ecl = min(inside, key=lambda t: abs(t - 0.5 * (t0 + t1)))
    bias = phase_model_bias(lc, time, PHASE_BIAS_MODELS, t_ecl_bmjd=t_ecl)
    return {
        "system": system.name,
        "epoch": int(epoch),
        "phase_bias_ppm": bias,
        "depth_ppm": lc.depth_ppm,
        "t_eclipse_bmjd": float(t_ecl),
        "eclipse_after_start_hours": (float(t_ecl) - t0) * 24.0,
        "start_bmjd": t0,
        "stop_bmjd": t1,
        "n_frames": int(time.size),
        "options": lc.options,
    }


def run(args: argparse.Namespace) -> dict:
    import numpy as np

    from ..astro.bias import epoch_times
    from ..astro.lightcurve import light_curve_function

    if args.phase_bias:
        return _run_phase_bias(args)
    if args.epoch is not None:
        raise InputError("--epoch: only with --phase-bias")
    for name, value in _WINDOW_DEFAULTS.items():
        if getattr(args, name) is None:
            setattr(args, name, value)
    if args.out:
        check_output_path(args.out, "--out", "file")
    if args.plot:
        check_plot_path(args.plot, "--plot")
    options = _light_curve_options(args)
    system = planet_from_args(args, args.system)
    lc = light_curve_function(system, fix_depth_ppm=_fixed_depth_ppm(args, system), **options)
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
        "depth_fixed": _fixed_depth_ppm(args, system) > 0,
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
    from astropy.table import Table

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

    from ..fit.result.plot import literal_text

    fig = Figure(figsize=(7, 3.5))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(1, 1, 1)
    hours = (time - time[0]) * 24.0
    ax.plot(hours, (flux - 1.0) * 1e6, lw=1.0)
    ax.set_xlabel(f"hours since BMJD {time[0]:.4f}")
    ax.set_ylabel("L(t) - 1 (ppm)")
    ax.set_title(f"{literal_text(lc.system.name)}: depth {lc.depth_ppm:.0f} ppm "
                 f"(A={lc.options['albedo']:g}, tau_rad={lc.options['tau_rad_days']:g} d, "
                 f"Omega_rot={lc.options['omega_rot']:g})", fontsize=9)
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format=path.rsplit(".", 1)[-1] if "." in path else "png", dpi=120)
