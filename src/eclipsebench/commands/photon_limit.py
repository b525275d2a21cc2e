"""``eclipsebench photon-limit``: the paper's Section 3.3 calculator."""

from __future__ import annotations

import argparse

from ..detector.constants import READ_NOISE_E, SHOT_NOISE_FORMS, SUB_2S
from ..errors import InputError
from .options import nonnegative_float, open_unit_float, positive_float, positive_int

NAME = "photon-limit"
HELP = ("Single-frame S/N of Fowler-sampled aperture photometry and the photon-noise limit "
        "of an eclipse depth (Ingalls et al. 2016, Section 3.3).")


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--flux-net", type=positive_float(), required=True, metavar="E",
                   help="background-subtracted aperture flux, electrons per frame")
    p.add_argument("--flux-aperture", type=positive_float(), required=True, metavar="E",
                   help="aperture flux before background subtraction, electrons per frame")
    p.add_argument("--flux-background", type=nonnegative_float(), required=True, metavar="E",
                   help="background electrons within the aperture area, per frame")
    p.add_argument("--frames", type=positive_int(), metavar="N",
                   help="number of frames in the light curve (with --depth-ppm gives sigma_phot)")
    p.add_argument("--depth-ppm", type=nonnegative_float(), metavar="PPM",
                   help="eclipse depth D in ppm")
    p.add_argument("--f-in", type=open_unit_float(), default=1.0 / 3.0, metavar="F",
                   help="fraction of frames in eclipse, 0 < F < 1")
    p.add_argument("--fowler", type=positive_int(), default=SUB_2S.fowler, metavar="FN", help="Fowler number")
    p.add_argument("--wait", type=positive_int(minimum=0), default=SUB_2S.wait, metavar="WT",
                   help="wait ticks between pedestal and signal reads")
    p.add_argument("--sample-time", type=positive_float(), default=SUB_2S.sample_time_s, metavar="S",
                   help="sample time in seconds (0.01 subarray, 0.2 full array)")
    p.add_argument("--read-noise", type=nonnegative_float(), default=READ_NOISE_E, metavar="E",
                   help="read noise per read, electrons")
    p.add_argument("--aperture-pixels", type=positive_float(), metavar="NPIX",
                   help="aperture area in pixels; adds read noise per pixel (default: the paper's "
                        "single read-noise term)")
    p.add_argument("--shot-noise", choices=SHOT_NOISE_FORMS, default="paper",
                   help="Fowler shot-noise term: 'paper' (Eq. gar_for_var as printed, default) or "
                        "'poisson' (exact for Poisson increments, 2.7%% lower for FN=8, WT=184)")


def run(args: argparse.Namespace) -> dict:
    from ..stats.photon_limit import photon_limit  # numpy: not at CLI start

    if (args.frames is None) != (args.depth_ppm is None):
        raise InputError("--frames and --depth-ppm: give both to compute sigma_phot_ppm")
    if args.flux_aperture < args.flux_net:
        raise InputError(f"--flux-aperture {args.flux_aperture:g}: expected at least --flux-net "
                         f"{args.flux_net:g} (the aperture flux is the net flux plus the "
                         "background in the aperture)")
    result = photon_limit(args.flux_net, args.flux_aperture, args.flux_background,
                          frames=args.frames, depth_ppm=args.depth_ppm, f_in=args.f_in,
                          fowler=args.fowler, wait=args.wait, sample_time_s=args.sample_time,
                          read_noise_e=args.read_noise, aperture_pixels=args.aperture_pixels,
                          shot_noise=args.shot_noise)
    out = result.to_dict()
    out.update({"inputs": {"flux_net_e": args.flux_net, "flux_aperture_e": args.flux_aperture,
                           "flux_background_e": args.flux_background, "frames": args.frames,
                           "depth_ppm": args.depth_ppm, "f_in": args.f_in, "fowler": args.fowler,
                           "wait": args.wait, "sample_time_s": args.sample_time,
                           "read_noise_e": args.read_noise,
                           "aperture_pixels": args.aperture_pixels,
                           "shot_noise": args.shot_noise}})
    return out


def format_text(result: dict) -> str:
    lines = [f"sigma_e        {result['sigma_e']:.1f} e per frame",
             f"snr_single     {result['snr_single']:.1f}",
             f"t_int / t_exp  {result['t_int_s']:.3f} s / {result['t_exp_s']:.3f} s"]
    if result["sigma_phot_ppm"] is not None:
        lines.append(f"sigma_phot     {result['sigma_phot_ppm']:.1f} ppm")
    return "\n".join(lines)
