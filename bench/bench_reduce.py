"""Speed (and a recovery check) of ``reduce_epoch`` for every registered method.

One synthetic XO-3b epoch of 15,000 frames (8.8 h, eclipse from the catalogue
orbit, quadratic phase curve, a drifting and wobbling pointing track through a
smooth intra-pixel gain, a 5x5 Gaussian-PSF stamp, white noise of 0.3 % per
frame) and a 200,000-frame calibration-star table for KR/Pmap. Each method is
fitted with the defaults (least squares, Jacobian x beta_red, 16-shift prayer
bead); ``--mcmc`` adds an emcee run. The reference, timed in the same
process, is one batman secondary-eclipse light curve of the same 15,000
frames; the ratio (method time / reference) is comparable between machines.
Everything runs on one core (BLAS, OpenMP and numba threads set to 1).

``--recovery`` also fits noiseless copies (with and without the gain) and
prints depth minus truth, for the acceptance points of issue 6.

Usage: ``python bench/bench_reduce.py [--repeats 3] [--mcmc] [--recovery] [--methods bliss pld]``
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
from scipy.special import erf  # noqa: E402

DEPTH = 1875e-6
C1, C2 = 2.0e-3, -1.2e-2      # phase curve, per day and per day^2 (concave down)
NOISE = 3e-3                  # per frame
F0 = 1.0e5                    # electrons
SIGMA_PSF = 0.55              # px


def gain(x, y):
    """A smooth intra-pixel gain peaking near the pixel centre (about 1 % over 0.15 px)."""
    dx, dy = x - 15.0, y - 15.0
    return 1.0 + 0.02 * dx - 0.015 * dy - 0.5 * dx**2 - 0.35 * dy**2 + 0.1 * dx * dy


def track(t_d, rng):
    """Pointing: drift, a 40-min wobble, a 1-min jitter and white centroid noise."""
    t = t_d - t_d[0]
    x = 15.03 + 0.02 * t + 0.04 * np.sin(2 * np.pi * t / (40 / 1440)) \
        + 0.01 * np.sin(2 * np.pi * t / (1 / 1440)) + 0.005 * rng.standard_normal(len(t))
    y = 14.98 + 0.12 * t + 0.03 * np.cos(2 * np.pi * t / (40 / 1440)) \
        + 0.01 * np.cos(2 * np.pi * t / (1.3 / 1440)) + 0.005 * rng.standard_normal(len(t))
    return x, y


def stamps(x, y, total):
    """5x5 pixel values of a Gaussian PSF centred at (x, y), pixel centres at integers."""
    edges = np.arange(13, 18)[None, :]
    s = SIGMA_PSF * np.sqrt(2)
    fx = 0.5 * (erf((edges + 0.5 - x[:, None]) / s) - erf((edges - 0.5 - x[:, None]) / s))
    fy = 0.5 * (erf((edges + 0.5 - y[:, None]) / s) - erf((edges - 0.5 - y[:, None]) / s))
    return total[:, None, None] * fy[:, :, None] * fx[:, None, :]


def make_table(system, *, n_frames=15000, systematics=True, noise=NOISE, seed=2015, simdir=""):
    from astropy.table import Table

    from eclipsebench.astro.eclipse import EclipseShape
    from eclipsebench.astro.orbit import eclipse_time_bmjd
    rng = np.random.default_rng(seed)
    t_ecl = eclipse_time_bmjd(system, 57100.0) + 0.002
    time_bmjd = t_ecl - 0.19 + np.arange(n_frames) * (8.8 / 24 / n_frames)
    visible = EclipseShape(time_bmjd, system).visible_fraction(t_ecl)
    dt = time_bmjd - t_ecl
    astro = 1 + visible * (DEPTH + C1 * dt + C2 * dt**2)
    x, y = track(time_bmjd, rng)
    g = gain(x, y) if systematics else np.ones(n_frames)
    total = F0 * g * astro * (1 + noise * rng.standard_normal(n_frames))
    pix = stamps(x, y, total)
    flux = pix.sum(axis=(1, 2))
    xc = (pix.sum(axis=1) * np.arange(13, 18)).sum(axis=1) / flux
    yc = (pix.sum(axis=2) * np.arange(13, 18)).sum(axis=1) / flux
    npix = flux**2 / (pix**2).sum(axis=(1, 2))
    table = Table({"time_bmjd": time_bmjd, "aorkey": np.full(n_frames, 20150001),
                   "x": xc, "y": yc, "noise_pixels": npix, "flux": flux,
                   "flux_err": np.full(n_frames, F0 * max(noise, 1e-4)),
                   "flag": np.zeros(n_frames, dtype=np.int32), "stamp3": pix[:, 1:4, 1:4],
                   "stamp5": pix})
    table.meta.update({"EPOCH": 1, "SIMDIR": simdir})
    return table


def write_calibration(folder: Path, *, systematics=True, n_points=200000, seed=7):
    """A calibration-star table (the simulator's columns) over the sweet spot."""
    from astropy.table import Table
    rng = np.random.default_rng(seed)
    x = 15.0 + rng.uniform(-0.35, 0.35, n_points)
    y = 15.0 + rng.uniform(-0.35, 0.45, n_points)
    g = gain(x, y) if systematics else np.ones(n_points)
    total = 5e4 * g
    pix = stamps(x, y, total)
    flux = pix.sum(axis=(1, 2))
    xc = (pix.sum(axis=1) * np.arange(13, 18)).sum(axis=1) / flux
    yc = (pix.sum(axis=2) * np.arange(13, 18)).sum(axis=1) / flux
    npix = flux**2 / (pix**2).sum(axis=(1, 2))
    (folder / "calibration").mkdir(parents=True, exist_ok=True)
    Table({"x": xc, "y": yc, "noise_pixels": npix, "flux": flux,
           "flux_err": np.sqrt(flux)}).write(folder / "calibration" / "pmap_calibration.fits",
                                             overwrite=True)


def batman_reference(system, time_bmjd, repeats):
    """Median seconds of one batman secondary-eclipse light curve on ``time_bmjd``."""
    import batman
    p = batman.TransitParams()
    p.t0, p.per, p.rp, p.a = 0.0, system.period_days, system.rp_rs, system.a_rs
    p.inc, p.ecc, p.w = system.inc_deg, system.ecc, system.omega_deg
    p.limb_dark, p.u, p.fp = "uniform", [], DEPTH
    p.t_secondary = float(np.median(time_bmjd) - 57000.0)
    m = batman.TransitModel(p, time_bmjd - 57000.0, transittype="secondary")
    runs = []
    for _ in range(repeats):
        n, t0 = 0, time.perf_counter()
        while time.perf_counter() - t0 < 0.3:
            m.light_curve(p)
            n += 1
        runs.append((time.perf_counter() - t0) / n)
    return float(np.median(runs))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--frames", type=int, default=15000)
    ap.add_argument("--mcmc", action="store_true", help="also time least squares + emcee")
    ap.add_argument("--recovery", action="store_true",
                    help="noiseless recovery with and without systematics")
    ap.add_argument("--methods", nargs="*", default=None)
    args = ap.parse_args(argv)

    from eclipsebench.astro.catalogue import get_system
    from eclipsebench.config.reduce import ReduceSection
    from eclipsebench.decorrelate import available_methods
    from eclipsebench.fit.reduce import reduce_epoch

    system = get_system("XO-3b")
    methods = args.methods or list(available_methods())
    with tempfile.TemporaryDirectory() as tmp:
        write_calibration(Path(tmp))
        table = make_table(system, n_frames=args.frames, simdir=tmp)
        ref = batman_reference(system, np.asarray(table["time_bmjd"]), args.repeats)
        print(f"frames: {args.frames}, repeats: {args.repeats} (medians), one core")
        print(f"reference: one batman secondary-eclipse light curve = {ref * 1e3:.3f} ms")
        print(f"{'method':<10s} {'sampler':<8s} {'time s':>8s} {'x batman':>10s} "
              f"{'depth-true':>11s} {'err ppm':>8s} {'err from':>14s} {'beta':>6s}")
        samplers = ["leastsq"] + (["mcmc"] if args.mcmc else [])
        for name in methods:
            for sampler in samplers:
                opts = ReduceSection(sampler=sampler)
                times, res = [], None
                for _ in range(args.repeats if sampler == "leastsq" else 1):
                    t0 = time.perf_counter()
                    res = reduce_epoch(table, name, options=opts, seed=1)
                    times.append(time.perf_counter() - t0)
                dt = float(np.median(times))
                extra = ""
                if res.depth_err_separation_ppm:
                    extra = f"  (ICA separation error {res.depth_err_separation_ppm:.1f} ppm)"
                print(f"{name:<10s} {sampler:<8s} {dt:8.2f} {dt / ref:10.3g} "
                      f"{res.depth_ppm - DEPTH * 1e6:11.1f} {res.depth_err_ppm:8.1f} "
                      f"{res.depth_err_method:>14s} {res.beta_red:6.2f}{extra}", flush=True)
        if args.recovery:
            print("\nnoiseless recovery (quadratic phase, leastsq, no prayer bead): depth - truth, ppm")
            flat_dir = Path(tmp) / "flat"
            write_calibration(flat_dir, systematics=False)
            sys_tab = make_table(system, n_frames=args.frames, noise=0.0, simdir=tmp)
            flat_tab = make_table(system, n_frames=args.frames, noise=0.0, systematics=False,
                                  simdir=str(flat_dir))
            flat_depths = {}
            for name in methods:
                # The shared (physical) eclipse shape for every method; segpoly also with its
                # faithful default, the team's box eclipse.
                shapes = ["physical"] + (["auto"] if name == "segpoly" else [])
                for shape in shapes:
                    shape_opts = ReduceSection(prayer_bead_shifts=0, eclipse_shape=shape)
                    with_sys = reduce_epoch(sys_tab, name, options=shape_opts).depth_ppm
                    flat = reduce_epoch(flat_tab, name, options=shape_opts).depth_ppm
                    if shape == "physical":
                        flat_depths[name] = flat
                    label = f"{name} ({'box' if shape == 'auto' else shape})"
                    print(f"{label:<20s} with systematics {with_sys - DEPTH * 1e6:8.2f}   without "
                          f"{flat - DEPTH * 1e6:8.2f}", flush=True)
            spread = max(flat_depths.values()) - min(flat_depths.values())
            print(f"spread of the no-systematics depths across methods: {spread:.2f} ppm")
    return 0


if __name__ == "__main__":
    sys.exit(main())
